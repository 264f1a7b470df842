// MeshField: orientation repair, the BVH with far-field expansions, and the queries.
//
// Far field (Barill et al. 2018, §3.2). The solid angle of a surface patch S seen from q is
//   Ω(q) = ∫_S n(x)·K(x − q) dA,   K(y) = y / |y|³,
// positive when q is behind the outward normals. Expanding K(x − q) = K(r + d) about a node's area-weighted
// centroid p̃ (r = p̃ − q, d = x − p̃) to second order,
//   K_i(r + d) ≈ K_i(r) + J_ij(r) d_j + ½ H_ijk(r) d_j d_k,
//   J_ij = δ_ij/L³ − 3 r_i r_j/L⁵,
//   H_ijk = −3 (δ_ij r_k + δ_ik r_j + δ_jk r_i)/L⁵ + 15 r_i r_j r_k/L⁷,   L = |r|,
// gives Ω ≈ N·K(r) + M:J(r) + ½ T:H(r) with the node's moments
//   N_i = ∫ n_i dA,  M_ij = ∫ n_i d_j dA,  T_ijk = ∫ n_i d_j d_k dA,
// which are exact per (flat) triangle: ∫_t d dA = a (c − p̃) and ∫_t d dᵀ dA = a/12 (Σ_v d_v d_vᵀ + s sᵀ),
// s = Σ_v d_v. With r̂ = r/L the three terms are N·r̂/L², (tr M − 3 r̂ᵀMr̂)/L³ and
// ½ (−3 (2u + τ)·r̂ + 15 Σ_i r̂_i r̂ᵀT_i r̂)/L⁴ (u_k = Σ_i T_iik, τ_i = Σ_j T_ijj): every factor is O(1) in the
// node's own scale, so millimetre and kilometre meshes are equally safe in float.
//
// Near field: the solid angle of a triangle (Van Oosterom & Strackee 1983),
//   tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|),  a, b, c = vertices − q,
// in double: q may be within a rounding error of the triangle, where float would lose the sign.
#include "sampling/mesh_field.h"

#include "core/parallel.h"

#include <fmt/format.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cstring>
#include <cassert>
#include <cmath>
#include <numbers>
#include <numeric>
#include <tuple>
#include <unordered_map>

namespace ff::sampling {
namespace {

constexpr Index kLeafSize = 4;  // triangles per BVH leaf: small leaves keep exact near-field work low
constexpr int kSahBins = 16;    // candidate split planes per axis
constexpr int kSahDepth = 24;   // SAH above this depth, median below: depth ≤ 24 + log2(2^32 / kLeafSize) + 1
constexpr int kStackSize = 64;  // the traversal stacks grow by at most one per level
constexpr double kFourPi = 4.0 * std::numbers::pi;

using Tri = std::array<Index, 3>;

Vec3d to_d(const Vec3f& v) { return v.cast<double>(); }

Vec3d cross_d(const io::TriangleMesh& m, const Tri& t) {
  const Vec3d a = to_d(m.vertices[t[0]]);
  return (to_d(m.vertices[t[1]]) - a).cross(to_d(m.vertices[t[2]]) - a);
}

Status validate(const io::TriangleMesh& mesh) {
  if (mesh.vertices.empty()) return input_error("mesh has no vertices");
  if (mesh.triangles.empty()) return input_error("mesh has no triangles");
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (!mesh.vertices[i].allFinite()) return input_error(fmt::format("mesh vertex {} is not finite", i));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (const Index v : mesh.triangles[t])
      if (v >= mesh.vertices.size())
        return input_error(fmt::format("mesh triangle {} references vertex {} of {}", t, v, mesh.vertices.size()));
  return {};
}

// ---- orientation ---------------------------------------------------------------------------------------

struct EdgeUse {
  Index lo, hi;  // vertex ids, lo < hi
  Index tri;
  bool forward;  // the triangle walks lo → hi
};

// Every (edge, triangle) incidence, sorted so that the uses of one edge are adjacent.
std::vector<EdgeUse> edge_uses(const std::vector<Tri>& tris) {
  std::vector<EdgeUse> uses;
  uses.reserve(3 * tris.size());
  for (Index t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Index a = tris[t][k], b = tris[t][(k + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), t, a < b});
    }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return std::tie(x.lo, x.hi, x.tri) < std::tie(y.lo, y.hi, y.tri);
  });
  return uses;
}

struct Adjacency {
  std::vector<std::array<Index, 3>> neighbor;  // across each manifold edge, kInvalidIndex if none
  std::vector<std::array<bool, 3>> same;       // both triangles walk the shared edge the same way
  std::vector<EdgeUse> boundary;               // edges with one triangle
  std::size_t nonmanifold_edges = 0;
};

Adjacency adjacency_of(const std::vector<Tri>& tris) {
  const std::vector<EdgeUse> uses = edge_uses(tris);
  Adjacency adj;
  adj.neighbor.assign(tris.size(), {kInvalidIndex, kInvalidIndex, kInvalidIndex});
  adj.same.assign(tris.size(), {false, false, false});
  auto add = [&](Index t, Index u, bool same) {
    for (int k = 0; k < 3; ++k)
      if (adj.neighbor[t][k] == kInvalidIndex) {
        adj.neighbor[t][k] = u;
        adj.same[t][k] = same;
        return;
      }
  };
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    const std::size_t n = j - i;
    if (n == 1) adj.boundary.push_back(uses[i]);
    if (n > 2) ++adj.nonmanifold_edges;
    if (n == 2 && uses[i].tri != uses[i + 1].tri) {
      const bool same = uses[i].forward == uses[i + 1].forward;
      add(uses[i].tri, uses[i + 1].tri, same);
      add(uses[i + 1].tri, uses[i].tri, same);
    }
    i = j;
  }
  return adj;
}

// Patches: triangles connected through manifold edges, each made consistently oriented (the majority
// orientation wins, so a mostly-correct patch keeps its winding). Returns the patch id per triangle.
std::vector<Index> orient_patches(std::vector<Tri>& tris, const Adjacency& adj, std::size_t& flipped) {
  const std::size_t n = tris.size();
  std::vector<Index> patch(n, kInvalidIndex);
  std::vector<std::uint8_t> flip(n, 0);
  std::vector<Index> members;
  Index patches = 0;
  for (Index seed = 0; seed < n; ++seed) {
    if (patch[seed] != kInvalidIndex) continue;
    members.clear();
    members.push_back(seed);
    patch[seed] = patches;
    for (std::size_t q = 0; q < members.size(); ++q) {  // breadth-first over `members` itself
      const Index t = members[q];
      for (int k = 0; k < 3; ++k) {
        const Index u = adj.neighbor[t][k];
        if (u == kInvalidIndex || patch[u] != kInvalidIndex) continue;  // conflicts (Möbius) are left as found
        patch[u] = patches;
        flip[u] = static_cast<std::uint8_t>(flip[t] ^ static_cast<std::uint8_t>(adj.same[t][k]));
        members.push_back(u);
      }
    }
    std::size_t count = 0;
    for (const Index t : members) count += flip[t];
    const bool invert = 2 * count > members.size();
    for (const Index t : members)
      if ((flip[t] != 0) != invert) {
        std::swap(tris[t][1], tris[t][2]);
        ++flipped;
      }
    ++patches;
  }
  return patch;
}

// Vertex-connected components (union-find), numbered in order of first triangle.
std::vector<Index> components_of(const std::vector<Tri>& tris, std::size_t vertex_count, std::size_t& count) {
  std::vector<Index> parent(vertex_count);
  std::iota(parent.begin(), parent.end(), Index{0});
  auto find = [&](Index v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& t : tris) {
    const Index a = find(t[0]);
    for (int k = 1; k < 3; ++k) {
      const Index b = find(t[k]);
      if (a != b) parent[b] = a;
    }
  }
  std::vector<Index> id(vertex_count, kInvalidIndex), comp(tris.size());
  count = 0;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const Index r = find(tris[t][0]);
    if (id[r] == kInvalidIndex) id[r] = static_cast<Index>(count++);
    comp[t] = id[r];
  }
  return comp;
}

// Does the ray o + s·d (s > 0) meet any triangle? Möller–Trumbore in double, every triangle (no BVH yet).
bool ray_blocked(const io::TriangleMesh& mesh, const std::vector<Tri>& tris, const Vec3d& o, const Vec3d& d) {
  for (const Tri& t : tris) {
    const Vec3d a = to_d(mesh.vertices[t[0]]), e1 = to_d(mesh.vertices[t[1]]) - a, e2 = to_d(mesh.vertices[t[2]]) - a;
    const Vec3d q = d.cross(e2);
    const double det = e1.dot(q);
    if (std::abs(det) < 1e-300) continue;
    const Vec3d r = o - a;
    const double u = r.dot(q) / det;
    if (u < 0.0 || u > 1.0) continue;
    const Vec3d w = r.cross(e1);
    const double v = d.dot(w) / det;
    if (v < 0.0 || u + v > 1.0) continue;
    if (e2.dot(w) / det > 0.0) return true;
  }
  return false;
}

// Which side of open patch p faces out, by what can be seen from it (Takayama et al., "Simple and robust
// consistent orientation of facets", 2014, in short): rays from the centres of 8 of its triangles, over the
// hemisphere on each side, that leave the mesh without meeting a triangle. +1: the side its normals point to
// sees out more; −1: the other; 0: no clear answer (both sides or neither see out), left to the volume rule.
int visible_side(const io::TriangleMesh& mesh, const std::vector<Tri>& tris, const std::vector<Index>& patch, Index p,
                 double offset) {
  std::vector<std::size_t> members;
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (patch[t] == p && cross_d(mesh, tris[t]).squaredNorm() > 0.0) members.push_back(t);
  constexpr std::size_t kPoints = 8;  // spread over the patch: evenly spaced in its triangle order
  constexpr int kDirections = 48;
  int front = 0, back = 0;
  for (std::size_t k = 0; k < std::min(kPoints, members.size()); ++k) {
    const Tri& t = tris[members[k * members.size() / std::min(kPoints, members.size())]];
    const Vec3d n = cross_d(mesh, t).normalized();
    const Vec3d c = (to_d(mesh.vertices[t[0]]) + to_d(mesh.vertices[t[1]]) + to_d(mesh.vertices[t[2]])) / 3.0;
    for (int i = 0; i < kDirections; ++i) {  // a Fibonacci sphere: every direction once, fixed
      const double z = 1.0 - (2.0 * i + 1.0) / kDirections, r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double phi = i * std::numbers::pi * (3.0 - std::sqrt(5.0));
      const Vec3d d(r * std::cos(phi), r * std::sin(phi), z);
      const double along = d.dot(n);
      if (std::abs(along) < 0.1) continue;  // grazing the patch itself
      const Vec3d o = c + (along > 0.0 ? offset : -offset) * n;
      if (!ray_blocked(mesh, tris, o, d)) ++(along > 0.0 ? front : back);
    }
  }
  if (front > 2 * back + 2) return 1;
  if (back > 2 * front + 2) return -1;
  return 0;
}

// Flips every patch whose signed volume, taken about its component's box centre, is negative: for closed
// patches the origin does not matter; for open ones (a cap, a sphere with a hole) the centre of the component
// is the natural "inside". Except where that centre lies in a concave part of a component of several open
// patches: the inner face of a bin whose parts were welded where they touch (a loader welds coincident vertices;
// the edges where three or four faces then meet split the parts into open patches) faces the centre and was
// flipped, which filled the bottom of the bin.
// An open patch the volume rule would flip, in a component of several patches, is flipped only if what it sees
// agrees (visible_side) or says nothing. Returns Σ of the (now positive) volumes.
double orient_by_volume(const io::TriangleMesh& mesh, std::vector<Tri>& tris, const std::vector<Index>& patch,
                        const std::vector<Index>& comp, std::size_t components, std::size_t& flipped) {
  std::vector<Aabb> box(components);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (const Index v : tris[t]) box[comp[t]].extend(mesh.vertices[v]);
  const Index patches = tris.empty() ? 0 : *std::max_element(patch.begin(), patch.end()) + 1;
  std::vector<double> volume(patches, 0.0), area(patches, 0.0);
  std::vector<Vec3d> vector_area(patches, Vec3d::Zero());  // ½ Σ n·A: zero for a closed patch
  std::vector<Index> comp_of(patches, kInvalidIndex);
  std::vector<std::size_t> patches_in(components, 0);
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const Vec3d o = (0.5 * (to_d(box[comp[t]].min) + to_d(box[comp[t]].max))).eval();
    const Vec3d a = to_d(mesh.vertices[tris[t][0]]) - o, b = to_d(mesh.vertices[tris[t][1]]) - o,
                c = to_d(mesh.vertices[tris[t][2]]) - o;
    volume[patch[t]] += a.dot(b.cross(c)) / 6.0;
    const Vec3d n = cross_d(mesh, tris[t]);
    vector_area[patch[t]] += 0.5 * n, area[patch[t]] += 0.5 * n.norm();
    if (comp_of[patch[t]] == kInvalidIndex) comp_of[patch[t]] = comp[t], ++patches_in[comp[t]];
  }
  // The visibility check costs ~350 rays × every triangle per patch: done for at most ~4e8 ray-triangle tests.
  std::vector<Index> doubtful;
  std::vector<std::uint8_t> keep(patches, 0);
  for (Index p = 0; p < patches; ++p)
    if (volume[p] < 0.0 && patches_in[comp_of[p]] > 1 && vector_area[p].norm() > 1e-6 * area[p]) doubtful.push_back(p);
  if (!doubtful.empty() && double(doubtful.size()) * 350.0 * double(tris.size()) <= 4e8) {
    std::vector<int> side(doubtful.size(), 0);
    core::parallel_for(static_cast<std::int64_t>(doubtful.size()), [&](std::int64_t i) {
      const auto k = static_cast<std::size_t>(i);
      const double offset = 1e-5 * box[comp_of[doubtful[k]]].size().norm();  // off the patch, into each side
      side[k] = visible_side(mesh, tris, patch, doubtful[k], offset);
    });
    for (std::size_t k = 0; k < doubtful.size(); ++k)
      if (side[k] > 0) keep[doubtful[k]] = 1;  // it faces out as it is
  }
  // A patch is flipped when its volume is negative and it is not kept. The total is Σ of the oriented patches'
  // signed volumes about their component's centre: a kept open patch adds its (negative) share, so the welded
  // bin reads its slabs' volume, not the box's.
  double total = 0.0;
  for (Index p = 0; p < patches; ++p) {
    const bool flip = volume[p] < 0.0 && !keep[p];
    flipped += flip;
    total += flip ? -volume[p] : volume[p];
    volume[p] = flip ? -1.0 : 1.0;  // from here on: the flip mark
  }
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (volume[patch[t]] < 0.0) std::swap(tris[t][1], tris[t][2]);
  return std::max(total, 0.0);
}

// Σ over boundary loops of |½ Σ p_i × p_{i+1}|: the area of the hole each loop leaves. Boundary edges are
// chained by their direction in the (oriented) triangles; a chain that cannot close is closed by a straight
// segment.
double hole_area(const io::TriangleMesh& mesh, const std::vector<Tri>& tris, const std::vector<EdgeUse>& boundary) {
  std::vector<std::pair<Index, Index>> edges;  // (from, to) as the triangle now walks it
  edges.reserve(boundary.size());
  for (const EdgeUse& e : boundary) {
    const Tri& t = tris[e.tri];
    const bool forward =
        (t[0] == e.lo && t[1] == e.hi) || (t[1] == e.lo && t[2] == e.hi) || (t[2] == e.lo && t[0] == e.hi);
    edges.emplace_back(forward ? e.lo : e.hi, forward ? e.hi : e.lo);
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::uint8_t> used(edges.size(), 0);
  double total = 0.0;
  for (std::size_t e0 = 0; e0 < edges.size(); ++e0) {
    if (used[e0]) continue;
    used[e0] = 1;
    const Index start = edges[e0].first;
    const Vec3d p0 = to_d(mesh.vertices[start]);
    Vec3d area = Vec3d::Zero();
    Index cur = edges[e0].second;
    Vec3d prev = to_d(mesh.vertices[cur]) - p0;
    while (cur != start) {
      auto it = std::lower_bound(edges.begin(), edges.end(), std::make_pair(cur, Index{0}));
      std::size_t next = edges.size();
      for (auto i = static_cast<std::size_t>(it - edges.begin()); i < edges.size() && edges[i].first == cur; ++i)
        if (!used[i]) {
          next = i;
          break;
        }
      if (next == edges.size()) break;  // open chain: closed implicitly back to `start`
      used[next] = 1;
      cur = edges[next].second;
      const Vec3d p = to_d(mesh.vertices[cur]) - p0;
      area += prev.cross(p);
      prev = p;
    }
    total += 0.5 * area.norm();
  }
  return total;
}

// ---- closedness ----------------------------------------------------------------------------------------

// Per vertex, the first vertex at exactly its position (−0 and +0 are one position): split vertices (a UV or
// normal seam) are one point of the surface.
std::vector<Index> weld_by_position(std::span<const Vec3f> vertices) {
  struct Key {
    std::uint32_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct Hash {
    std::size_t operator()(const Key& k) const {
      return (std::size_t{k.x} * 0x9E3779B97F4A7C15ull) ^ (std::size_t{k.y} * 0xC2B2AE3D27D4EB4Full) ^ k.z;
    }
  };
  auto bits = [](float v) {
    const float w = v == 0.0f ? 0.0f : v;  // −0 → +0
    std::uint32_t b;
    std::memcpy(&b, &w, sizeof b);
    return b;
  };
  std::unordered_map<Key, Index, Hash> first;
  first.reserve(vertices.size());
  std::vector<Index> weld(vertices.size());
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const Key k{bits(vertices[v].x()), bits(vertices[v].y()), bits(vertices[v].z())};
    weld[v] = first.try_emplace(k, static_cast<Index>(v)).first->second;
  }
  return weld;
}

// Whether the triangles, their corners welded, walk every edge as often one way as the other.
bool edges_balanced(const std::vector<Tri>& tris, const std::vector<Index>& weld) {
  std::vector<Tri> welded(tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t) {
    for (int k = 0; k < 3; ++k) welded[t][k] = weld[tris[t][k]];
    const Tri& w = welded[t];
    if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0]) return false;  // no sound edge to count
  }
  const std::vector<EdgeUse> uses = edge_uses(welded);
  for (std::size_t i = 0; i < uses.size();) {
    int sum = 0;
    std::size_t j = i;
    for (; j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi; ++j) sum += uses[j].forward ? 1 : -1;
    if (sum != 0) return false;
    i = j;
  }
  return true;
}

// ---- exact per-triangle kernels ------------------------------------------------------------------------

double solid_angle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double det = a.dot(b.cross(c));
  const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
  return 2.0 * std::atan2(det, den);
}

float safe_ratio(float num, float den) { return den > 0.0f ? std::clamp(num / den, 0.0f, 1.0f) : 0.0f; }

Vec3f closest_on_segment(const Vec3f& p, const Vec3f& a, const Vec3f& b) {
  const Vec3f ab = b - a;
  return a + safe_ratio((p - a).dot(ab), ab.squaredNorm()) * ab;
}

}  // namespace

// Closest point of a triangle by its Voronoi regions (vertex, edge, face), tested in that order so that the
// divisions only happen where their denominators are known to be positive; a face-region denominator lost
// to rounding (a needle triangle) falls back to the nearest edge.
Vec3f closest_point_on_triangle(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const Vec3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const Vec3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + safe_ratio(d1, d1 - d3) * ab;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + safe_ratio(d2, d2 - d6) * ac;
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && d4 >= d3 && d5 >= d6) return b + safe_ratio(d4 - d3, (d4 - d3) + (d5 - d6)) * (c - b);
  const float sum = va + vb + vc;
  if (sum > 0.0f && std::isfinite(sum)) return a + (vb / sum) * ab + (vc / sum) * ac;
  const Vec3f e[3] = {closest_on_segment(p, a, b), closest_on_segment(p, b, c), closest_on_segment(p, c, a)};
  int best = 0;
  for (int k = 1; k < 3; ++k)
    if ((e[k] - p).squaredNorm() < (e[best] - p).squaredNorm()) best = k;
  return e[best];
}

namespace {

// Squared distance from p to the box [lo, hi] (0 inside). Scalar on purpose: it is the innermost operation of
// every closest-point query, and the Eigen expression was not inlined.
inline float box_distance2(const Vec3f& p, const Vec3f& lo, const Vec3f& hi) {
  float s = 0.0f;
  for (int a = 0; a < 3; ++a) {
    const float d = std::max(std::max(lo[a] - p[a], p[a] - hi[a]), 0.0f);
    s += d * d;
  }
  return s;
}

// ---- ray parity ----------------------------------------------------------------------------------------

constexpr int kRayDirections = 16;

// Directions on a Fibonacci spiral, offset so that none is axis-aligned or in a coordinate plane (procedural
// and CAD meshes are full of axis-aligned edges a ray could graze).
Vec3d ray_direction(int k) {
  const double z = 1.0 - 2.0 * (k + 0.37) / kRayDirections;
  const double phi = 2.399963229728653 * k + 0.61;
  const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Vec3d(s * std::cos(phi), s * std::sin(phi), z).normalized();
}

}  // namespace

// ---- build ---------------------------------------------------------------------------------------------

Result<MeshField> MeshField::build(const io::TriangleMesh& mesh) {
  FF_CHECK(validate(mesh));
  MeshField f;
  std::vector<Tri> tris;
  std::vector<Index> source;
  tris.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (cross_d(mesh, mesh.triangles[t]).squaredNorm() == 0.0) {
      ++f.stats_.dropped_degenerate;
      continue;
    }
    tris.push_back(mesh.triangles[t]);
    source.push_back(static_cast<Index>(t));
  }
  if (tris.empty()) return input_error("mesh has zero area (every triangle is degenerate)");

  const Adjacency adj = adjacency_of(tris);
  f.stats_.boundary_edges = adj.boundary.size();
  f.stats_.nonmanifold_edges = adj.nonmanifold_edges;
  const std::vector<Index> patch = orient_patches(tris, adj, f.stats_.reoriented_triangles);
  const std::vector<Index> comp = components_of(tris, mesh.vertices.size(), f.stats_.components);
  f.stats_.patches = *std::max_element(patch.begin(), patch.end()) + std::size_t{1};
  f.volume_ = orient_by_volume(mesh, tris, patch, comp, f.stats_.components, f.stats_.flipped_patches);
  f.stats_.hole_area = hole_area(mesh, tris, adj.boundary);
  f.stats_.triangles = tris.size();

  std::vector<Triangle> geometry(tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t) {
    geometry[t] = {mesh.vertices[tris[t][0]], mesh.vertices[tris[t][1]], mesh.vertices[tris[t][2]]};
    f.area_ += 0.5 * cross_d(mesh, tris[t]).norm();
    for (const Index v : tris[t]) f.bounds_.extend(mesh.vertices[v]);
  }
  f.encloses_volume_ = f.stats_.hole_area <= kMaxHoleFraction * f.area_ && f.volume_ > 1e-6 * std::pow(f.area_, 1.5);
  f.vertex_count_ = mesh.vertices.size();
  {  // edges are matched across seams split by index (by position)
    std::vector<Index> weld = weld_by_position(mesh.vertices);
    if (edges_balanced(tris, weld))
      f.closed_ = true, f.weld_ = std::make_shared<const std::vector<Index>>(std::move(weld));
  }
  f.build_bvh(std::move(geometry), std::move(source), std::move(tris));
  return f;
}

Result<MeshField> MeshField::moved(std::span<const Vec3f> vertices, bool far_field) const {
  if (vertices.size() != vertex_count_)
    return input_error(fmt::format("moved mesh has {} vertices, its field was built with {}", vertices.size(), vertex_count_));
  for (std::size_t v = 0; v < vertices.size(); ++v)
    if (!vertices[v].allFinite()) return input_error(fmt::format("moved mesh: vertex {} is not finite", v));
  MeshField f;
  f.volume_ = volume_, f.encloses_volume_ = encloses_volume_, f.stats_ = stats_;
  f.source_ = source_, f.bvh_index_ = bvh_index_, f.corners_ = corners_, f.vertex_count_ = vertex_count_;
  f.nodes_ = nodes_;
  // Closed only while every welded vertex still sits exactly on its first: a seam the move opens is a crack a
  // ray could pass through.
  f.closed_ = closed_;
  for (std::size_t v = 0; f.closed_ && v < weld_->size(); ++v)
    f.closed_ = (*weld_)[v] == v || vertices[v] == vertices[(*weld_)[v]];
  if (f.closed_) f.weld_ = weld_;
  f.tris_.resize(tris_.size());
  f.normal_.resize(tris_.size());
  for (std::size_t k = 0; k < tris_.size(); ++k) {
    const auto& c = corners_[k];
    Triangle& t = f.tris_[k];
    t = {vertices[c[0]], vertices[c[1]], vertices[c[2]]};
    f.normal_[k] = (t.b - t.a).cross(t.c - t.a).normalized();  // Eigen: a zero vector stays zero
    f.area_ += 0.5 * (to_d(t.b) - to_d(t.a)).cross(to_d(t.c) - to_d(t.a)).norm();
    f.bounds_.extend(t.a), f.bounds_.extend(t.b), f.bounds_.extend(t.c);
  }
  // Refit: children follow their parent in nodes_ (build_node allocates a pair after its parent), so a reverse
  // sweep meets every child before its parent. range: each node's triangles, for the expansions.
  std::vector<std::array<Index, 2>> range(nodes_.size());
  for (std::size_t k = nodes_.size(); k-- > 0;) {
    Node& n = f.nodes_[k];
    Aabb box;
    if (n.count > 0) {
      for (Index t = n.first; t < n.first + n.count; ++t) box.extend(f.tris_[t].a), box.extend(f.tris_[t].b), box.extend(f.tris_[t].c);
      range[k] = {n.first, n.first + n.count};
    } else {
      const Node &l = f.nodes_[n.first], &r = f.nodes_[n.first + 1];
      box.extend(l.lo), box.extend(l.hi), box.extend(r.lo), box.extend(r.hi);
      range[k] = {range[n.first][0], range[n.first + 1][1]};
    }
    n.lo = box.min, n.hi = box.max;
  }
  if (far_field || !f.closed_) f.build_expansions(range);
  return f;
}

void MeshField::build_bvh(std::vector<Triangle> tris, std::vector<Index> source, std::vector<std::array<Index, 3>> corners) {
  std::vector<Index> order(tris.size());
  std::iota(order.begin(), order.end(), Index{0});
  std::vector<std::array<Index, 2>> range;
  nodes_.clear();
  nodes_.reserve(2 * tris.size() / kLeafSize + 2);
  nodes_.push_back({});
  range.push_back({});
  build_node(0, order, 0, static_cast<Index>(tris.size()), tris, range, 0);
  tris_.resize(tris.size());
  source_.resize(tris.size());
  normal_.resize(tris.size());
  corners_.resize(tris.size());
  bvh_index_.assign(source.empty() ? 0 : std::size_t{source.back()} + 1, kInvalidIndex);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Triangle& t = tris[order[k]];
    tris_[k] = t;
    source_[k] = source[order[k]];
    corners_[k] = corners[order[k]];
    bvh_index_[source_[k]] = static_cast<Index>(k);
    normal_[k] = (t.b - t.a).cross(t.c - t.a).normalized();
  }
  build_expansions(range);
}

// Where to split a node: the binned surface-area heuristic (SAH) over all three axes, which keeps boxes tight
// and so prunes closest-point queries far better than a median split. Returns the axis and the bin boundary,
// or axis = -1 when every centroid falls into one bin.
struct Split {
  int axis = -1;
  int bin = 0;  // triangles in bins [0, bin] go left
};

float half_area(const Aabb& b) {
  const Vec3f e = b.size();
  return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
}

template <class BinOf>
Split sah_split(const std::vector<Index>& order, Index begin, Index end, const Aabb& centroids, BinOf&& bin_of) {
  Split best;
  float best_cost = std::numeric_limits<float>::max();
  for (int axis = 0; axis < 3; ++axis) {
    if (!(centroids.size()[axis] > 0.0f)) continue;
    std::array<Aabb, kSahBins> box{};
    std::array<Index, kSahBins> count{};
    for (Index k = begin; k < end; ++k) {
      const auto [b, bounds] = bin_of(order[k], axis);
      box[static_cast<std::size_t>(b)].extend(bounds.min), box[static_cast<std::size_t>(b)].extend(bounds.max);
      ++count[static_cast<std::size_t>(b)];
    }
    std::array<float, kSahBins> right_cost{};
    Aabb acc;
    Index n = 0;
    for (int b = kSahBins - 1; b > 0; --b) {  // right_cost[b]: bins [b, K) on the right
      const auto u = static_cast<std::size_t>(b);
      if (count[u]) acc.extend(box[u].min), acc.extend(box[u].max);
      n += count[u];
      right_cost[u] = n ? half_area(acc) * float(n) : 0.0f;
    }
    acc = Aabb{};
    n = 0;
    for (int b = 0; b + 1 < kSahBins; ++b) {
      const auto u = static_cast<std::size_t>(b);
      if (count[u]) acc.extend(box[u].min), acc.extend(box[u].max);
      n += count[u];
      if (n == 0 || n == end - begin) continue;
      const float cost = half_area(acc) * float(n) + right_cost[u + 1];
      if (cost < best_cost) best_cost = cost, best = {axis, b};
    }
  }
  return best;
}

// Fills node `self` with the triangles order[begin, end): a leaf, or two children allocated as a pair (so an
// inner node stores one index), split by SAH; below depth kSahDepth by the median, which bounds the depth (and
// so the traversal stacks) whatever the geometry. Nodes are addressed by index: nodes_ grows in the recursion.
void MeshField::build_node(Index self, std::vector<Index>& order, Index begin, Index end,
                           const std::vector<Triangle>& all, std::vector<std::array<Index, 2>>& range, int depth) {
  Aabb box, centroids;
  for (Index k = begin; k < end; ++k) {
    const Triangle& t = all[order[k]];
    box.extend(t.a), box.extend(t.b), box.extend(t.c);
    centroids.extend((t.a + t.b + t.c) / 3.0f);
  }
  nodes_[self] = {box.min, begin, box.max, end - begin};
  range[self] = {begin, end};
  const Vec3f extent = centroids.size();
  int axis = 0;
  extent.maxCoeff(&axis);
  if (end - begin <= kLeafSize || extent[axis] <= 0.0f) return;  // identical centroids cannot be split
  auto centroid = [&](Index i, int a) { return (all[i].a[a] + all[i].b[a] + all[i].c[a]) / 3.0f; };
  auto bin_of = [&](Index i, int a) {
    const float f = (centroid(i, a) - centroids.min[a]) / extent[a];
    const int b = std::clamp(static_cast<int>(f * float(kSahBins)), 0, kSahBins - 1);
    Aabb t;
    t.extend(all[i].a), t.extend(all[i].b), t.extend(all[i].c);
    return std::make_pair(b, t);
  };
  Index mid = begin + (end - begin) / 2;
  const Split split = depth < kSahDepth ? sah_split(order, begin, end, centroids, bin_of) : Split{};
  if (split.axis >= 0) {
    const auto it = std::stable_partition(order.begin() + begin, order.begin() + end,
                                          [&](Index i) { return bin_of(i, split.axis).first <= split.bin; });
    mid = static_cast<Index>(it - order.begin());
  } else {
    auto key = [&](Index i) { return std::make_pair(centroid(i, axis), i); };  // index breaks ties: one answer
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                     [&](Index x, Index y) { return key(x) < key(y); });
  }
  const auto first = static_cast<Index>(nodes_.size());
  nodes_[self].first = first;
  nodes_[self].count = 0;
  nodes_.resize(first + 2);
  range.resize(first + 2);
  build_node(first, order, begin, mid, all, range, depth + 1);
  build_node(first + 1, order, mid, end, all, range, depth + 1);
}

// Moments of each node, straight from its triangles (O(n log n) in all), in double, then stored in float
// relative to the node's own centre (see the file comment for the formulas).
void MeshField::build_expansions(const std::vector<std::array<Index, 2>>& range) {
  expansion_.resize(nodes_.size());
  core::parallel_for(static_cast<std::int64_t>(nodes_.size()), [&](std::int64_t k) {
    const auto [begin, end] = range[static_cast<std::size_t>(k)];
    double area = 0.0;
    Vec3d centre = Vec3d::Zero(), n = Vec3d::Zero();
    for (Index t = begin; t < end; ++t) {
      const Vec3d a = to_d(tris_[t].a), b = to_d(tris_[t].b), c = to_d(tris_[t].c);
      const Vec3d an = 0.5 * (b - a).cross(c - a);  // a_t n_t
      area += an.norm();
      centre += an.norm() * (a + b + c) / 3.0;
      n += an;
    }
    // A node whose triangles a move (moved()) collapsed has no area: its vertices' mean stands in for the centre.
    if (area > 0.0) {
      centre /= area;
    } else {
      for (Index t = begin; t < end; ++t) centre += (to_d(tris_[t].a) + to_d(tris_[t].b) + to_d(tris_[t].c)) / 3.0;
      centre /= double(end - begin);
    }
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d t3[3] = {Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero()};
    double r2 = 0.0;
    for (Index t = begin; t < end; ++t) {
      const Vec3d d[3] = {to_d(tris_[t].a) - centre, to_d(tris_[t].b) - centre, to_d(tris_[t].c) - centre};
      const Vec3d an = 0.5 * (d[1] - d[0]).cross(d[2] - d[0]);
      const Vec3d s = d[0] + d[1] + d[2];
      m += an * (s / 3.0).transpose();
      const Eigen::Matrix3d second =
          (d[0] * d[0].transpose() + d[1] * d[1].transpose() + d[2] * d[2].transpose() + s * s.transpose()) / 12.0;
      for (int i = 0; i < 3; ++i) t3[i] += an[i] * second;
      for (const auto& v : d) r2 = std::max(r2, v.squaredNorm());
    }
    Expansion& e = expansion_[static_cast<std::size_t>(k)];
    e.center = centre.cast<float>();
    e.radius2 = static_cast<float>(double(kBeta) * double(kBeta) * r2);
    e.n = n.cast<float>();
    e.trace_m = static_cast<float>(m.trace());
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) e.m[static_cast<std::size_t>(3 * i + j)] = static_cast<float>(m(i, j));
    Vec3d v = Vec3d::Zero();
    for (int i = 0; i < 3; ++i) {
      const Eigen::Matrix3d& ti = t3[i];
      v[i] += ti.trace();                                       // τ_i = Σ_j T_ijj
      for (int kk = 0; kk < 3; ++kk) v[kk] += 2.0 * ti(i, kk);  // 2 u_k = 2 Σ_i T_iik
      const double sym[6] = {ti(0, 0), ti(0, 1), ti(0, 2), ti(1, 1), ti(1, 2), ti(2, 2)};
      for (int s = 0; s < 6; ++s) e.t[static_cast<std::size_t>(6 * i + s)] = static_cast<float>(sym[s]);
    }
    e.v = v.cast<float>();
  });
}

// ---- queries -------------------------------------------------------------------------------------------

// Ω of a node seen from q by its expansion; r = p̃ − q, l2 = |r|² > 0 (see the file comment).
float MeshField::far_solid_angle(const Expansion& e, const Vec3f& r, float l2) {
  const float inv_l = 1.0f / std::sqrt(l2);
  const Vec3f h = r * inv_l;  // r̂
  const float inv_l2 = inv_l * inv_l;
  const float hmh = h.x() * (e.m[0] * h.x() + e.m[1] * h.y() + e.m[2] * h.z()) +
                    h.y() * (e.m[3] * h.x() + e.m[4] * h.y() + e.m[5] * h.z()) +
                    h.z() * (e.m[6] * h.x() + e.m[7] * h.y() + e.m[8] * h.z());
  float cubic = 0.0f;  // Σ_i r̂_i r̂ᵀ T_i r̂
  for (int i = 0; i < 3; ++i) {
    const float* t = e.t.data() + 6 * i;
    const float q = t[0] * h.x() * h.x() + t[3] * h.y() * h.y() + t[5] * h.z() * h.z() +
                    2.0f * (t[1] * h.x() * h.y() + t[2] * h.x() * h.z() + t[4] * h.y() * h.z());
    cubic += h[i] * q;
  }
  const float order0 = e.n.dot(h);
  const float order1 = (e.trace_m - 3.0f * hmh) * inv_l;
  const float order2 = 0.5f * (15.0f * cubic - 3.0f * e.v.dot(h)) * inv_l2;
  return (order0 + order1 + order2) * inv_l2;
}

float MeshField::winding_number(const Vec3f& p) const {
  if (expansion_.empty()) return static_cast<float>(winding_number_exact(p));  // moved() without the far field
  const Vec3d q = to_d(p);
  double omega = 0.0;
  Index stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Index k = stack[--top];
    const Expansion& e = expansion_[k];
    const Vec3f r = e.center - p;
    const float l2 = r.squaredNorm();
    if (l2 > e.radius2) {
      omega += far_solid_angle(e, r, l2);
      continue;
    }
    const Node& node = nodes_[k];
    if (node.count > 0) {
      for (Index t = node.first; t < node.first + node.count; ++t)
        omega += solid_angle(to_d(tris_[t].a) - q, to_d(tris_[t].b) - q, to_d(tris_[t].c) - q);
      continue;
    }
    stack[top++] = node.first;
    stack[top++] = node.first + 1;
  }
  return static_cast<float>(omega / kFourPi);
}

bool MeshField::inside(const Vec3f& p) const {
  if (closed_)
    if (const std::optional<int> w = ray_winding(p)) return *w > 0;
  return winding_number(p) > 0.5f;
}

std::optional<int> MeshField::ray_winding(const Vec3f& p) const {
  if (!closed_ || !p.allFinite()) return std::nullopt;
  // The six axis directions, the one that leaves the bounds soonest first: it meets the fewest nodes.
  std::array<std::pair<float, int>, 6> order;
  for (int a = 0; a < 3; ++a) {
    order[2 * a] = {bounds_.max[a] - p[a], 2 * a};          // +axis
    order[2 * a + 1] = {p[a] - bounds_.min[a], 2 * a + 1};  // −axis
  }
  std::sort(order.begin(), order.end());
  Index stack[kStackSize];
  for (const auto& [unused, dir] : order) {
    const int a = dir / 2, u = (a + 1) % 3, v = (a + 2) % 3;  // (a, u, v) cyclic: the projection keeps handedness
    const bool forward = dir % 2 == 0;
    int winding = 0;
    bool grazed = false;
    int top = 0;
    stack[top++] = 0;
    while (top > 0 && !grazed) {
      const Node& node = nodes_[stack[--top]];
      // The ray is the half-line {p + s·e_a}: a box it meets holds p's other two coordinates.
      if (p[u] < node.lo[u] || p[u] > node.hi[u] || p[v] < node.lo[v] || p[v] > node.hi[v]) continue;
      if (forward ? node.hi[a] < p[a] : node.lo[a] > p[a]) continue;
      if (node.count == 0) {
        stack[top++] = node.first;
        stack[top++] = node.first + 1;
        continue;
      }
      for (Index t = node.first; t < node.first + node.count; ++t) {
        const Triangle& tr = tris_[t];
        const Vec3f A = tr.a - p, B = tr.b - p, C = tr.c - p;
        // Edge functions of the projected triangle about the ray (the origin): each is the 2D cross product of
        // its edge's two corners, products of floats exact in double and one rounding, so it is antisymmetric
        // in the corners whatever the compiler contracts.
        auto edge = [&](const Vec3f& x, const Vec3f& y) {
          return double(x[u]) * double(y[v]) - double(x[v]) * double(y[u]);
        };
        const double e0 = edge(B, C), e1 = edge(C, A), e2 = edge(A, B);
        const bool pos = e0 > 0 || e1 > 0 || e2 > 0, neg = e0 < 0 || e1 < 0 || e2 < 0;
        if (pos && neg) continue;  // the ray's line passes beside the triangle
        const double det = e0 + e1 + e2;  // = the triangle's normal · e_a, twice its area (signed)
        if (det == 0.0) {  // every edge function zero: the projection is a segment or point through the ray's line
          const float lo = std::min({A[a], B[a], C[a]}), hi = std::max({A[a], B[a], C[a]});
          if (forward ? hi < 0.0f : lo > 0.0f) continue;  // wholly behind p: the ray cannot meet it
          grazed = true;
          break;
        }
        // The hit's offset from p along e_a: the barycentric mean of the corners' a-coordinates.
        const double along = (e0 * A[a] + e1 * B[a] + e2 * C[a]) / det;
        if (along == 0.0) {  // p on the triangle
          grazed = true;
          break;
        }
        if (forward ? along < 0.0 : along > 0.0) continue;  // behind p
        if (e0 == 0 || e1 == 0 || e2 == 0) {  // through an edge or a corner
          grazed = true;
          break;
        }
        // The surface leaves towards the ray (its normal along the ray) where p is inside: +1.
        winding += (det > 0.0) == forward ? 1 : -1;
      }
    }
    if (!grazed) return winding;
  }
  return std::nullopt;
}

double MeshField::winding_number_exact(const Vec3f& p) const {
  const Vec3d q = to_d(p);
  double omega = 0.0;
  for (const Triangle& t : tris_) omega += solid_angle(to_d(t.a) - q, to_d(t.b) - q, to_d(t.c) - q);
  return omega / kFourPi;
}

// Nearest-first descent; `best2` starts at the caller's bound (squared), so only strictly closer surface
// points are reported when the bound is finite.
MeshField::Closest MeshField::closest_bounded(const Vec3f& p, float best2, Index hint) const {
  Closest out{p, Vec3f::Zero(), std::numeric_limits<float>::infinity(), kInvalidIndex};
  Index best = kInvalidIndex;
  if (hint != kInvalidIndex) {  // a neighbour's answer is usually (nearly) ours: a tight bound from the start
    const Vec3f c = closest_point_on_triangle(p, tris_[hint].a, tris_[hint].b, tris_[hint].c);
    if (const float d2 = (c - p).squaredNorm(); d2 <= best2) best2 = d2, best = hint, out.point = c;
  }
  // The stack keeps each node's box distance, so a pop re-checks it against the improved bound for free.
  struct Entry {
    Index node;
    float d2;
  };
  Entry stack[kStackSize];
  int top = 0;
  if (const float d2 = box_distance2(p, nodes_[0].lo, nodes_[0].hi); d2 <= best2) stack[top++] = {0, d2};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.d2 > best2) continue;  // best improved since it was pushed
    const Node& node = nodes_[e.node];
    if (node.count > 0) {
      for (Index t = node.first; t < node.first + node.count; ++t) {
        const Triangle& tr = tris_[t];
        // The triangle's own box is a cheap lower bound that skips most of the exact tests.
        if (box_distance2(p, tr.a.cwiseMin(tr.b).cwiseMin(tr.c), tr.a.cwiseMax(tr.b).cwiseMax(tr.c)) > best2) continue;
        const Vec3f c = closest_point_on_triangle(p, tr.a, tr.b, tr.c);
        const float d2 = (c - p).squaredNorm();
        if (d2 < best2 || (best == kInvalidIndex && d2 <= best2)) {
          best2 = d2;
          best = t;
          out.point = c;
        }
      }
      continue;
    }
    const Node& l = nodes_[node.first];
    const Node& r = nodes_[node.first + 1];
    const float dl = box_distance2(p, l.lo, l.hi), dr = box_distance2(p, r.lo, r.hi);
    const Entry near = dl <= dr ? Entry{node.first, dl} : Entry{node.first + 1, dr};
    const Entry far = dl <= dr ? Entry{node.first + 1, dr} : Entry{node.first, dl};
    if (far.d2 <= best2) stack[top++] = far;  // nearest on top: it is searched first
    if (near.d2 <= best2) stack[top++] = near;
  }
  if (best != kInvalidIndex) {
    out.normal = normal_[best];
    out.distance = std::sqrt(best2);
    out.triangle = source_[best];
  }
  return out;
}

MeshField::Closest MeshField::closest(const Vec3f& p) const {
  return closest_bounded(p, std::numeric_limits<float>::infinity(), kInvalidIndex);
}

MeshField::Closest MeshField::closest_near(const Vec3f& p, Index hint) const {
  const Index h = hint < bvh_index_.size() ? bvh_index_[hint] : kInvalidIndex;
  return closest_bounded(p, std::numeric_limits<float>::infinity(), h);
}

MeshField::Closest MeshField::closest(const Vec3f& p, float max_distance) const {
  if (!(max_distance >= 0.0f)) return closest_bounded(p, -1.0f, kInvalidIndex);  // NaN or < 0: nothing is
  return closest_bounded(p, max_distance * max_distance, kInvalidIndex);
}

float MeshField::signed_distance(const Vec3f& p) const {
  const float d = closest(p).distance;
  return inside(p) ? -d : d;
}

void MeshField::inside(std::span<const Vec3f> p, std::span<std::uint8_t> out) const {
  assert(p.size() == out.size());
  core::parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t i) {
    const auto k = static_cast<std::size_t>(i);
    out[k] = inside(p[k]) ? 1 : 0;
  });
}

void MeshField::winding_number(std::span<const Vec3f> p, std::span<float> out) const {
  assert(p.size() == out.size());
  core::parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t i) {
    const auto k = static_cast<std::size_t>(i);
    out[k] = winding_number(p[k]);
  });
}

void MeshField::signed_distance(std::span<const Vec3f> p, std::span<float> out) const {
  assert(p.size() == out.size());
  core::parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t i) {
    const auto k = static_cast<std::size_t>(i);
    out[k] = signed_distance(p[k]);
  });
}

std::size_t MeshField::bytes() const {
  return sizeof(*this) + nodes_.capacity() * sizeof(Node) + expansion_.capacity() * sizeof(Expansion) +
         tris_.capacity() * sizeof(Triangle) + normal_.capacity() * sizeof(Vec3f) + source_.capacity() * sizeof(Index) +
         bvh_index_.capacity() * sizeof(Index) + corners_.capacity() * sizeof(corners_[0]) +
         (weld_ ? weld_->capacity() * sizeof(Index) : 0);
}

// ---- ray parity ----------------------------------------------------------------------------------------

int ray_parity(const io::TriangleMesh& mesh, const Vec3f& p, int k) {
  constexpr double kEps = 1e-9;  // relative: far above double rounding, far below any real gap
  const Vec3d o = to_d(p), d = ray_direction(k);
  int crossings = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3d a = to_d(mesh.vertices[t[0]]) - o, b = to_d(mesh.vertices[t[1]]) - o, c = to_d(mesh.vertices[t[2]]) - o;
    // Which side of each edge the ray's line passes (signed volumes): all equal = through the interior.
    const double s[3] = {d.dot(a.cross(b)), d.dot(b.cross(c)), d.dot(c.cross(a))};
    const double tol[3] = {kEps * a.norm() * b.norm(), kEps * b.norm() * c.norm(), kEps * c.norm() * a.norm()};
    bool pos = false, neg = false, graze = false;
    for (int e = 0; e < 3; ++e) {
      if (s[e] > tol[e])
        pos = true;
      else if (s[e] < -tol[e])
        neg = true;
      else
        graze = true;
    }
    if (pos && neg) continue;  // the line misses the triangle
    const Vec3d n = (b - a).cross(c - a);
    const double along = n.dot(a), across = n.dot(d);  // the hit is at t = along / across
    // The line crosses the triangle (or its edge) and p is in its plane: p is on the surface.
    if (std::abs(along) <= kEps * n.norm() * std::max({a.norm(), b.norm(), c.norm()})) return -1;
    if (along / across <= 0.0) continue;  // behind the origin
    if (graze) return -1;                 // through an edge or a vertex: the count is ambiguous
    ++crossings;
  }
  return crossings & 1;
}

bool inside_by_ray_parity(const io::TriangleMesh& mesh, const Vec3f& p) {
  for (int k = 0; k < kRayDirections; ++k)
    if (const int parity = ray_parity(mesh, p, k); parity >= 0) return parity == 1;
  return false;
}

}  // namespace ff::sampling
