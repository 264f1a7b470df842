#pragma once
// What the two mesh targets share (fuzz_mesh.cpp: the whole import; fuzz_mesh_checks.cpp: our checks without
// Assimp): how the first byte picks the file name Assimp is told and the transform applied after import, and what a
// mesh that loads must hold.
#include "fuzz_target.h"
#include "io/load_mesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ff::fuzz {

/// Bits 0-1 of the first byte: the format (OBJ, PLY, STL or OFF, the formats whose headers and contents we check).
inline const char* mesh_name(std::uint8_t first) {
  static constexpr std::array<const char*, 4> kNames{"mesh.obj", "mesh.ply", "mesh.stl", "mesh.off"};
  return kNames[first & 3];
}

/// Bits 2-3 of the first byte: the transform applied after import.
inline io::LoadOptions mesh_options(std::uint8_t first) {
  io::LoadOptions options;
  switch ((first >> 2) & 3) {
    case 1: options.transform.scale = {-2.0f, 1.0f, 1.0f}; break;  // a mirror: the windings are reversed
    case 2: options.transform.rotate_deg = {30.0f, 45.0f, 60.0f}, options.transform.translate = {1e3f, 0, 0}; break;
    case 3: options.transform.scale = {1e30f, 1e30f, 1e30f}; break;  // may overflow to Inf: refused
    default: break;
  }
  return options;
}

/// A mesh that loads has triangles, every index in range, no repeated index in a triangle, finite vertices, and no
/// vertex that no triangle uses.
inline void check_loaded_mesh(const io::TriangleMesh& m) {
  FF_FUZZ_CHECK(!m.triangles.empty() && !m.vertices.empty());
  std::vector<bool> used(m.vertices.size(), false);
  for (const auto& t : m.triangles) {
    for (const Index i : t) {
      FF_FUZZ_CHECK(i < m.vertices.size());
      used[i] = true;
    }
    FF_FUZZ_CHECK(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
  }
  for (std::size_t i = 0; i < m.vertices.size(); ++i) FF_FUZZ_CHECK(used[i] && m.vertices[i].allFinite());
}

}  // namespace ff::fuzz
