#include "surface/mesh_topology.h"

#include <algorithm>
#include <numeric>

namespace ff::surface {

VertexStar vertex_star(const io::TriangleMesh& mesh) {
  const std::size_t nv = mesh.vertices.size();
  VertexStar s;
  s.start.assign(nv + 1, 0);
  auto valid = [&](const std::array<Index, 3>& t) { return t[0] < nv && t[1] < nv && t[2] < nv; };
  for (const auto& t : mesh.triangles)
    if (valid(t))
      for (int k = 0; k < 3; ++k) ++s.start[t[std::size_t(k)] + 1];
  for (std::size_t v = 0; v < nv; ++v) s.start[v + 1] += s.start[v];
  const std::size_t nh = s.start[nv];
  s.to.resize(nh);
  s.third.resize(nh);
  s.tri.resize(nh);
  std::vector<Index> fill(s.start.begin(), s.start.end() - 1);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    if (!valid(t)) continue;
    for (int k = 0; k < 3; ++k) {
      const Index v = t[std::size_t(k)];
      const Index h = fill[v]++;
      s.to[h] = t[std::size_t((k + 1) % 3)];
      s.third[h] = t[std::size_t((k + 2) % 3)];
      s.tri[h] = Index(f);
    }
  }
  return s;
}

namespace {
Index find_root(std::vector<Index>& parent, Index x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}
}  // namespace

Components connected_components(const io::TriangleMesh& mesh) {
  const std::size_t nv = mesh.vertices.size();
  std::vector<Index> parent(nv);
  std::iota(parent.begin(), parent.end(), Index(0));
  std::vector<unsigned char> used(nv, 0);
  for (const auto& t : mesh.triangles) {
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv) continue;
    for (const Index v : t) used[v] = 1;
    for (int k = 1; k < 3; ++k) {
      const Index a = find_root(parent, t[0]), b = find_root(parent, t[std::size_t(k)]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the smaller root wins: independent of order
    }
  }
  Components c;
  c.of_vertex.assign(nv, kInvalidIndex);
  std::vector<Index> id_of_root(nv, kInvalidIndex);
  for (const auto& t : mesh.triangles) {
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv) continue;
    const Index r = find_root(parent, t[0]);
    if (id_of_root[r] == kInvalidIndex) id_of_root[r] = Index(c.count++);
  }
  for (std::size_t v = 0; v < nv; ++v)
    if (used[v]) c.of_vertex[v] = id_of_root[find_root(parent, Index(v))];
  return c;
}

std::vector<Index> keep_triangles(io::TriangleMesh& mesh, const std::vector<unsigned char>& keep) {
  std::size_t out_t = 0;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    if (keep[f]) mesh.triangles[out_t++] = mesh.triangles[f];
  mesh.triangles.resize(out_t);
  return io::drop_unused_vertices(mesh);
}

}  // namespace ff::surface
