#include "surface/decimate.h"

#include "surface/mesh_topology.h"

#include "core/point_tree.h"

#include <Eigen/Geometry>
#include <meshoptimizer.h>

#include <algorithm>
#include <limits>
#include <optional>
#include <vector>

namespace ff::surface {
namespace {

static_assert(sizeof(Vec3f) == 3 * sizeof(float), "meshoptimizer reads positions as packed float triples");

// One simplifier pass to at most `target` triangles within `error` (m), never moving a vertex with locked[v].
// meshoptimizer 0.18 has no per-vertex lock, but it never collapses a vertex that has more than two copies at
// its position (it takes such a vertex for a meeting point of attribute seams): two unused copies of each
// locked vertex are appended to the position buffer. The result indexes `in.vertices` (not compacted).
io::TriangleMesh simplify(const io::TriangleMesh& in, std::size_t target, float error,
                          const std::vector<unsigned char>& locked, float* result_error) {
  std::vector<Vec3f> positions = in.vertices;
  for (std::size_t v = 0; v < in.vertices.size(); ++v)
    if (locked[v]) positions.insert(positions.end(), 2, in.vertices[v]);
  const float scale = meshopt_simplifyScale(positions.front().data(), positions.size(), sizeof(Vec3f));
  std::vector<unsigned int> idx(in.triangles.size() * 3);
  for (std::size_t f = 0; f < in.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) idx[3 * f + std::size_t(k)] = in.triangles[f][std::size_t(k)];
  std::vector<unsigned int> dst(idx.size());
  float rel = 0.0f;
  const float rel_target = scale > 0.0f ? error / scale : 0.0f;
  const std::size_t n = meshopt_simplify(dst.data(), idx.data(), idx.size(), positions.front().data(), positions.size(),
                                         sizeof(Vec3f), target * 3, rel_target, 0, &rel);
  *result_error = rel * scale;
  io::TriangleMesh out;
  out.vertices = in.vertices;
  out.triangles.resize(n / 3);
  for (std::size_t f = 0; f < n / 3; ++f) out.triangles[f] = {dst[3 * f], dst[3 * f + 1], dst[3 * f + 2]};
  return out;
}

// Vertices of `raw` (uncompacted) where it is not a clean closed manifold: defect_vertices() plus the corners of
// zero-area triangles.
std::vector<Index> broken_vertices(const io::TriangleMesh& raw) {
  std::vector<Index> bad = defect_vertices(raw);
  for (const auto& t : raw.triangles) {
    const Vec3f n = (raw.vertices[t[1]] - raw.vertices[t[0]]).cross(raw.vertices[t[2]] - raw.vertices[t[0]]);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(n.squaredNorm() > 0.0f))
      bad.insert(bad.end(), t.begin(), t.end());
  }
  return bad;
}

}  // namespace

io::TriangleMesh decimate(const io::TriangleMesh& mesh, const DecimateParams& params, DecimateStats* stats) {
  DecimateStats st;
  io::TriangleMesh cur = mesh;
  const std::size_t components = check_mesh(mesh).components;
  auto good = [&](const io::TriangleMesh& m) {
    const MeshCheck c = check_mesh(m);
    return (params.allow_cavities ? c.ok_allowing_cavities() : c.ok()) && c.components == components &&
           !m.triangles.empty();
  };
  // One pass from `cur`. When the result breaks the mesh, the broken places and two rings around them (in the
  // input) are locked and the pass is redone, up to four times; the pass is dropped if it still fails.
  auto pass = [&](std::size_t target, float error) -> std::optional<io::TriangleMesh> {
    std::vector<unsigned char> locked(cur.vertices.size(), 0);
    for (int attempt = 0; attempt < 5; ++attempt) {
      float err = 0.0f;
      io::TriangleMesh next = simplify(cur, target, error, locked, &err);
      if (next.triangles.size() >= cur.triangles.size()) return std::nullopt;
      const std::vector<Index> bad = broken_vertices(next);
      if (bad.empty()) {
        std::vector<unsigned char> keep(next.triangles.size(), 1);
        keep_triangles(next, keep);
        if (!good(next)) break;  // nothing local to lock (a component lost or turned inside out)
        st.error += err;
        ++st.passes;
        return next;
      }
      ++st.rejected_passes;
      const VertexStar star = vertex_star(cur);
      std::vector<Index> ring(bad.begin(), bad.end());
      for (int r = 0; r < 2; ++r) {
        const std::size_t n = ring.size();
        for (std::size_t i = 0; i < n; ++i)
          for (Index h = star.start[ring[i]]; h < star.start[ring[i] + 1]; ++h) ring.push_back(star.to[h]);
      }
      for (const Index v : ring) locked[v] = 1;
    }
    ++st.rejected_passes;
    return std::nullopt;
  };

  if (params.max_error > 0.0f && !cur.triangles.empty())
    if (auto next = pass(0, params.max_error)) cur = std::move(*next);  // phase 1: as far as the error allows
  if (params.max_triangles > 0) {
    // Phase 2: halve per pass down to the budget (a pass that cannot be made clean ends the phase).
    while (cur.triangles.size() > params.max_triangles) {
      const std::size_t target = std::max(params.max_triangles, cur.triangles.size() / 2);
      auto next = pass(target, std::numeric_limits<float>::max());
      if (!next) break;
      cur = std::move(*next);
    }
    st.budget_met = cur.triangles.size() <= params.max_triangles;
  }
  if (stats) *stats = st;
  return cur;
}

void carry_colours(const io::TriangleMesh& from, io::TriangleMesh& to) {
  to.colours.clear();
  if (from.colours.size() != from.vertices.size() || from.vertices.empty()) return;
  const core::PointTree tree(from.vertices);
  to.colours.resize(to.vertices.size());
  Index hint = kInvalidIndex;
  for (std::size_t v = 0; v < to.vertices.size(); ++v) {
    const auto n = tree.nearest(to.vertices[v], hint);
    hint = n.slot;
    to.colours[v] = from.colours[tree.original(n.slot)];
  }
}

}  // namespace ff::surface
