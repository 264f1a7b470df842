#include "surface/smooth.h"

#include "core/parallel.h"
#include "surface/mesh_topology.h"

#include <Eigen/Geometry>

#include <array>
#include <vector>

namespace ff::surface {

namespace {

Vec3f normal(const std::vector<Vec3f>& x, const std::array<Index, 3>& t) {
  return (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
}

// Smoothing a rough, coarse mesh can turn a triangle over (a fold the connectivity checks cannot see): the
// corners of every triangle whose normal turned by more than 90° go back to where they were, which can turn a
// neighbour over in turn, so this repeats (a few rounds), and gives the original positions back if it must.
void keep_unfolded(io::TriangleMesh& mesh, const std::vector<Vec3f>& original) {
  for (int round = 0; round < 8; ++round) {
    bool folded = false;
    for (const auto& t : mesh.triangles) {
      if (normal(mesh.vertices, t).dot(normal(original, t)) > 0.0f) continue;
      folded = true;
      for (const Index v : t) mesh.vertices[v] = original[v];
    }
    if (!folded) return;
  }
  mesh.vertices = original;
}

}  // namespace

void smooth_weighted(io::TriangleMesh& mesh, const SmoothParams& params) {
  if (params.passes <= 0 || params.beta <= 0.0f || mesh.triangles.empty()) return;
  const std::vector<Vec3f> original = mesh.vertices;
  const VertexStar star = vertex_star(mesh);  // on a closed manifold mesh, `to` lists each 1-ring once
  const float h2 = params.radius * params.radius;
  const auto nv = std::int64_t(mesh.vertices.size());
  std::vector<Vec3f> next(mesh.vertices.size());
  // Step k of a pass moves every vertex by factor · ΔV (eq. 20): +β, then −μ for Taubin.
  const int steps = params.inflate > 0.0f ? 2 : 1;
  for (int step = 0; step < params.passes * steps; ++step) {
    const float factor = step % steps == 0 ? params.beta : -params.inflate;
    const Vec3f* x = mesh.vertices.data();
    core::parallel_for(nv, [&](std::int64_t v) {
      const Vec3f xi = x[v];
      Vec3f sum = Vec3f::Zero();
      float wsum = 0.0f;
      for (Index h = star.start[std::size_t(v)]; h < star.start[std::size_t(v) + 1]; ++h) {
        const Vec3f& xj = x[star.to[h]];
        const float r2 = (xj - xi).squaredNorm();
        if (r2 >= h2) continue;
        const float q = h2 - r2;
        const float w = q * q * q;  // W_poly6 up to its constant, which the normalisation cancels
        sum += w * xj;
        wsum += w;
      }
      next[std::size_t(v)] = wsum > 0.0f ? Vec3f(xi + factor * (sum / wsum - xi)) : xi;
    });
    mesh.vertices.swap(next);
  }
  keep_unfolded(mesh, original);
}

}  // namespace ff::surface
