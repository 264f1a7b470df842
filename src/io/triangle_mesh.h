#pragma once
// The mesh type handed between stages (docs/ARCHITECTURE.md "Data between stages").
#include "core/types.h"
#include "io/texture.h"

#include <array>
#include <memory>
#include <vector>

namespace ff::io {

struct TriangleMesh {
  std::vector<Vec3f> vertices;                  ///< metres
  std::vector<std::array<Index, 3>> triangles;  ///< counter-clockwise seen from outside (when the source is)
  /// Per vertex, linear RGB in [0, 1] (the liquid's look, pipeline/liquid_look.h); empty: the mesh has no colours.
  std::vector<Vec3f> colours;
  /// Per triangle, the UVs of its three corners into `texture` (the liquid wears its target's texture, pipeline/
  /// liquid_look.h); empty: none. Per corner, not per vertex: a triangle across a UV seam of the target takes its own
  /// UVs, so the writers split vertices only there (the mesh itself stays welded: watertight, one vertex per point).
  std::vector<std::array<Vec2f, 3>> corner_uv;
  std::shared_ptr<const MeshTexture> texture;  ///< what corner_uv index (shared by every frame of a run)

  Aabb bounds() const {
    Aabb b;
    for (const auto& v : vertices) b.extend(v);
    return b;
  }
};

/// Removes the vertices no triangle uses; the others keep their relative order (new index = rank among the used).
/// Returns the map old → new index (kInvalidIndex: removed).
inline std::vector<Index> drop_unused_vertices(TriangleMesh& mesh) {
  if (mesh.colours.size() != mesh.vertices.size()) mesh.colours.clear();  // colours that do not match are none
  std::vector<Index> map(mesh.vertices.size(), kInvalidIndex);
  for (const auto& t : mesh.triangles)
    for (const Index v : t) map[v] = 0;
  Index next = 0;
  for (std::size_t v = 0; v < map.size(); ++v)
    if (map[v] != kInvalidIndex) {
      map[v] = next;
      if (!mesh.colours.empty()) mesh.colours[next] = mesh.colours[v];
      mesh.vertices[next++] = mesh.vertices[v];
    }
  mesh.vertices.resize(next);
  if (!mesh.colours.empty()) mesh.colours.resize(next);
  for (auto& t : mesh.triangles)
    for (Index& v : t) v = map[v];
  return map;
}

}  // namespace ff::io
