#pragma once
// Internal to io/: the pieces the GLB writers share (write_mesh.cpp's mesh animation, write_rigged_glb.cpp's rigged
// mesh): glTF enums, the binary chunk under construction with its buffer views and accessors, the GLB container, the
// water material, and a textured mesh's pieces (split at its UV seams, TEXCOORD_0, the embedded texture and its
// material). Not an interface for other stages.
#include "core/error.h"
#include "core/types.h"
#include "io/write_mesh.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace ff::io::glb {

using nlohmann::json;

// glTF enums (WebGL names).
inline constexpr int kFloat = 5126, kUnsignedInt = 5125, kUnsignedShort = 5123, kShort = 5122, kByte = 5120;
inline constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

/// Appends the little-endian bytes of `v`.
template <class T>
void put(std::vector<std::uint8_t>& out, T v) {
  std::uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.insert(out.end(), b, b + sizeof(T));
}

/// The binary chunk under construction and the JSON arrays that describe it.
struct GlbBuilder {
  std::vector<std::uint8_t> bin;
  json views = json::array(), accessors = json::array();

  /// Appends `bytes` as one buffer view (4-byte aligned); returns its index.
  int view(const void* data, std::size_t bytes, int target = 0, int stride = 0) {
    while (bin.size() % 4) bin.push_back(0);
    json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target) v["target"] = target;
    if (stride) v["byteStride"] = stride;
    const auto* p = static_cast<const std::uint8_t*>(data);
    bin.insert(bin.end(), p, p + bytes);
    views.push_back(v);
    return static_cast<int>(views.size()) - 1;
  }
  int accessor(int view, int component, std::size_t count, const char* type, json min = nullptr, json max = nullptr,
               bool normalized = false) {
    json a = {{"bufferView", view}, {"componentType", component}, {"count", count}, {"type", type}};
    if (normalized) a["normalized"] = true;
    if (!min.is_null()) a["min"] = std::move(min), a["max"] = std::move(max);
    accessors.push_back(a);
    return static_cast<int>(accessors.size()) - 1;
  }
};

/// The GLB container: header, the JSON chunk (space-padded) and the BIN chunk (zero-padded by the builder).
inline Result<std::vector<std::uint8_t>> pack_glb(const json& doc, const std::vector<std::uint8_t>& bin) {
  std::string text = doc.dump();
  while (text.size() % 4) text.push_back(' ');
  const std::size_t total = 12 + 8 + text.size() + 8 + bin.size();
  if (total > std::numeric_limits<std::uint32_t>::max())
    return param_error(fmt::format("glb: {} bytes is more than a GLB can hold (4 GiB); mesh fewer frames", total));
  std::vector<std::uint8_t> out;
  out.reserve(total);
  put<std::uint32_t>(out, 0x46546C67u);  // "glTF"
  put<std::uint32_t>(out, 2);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(total));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(text.size()));
  put<std::uint32_t>(out, 0x4E4F534Au);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  put<std::uint32_t>(out, static_cast<std::uint32_t>(bin.size()));
  put<std::uint32_t>(out, 0x004E4942u);  // "BIN\0"
  out.insert(out.end(), bin.begin(), bin.end());
  return out;
}

/// Roughness of the opaque, vertex-coloured liquid (appearance tint or target): a wet, glossy surface.
inline constexpr float kColouredRoughness = 0.3f;

/// COLOR_0 of a mesh: linear RGB as normalized unsigned shorts, VEC4 (8 bytes, 4-byte aligned; alpha 1): 8 bits of
/// linear light would band in the darks (sRGB 0–12 fall on two steps).
inline int colour_accessor(GlbBuilder& b, const std::vector<Vec3f>& colours) {
  std::vector<std::uint16_t> c(4 * colours.size(), 65535);
  for (std::size_t i = 0; i < colours.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const float v = colours[i][a];
      c[4 * i + std::size_t(a)] = static_cast<std::uint16_t>(std::lround(std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) * 65535.0f : 0.0f));
    }
  return b.accessor(b.view(c.data(), c.size() * 2, kArrayBuffer, 8), kUnsignedShort, colours.size(), "VEC4", nullptr, nullptr, true);
}

/// The water material (KHR_materials_transmission, _ior, _volume; a closed mesh, so the volume extension's
/// "thickness" is the mesh's own). Base colour white: the tint comes from absorption along the path through the
/// liquid, deeper where it is thicker, as in real water.
/// thicknessFactor is in the mesh's own coordinates, attenuationDistance in the world's: a quantized mesh lives in
/// [-1, 1]³ under a node scaled by its half-extent, so its thickness is a quarter of that cube's diagonal.
inline json water_material(const WaterMaterial& w, const Aabb& box, bool quantized, const std::string& name = "water") {
  if (w.coloured)  // opaque: its vertex colours (COLOR_0) times a white base colour
    return {{"name", name == "water" ? std::string("liquid") : name},
            {"pbrMetallicRoughness", {{"baseColorFactor", {1.0, 1.0, 1.0, 1.0}}, {"metallicFactor", 0.0}, {"roughnessFactor", kColouredRoughness}}}};
  const Vec3f ext = box.max - box.min;
  const float size = ext.allFinite() && ext.minCoeff() >= 0.0f && ext.norm() > 0.0f ? ext.norm() : 1.0f;
  const float distance = w.attenuation_distance > 0.0f ? w.attenuation_distance : 0.5f * size;
  const float thickness = 0.25f * (quantized ? 2.0f * std::sqrt(3.0f) : size);
  return {{"name", name},
          {"pbrMetallicRoughness", {{"baseColorFactor", {1.0, 1.0, 1.0, 1.0}}, {"metallicFactor", 0.0}, {"roughnessFactor", w.roughness}}},
          {"extensions",
           {{"KHR_materials_transmission", {{"transmissionFactor", 1.0}}},
            {"KHR_materials_ior", {{"ior", w.ior}}},
            {"KHR_materials_volume",
             {{"thicknessFactor", thickness}, {"attenuationDistance", distance}, {"attenuationColor", {w.tint.x(), w.tint.y(), w.tint.z()}}}}}}};
}

/// A mesh with per-vertex UVs made from one with per-corner UVs (TriangleMesh::corner_uv): a vertex is split where its
/// corners carry different UVs (across a seam of the target's texture), and only there. `source`: per vertex of
/// `mesh`, the vertex of the input it copies (its colours are carried; normals are the caller's, through `source`).
struct UvSplit {
  TriangleMesh mesh;
  std::vector<Vec2f> uv;
  std::vector<Index> source;
};
UvSplit split_uv(const TriangleMesh& m);

/// Whether `m` is to be written with its texture: UVs for every triangle and an image to index.
inline bool textured(const TriangleMesh& m) {
  return m.texture != nullptr && m.texture->image.width > 0 && !m.corner_uv.empty() && m.corner_uv.size() == m.triangles.size();
}

/// TEXCOORD_0 of a split mesh: floats, glTF's convention (origin top-left: v flipped from OpenGL's).
inline int uv_accessor(GlbBuilder& b, const std::vector<Vec2f>& uv) {
  std::vector<float> t(2 * uv.size());
  for (std::size_t i = 0; i < uv.size(); ++i) t[2 * i] = uv[i].x(), t[2 * i + 1] = 1.0f - uv[i].y();
  return b.accessor(b.view(t.data(), t.size() * 4, kArrayBuffer), kFloat, uv.size(), "VEC2");
}

/// The texture as glTF's "images" (a PNG in the binary chunk), "textures" and "samplers" entries (bilinear and
/// repeating, as measure_look samples it, and mipmapped, as a viewer minifies it); returns the texture's index.
Result<int> add_texture(GlbBuilder& b, json& doc, const MeshTexture& t);

/// The opaque liquid in its target's texture: baseColorTexture `texture` times the texture's factor.
inline json textured_material(const MeshTexture& t, int texture, const std::string& name = "liquid_textured") {
  return {{"name", name},
          {"pbrMetallicRoughness",
           {{"baseColorFactor", {t.factor.x(), t.factor.y(), t.factor.z(), 1.0}},
            {"baseColorTexture", {{"index", texture}}},
            {"metallicFactor", 0.0},
            {"roughnessFactor", kColouredRoughness}}}};
}

/// The extensions water_material uses (for "extensionsUsed").
inline json water_extensions() { return {"KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"}; }

}  // namespace ff::io::glb
