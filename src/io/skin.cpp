// The skin of a mesh file through Assimp (io/skin.h): nodes, bones, weights, clips.
//
// The file is read a second time (load_mesh has already checked it and made the mesh), now keeping what load_mesh
// throws away: bone weights and animations, and the meshes separate with their nodes (no PreTransformVertices,
// which drops bones). Each raw vertex's bind position is computed as load_mesh computes it (its mesh node's
// global matrix, then T), and every vertex of load_mesh's welded mesh takes the weights of the raw vertex
// nearest to it (distance ~0: the weld is by identical position). As in load_mesh, Assimp runs in a child process
// (io/isolate.h) and the skin comes back as bytes.
#include "io/skin.h"

#include "core/point_tree.h"
#include "core/rotation.h"
#include "io/isolate.h"

#include <assimp/Importer.hpp>
#include <assimp/anim.h>
#include <assimp/mesh.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <exception>
#include <map>
#include <new>
#include <string>

namespace ff::io {
namespace {
namespace fs = std::filesystem;

Error skin_error(const fs::path& path, std::string_view reason) {
  return input_error(fmt::format("{}: {}", path.filename().string(), reason));
}

Mat4f to_eigen(const aiMatrix4x4& m) {
  Mat4f e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return e;
}

bool finite(const Mat4f& m) { return m.allFinite(); }

/// The node tree flattened parents-first, with every node's name → index.
struct Flattened {
  std::vector<SkinNode> nodes;
  std::vector<const aiNode*> source;
  std::map<std::string, int> by_name;
};

Status flatten(const fs::path& path, const aiNode* node, int parent, Flattened& f, int depth) {
  if (depth > 1000) return skin_error(path, "node hierarchy deeper than 1000 levels");
  SkinNode n;
  n.name = node->mName.C_Str();
  n.parent = parent;
  aiVector3D s, t;
  aiQuaternion r;
  node->mTransformation.Decompose(s, r, t);
  n.translation = Vec3f(t.x, t.y, t.z);
  n.rotation = Quatf(r.w, r.x, r.y, r.z).normalized();
  n.scale = Vec3f(s.x, s.y, s.z);
  if (!n.translation.allFinite() || !n.rotation.coeffs().allFinite() || !n.scale.allFinite())
    return skin_error(path, fmt::format("node '{}' has a non-finite transform", n.name));
  const int index = static_cast<int>(f.nodes.size());
  f.by_name.emplace(n.name, index);  // the first of equal names wins, as Assimp's FindNode
  f.nodes.push_back(std::move(n));
  f.source.push_back(node);
  for (unsigned c = 0; c < node->mNumChildren; ++c) FF_CHECK(flatten(path, node->mChildren[c], index, f, depth + 1));
  return {};
}

/// The vertex weights being gathered: up to all of a vertex's influences, cut to the 4 largest at the end.
struct Influences {
  std::vector<std::pair<float, int>> w;  // (weight, joint)
};

/// The joint of (node, inverse bind): one per pair, shared by meshes that agree on it.
Result<int> joint_for(const fs::path& path, Skin& skin, int node, const Mat4f& inverse_bind) {
  for (std::size_t j = 0; j < skin.joint_nodes.size(); ++j)
    if (skin.joint_nodes[j] == node && skin.inverse_bind[j].isApprox(inverse_bind, 1e-6f)) return static_cast<int>(j);
  if (skin.joint_nodes.size() >= 65535) return skin_error(path, "more than 65535 joints");
  skin.joint_nodes.push_back(node);
  skin.inverse_bind.push_back(inverse_bind);
  return static_cast<int>(skin.joint_nodes.size() - 1);
}

/// The raw vertices of the file's meshes: bind position in the world and influences.
struct RawVertices {
  std::vector<Vec3f> position;
  std::vector<Influences> influence;
};

/// The bones of mesh m (on node n, global rest matrix G) as influences of its raw vertices from `base` on.
Status add_bone_weights(const fs::path& path, const aiMesh* m, std::size_t base, std::size_t n, const Mat4f& G_inv,
                        const Flattened& f, Skin& skin, RawVertices& raw) {
  for (unsigned b = 0; b < m->mNumBones; ++b) {
    const aiBone* bone = m->mBones[b];
    const Mat4f offset = to_eigen(bone->mOffsetMatrix);
    if (!finite(offset)) return skin_error(path, fmt::format("bone '{}' has a non-finite offset matrix", bone->mName.C_Str()));
    const auto it = f.by_name.find(bone->mName.C_Str());
    int j = -1;
    if (it == f.by_name.end()) {
      // A bone without its node (assimp-testmodels' X/anim_test.x has two): nothing moves it, so its vertices
      // keep their place on the mesh's node, as a viewer that finds no node for a bone shows them.
      skin.warnings.push_back(fmt::format("bone '{}' names no node of the file: its vertices follow the mesh's node '{}'",
                                          bone->mName.C_Str(), f.nodes[n].name));
      FF_TRY(j, joint_for(path, skin, static_cast<int>(n), G_inv));
    } else {
      FF_TRY(j, joint_for(path, skin, it->second, Mat4f(offset * G_inv)));
    }
    for (unsigned i = 0; i < bone->mNumWeights; ++i) {
      const aiVertexWeight& vw = bone->mWeights[i];
      if (!std::isfinite(vw.mWeight) || vw.mWeight < 0.0f)
        return skin_error(path, fmt::format("bone '{}' has weight {} (not a finite number ≥ 0)", bone->mName.C_Str(), vw.mWeight));
      if (vw.mVertexId >= m->mNumVertices)
        return skin_error(path, fmt::format("bone '{}' weights vertex {} of a mesh with {}", bone->mName.C_Str(),
                                            vw.mVertexId, m->mNumVertices));
      if (vw.mWeight > 0.0f) raw.influence[base + vw.mVertexId].w.emplace_back(vw.mWeight, j);
    }
  }
  return {};
}

/// Raw vertices: bind position in the world and influences, mesh by mesh, node by node (instances repeat).
Status gather_raw_vertices(const fs::path& path, const aiScene* scene, const Flattened& f,
                           const std::vector<Mat4f>& rest, const Mat4f& T, Skin& skin, RawVertices& raw) {
  for (std::size_t n = 0; n < f.nodes.size(); ++n) {
    const aiNode* node = f.source[n];
    const Mat4f G = rest[n];
    if (!finite(G)) return skin_error(path, fmt::format("node '{}' has a non-finite global transform", f.nodes[n].name));
    const Mat4f G_inv = G.inverse();
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      const aiMesh* m = scene->mMeshes[node->mMeshes[k]];
      if (m == nullptr || !(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
      const std::size_t base = raw.position.size();
      raw.position.resize(base + m->mNumVertices);
      raw.influence.resize(base + m->mNumVertices);
      for (unsigned v = 0; v < m->mNumVertices; ++v) {
        const aiVector3D& p = m->mVertices[v];
        const Eigen::Vector4f w = T * (G * Eigen::Vector4f(p.x, p.y, p.z, 1.0f));
        raw.position[base + v] = w.head<3>();
      }
      FF_CHECK(add_bone_weights(path, m, base, n, G_inv, f, skin, raw));
      // Vertices no bone reaches follow their node rigidly.
      int rigid = -1;
      for (unsigned v = 0; v < m->mNumVertices; ++v) {
        if (!raw.influence[base + v].w.empty()) continue;
        if (rigid < 0) {
          FF_TRY(rigid, joint_for(path, skin, static_cast<int>(n), G_inv));  // x(t) = G_n(t) · G_n(rest)⁻¹ · x_bind
        }
        raw.influence[base + v].w.emplace_back(1.0f, rigid);
      }
    }
  }
  return {};
}

/// load_mesh's vertices take their raw vertex's weights: the 4 largest, renormalised.
void take_nearest_weights(const TriangleMesh& mesh, const RawVertices& raw, Skin& skin) {
  const core::PointTree tree(raw.position);
  skin.joints.resize(mesh.vertices.size());
  skin.weights.resize(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const auto near = tree.nearest(mesh.vertices[v]);
    auto w = raw.influence[tree.original(near.slot)].w;
    std::sort(w.begin(), w.end(), [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
    if (w.size() > kMaxInfluences) w.resize(kMaxInfluences);
    double sum = 0.0;
    for (const auto& [wt, j] : w) sum += wt;
    skin.joints[v].fill(0);
    skin.weights[v].fill(0.0f);
    for (std::size_t k = 0; k < w.size(); ++k) {
      skin.joints[v][k] = static_cast<std::uint16_t>(w[k].second);
      skin.weights[v][k] = static_cast<float>(w[k].first / sum);
    }
  }
}

/// One channel of clip `clip_name` (tps ticks per second): its keys in seconds, later keys at an equal or earlier time
/// dropped (keys must increase).
Result<NodeChannel> read_channel(const fs::path& path, const aiNodeAnim* ch, int node, const std::string& clip_name,
                                 double tps) {
  NodeChannel nc;
  nc.node = node;
  auto time = [&](double ticks, const char* what) -> Result<double> {
    if (!std::isfinite(ticks)) return skin_error(path, fmt::format("clip '{}' has a non-finite {} key time", clip_name, what));
    return ticks / tps;
  };
  for (unsigned k = 0; k < ch->mNumPositionKeys; ++k) {
    FF_TRY(const double t, time(ch->mPositionKeys[k].mTime, "position"));
    const auto& p = ch->mPositionKeys[k].mValue;
    if (!nc.translation_times.empty() && t <= nc.translation_times.back()) continue;  // keys must increase
    nc.translation_times.push_back(t);
    nc.translations.emplace_back(p.x, p.y, p.z);
  }
  for (unsigned k = 0; k < ch->mNumRotationKeys; ++k) {
    FF_TRY(const double t, time(ch->mRotationKeys[k].mTime, "rotation"));
    const auto& q = ch->mRotationKeys[k].mValue;
    if (!nc.rotation_times.empty() && t <= nc.rotation_times.back()) continue;
    nc.rotation_times.push_back(t);
    nc.rotations.push_back(Quatf(q.w, q.x, q.y, q.z).normalized());
  }
  for (unsigned k = 0; k < ch->mNumScalingKeys; ++k) {
    FF_TRY(const double t, time(ch->mScalingKeys[k].mTime, "scale"));
    const auto& s = ch->mScalingKeys[k].mValue;
    if (!nc.scale_times.empty() && t <= nc.scale_times.back()) continue;
    nc.scale_times.push_back(t);
    nc.scales.emplace_back(s.x, s.y, s.z);
  }
  for (const auto& v : nc.translations)
    if (!v.allFinite()) return skin_error(path, fmt::format("clip '{}' has a non-finite position key", clip_name));
  for (const auto& q : nc.rotations)
    if (!q.coeffs().allFinite()) return skin_error(path, fmt::format("clip '{}' has a non-finite rotation key", clip_name));
  for (const auto& v : nc.scales)
    if (!v.allFinite()) return skin_error(path, fmt::format("clip '{}' has a non-finite scale key", clip_name));
  return nc;
}

/// Clips: keys in ticks → seconds (25 ticks per second where the file does not say, as Assimp's viewer).
Status read_clips(const fs::path& path, const aiScene* scene, const Flattened& f, Skin& skin) {
  for (unsigned a = 0; a < scene->mNumAnimations; ++a) {
    const aiAnimation* anim = scene->mAnimations[a];
    const double tps = anim->mTicksPerSecond > 0.0 ? anim->mTicksPerSecond : 25.0;
    AnimationClip clip;
    clip.name = anim->mName.C_Str();
    double last = 0.0;
    for (unsigned c = 0; c < anim->mNumChannels; ++c) {
      const aiNodeAnim* ch = anim->mChannels[c];
      const auto it = f.by_name.find(ch->mNodeName.C_Str());
      if (it == f.by_name.end()) continue;  // a channel for a node the file lacks moves nothing
      FF_TRY(NodeChannel nc, read_channel(path, ch, it->second, clip.name, tps));
      for (const auto* times : {&nc.translation_times, &nc.rotation_times, &nc.scale_times})
        if (!times->empty()) last = std::max(last, times->back());
      clip.channels.push_back(std::move(nc));
    }
    const double said = std::isfinite(anim->mDuration) ? anim->mDuration / tps : 0.0;
    clip.duration = std::max(said, last);
    skin.clips.push_back(std::move(clip));
  }
  return {};
}

Result<std::optional<Skin>> load_skin_impl(const fs::path& path, const TriangleMesh& mesh, const MeshTransform& transform) {
  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  const aiScene* scene = importer.ReadFile(path.string(), aiProcess_ValidateDataStructure | aiProcess_Triangulate);
  if (scene == nullptr || scene->mRootNode == nullptr)
    return skin_error(path, fmt::format("cannot be read for its skin: {}", importer.GetErrorString()));
  bool any_bones = false;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) any_bones = any_bones || scene->mMeshes[m]->mNumBones > 0;
  if (!any_bones) return std::optional<Skin>{};

  Flattened f;
  FF_CHECK(flatten(path, scene->mRootNode, -1, f, 0));
  Skin skin;
  skin.nodes = f.nodes;
  std::vector<Mat4f> rest;
  skin.rest_matrices(rest);
  const Mat4f T = transform_matrix(transform);

  RawVertices raw;
  FF_CHECK(gather_raw_vertices(path, scene, f, rest, T, skin, raw));
  if (raw.position.empty()) return skin_error(path, "has bones but no triangle mesh");
  take_nearest_weights(mesh, raw, skin);
  FF_CHECK(read_clips(path, scene, f, skin));
  return std::optional<Skin>(std::move(skin));
}

/// load_skin_impl with the no-throw promise kept.
Result<std::optional<Skin>> load_skin_here(const fs::path& path, const TriangleMesh& mesh, const MeshTransform& transform) {
  try {
    return load_skin_impl(path, mesh, transform);
  } catch (const std::bad_alloc&) {
    return skin_error(path, "out of memory while reading its skin");
  } catch (const std::exception& e) {
    return skin_error(path, e.what());
  }
}

// ---- the skin read in a child process (io/isolate.h), as bytes ----
//
// One byte: 0 an error (kind, message), 2 no bones, 1 a skin: nodes, joint nodes, inverse binds, per-vertex joints and
// weights, clips, warnings, each list with its count first.

void put_vec3(AnswerWriter& w, const Vec3f& v) { w.put(std::array<float, 3>{v.x(), v.y(), v.z()}); }
void put_quat(AnswerWriter& w, const Quatf& q) { w.put(std::array<float, 4>{q.w(), q.x(), q.y(), q.z()}); }
void put_mat(AnswerWriter& w, const Mat4f& m) {
  std::array<float, 16> a{};
  std::copy(m.data(), m.data() + 16, a.begin());
  w.put(a);
}
bool get_vec3(AnswerReader& r, Vec3f& v) {
  std::array<float, 3> a{};
  return r.get(a) && (v = Vec3f(a[0], a[1], a[2]), true);
}
bool get_quat(AnswerReader& r, Quatf& q) {
  std::array<float, 4> a{};
  return r.get(a) && (q = Quatf(a[0], a[1], a[2], a[3]), true);
}
bool get_mat(AnswerReader& r, Mat4f& m) {
  std::array<float, 16> a{};
  return r.get(a) && (std::copy(a.begin(), a.end(), m.data()), true);
}
template <class T, class Put>
void put_list(AnswerWriter& w, const std::vector<T>& v, Put&& put) {
  w.put(std::uint64_t{v.size()});
  for (const T& x : v) put(w, x);
}
template <class T, class Get>
bool get_list(AnswerReader& r, std::vector<T>& v, std::size_t min_bytes, Get&& get) {
  std::uint64_t n = 0;
  if (!r.get_count(n, min_bytes)) return false;
  v.resize(n);
  for (T& x : v)
    if (!get(r, x)) return false;
  return true;
}

std::string encode_skin(const Result<std::optional<Skin>>& r) {
  AnswerWriter w;
  if (!r) {
    w.put(std::uint8_t{0});
    w.put(static_cast<std::uint8_t>(r.error().kind));
    w.put_string(r.error().message);
    return w.take();
  }
  if (!r.value()) {
    w.put(std::uint8_t{2});
    return w.take();
  }
  const Skin& s = *r.value();
  w.put(std::uint8_t{1});
  put_list(w, s.nodes, [](AnswerWriter& o, const SkinNode& n) {
    o.put_string(n.name);
    o.put(std::int32_t{n.parent});
    put_vec3(o, n.translation), put_quat(o, n.rotation), put_vec3(o, n.scale);
  });
  w.put_vector(s.joint_nodes);
  put_list(w, s.inverse_bind, put_mat);
  w.put_vector(s.joints);
  w.put_vector(s.weights);
  put_list(w, s.clips, [](AnswerWriter& o, const AnimationClip& c) {
    o.put_string(c.name);
    o.put(c.duration);
    put_list(o, c.channels, [](AnswerWriter& p, const NodeChannel& ch) {
      p.put(std::int32_t{ch.node});
      p.put_vector(ch.translation_times), p.put_vector(ch.rotation_times), p.put_vector(ch.scale_times);
      put_list(p, ch.translations, put_vec3), put_list(p, ch.rotations, put_quat), put_list(p, ch.scales, put_vec3);
    });
  });
  put_list(w, s.warnings, [](AnswerWriter& o, const std::string& x) { o.put_string(x); });
  return w.take();
}

/// The child's answer back into a skin. Every count is checked against the bytes that came and every index against
/// what it indexes (a parent before its child, joints' nodes, vertices' joints, channels' nodes), since a child whose
/// heap Assimp corrupted may still have answered; the values themselves the child has checked.
Result<std::optional<Skin>> decode_skin(const fs::path& path, std::string_view bytes, std::size_t n_vertices) {
  const Error garbled = skin_error(path, "the import process sent a garbled answer for its skin");
  AnswerReader r(bytes);
  std::uint8_t tag = 0;
  if (!r.get(tag)) return garbled;
  if (tag == 0) {
    // The child's errors are all about the file (skin_error): any other kind is a garbled answer, not an exit 1.
    std::string message;
    return r.get_input_error(message) ? input_error(std::move(message)) : garbled;
  }
  if (tag == 2) return r.at_end() ? Result<std::optional<Skin>>(std::optional<Skin>{}) : garbled;
  if (tag != 1) return garbled;
  Skin s;
  get_list(r, s.nodes, 8 + 4 + 40, [](AnswerReader& in, SkinNode& n) {
    std::int32_t parent = 0;
    return in.get_string(n.name) && in.get(parent) && (n.parent = parent, true) && get_vec3(in, n.translation) &&
           get_quat(in, n.rotation) && get_vec3(in, n.scale);
  });
  r.get_vector(s.joint_nodes);
  get_list(r, s.inverse_bind, 64, get_mat);
  r.get_vector(s.joints);
  r.get_vector(s.weights);
  get_list(r, s.clips, 8 + 8 + 8, [](AnswerReader& in, AnimationClip& c) {
    return in.get_string(c.name) && in.get(c.duration) &&
           get_list(in, c.channels, 4 + 6 * 8, [](AnswerReader& p, NodeChannel& ch) {
             std::int32_t node = 0;
             return p.get(node) && (ch.node = node, true) && p.get_vector(ch.translation_times) &&
                    p.get_vector(ch.rotation_times) && p.get_vector(ch.scale_times) &&
                    get_list(p, ch.translations, 12, get_vec3) && get_list(p, ch.rotations, 16, get_quat) &&
                    get_list(p, ch.scales, 12, get_vec3);
           });
  });
  get_list(r, s.warnings, 8, [](AnswerReader& in, std::string& x) { return in.get_string(x); });
  if (!r.ok() || !r.at_end()) return garbled;

  const auto n_nodes = static_cast<int>(s.nodes.size());
  for (int i = 0; i < n_nodes; ++i)
    if (s.nodes[i].parent < -1 || s.nodes[i].parent >= i) return garbled;
  for (const int j : s.joint_nodes)
    if (j < 0 || j >= n_nodes) return garbled;
  if (s.inverse_bind.size() != s.joint_nodes.size() || s.joints.size() != n_vertices || s.weights.size() != n_vertices)
    return garbled;
  for (const auto& j : s.joints)
    for (const std::uint16_t k : j)
      if (k >= s.joint_nodes.size()) return garbled;
  for (const auto& c : s.clips)
    for (const auto& ch : c.channels)
      if (ch.node < 0 || ch.node >= n_nodes || ch.translation_times.size() != ch.translations.size() ||
          ch.rotation_times.size() != ch.rotations.size() || ch.scale_times.size() != ch.scales.size())
        return garbled;
  return std::optional<Skin>(std::move(s));
}

}  // namespace

Mat4f trs(const Vec3f& t, const Quatf& r, const Vec3f& s) {
  Mat4f m = Mat4f::Identity();
  m.topLeftCorner<3, 3>() = r.normalized().toRotationMatrix() * s.asDiagonal();
  m.topRightCorner<3, 1>() = t;
  return m;
}

Mat4f SkinNode::local() const { return trs(translation, rotation, scale); }

void Skin::rest_matrices(std::vector<Mat4f>& out) const {
  out.resize(nodes.size());
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    const Mat4f local = nodes[n].local();
    out[n] = nodes[n].parent >= 0 ? Mat4f(out[static_cast<std::size_t>(nodes[n].parent)] * local) : local;
  }
}

Result<std::size_t> Skin::find_clip(const std::string& name) const {
  for (std::size_t c = 0; c < clips.size(); ++c)
    if (clips[c].name == name) return c;
  std::size_t index = 0;
  const auto [end, ec] = std::from_chars(name.data(), name.data() + name.size(), index);
  if (ec == std::errc() && end == name.data() + name.size() && index < clips.size()) return index;
  std::string there;
  for (std::size_t c = 0; c < clips.size(); ++c)
    there += fmt::format("{}{} '{}'", c ? ", " : "", c, clips[c].name);
  return input_error(fmt::format("no animation clip '{}' (the file has {})", name,
                                 clips.empty() ? std::string("none") : there));
}

Mat4f transform_matrix(const MeshTransform& t) {
  // As MeshTransform::apply: R = Rz · Ry · Rx from degrees (core/rotation.h), in double.
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = core::rotation_from_degrees<double>(t.rotate_deg.cast<double>()) * t.scale.cast<double>().asDiagonal();
  m.topRightCorner<3, 1>() = t.translate.cast<double>();
  return m.cast<float>();
}

Result<std::optional<Skin>> load_skin(const fs::path& path, const TriangleMesh& mesh, const MeshTransform& transform,
                                      bool isolate) {
  if (!isolate) return load_skin_here(path, mesh, transform);
  auto answer = run_isolated([&] { return encode_skin(load_skin_here(path, mesh, transform)); }, "Assimp's import");
  if (!answer) return answer.error().kind == Error::Kind::Input ? skin_error(path, answer.error().message) : answer.error();
  return decode_skin(path, *answer, mesh.vertices.size());
}

}  // namespace ff::io
