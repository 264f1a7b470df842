#include "surface/cluster_reduce.h"

#include "core/parallel.h"
#include "surface/mesh_check.h"
#include "surface/mesh_topology.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <utility>
#include <vector>

namespace ff::surface {
namespace {

// Dense cluster ids, members in vertex order: cluster c's members are kv[cstart[c] .. cstart[c + 1]), cl[v] is
// vertex v's cluster (kInvalidIndex: none).
struct Clusters {
  std::vector<std::pair<std::uint64_t, Index>> kv;
  std::vector<Index> cl, cstart;
  std::size_t count = 0;
};

Clusters dense_clusters(std::size_t nv, std::span<const std::uint64_t> cluster, std::uint64_t no_cluster) {
  Clusters c;
  c.kv.reserve(nv);
  for (std::size_t v = 0; v < nv; ++v)
    if (cluster[v] != no_cluster) c.kv.emplace_back(cluster[v], Index(v));
  std::sort(c.kv.begin(), c.kv.end());
  c.cl.assign(nv, kInvalidIndex);
  for (std::size_t i = 0; i < c.kv.size(); ++i) {
    if (i == 0 || c.kv[i].first != c.kv[i - 1].first) c.cstart.push_back(Index(i));
    c.cl[c.kv[i].second] = Index(c.cstart.size() - 1);
  }
  c.count = c.cstart.size();
  c.cstart.push_back(Index(c.kv.size()));
  return c;
}

// Where each merged cluster's vertex goes (computed once: it does not depend on the other merges).
std::vector<Vec3f> merged_spots(const io::TriangleMesh& mesh, const Clusters& cs,
                                const std::vector<unsigned char>& merged, const PlaceVertex& place) {
  const auto& kv = cs.kv;
  const auto& cstart = cs.cstart;
  std::vector<Vec3f> spot(cs.count);
  core::parallel_for(std::int64_t(cs.count), [&](std::int64_t c) {
    if (!merged[std::size_t(c)]) return;
    Vec3d sum = Vec3d::Zero();
    for (Index i = cstart[std::size_t(c)]; i < cstart[std::size_t(c) + 1]; ++i)
      sum += mesh.vertices[kv[i].second].cast<double>();
    const Vec3f mean = (sum / double(cstart[std::size_t(c) + 1] - cstart[std::size_t(c)])).cast<float>();
    spot[std::size_t(c)] = place ? place(mean) : mean;
  });
  return spot;
}

// The reduced mesh of one round, rebuilt with the current merges: `out`, each new vertex's cluster (kInvalidIndex:
// not merged) and each kept triangle's source triangle. `map` and `cluster_vertex` are scratch.
struct Rebuilt {
  io::TriangleMesh out;
  std::vector<Index> map, cluster_vertex, cluster_of_new, source_tri;
};

void rebuild(const io::TriangleMesh& mesh, const Clusters& cs, const std::vector<unsigned char>& merged,
             const std::vector<Vec3f>& spot, Rebuilt& r) {
  const std::size_t nv = mesh.vertices.size();
  io::TriangleMesh& out = r.out;
  out.vertices.clear();
  out.triangles.clear();
  r.cluster_of_new.clear();
  std::fill(r.cluster_vertex.begin(), r.cluster_vertex.end(), kInvalidIndex);
  for (std::size_t v = 0; v < nv; ++v) {
    const Index c = cs.cl[v];
    if (c != kInvalidIndex && merged[c]) {
      if (r.cluster_vertex[c] == kInvalidIndex) {
        r.cluster_vertex[c] = Index(out.vertices.size());
        out.vertices.push_back(spot[c]);
        r.cluster_of_new.push_back(c);
      }
      r.map[v] = r.cluster_vertex[c];
    } else {
      r.map[v] = Index(out.vertices.size());
      out.vertices.push_back(mesh.vertices[v]);
      r.cluster_of_new.push_back(kInvalidIndex);
    }
  }
  r.source_tri.clear();
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    const std::array<Index, 3> m = {r.map[t[0]], r.map[t[1]], r.map[t[2]]};
    if (m[0] == m[1] || m[1] == m[2] || m[0] == m[2]) continue;
    out.triangles.push_back(m);
    r.source_tri.push_back(Index(f));
  }
}

// The merges that hurt: undo[c] = 1 for every cluster next to a folded or zero-area triangle or around a defect
// vertex. Returns whether any was marked; `defects` gets the defect vertices.
bool find_hurting_merges(const Rebuilt& r, const std::vector<Vec3f>& n0, std::vector<unsigned char>& undo,
                         std::vector<Index>& defects) {
  const io::TriangleMesh& out = r.out;
  bool any = false;
  auto mark = [&](Index new_vertex) {
    const Index c = r.cluster_of_new[new_vertex];
    if (c != kInvalidIndex) {
      undo[c] = 1;
      any = true;
    }
  };
  for (std::size_t i = 0; i < out.triangles.size(); ++i) {
    const auto& t = out.triangles[i];
    const Vec3f n = (out.vertices[t[1]] - out.vertices[t[0]]).cross(out.vertices[t[2]] - out.vertices[t[0]]);
    if (n.squaredNorm() == 0.0f || !(n.dot(n0[r.source_tri[i]]) > 0.0f))
      for (const Index v : t) mark(v);
  }
  defects = defect_vertices(out);
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
  return any;
}

}  // namespace

io::TriangleMesh cluster_reduce(const io::TriangleMesh& mesh, std::span<const std::uint64_t> cluster,
                                std::uint64_t no_cluster, const PlaceVertex& place, ClusterStats* stats) {
  const std::size_t nv = mesh.vertices.size();
  ClusterStats st;

  const Clusters cs = dense_clusters(nv, cluster, no_cluster);
  const std::size_t nc = cs.count;
  std::vector<unsigned char> merged(nc, 0);
  for (std::size_t c = 0; c < nc; ++c) merged[c] = cs.cstart[c + 1] - cs.cstart[c] >= 2;
  const std::vector<Vec3f> spot = merged_spots(mesh, cs, merged, place);

  std::vector<Vec3f> n0(mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    n0[f] = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
  }

  Rebuilt r;
  r.map.resize(nv);
  r.cluster_vertex.resize(nc);
  for (int round = 0;; ++round) {
    // --- rebuild with the current merges -----------------------------------------------------------------------
    rebuild(mesh, cs, merged, spot, r);

    // --- find merges that hurt -------------------------------------------------------------------------------------
    std::vector<unsigned char> undo(nc, 0);
    std::vector<Index> defects;
    const bool any = find_hurting_merges(r, n0, undo, defects);
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
      io::TriangleMesh out = mesh;
      st = ClusterStats{};
      st.rounds = round + 1;
      if (stats) *stats = st;
      return out;
    }
  }
  io::TriangleMesh out = std::move(r.out);
  for (std::size_t c = 0; c < nc; ++c) st.clusters_merged += merged[c];
  // Clusters whose triangles all vanished leave unused vertices behind.
  std::vector<unsigned char> keep(out.triangles.size(), 1);
  keep_triangles(out, keep);
  if (stats) *stats = st;
  return out;
}

}  // namespace ff::surface
