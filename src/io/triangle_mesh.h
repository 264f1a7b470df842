#pragma once
// The mesh type handed between stages (DESIGN.md "Data between stages").
#include "core/types.h"

#include <array>
#include <vector>

namespace ff::io {

struct TriangleMesh {
  std::vector<Vec3f> vertices;                  ///< metres
  std::vector<std::array<Index, 3>> triangles;  ///< counter-clockwise seen from outside (when the source is)

  Aabb bounds() const {
    Aabb b;
    for (const auto& v : vertices) b.extend(v);
    return b;
  }
};

}  // namespace ff::io
