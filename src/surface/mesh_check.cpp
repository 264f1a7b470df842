#include "surface/mesh_check.h"

#include "core/parallel.h"
#include "surface/mesh_topology.h"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace ff::surface {
namespace {

// What one vertex sees of the mesh around it.
struct VertexReport {
  std::uint32_t edges = 0, boundary = 0, nonmanifold = 0, misoriented = 0;  // edges counted at this vertex
  bool bad_edge = false;  // an incident edge that is not exactly one half-edge each way
  bool bad_link = false;  // the link is not a single cycle (of length ≥ 3)
};

std::uint32_t count_to(const VertexStar& s, Index from, Index to) {
  std::uint32_t n = 0;
  for (Index h = s.start[from]; h < s.start[from + 1]; ++h) n += s.to[h] == to;
  return n;
}

// Is the undirected graph on the link edges (a_i, b_i) one cycle through every link vertex?
bool single_cycle(const VertexStar& s, Index v) {
  const Index h0 = s.start[v], deg = s.start[v + 1] - h0;
  if (deg < 3) return false;
  // Every link vertex must appear exactly twice among the 2·deg endpoints.
  for (Index i = 0; i < deg; ++i)
    for (const Index x : {s.to[h0 + i], s.third[h0 + i]}) {
      Index n = 0;
      for (Index j = 0; j < deg; ++j) n += (s.to[h0 + j] == x) + (s.third[h0 + j] == x);
      if (n != 2 || x == v) return false;
    }
  // Walk the cycle from edge 0: it must come back after using every edge.
  Index edge = 0, at = s.third[h0], steps = 1;
  while (at != s.to[h0]) {
    Index next_edge = kInvalidIndex;
    for (Index j = 0; j < deg && next_edge == kInvalidIndex; ++j)
      if (j != edge && (s.to[h0 + j] == at || s.third[h0 + j] == at)) next_edge = j;
    if (next_edge == kInvalidIndex) return false;
    at = s.to[h0 + next_edge] == at ? s.third[h0 + next_edge] : s.to[h0 + next_edge];
    edge = next_edge;
    if (++steps > deg) return false;
  }
  return steps == deg;
}

VertexReport inspect(const VertexStar& s, Index v) {
  VertexReport r;
  for (Index h = s.start[v]; h < s.start[v + 1]; ++h) {
    const Index w = s.to[h];
    bool first = true;  // count a repeated half-edge v → w once
    for (Index g = s.start[v]; g < h && first; ++g) first = s.to[g] != w;
    const std::uint32_t same = count_to(s, v, w), rev = count_to(s, w, v);
    if (same != 1 || rev != 1) r.bad_edge = true;
    // Each undirected edge is counted at one end: the smaller one, or the only one with a half-edge.
    if (!first || !(v < w || rev == 0)) continue;
    ++r.edges;
    const std::uint32_t total = same + rev;
    if (total == 1)
      ++r.boundary;
    else if (total > 2)
      ++r.nonmanifold;
    else if (same != 1)
      ++r.misoriented;
  }
  r.bad_link = s.degree(v) > 0 && !single_cycle(s, v);
  return r;
}

bool degenerate(const io::TriangleMesh& m, const std::array<Index, 3>& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Vec3f &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
  if (!a.allFinite() || !b.allFinite() || !c.allFinite()) return true;
  return (b - a).cross(c - a).squaredNorm() == 0.0f;
}

}  // namespace

std::string MeshCheck::summary() const {
  return fmt::format(
      "{} vertices, {} triangles, {} edges, {} components, genus {}, χ {}, volume {:.6g}: boundary {}, "
      "non-manifold edges {} / vertices {}, misoriented {}, inward components {}, degenerate {}, "
      "invalid {}, unreferenced vertices {}",
      vertices, triangles, edges, components, genus, euler, volume, boundary_edges, nonmanifold_edges,
      nonmanifold_vertices, misoriented_edges, inward_components, degenerate_triangles, invalid_triangles,
      unreferenced_vertices);
}

MeshCheck check_mesh(const io::TriangleMesh& mesh) {
  MeshCheck c;
  c.vertices = mesh.vertices.size();
  c.triangles = mesh.triangles.size();
  const std::size_t nv = mesh.vertices.size();
  std::vector<unsigned char> valid(mesh.triangles.size(), 1);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv) {
      valid[f] = 0;
      ++c.invalid_triangles;
    } else if (degenerate(mesh, t)) {
      ++c.degenerate_triangles;
    }
  }

  const VertexStar star = vertex_star(mesh);
  std::vector<VertexReport> rep(nv);
  core::parallel_for(std::int64_t(nv), [&](std::int64_t v) { rep[std::size_t(v)] = inspect(star, Index(v)); });
  std::size_t referenced = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    const auto& r = rep[v];
    c.edges += r.edges;
    c.boundary_edges += r.boundary;
    c.nonmanifold_edges += r.nonmanifold;
    c.misoriented_edges += r.misoriented;
    c.nonmanifold_vertices += r.bad_link;
    if (star.degree(Index(v)) > 0) ++referenced;
  }
  c.unreferenced_vertices = nv - referenced;
  std::size_t valid_tris = 0;
  for (auto x : valid) valid_tris += x;
  c.euler = (long long)referenced - (long long)c.edges + (long long)valid_tris;

  // Components and their signed volumes (summed in triangle order: deterministic).
  const Components comp = connected_components(mesh);
  c.components = comp.count;
  std::vector<double> vol(comp.count, 0.0);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    if (!valid[f]) continue;
    const auto& t = mesh.triangles[f];
    const Vec3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                b2 = mesh.vertices[t[2]].cast<double>();
    vol[comp.of_vertex[t[0]]] += a.dot(b.cross(b2)) / 6.0;
  }
  for (const double x : vol) {
    c.volume += x;
    c.inward_components += !(x > 0.0);
  }
  if (c.watertight() && c.manifold()) c.genus = int((2 * (long long)c.components - c.euler) / 2);
  return c;
}

std::vector<Index> defect_vertices(const io::TriangleMesh& mesh) {
  const VertexStar star = vertex_star(mesh);
  const std::size_t nv = mesh.vertices.size();
  std::vector<unsigned char> bad(nv, 0);
  core::parallel_for(std::int64_t(nv), [&](std::int64_t v) {
    const VertexReport r = inspect(star, Index(v));
    bad[std::size_t(v)] = r.bad_edge || r.bad_link;
  });
  std::vector<Index> out;
  for (std::size_t v = 0; v < nv; ++v)
    if (bad[v]) out.push_back(Index(v));
  return out;
}

}  // namespace ff::surface
