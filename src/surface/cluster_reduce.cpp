#include "surface/cluster_reduce.h"

#include "core/parallel.h"
#include "surface/mesh_check.h"
#include "surface/mesh_topology.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <utility>
#include <vector>

namespace ff::surface {

io::TriangleMesh cluster_reduce(const io::TriangleMesh& mesh, std::span<const std::uint64_t> cluster,
                                std::uint64_t no_cluster, const PlaceVertex& place, ClusterStats* stats) {
  const std::size_t nv = mesh.vertices.size();
  ClusterStats st;

  // Dense cluster ids, members in vertex order.
  std::vector<std::pair<std::uint64_t, Index>> kv;
  kv.reserve(nv);
  for (std::size_t v = 0; v < nv; ++v)
    if (cluster[v] != no_cluster) kv.emplace_back(cluster[v], Index(v));
  std::sort(kv.begin(), kv.end());
  std::vector<Index> cl(nv, kInvalidIndex);
  std::vector<Index> cstart;
  for (std::size_t i = 0; i < kv.size(); ++i) {
    if (i == 0 || kv[i].first != kv[i - 1].first) cstart.push_back(Index(i));
    cl[kv[i].second] = Index(cstart.size() - 1);
  }
  const std::size_t nc = cstart.size();
  cstart.push_back(Index(kv.size()));
  std::vector<unsigned char> merged(nc, 0);
  for (std::size_t c = 0; c < nc; ++c) merged[c] = cstart[c + 1] - cstart[c] >= 2;
  // Where each cluster's merged vertex goes (computed once: it does not depend on the other merges).
  std::vector<Vec3f> spot(nc);
  core::parallel_for(std::int64_t(nc), [&](std::int64_t c) {
    if (!merged[std::size_t(c)]) return;
    Vec3d sum = Vec3d::Zero();
    for (Index i = cstart[std::size_t(c)]; i < cstart[std::size_t(c) + 1]; ++i)
      sum += mesh.vertices[kv[i].second].cast<double>();
    const Vec3f mean = (sum / double(cstart[std::size_t(c) + 1] - cstart[std::size_t(c)])).cast<float>();
    spot[std::size_t(c)] = place ? place(mean) : mean;
  });

  std::vector<Vec3f> n0(mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    n0[f] = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
  }

  io::TriangleMesh out;
  std::vector<Index> map(nv), cluster_vertex(nc), cluster_of_new;
  std::vector<Index> source_tri;
  for (int round = 0;; ++round) {
    // --- rebuild with the current merges -----------------------------------------------------------------------
    out.vertices.clear();
    out.triangles.clear();
    cluster_of_new.clear();
    std::fill(cluster_vertex.begin(), cluster_vertex.end(), kInvalidIndex);
    for (std::size_t v = 0; v < nv; ++v) {
      const Index c = cl[v];
      if (c != kInvalidIndex && merged[c]) {
        if (cluster_vertex[c] == kInvalidIndex) {
          cluster_vertex[c] = Index(out.vertices.size());
          out.vertices.push_back(spot[c]);
          cluster_of_new.push_back(c);
        }
        map[v] = cluster_vertex[c];
      } else {
        map[v] = Index(out.vertices.size());
        out.vertices.push_back(mesh.vertices[v]);
        cluster_of_new.push_back(kInvalidIndex);
      }
    }
    source_tri.clear();
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      const auto& t = mesh.triangles[f];
      const std::array<Index, 3> m = {map[t[0]], map[t[1]], map[t[2]]};
      if (m[0] == m[1] || m[1] == m[2] || m[0] == m[2]) continue;
      out.triangles.push_back(m);
      source_tri.push_back(Index(f));
    }

    // --- find merges that hurt -------------------------------------------------------------------------------------
    std::vector<unsigned char> undo(nc, 0);
    bool any = false;
    auto mark = [&](Index new_vertex) {
      const Index c = cluster_of_new[new_vertex];
      if (c != kInvalidIndex) {
        undo[c] = 1;
        any = true;
      }
    };
    for (std::size_t i = 0; i < out.triangles.size(); ++i) {
      const auto& t = out.triangles[i];
      const Vec3f n = (out.vertices[t[1]] - out.vertices[t[0]]).cross(out.vertices[t[2]] - out.vertices[t[0]]);
      if (n.squaredNorm() == 0.0f || !(n.dot(n0[source_tri[i]]) > 0.0f))
        for (const Index v : t) mark(v);
    }
    const std::vector<Index> defects = defect_vertices(out);
    if (!defects.empty()) {
      // The cause may be a merged neighbour of a clean vertex: undo the whole 1-ring.
      const VertexStar star = vertex_star(out);
      for (const Index w : defects) {
        mark(w);
        for (Index h = star.start[w]; h < star.start[w + 1]; ++h) {
          mark(star.to[h]);
          mark(star.third[h]);
        }
      }
    }
    bool progress = false;
    for (std::size_t c = 0; c < nc; ++c)
      if (undo[c] && merged[c]) {
        merged[c] = 0;
        ++st.clusters_undone;
        progress = true;
      }
    st.rounds = round + 1;
    if (!any && defects.empty()) break;
    if (!progress) {  // defects the merges did not cause (bad input): give the input back unchanged
      out = mesh;
      st = ClusterStats{};
      st.rounds = round + 1;
      if (stats) *stats = st;
      return out;
    }
  }
  for (std::size_t c = 0; c < nc; ++c) st.clusters_merged += merged[c];
  // Clusters whose triangles all vanished leave unused vertices behind.
  std::vector<unsigned char> keep(out.triangles.size(), 1);
  keep_triangles(out, keep);
  if (stats) *stats = st;
  return out;
}

}  // namespace ff::surface
