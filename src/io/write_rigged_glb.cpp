// The rigged GLB (io/write_rigged_glb.h): skeleton, skin, clips and the bind-pose mesh in one glTF 2.0 binary.
#include "io/write_rigged_glb.h"

#include "core/rotation.h"
#include "io/atomic_file.h"
#include "io/glb_builder.h"
#include "io/write_mesh.h"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace ff::io {
namespace {

using glb::GlbBuilder;
using glb::json;

bool finite_quat(const Quatf& q) { return q.coeffs().allFinite() && q.coeffs().squaredNorm() > 0.0f; }

json vec3(const Vec3f& v) { return {v.x(), v.y(), v.z()}; }
json quat(const Quatf& q) {
  const Quatf n = q.normalized();
  return {n.x(), n.y(), n.z(), n.w()};  // glTF: x, y, z, w
}

// The interpolation of pose::global_matrices (pose/skin_eval.cpp), for keys made at times the file has none
// (a clip's start and end).
Vec3f lerp_value(const Vec3f& a, const Vec3f& b, float u) { return (1.0f - u) * a + u * b; }
Quatf lerp_value(const Quatf& a, const Quatf& b, float u) { return a.slerp(u, b); }

template <class V>
V value_at(const std::vector<double>& times, const std::vector<V>& values, double t) {
  if (t <= times.front()) return values.front();
  if (t >= times.back()) return values.back();
  const auto i = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
  const double span = times[i + 1] - times[i];
  return span > 0.0 ? lerp_value(values[i], values[i + 1], static_cast<float>((t - times[i]) / span)) : values[i];
}

/// One path's keys as glTF wants them: float times strictly increasing in [0, duration], the last at the duration
/// (the value held, as Skin::global_matrices clamps), keys outside [0, duration] replaced by the value at the end they
/// pass (what the C++ pose shows there). Keys closer than float resolution keep the first.
template <class V>
Status clean_keys(const std::vector<double>& times, const std::vector<V>& values, double duration,
                  const std::string& what, std::vector<float>& out_t, std::vector<V>& out_v) {
  out_t.clear(), out_v.clear();
  if (times.size() != values.size())
    return input_error(fmt::format("rigged glb: {} has {} key times for {} values", what, times.size(), values.size()));
  if (times.empty()) return {};
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (!std::isfinite(times[k])) return input_error(fmt::format("rigged glb: {} has a non-finite key time", what));
    if (k && times[k] < times[k - 1])
      return input_error(fmt::format("rigged glb: {} has decreasing key times ({} after {})", what, times[k], times[k - 1]));
  }
  const double end = std::max(duration, 0.0);
  std::vector<double> t;
  std::vector<V> v;
  if (times.front() < 0.0) t.push_back(0.0), v.push_back(value_at(times, values, 0.0));
  for (std::size_t k = 0; k < times.size(); ++k)
    if (times[k] >= 0.0 && times[k] <= end) t.push_back(times[k]), v.push_back(values[k]);
  if (t.empty() || t.back() < end) t.push_back(end), v.push_back(value_at(times, values, end));
  for (std::size_t k = 0; k < t.size(); ++k) {
    const auto f = static_cast<float>(t[k]);
    if (!out_t.empty() && !(f > out_t.back())) continue;
    out_t.push_back(f);
    out_v.push_back(v[k]);
  }
  return {};
}

Status check_skin(const Skin& skin) {
  if (skin.joint_nodes.empty()) return input_error("rigged glb: the skin has no joints");
  if (skin.joint_nodes.size() > 65536)
    return input_error(fmt::format("rigged glb: {} joints, at most 65536", skin.joint_nodes.size()));
  if (skin.inverse_bind.size() != skin.joint_nodes.size())
    return input_error(fmt::format("rigged glb: {} inverse bind matrices for {} joints", skin.inverse_bind.size(),
                                   skin.joint_nodes.size()));
  for (std::size_t n = 0; n < skin.nodes.size(); ++n) {
    const SkinNode& node = skin.nodes[n];
    if (node.parent >= static_cast<int>(n) || node.parent < -1)
      return input_error(fmt::format("rigged glb: node {} '{}' has parent {} (parents come first)", n, node.name, node.parent));
    if (!node.translation.allFinite() || !node.scale.allFinite() || !finite_quat(node.rotation))
      return input_error(fmt::format("rigged glb: node {} '{}' has a non-finite rest transform", n, node.name));
  }
  for (std::size_t j = 0; j < skin.joint_nodes.size(); ++j) {
    if (skin.joint_nodes[j] < 0 || static_cast<std::size_t>(skin.joint_nodes[j]) >= skin.nodes.size())
      return input_error(fmt::format("rigged glb: joint {} refers to node {} of {}", j, skin.joint_nodes[j], skin.nodes.size()));
    const Mat4f& m = skin.inverse_bind[j];
    if (!m.allFinite()) return input_error(fmt::format("rigged glb: joint {} has a non-finite inverse bind matrix", j));
    // glTF's inverse bind matrices are affine (the validator wants the last row exactly 0 0 0 1).
    if ((m.row(3) - Eigen::RowVector4f(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-5f)
      return input_error(fmt::format("rigged glb: joint {} has an inverse bind matrix that is not affine", j));
  }
  return {};
}

/// Normalised influences: merged duplicate joints, zero weights on joint 0, the float sum 1 within 2e-7 per weight
/// (the Khronos validator sums them in float, in slot order).
Status clean_influences(std::array<std::uint16_t, kMaxInfluences>& j, std::array<float, kMaxInfluences>& w,
                        std::size_t joints, std::size_t vertex) {
  double sum = 0.0;
  for (int k = 0; k < kMaxInfluences; ++k) {
    if (!std::isfinite(w[k]) || w[k] < 0.0f)
      return input_error(fmt::format("rigged glb: vertex {} has weight {}", vertex, w[k]));
    if (w[k] == 0.0f) continue;
    if (j[k] >= joints)
      return input_error(fmt::format("rigged glb: vertex {} refers to joint {} of {}", vertex, j[k], joints));
    for (int m = 0; m < k; ++m)
      if (w[m] != 0.0f && j[m] == j[k]) w[m] += w[k], w[k] = 0.0f;
  }
  for (int k = 0; k < kMaxInfluences; ++k) sum += w[k];
  if (!(sum > 0.0)) return input_error(fmt::format("rigged glb: vertex {} has no weight", vertex));
  int largest = 0;
  for (int k = 0; k < kMaxInfluences; ++k) {
    w[k] = static_cast<float>(w[k] / sum);
    if (w[k] == 0.0f) j[k] = 0;
    if (w[k] > w[largest]) largest = k;
  }
  for (int pass = 0; pass < 4; ++pass) {
    float fsum = 0.0f;
    for (int k = 0; k < kMaxInfluences; ++k) fsum += w[k];
    if (fsum == 1.0f) break;
    w[largest] += 1.0f - fsum;
  }
  return {};
}

/// The mesh and its influences as encode_rigged_glb takes them: sizes agree, indices in range, vertices finite.
Status check_rig_input(const TriangleMesh& mesh, const std::vector<std::array<std::uint16_t, kMaxInfluences>>& joints,
                       const std::vector<std::array<float, kMaxInfluences>>& weights, const Skin& skin,
                       const MeshTransform& transform) {
  if (auto s = transform.validate(); !s) return input_error("rigged glb: " + s.error().message);
  FF_CHECK(check_skin(skin));
  const std::size_t nv = mesh.vertices.size();
  if (mesh.triangles.empty()) return input_error("rigged glb: the mesh has no triangles");
  if (joints.size() != nv || weights.size() != nv)
    return input_error(fmt::format("rigged glb: {} joint sets and {} weight sets for {} vertices", joints.size(),
                                   weights.size(), nv));
  for (const auto& t : mesh.triangles)
    for (Index v : t)
      if (v >= nv) return input_error(fmt::format("rigged glb: a triangle refers to vertex {} of {}", v, nv));
  for (const auto& v : mesh.vertices)
    if (!v.allFinite()) return input_error("rigged glb: the mesh has a non-finite vertex");
  return {};
}

/// The mesh in the file's scene space: T = translate · R · scale (R = Rz · Ry · Rx, as MeshTransform::apply) undone.
struct FileSpace {
  Eigen::Matrix3d rot;
  std::vector<Vec3f> pos, nrm;
  Aabb file_box, world_box;
};

FileSpace to_file_space(const TriangleMesh& mesh, const MeshTransform& transform, const std::vector<Vec3f>& world_normals) {
  const std::size_t nv = mesh.vertices.size();
  FileSpace f;
  // T and its inverse, in double (MeshTransform::apply's R = Rz · Ry · Rx).
  f.rot = core::rotation_from_degrees<double>(transform.rotate_deg.cast<double>());
  const Eigen::Matrix3d lin = f.rot * transform.scale.cast<double>().asDiagonal();
  const Eigen::Matrix3d lin_inv = lin.inverse();
  const Eigen::Vector3d shift = transform.translate.cast<double>();

  // Vertices in the file's scene space; normals outward in the world after T (n_file ∝ Lᵀ n_world, the inverse
  // transpose of T⁻¹'s linear part, which also undoes a mirror's reversal).
  f.pos.resize(nv), f.nrm.resize(nv);
  f.world_box = mesh.bounds();
  for (std::size_t i = 0; i < nv; ++i) {
    f.pos[i] = (lin_inv * (mesh.vertices[i].cast<double>() - shift)).cast<float>();
    f.file_box.extend(f.pos[i]);
    const Eigen::Vector3d n = lin.transpose() * world_normals[i].cast<double>();
    f.nrm[i] = n.norm() > 0.0 ? Vec3f(n.normalized().cast<float>()) : Vec3f(0.0f, 1.0f, 0.0f);
  }
  return f;
}

/// The primitive's vertex attributes (positions, normals, joints, weights) in `b`.
json vertex_attributes(GlbBuilder& b, const FileSpace& f, const std::vector<std::array<std::uint16_t, kMaxInfluences>>& jo,
                       const std::vector<std::array<float, kMaxInfluences>>& we) {
  const std::size_t nv = f.pos.size();
  json attributes;
  attributes["POSITION"] = b.accessor(b.view(f.pos.data(), nv * sizeof(Vec3f), glb::kArrayBuffer), glb::kFloat, nv,
                                      "VEC3", vec3(f.file_box.min), vec3(f.file_box.max));
  attributes["NORMAL"] = b.accessor(b.view(f.nrm.data(), nv * sizeof(Vec3f), glb::kArrayBuffer), glb::kFloat, nv, "VEC3");
  attributes["JOINTS_0"] = b.accessor(b.view(jo.data(), nv * sizeof(jo[0]), glb::kArrayBuffer), glb::kUnsignedShort, nv, "VEC4");
  attributes["WEIGHTS_0"] = b.accessor(b.view(we.data(), nv * sizeof(we[0]), glb::kArrayBuffer), glb::kFloat, nv, "VEC4");
  return attributes;
}

/// The triangle indices' accessor in `b`: 16-bit while the vertices fit, 32-bit beyond.
int index_accessor(GlbBuilder& b, const TriangleMesh& mesh) {
  if (mesh.vertices.size() <= 65535) {
    std::vector<std::uint16_t> idx;
    idx.reserve(3 * mesh.triangles.size());
    for (const auto& t : mesh.triangles)
      for (Index v : t) idx.push_back(static_cast<std::uint16_t>(v));
    return b.accessor(b.view(idx.data(), idx.size() * 2, glb::kElementArrayBuffer), glb::kUnsignedShort, idx.size(), "SCALAR");
  }
  return b.accessor(b.view(mesh.triangles.data(), mesh.triangles.size() * 12, glb::kElementArrayBuffer),
                    glb::kUnsignedInt, 3 * mesh.triangles.size(), "SCALAR");
}

/// Nodes: 0 the rig root (T), 1 … n the skeleton, n + 1 the skinned mesh.
json rig_nodes(const Skin& skin, const MeshTransform& transform, const Eigen::Matrix3d& rot) {
  const std::size_t nn = skin.nodes.size();
  json nodes = json::array();
  const Eigen::Quaterniond rq(rot);
  json root = {{"name", "fluidform_rig"},
               {"translation", vec3(transform.translate)},
               {"rotation", {rq.x(), rq.y(), rq.z(), rq.w()}},
               {"scale", vec3(transform.scale)}};
  std::vector<json> children(nn, json::array());
  json root_children = json::array();
  for (std::size_t n = 0; n < nn; ++n)
    (skin.nodes[n].parent < 0 ? root_children : children[static_cast<std::size_t>(skin.nodes[n].parent)]).push_back(n + 1);
  if (!root_children.empty()) root["children"] = root_children;
  nodes.push_back(root);
  for (std::size_t n = 0; n < nn; ++n) {
    const SkinNode& s = skin.nodes[n];
    json node = {{"name", s.name.empty() ? fmt::format("node_{}", n) : s.name},
                 {"translation", vec3(s.translation)}, {"rotation", quat(s.rotation)}, {"scale", vec3(s.scale)}};
    if (!children[n].empty()) node["children"] = children[n];
    nodes.push_back(node);
  }
  nodes.push_back({{"name", "fluidform_mesh"}, {"mesh", 0}, {"skin", 0}});
  return nodes;
}

/// The skin: its joints (node index + 1) and their inverse bind matrices (affine) in `b`.
json rig_skins(GlbBuilder& b, const Skin& skin) {
  std::vector<Mat4f> ibm(skin.inverse_bind);
  json joint_list = json::array();
  for (std::size_t j = 0; j < ibm.size(); ++j) {
    ibm[j].row(3) << 0.0f, 0.0f, 0.0f, 1.0f;
    joint_list.push_back(skin.joint_nodes[j] + 1);
  }
  // Eigen stores column-major, as glTF's MAT4.
  const int ibm_accessor = b.accessor(b.view(ibm.data(), ibm.size() * sizeof(Mat4f)), glb::kFloat, ibm.size(), "MAT4");
  return json::array({{{"name", "fluidform_skin"}, {"inverseBindMatrices", ibm_accessor}, {"joints", joint_list},
                       {"skeleton", 0}}});
}

/// One clip's samplers and channels as they are added, their key data in `b`.
struct ClipWriter {
  GlbBuilder& b;
  json channels = json::array(), samplers = json::array();

  void add(std::size_t node, const char* path, const std::vector<float>& t, const float* values, int width) {
    const int in = b.accessor(b.view(t.data(), t.size() * 4), glb::kFloat, t.size(), "SCALAR", {t.front()}, {t.back()});
    const int out = b.accessor(b.view(values, t.size() * static_cast<std::size_t>(width) * 4), glb::kFloat, t.size(),
                               width == 4 ? "VEC4" : "VEC3");
    samplers.push_back({{"input", in}, {"output", out}, {"interpolation", "LINEAR"}});
    channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", node + 1}, {"path", path}}}});
  }
};

/// One node channel of clip `name`: its translation, rotation (on the short arc from key to key) and scale keys.
Status add_channel(ClipWriter& w, const Skin& skin, const AnimationClip& clip, const std::string& name,
                   const NodeChannel& ch) {
  const std::size_t nn = skin.nodes.size();
  if (ch.node < 0 || static_cast<std::size_t>(ch.node) >= nn)
    return input_error(fmt::format("rigged glb: clip '{}' animates node {} of {}", name, ch.node, nn));
  const auto node = static_cast<std::size_t>(ch.node);
  const std::string what = fmt::format("clip '{}' node '{}'", name, skin.nodes[node].name);
  std::vector<float> t;
  std::vector<Vec3f> v3;
  std::vector<Quatf> q;
  for (const auto* p : {&ch.translations, &ch.scales})
    for (const Vec3f& v : *p)
      if (!v.allFinite()) return input_error(fmt::format("rigged glb: {} has a non-finite key", what));
  for (const Quatf& r : ch.rotations)
    if (!finite_quat(r)) return input_error(fmt::format("rigged glb: {} has a non-finite or zero rotation key", what));
  FF_CHECK(clean_keys(ch.translation_times, ch.translations, clip.duration, what + " translation", t, v3));
  if (!t.empty()) {
    std::vector<float> flat;
    for (const Vec3f& v : v3) flat.insert(flat.end(), {v.x(), v.y(), v.z()});
    w.add(node, "translation", t, flat.data(), 3);
  }
  FF_CHECK(clean_keys(ch.rotation_times, ch.rotations, clip.duration, what + " rotation", t, q));
  if (!t.empty()) {
    std::vector<float> flat;
    Quatf prev = Quatf::Identity();
    for (std::size_t k = 0; k < q.size(); ++k) {
      Quatf n = q[k].normalized();
      if (k && n.dot(prev) < 0.0f) n.coeffs() = -n.coeffs();  // the same rotation, on the short arc from the last
      prev = n;
      flat.insert(flat.end(), {n.x(), n.y(), n.z(), n.w()});
    }
    w.add(node, "rotation", t, flat.data(), 4);
  }
  FF_CHECK(clean_keys(ch.scale_times, ch.scales, clip.duration, what + " scale", t, v3));
  if (!t.empty()) {
    std::vector<float> flat;
    for (const Vec3f& v : v3) flat.insert(flat.end(), {v.x(), v.y(), v.z()});
    w.add(node, "scale", t, flat.data(), 3);
  }
  return {};
}

/// The clips as glTF animations, their keys in `b`.
Result<json> rig_animations(GlbBuilder& b, const Skin& skin) {
  const std::size_t nn = skin.nodes.size();
  json animations = json::array();
  for (std::size_t c = 0; c < skin.clips.size(); ++c) {
    const AnimationClip& clip = skin.clips[c];
    const std::string name = clip.name.empty() ? fmt::format("clip_{}", c) : clip.name;
    if (!std::isfinite(clip.duration)) return input_error(fmt::format("rigged glb: clip '{}' has a non-finite duration", name));
    ClipWriter w{b};
    for (const NodeChannel& ch : clip.channels) FF_CHECK(add_channel(w, skin, clip, name, ch));
    if (w.channels.empty() && nn > 0) {  // keep the clip (its name, its length): the first node at rest
      std::vector<float> t = {0.0f};
      if (clip.duration > 0.0 && static_cast<float>(clip.duration) > 0.0f) t.push_back(static_cast<float>(clip.duration));
      const Quatf r = skin.nodes[0].rotation.normalized();
      std::vector<float> flat;
      for (std::size_t k = 0; k < t.size(); ++k) flat.insert(flat.end(), {r.x(), r.y(), r.z(), r.w()});
      w.add(0, "rotation", t, flat.data(), 4);
    }
    if (!w.channels.empty()) animations.push_back({{"name", name}, {"channels", w.channels}, {"samplers", w.samplers}});
  }
  return animations;
}

}  // namespace

Result<std::vector<std::uint8_t>> encode_rigged_glb(const TriangleMesh& welded,
                                                    const std::vector<std::array<std::uint16_t, kMaxInfluences>>& joints,
                                                    const std::vector<std::array<float, kMaxInfluences>>& weights,
                                                    const Skin& skin, const MeshTransform& transform, const Vec3f& tint) {
  FF_CHECK(check_rig_input(welded, joints, weights, skin, transform));
  FF_CHECK(check_uv(welded, "rigged glb"));
  const bool coloured = !welded.colours.empty() || glb::textured(welded);  // opaque: vertex colours or texture
  if (!welded.colours.empty() && welded.colours.size() != welded.vertices.size())
    return input_error(fmt::format("rigged glb: {} vertex colours for {} vertices", welded.colours.size(), welded.vertices.size()));
  std::vector<std::array<std::uint16_t, kMaxInfluences>> jo = joints;
  std::vector<std::array<float, kMaxInfluences>> we = weights;
  for (std::size_t i = 0; i < jo.size(); ++i) FF_CHECK(clean_influences(jo[i], we[i], skin.joint_nodes.size(), i));
  // In its target's texture: split at the UV seams, each copy with its vertex's influences and normal.
  const bool uv = glb::textured(welded);
  glb::UvSplit split;
  std::vector<Vec3f> normals = vertex_normals(welded);
  if (uv) {
    split = glb::split_uv(welded);
    std::vector<std::array<std::uint16_t, kMaxInfluences>> sj(split.source.size());
    std::vector<std::array<float, kMaxInfluences>> sw(split.source.size());
    std::vector<Vec3f> sn(split.source.size());
    for (std::size_t i = 0; i < sj.size(); ++i)
      sj[i] = jo[split.source[i]], sw[i] = we[split.source[i]], sn[i] = normals[split.source[i]];
    jo = std::move(sj), we = std::move(sw), normals = std::move(sn);
  }
  const TriangleMesh& mesh = uv ? split.mesh : welded;
  const FileSpace f = to_file_space(mesh, transform, normals);

  GlbBuilder b;
  json attributes = vertex_attributes(b, f, jo, we);
  json extra = json::object();  // images, textures, samplers
  json textured = nullptr;
  if (uv) {
    attributes["TEXCOORD_0"] = glb::uv_accessor(b, split.uv);
    FF_TRY(const int texture, glb::add_texture(b, extra, *welded.texture));
    textured = glb::textured_material(*welded.texture, texture);
  } else if (coloured) {
    attributes["COLOR_0"] = glb::colour_accessor(b, mesh.colours);
  }
  const int indices = index_accessor(b, mesh);
  const json nodes = rig_nodes(skin, transform, f.rot);
  const std::size_t mesh_node = nodes.size() - 1;
  const json skins = rig_skins(b, skin);
  FF_TRY(const json animations, rig_animations(b, skin));

  WaterMaterial water;
  water.tint = tint;
  water.coloured = coloured;  // a liquid with the target's colours (or its tint) is opaque: its vertex colours
  json material = glb::water_material(water, f.world_box, false);
  // thicknessFactor is in the mesh's own (file) coordinates, attenuationDistance in the world's.
  const Vec3f file_ext = f.file_box.max - f.file_box.min;
  if (!coloured)
    material["extensions"]["KHR_materials_volume"]["thicknessFactor"] = 0.25f * (file_ext.norm() > 0.0f ? file_ext.norm() : 1.0f);

  while (b.bin.size() % 4) b.bin.push_back(0);
  json doc = {{"asset", {{"version", "2.0"}, {"generator", "fluidform"}}},
              {"scene", 0},
              {"scenes", {{{"name", "fluidform"}, {"nodes", {0, mesh_node}}}}},
              {"nodes", nodes},
              {"meshes", {{{"name", "fluidform"},
                           {"primitives", {{{"attributes", attributes}, {"indices", indices}, {"material", 0}, {"mode", 4}}}}}}},
              {"skins", skins},
              {"materials", json::array({material})},
              {"buffers", {{{"byteLength", b.bin.size()}}}},
              {"bufferViews", b.views},
              {"accessors", b.accessors},
              {"extensionsUsed", coloured ? json::array() : glb::water_extensions()}};
  if (coloured) doc.erase("extensionsUsed");
  if (!textured.is_null()) doc["materials"] = json::array({textured});
  for (auto& [key, value] : extra.items()) doc[key] = std::move(value);
  if (!animations.empty()) doc["animations"] = animations;
  return glb::pack_glb(doc, b.bin);
}

Status write_rigged_glb(const std::filesystem::path& path, const TriangleMesh& bind_mesh_world,
                        const std::vector<std::array<std::uint16_t, kMaxInfluences>>& joints,
                        const std::vector<std::array<float, kMaxInfluences>>& weights, const Skin& skin,
                        const MeshTransform& transform, const Vec3f& tint) {
  auto bytes = encode_rigged_glb(bind_mesh_world, joints, weights, skin, transform, tint);
  if (!bytes) {
    Error e = bytes.error();
    e.message = path.string() + ": " + e.message;
    return e;
  }
  return write_file_atomic(path, *bytes);
}

}  // namespace ff::io
