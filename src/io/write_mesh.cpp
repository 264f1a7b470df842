#include "io/write_mesh.h"

#include "io/atomic_file.h"
#include "io/glb_builder.h"
#include "io/picture.h"
#include "io/target_look.h"

#include <Eigen/Geometry>  // cross product
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

namespace ff::io {
namespace {

using nlohmann::json;
// The GLB pieces shared with write_rigged_glb.cpp (io/glb_builder.h).
using glb::GlbBuilder, glb::put, glb::pack_glb, glb::water_material, glb::kColouredRoughness;
using glb::kFloat, glb::kUnsignedInt, glb::kUnsignedShort, glb::kShort, glb::kByte, glb::kArrayBuffer,
    glb::kElementArrayBuffer;

// Snorm encodings of glTF 2.0 (KHR_mesh_quantization): value = max(q / (2ⁿ⁻¹ − 1), −1).
std::int16_t snorm16(float v) { return static_cast<std::int16_t>(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f)); }
std::int8_t snorm8(float v) { return static_cast<std::int8_t>(std::lround(std::clamp(v, -1.0f, 1.0f) * 127.0f)); }

}  // namespace

namespace glb {

UvSplit split_uv(const TriangleMesh& m) {
  UvSplit out;
  const std::size_t nv = m.vertices.size();
  const bool colours = m.colours.size() == nv;
  std::vector<Index> first(nv, kInvalidIndex);  // the copy of v with the UV it was first seen with
  std::map<std::array<std::uint32_t, 3>, Index> more;  // (v, UV bits) → its copy, for v's other UVs (seams: few)
  const auto add = [&](Index v, const Vec2f& uv) {
    const auto id = static_cast<Index>(out.mesh.vertices.size());
    out.mesh.vertices.push_back(m.vertices[v]);
    if (colours) out.mesh.colours.push_back(m.colours[v]);
    out.uv.push_back(uv);
    out.source.push_back(v);
    return id;
  };
  out.mesh.triangles.resize(m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const Index v = m.triangles[t][std::size_t(c)];
      const Vec2f& uv = m.corner_uv[t][std::size_t(c)];
      Index& to = out.mesh.triangles[t][std::size_t(c)];
      if (first[v] == kInvalidIndex) {
        to = first[v] = add(v, uv);
      } else if (out.uv[first[v]] == uv) {
        to = first[v];
      } else {
        std::array<std::uint32_t, 3> key{v, 0, 0};
        std::memcpy(&key[1], uv.data(), 8);
        const auto [it, fresh] = more.try_emplace(key, 0);
        if (fresh) it->second = add(v, uv);
        to = it->second;
      }
    }
  return out;
}

Result<int> add_texture(GlbBuilder& b, json& doc, const MeshTexture& t) {
  FF_TRY(const std::vector<std::uint8_t> png, encode_png(t.image));
  for (const char* key : {"images", "textures", "samplers"})
    if (!doc.contains(key)) doc[key] = json::array();
  doc["images"].push_back({{"bufferView", b.view(png.data(), png.size())}, {"mimeType", "image/png"}});
  if (doc["samplers"].empty())  // LINEAR, LINEAR_MIPMAP_LINEAR, REPEAT
    doc["samplers"].push_back({{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 10497}, {"wrapT", 10497}});
  doc["textures"].push_back({{"sampler", 0}, {"source", doc["images"].size() - 1}});
  return static_cast<int>(doc["textures"].size()) - 1;
}

}  // namespace glb

std::vector<Vec3f> vertex_normals(const TriangleMesh& mesh) {
  std::vector<Vec3f> n(mesh.vertices.size(), Vec3f::Zero());
  for (const auto& t : mesh.triangles) {
    // The cross product's length is twice the area: summing it weights each face by its area.
    const Vec3f c = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    for (Index v : t) n[v] += c;
  }
  for (auto& v : n) {
    const float len = v.norm();
    v = len > 0.0f && std::isfinite(len) ? Vec3f(v / len) : Vec3f(0.0f, 1.0f, 0.0f);
  }
  return n;
}

std::string encode_mtl(const WaterMaterial& m, std::string_view texture_file, const Vec3f& texture_factor) {
  const Vec3f c = m.tint;
  // illum 7: reflection and refraction (Fresnel); Tf 1 1 1: a clear body (Blender's OBJ importer takes the mean
  // of Tf as the Principled BSDF's transmission, so a tinted Tf would make it half opaque); the tint is Kd.
  // "liquid": the opaque look of a liquid with vertex colours (appearance tint or target), which multiply Kd.
  std::string s = fmt::format(
      "# fluidform water material\nnewmtl water\nKa 0 0 0\nKd {:.4f} {:.4f} {:.4f}\nKs 1 1 1\n"
      "Ns {:.1f}\nNi {:.3f}\nd 1\nTf 1 1 1\nillum 7\n"
      "\n# fluidform coloured liquid (its colours are the OBJ's vertex colours)\nnewmtl liquid\nKa 0 0 0\n"
      "Kd 1 1 1\nKs 0.5 0.5 0.5\nNs {:.1f}\nd 1\nillum 2\n",
      c.x(), c.y(), c.z(), 1000.0f * (1.0f - m.roughness), m.ior, 1000.0f * (1.0f - kColouredRoughness));
  if (!texture_file.empty())
    s += fmt::format("\n# fluidform liquid in its target's texture (the OBJ's vt)\nnewmtl liquid_textured\nKa 0 0 0\n"
                     "Kd {:.4f} {:.4f} {:.4f}\nKs 0.5 0.5 0.5\nNs {:.1f}\nd 1\nillum 2\nmap_Kd {}\n",
                     texture_factor.x(), texture_factor.y(), texture_factor.z(), 1000.0f * (1.0f - kColouredRoughness),
                     texture_file);
  return s;
}

std::string encode_obj(const TriangleMesh& input, bool normals, std::string_view comment, std::string_view mtllib) {
  // A textured mesh is written split at its UV seams (vt is per vertex here); normals are the welded mesh's, so a
  // seam is not a crease.
  const bool uv = glb::textured(input);
  glb::UvSplit split;
  if (uv) split = glb::split_uv(input);
  const TriangleMesh& mesh = uv ? split.mesh : input;
  std::string s;
  s.reserve(mesh.vertices.size() * (normals ? 64 : 32) + mesh.triangles.size() * 40);
  for (std::size_t a = 0, b; a <= comment.size(); a = b + 1) {
    b = comment.find('\n', a);
    if (b == std::string_view::npos) b = comment.size();
    s += fmt::format("# {}\n", comment.substr(a, b - a));
  }
  s += fmt::format("# {} vertices, {} triangles; Y up, metres\n", mesh.vertices.size(), mesh.triangles.size());
  // 9 significant digits round-trip a float exactly.
  // Vertex colours as `v x y z r g b` (sRGB, as MeshLab, three.js's OBJLoader and Blender ≥ 3.5 read them); a
  // textured mesh keeps them too (the material shows the texture; tools without textures can show these).
  const bool coloured = !mesh.colours.empty() && mesh.colours.size() == mesh.vertices.size();
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3f& v = mesh.vertices[i];
    if (coloured) {
      const Vec3f& c = mesh.colours[i];
      s += fmt::format("v {:.9g} {:.9g} {:.9g} {:.4f} {:.4f} {:.4f}\n", v.x(), v.y(), v.z(), linear_to_srgb(c.x()) / 255.0,
                       linear_to_srgb(c.y()) / 255.0, linear_to_srgb(c.z()) / 255.0);
    } else {
      s += fmt::format("v {:.9g} {:.9g} {:.9g}\n", v.x(), v.y(), v.z());
    }
  }
  if (uv)
    for (const Vec2f& t : split.uv) s += fmt::format("vt {:.7g} {:.7g}\n", t.x(), t.y());
  if (normals) {
    const std::vector<Vec3f> n = vertex_normals(input);
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Vec3f& v = n[uv ? split.source[i] : i];
      s += fmt::format("vn {:.6f} {:.6f} {:.6f}\n", v.x(), v.y(), v.z());
    }
  }
  if (!mtllib.empty()) s += fmt::format("mtllib {}\nusemtl {}\n", mtllib, uv ? "liquid_textured" : coloured ? "liquid" : "water");
  for (const auto& t : mesh.triangles) {
    if (normals && uv)
      s += fmt::format("f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    else if (normals)
      s += fmt::format("f {0}//{0} {1}//{1} {2}//{2}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    else if (uv)
      s += fmt::format("f {0}/{0} {1}/{1} {2}/{2}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    else
      s += fmt::format("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  return s;
}

Status check_uv(const TriangleMesh& m, std::string_view what) {
  if (m.corner_uv.empty()) return {};
  if (m.corner_uv.size() != m.triangles.size())
    return input_error(fmt::format("{}: UVs for {} triangles of {}", what, m.corner_uv.size(), m.triangles.size()));
  if (m.texture == nullptr || m.texture->image.width <= 0 || m.texture->image.height <= 0 ||
      m.texture->image.rgb.size() != std::size_t(m.texture->image.width) * std::size_t(m.texture->image.height) * 3)
    return input_error(fmt::format("{}: UVs without a texture to index", what));
  for (const auto& c : m.corner_uv)
    for (const Vec2f& t : c)
      if (!t.allFinite()) return input_error(fmt::format("{}: a UV is not finite", what));
  return {};
}

Status write_obj(const std::filesystem::path& path, const TriangleMesh& mesh, bool normals, std::string_view comment,
                 std::string_view mtllib) {
  FF_CHECK(check_uv(mesh, path.string()));
  for (const auto& t : mesh.triangles)
    for (Index v : t)
      if (v >= mesh.vertices.size())
        return input_error(fmt::format("{}: triangle refers to vertex {} of {}", path.string(), v, mesh.vertices.size()));
  return write_file_atomic(path, encode_obj(mesh, normals, comment, mtllib));
}

Status GlbOptions::validate(std::size_t frames) const {
  if (!(fps > 0.0) || !std::isfinite(fps)) return param_error(fmt::format("glb: fps = {} must be > 0", fps));
  if (!times.empty()) {
    if (times.size() != frames)
      return param_error(fmt::format("glb: {} frame times for {} frames", times.size(), frames));
    for (std::size_t k = 0; k < times.size(); ++k)
      if (!std::isfinite(times[k]) || (k && !(times[k] > times[k - 1])))
        return param_error("glb: frame times must be finite and increasing");
  }
  if (materials.empty() != triangle_material.empty())
    return param_error("glb: per-triangle materials need both the materials and each triangle's material");
  if (!triangle_material.empty()) {
    if (materials.size() > 256) return param_error(fmt::format("glb: {} materials, at most 256", materials.size()));
    if (triangle_material.size() != frames)
      return param_error(fmt::format("glb: triangle materials for {} frames, not {}", triangle_material.size(), frames));
  }
  return {};
}

namespace {

Status check_glb_frame(const TriangleMesh& m, std::size_t k) {
  if (!m.colours.empty() && m.colours.size() != m.vertices.size())
    return input_error(fmt::format("glb: frame {} has {} vertex colours for {} vertices", k, m.colours.size(), m.vertices.size()));
  FF_CHECK(check_uv(m, fmt::format("glb: frame {}", k)));
  for (const auto& t : m.triangles)
    for (Index v : t)
      if (v >= m.vertices.size())
        return input_error(fmt::format("glb: frame {} has a triangle that refers to vertex {} of {}", k, v, m.vertices.size()));
  if (m.triangles.empty()) return {};
  for (const auto& v : m.vertices)
    if (!v.allFinite()) return input_error(fmt::format("glb: frame {} has a non-finite vertex", k));
  return {};
}

/// POSITION and NORMAL of one frame as 16-bit and 8-bit snorms (KHR_mesh_quantization). Positions map to [−1, 1]³
/// of the bounding box and are dequantized by a child node's translation and scale, returned in `mesh_node`
/// (so the frame node's own scale stays free for the visibility animation).
json quantized_attributes(GlbBuilder& b, const TriangleMesh& m, const std::vector<Vec3f>& normals, const Aabb& box,
                          std::size_t mesh_index, std::size_t k, json& mesh_node) {
  const std::size_t nv = m.vertices.size();
  json attributes;
  const Vec3f c = 0.5f * (box.min + box.max);
  const Vec3f h = (0.5f * (box.max - box.min)).cwiseMax(Vec3f::Constant(1e-12f));
  std::vector<std::int16_t> q(4 * nv, 0);  // stride 8: vertex attributes must be 4-byte aligned
  std::array<int, 3> lo{32767, 32767, 32767}, hi{-32767, -32767, -32767};
  for (std::size_t i = 0; i < nv; ++i)
    for (int a = 0; a < 3; ++a) {
      const std::int16_t v = snorm16((m.vertices[i][a] - c[a]) / h[a]);
      q[4 * i + static_cast<std::size_t>(a)] = v;
      lo[static_cast<std::size_t>(a)] = std::min<int>(lo[static_cast<std::size_t>(a)], v);
      hi[static_cast<std::size_t>(a)] = std::max<int>(hi[static_cast<std::size_t>(a)], v);
    }
  const int pv = b.view(q.data(), q.size() * sizeof(std::int16_t), kArrayBuffer, 8);
  // min/max of a normalized accessor are its stored integers (the validator checks them so).
  attributes["POSITION"] = b.accessor(pv, kShort, nv, "VEC3", {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, true);
  std::vector<std::int8_t> qn(4 * nv, 0);
  for (std::size_t i = 0; i < nv; ++i)
    for (int a = 0; a < 3; ++a) qn[4 * i + static_cast<std::size_t>(a)] = snorm8(normals[i][a]);
  const int nview = b.view(qn.data(), qn.size(), kArrayBuffer, 4);
  attributes["NORMAL"] = b.accessor(nview, kByte, nv, "VEC3", nullptr, nullptr, true);
  mesh_node = {{"name", fmt::format("frame_{:05d}_mesh", k)}, {"mesh", mesh_index},
               {"translation", {c.x(), c.y(), c.z()}}, {"scale", {h.x(), h.y(), h.z()}}};
  return attributes;
}

/// POSITION and NORMAL of one frame as floats.
json float_attributes(GlbBuilder& b, const TriangleMesh& m, const std::vector<Vec3f>& normals, const Aabb& box) {
  const std::size_t nv = m.vertices.size();
  json attributes;
  const int pv = b.view(m.vertices.data(), nv * sizeof(Vec3f), kArrayBuffer);
  attributes["POSITION"] = b.accessor(pv, kFloat, nv, "VEC3", {box.min.x(), box.min.y(), box.min.z()},
                                      {box.max.x(), box.max.y(), box.max.z()});
  const int nview = b.view(normals.data(), nv * sizeof(Vec3f), kArrayBuffer);
  attributes["NORMAL"] = b.accessor(nview, kFloat, nv, "VEC3");
  return attributes;
}

/// The index accessor: 16-bit while the vertices allow it, else 32-bit.
int index_accessor(GlbBuilder& b, const TriangleMesh& m) {
  if (m.vertices.size() <= 65535) {
    std::vector<std::uint16_t> idx;
    idx.reserve(3 * m.triangles.size());
    for (const auto& t : m.triangles)
      for (Index v : t) idx.push_back(static_cast<std::uint16_t>(v));
    return b.accessor(b.view(idx.data(), idx.size() * 2, kElementArrayBuffer), kUnsignedShort, idx.size(), "SCALAR");
  }
  return b.accessor(b.view(m.triangles.data(), m.triangles.size() * 12, kElementArrayBuffer), kUnsignedInt,
                    3 * m.triangles.size(), "SCALAR");
}

/// Visibility: node k is scaled 1 on [t_k, t_{k+1}) and 0 elsewhere, with STEP keys (the first frame from 0, the
/// last one for 1/fps after its time, which is where the clip ends). One 0→1→0 sampler per frame; `frame_nodes[k]`
/// is frame k's node. Empty for a single frame.
json visibility_animation(GlbBuilder& b, const std::vector<float>& t, const json& frame_nodes, double fps) {
  json channels = json::array(), samplers = json::array();
  if (t.size() < 2) return nullptr;
  const float t0 = std::min(0.0f, t[0]);
  for (std::size_t k = 0; k < t.size(); ++k) {
    std::vector<float> keys, scales;
    auto key = [&](float time, float s) {
      keys.push_back(time);
      scales.insert(scales.end(), {s, s, s});
    };
    if (k == 0) {
      key(t0, 1.0f);
      key(t[1], 0.0f);
    } else {
      key(t0, 0.0f);
      key(t[k], 1.0f);
      // The last frame holds for one frame time, so the clip (and a loop of it) shows it like every other.
      key(k + 1 < t.size() ? t[k + 1] : t[k] + static_cast<float>(1.0 / fps), k + 1 < t.size() ? 0.0f : 1.0f);
    }
    // An input accessor needs min and max; the keys ascend.
    const int in = b.accessor(b.view(keys.data(), keys.size() * 4), kFloat, keys.size(), "SCALAR", {keys.front()}, {keys.back()});
    const int out = b.accessor(b.view(scales.data(), scales.size() * 4), kFloat, keys.size(), "VEC3");
    samplers.push_back({{"input", in}, {"output", out}, {"interpolation", "STEP"}});
    channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", frame_nodes[k]}, {"path", "scale"}}}});
  }
  return {{"name", "forming"}, {"channels", channels}, {"samplers", samplers}};
}

}  // namespace

namespace {

json glb_materials(const GlbOptions& o, const Aabb& box) {
  if (o.materials.empty()) return json::array({water_material(o.material, box, o.quantize)});
  json all = json::array();
  for (std::size_t k = 0; k < o.materials.size(); ++k)
    all.push_back(water_material(o.materials[k], box, o.quantize,
                                 fmt::format("{}_{}", o.materials[k].coloured ? "liquid" : "water", k)));
  return all;
}

// The water extensions, when a material is water.
bool any_water(const GlbOptions& o) {
  if (o.materials.empty()) return !o.material.coloured;
  return std::any_of(o.materials.begin(), o.materials.end(), [](const WaterMaterial& w) { return !w.coloured; });
}

// The frames' textures, each once (a run's frames share one): their materials (after the water/liquid ones), and the
// images, textures and samplers of the document.
struct FrameTextures {
  std::vector<const MeshTexture*> seen;
  json materials = json::array(), doc = json::object();
};

// Frame k's primitives: its vertex attributes (and `mesh_node`, the dequantizing node, when quantized), and one
// primitive per material present. A frame in its target's texture is split at the UV seams, with TEXCOORD_0 instead of
// COLOR_0 (glTF multiplies the two), the welded mesh's normals (a seam is no crease) and its texture's material.
Result<json> frame_primitives(GlbBuilder& b, const TriangleMesh& m, const GlbOptions& o, std::size_t k,
                              std::size_t mesh_index, FrameTextures& textures, json& mesh_node, Aabb& last_box) {
  const bool uv = glb::textured(m) && o.triangle_material.empty();
  glb::UvSplit split;
  if (uv) split = glb::split_uv(m);
  const TriangleMesh& w = uv ? split.mesh : m;
  std::vector<Vec3f> normals = vertex_normals(m);
  if (uv) {
    std::vector<Vec3f> n(w.vertices.size());
    for (std::size_t i = 0; i < n.size(); ++i) n[i] = normals[split.source[i]];
    normals = std::move(n);
  }
  Aabb box;
  for (const auto& v : w.vertices) box.extend(v);
  last_box = box;
  json attributes = o.quantize ? quantized_attributes(b, w, normals, box, mesh_index, k, mesh_node)
                               : float_attributes(b, w, normals, box);
  std::size_t material = 0;
  if (uv) {
    attributes["TEXCOORD_0"] = glb::uv_accessor(b, split.uv);
    auto seen = std::find(textures.seen.begin(), textures.seen.end(), m.texture.get());
    if (seen == textures.seen.end()) {
      FF_TRY(const int index, glb::add_texture(b, textures.doc, *m.texture));
      textures.materials.push_back(glb::textured_material(*m.texture, index, fmt::format("liquid_textured_{}", index)));
      seen = textures.seen.insert(textures.seen.end(), m.texture.get());
    }
    material = (o.materials.empty() ? 1 : o.materials.size()) + std::size_t(seen - textures.seen.begin());
  } else if (!m.colours.empty()) {
    attributes["COLOR_0"] = glb::colour_accessor(b, m.colours);
  }
  json primitives = json::array();
  if (o.triangle_material.empty()) {
    primitives.push_back({{"attributes", attributes}, {"indices", index_accessor(b, w)}, {"material", material}, {"mode", 4}});
  } else {
    // One primitive per material present, sharing the frame's vertices.
    const auto& mat = o.triangle_material[k];
    if (mat.size() != m.triangles.size())
      return param_error(fmt::format("glb: frame {}: {} triangle materials for {} triangles", k, mat.size(),
                                     m.triangles.size()));
    for (std::size_t id = 0; id < o.materials.size(); ++id) {
      TriangleMesh part;
      part.vertices = m.vertices;  // index_accessor's index width depends on the vertex count only
      for (std::size_t t = 0; t < mat.size(); ++t)
        if (mat[t] == id) part.triangles.push_back(m.triangles[t]);
      if (part.triangles.empty()) continue;
      primitives.push_back({{"attributes", attributes}, {"indices", index_accessor(b, part)}, {"material", id}, {"mode", 4}});
    }
    for (std::uint8_t id : mat)
      if (id >= o.materials.size())
        return param_error(fmt::format("glb: frame {}: material {} of {}", k, int(id), o.materials.size()));
  }
  return primitives;
}

}  // namespace

Result<std::vector<std::uint8_t>> encode_glb(std::span<const TriangleMesh> frames, const GlbOptions& o) {
  FF_CHECK(o.validate(frames.size()));
  if (frames.empty()) return param_error("glb: no frames to write");
  GlbBuilder b;
  json nodes = json::array(), meshes = json::array();
  json root = {{"name", "fluidform"}, {"children", json::array()}};
  nodes.push_back(root);
  Aabb last_box;  // of the last frame with a surface: sizes the material's absorption
  FrameTextures textures;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const TriangleMesh& m = frames[k];
    FF_CHECK(check_glb_frame(m, k));
    json node = {{"name", fmt::format("frame_{:05d}", k)}};
    // Static pose (no animation playing): the last frame, the formed shape.
    if (k + 1 != frames.size()) node["scale"] = {0.0, 0.0, 0.0};
    const int node_index = static_cast<int>(nodes.size());
    nodes[0]["children"].push_back(node_index);
    nodes.push_back(node);
    if (m.triangles.empty()) continue;
    json mesh_node = nullptr;  // quantized: the dequantizing child node that holds the mesh
    FF_TRY(json primitives, frame_primitives(b, m, o, k, meshes.size(), textures, mesh_node, last_box));
    meshes.push_back({{"name", fmt::format("frame_{:05d}", k)}, {"primitives", primitives}});
    if (mesh_node.is_null()) {
      nodes[static_cast<std::size_t>(node_index)]["mesh"] = meshes.size() - 1;
    } else {
      nodes[static_cast<std::size_t>(node_index)]["children"] = {nodes.size()};
      nodes.push_back(mesh_node);
    }
  }
  std::vector<float> times(frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k)
    times[k] = static_cast<float>(o.times.empty() ? double(k) / o.fps : o.times[k]);
  const json animation = visibility_animation(b, times, nodes[0]["children"], o.fps);

  while (b.bin.size() % 4) b.bin.push_back(0);
  json doc = {{"asset", {{"version", "2.0"}, {"generator", "fluidform"}}},
              {"scene", 0},
              {"scenes", {{{"name", "fluidform"}, {"nodes", {0}}}}},
              {"nodes", nodes},
              {"materials", glb_materials(o, last_box)},
              {"buffers", {{{"byteLength", b.bin.size()}}}},
              {"bufferViews", b.views},
              {"accessors", b.accessors}};
  for (auto& t : textures.materials) doc["materials"].push_back(std::move(t));
  for (auto& [key, value] : textures.doc.items()) doc[key] = std::move(value);
  if (!meshes.empty()) doc["meshes"] = meshes;
  if (!animation.is_null()) doc["animations"] = json::array({animation});
  doc["extensionsUsed"] = any_water(o) ? glb::water_extensions() : json::array();
  if (o.quantize && !meshes.empty()) {
    doc["extensionsUsed"].push_back("KHR_mesh_quantization");
    doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  }
  if (doc["extensionsUsed"].empty()) doc.erase("extensionsUsed");  // the schema wants at least one, or none
  return pack_glb(doc, b.bin);
}

Status write_glb(const std::filesystem::path& path, std::span<const TriangleMesh> frames, const GlbOptions& options) {
  auto bytes = encode_glb(frames, options);
  if (!bytes) return bytes.error();
  return write_file_atomic(path, *bytes);
}

namespace {

// PC2: "POINTCACHE2\0", int32 version 1, int32 points, float start frame, float sample rate (frames per sample),
// int32 samples; then samples × points × float[3], little-endian.
std::vector<std::uint8_t> pc2_header(std::size_t points, float start_frame, std::size_t samples) {
  std::vector<std::uint8_t> out;
  const char magic[12] = "POINTCACHE2";
  out.insert(out.end(), magic, magic + 12);
  put<std::int32_t>(out, 1);
  put<std::int32_t>(out, static_cast<std::int32_t>(points));
  put<float>(out, start_frame);
  put<float>(out, 1.0f);  // one sample per frame (Blender plays it at the scene's frame rate)
  put<std::int32_t>(out, static_cast<std::int32_t>(samples));
  return out;
}

}  // namespace

Status Pc2Writer::open(const std::filesystem::path& path, std::size_t points, float start_frame) {
  if (!std::isfinite(start_frame)) return param_error(fmt::format("{}: start frame must be finite", path.string()));
  if (points > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    return param_error(fmt::format("{}: {} points is too many for PC2", path.string(), points));
  path_ = path, points_ = points, frames_ = 0;
  FF_CHECK(file_.open(path));
  return file_.write(pc2_header(points, start_frame, 0));
}

Status Pc2Writer::add(std::span<const Vec3f> frame) {
  if (frame.size() != points_)
    return param_error(fmt::format("{}: frame {} has {} points, the cache has {}", path_.string(), frames_, frame.size(), points_));
  if (frames_ + 1 > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    return param_error(fmt::format("{}: too many frames for PC2", path_.string()));
  buf_.clear();
  for (const auto& p : frame) put<float>(buf_, p.x()), put<float>(buf_, p.y()), put<float>(buf_, p.z());
  FF_CHECK(file_.write(buf_));
  ++frames_;
  return {};
}

Status Pc2Writer::finish() {
  if (frames_ == 0) return param_error(fmt::format("{}: a point cache needs at least one frame", path_.string()));
  std::vector<std::uint8_t> count;
  put<std::int32_t>(count, static_cast<std::int32_t>(frames_));
  FF_CHECK(file_.write_at(28, count));
  return file_.commit();
}

Status write_pc2(const std::filesystem::path& path, std::span<const std::vector<Vec3f>> frames, float start_frame) {
  if (frames.empty()) return param_error(fmt::format("{}: a point cache needs at least one frame", path.string()));
  Pc2Writer w;
  FF_CHECK(w.open(path, frames.front().size(), start_frame));
  for (const auto& f : frames) FF_CHECK(w.add(f));
  return w.finish();
}

}  // namespace ff::io
