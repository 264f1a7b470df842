#include "surface/marching_tetrahedra.h"

#include "surface/block_loop.h"
#include "surface/crossed_edges.h"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>

namespace ff::surface {
namespace {

constexpr int kB = SparseField::kBlockCells;
constexpr int kDirs = 7;                             // edges a node owns: s ∈ {0, 1}³ \ {0}, bit a = step along a
using Edges = CrossedEdges<kDirs>;                    // 3584 owned edges per block

// Edge s − 1 of own node (i, j, k) of a block.
constexpr int node_edge(int i, int j, int k, int s) { return ((k * kB + j) * kB + i) * kDirs + (s - 1); }
constexpr std::array<int, kDirs> kSteps = {1, 2, 3, 4, 5, 6, 7};  // edge s − 1 of a node: to the node + s

// A tetrahedron edge from cube corner `lo` to corner lo | dir (corner c sits at (c & 1, c >> 1 & 1, c >> 2 & 1)).
// In the Kuhn subdivision one end of every edge is a subset of the other, so every edge runs "upwards".
struct TetEdge {
  std::uint8_t lo = 0, dir = 0;
};

// What one tetrahedron draws for one inside mask of its 4 corners: nothing (n = 0), a triangle (n = 3), or a
// quad (n = 4, its vertices in cycle order). Wound counter-clockwise seen from outside.
struct TetCase {
  std::uint8_t n = 0;
  std::array<TetEdge, 4> e{};
};

struct TetTable {
  std::array<std::array<std::uint8_t, 4>, 6> corners{};  // cube corners of each tetrahedron
  std::array<std::array<TetCase, 16>, 6> cases{};        // by tetrahedron and mask (bit q: corner q inside)
};

Vec3d corner_pos(int c) { return Vec3d(double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)); }

TetEdge tet_edge(int a, int b) {
  const int lo = a & b, hi = a | b;  // a ⊂ b or b ⊂ a
  return {std::uint8_t(lo), std::uint8_t(hi ^ lo)};
}

// Built once, like McTable: the winding is decided here from the geometry rather than typed in. For either case the
// side of the surface each corner lies on does not depend on where along its edges the vertices sit (a vertex moves
// along its edge, never across a face), so judging the winding with the vertices at the edges' midpoints holds for
// every field.
TetTable build_table() {
  TetTable t;
  static constexpr std::array<std::array<int, 3>, 6> kOrders = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (int k = 0; k < 6; ++k) {
    const auto& o = kOrders[std::size_t(k)];
    const int c1 = 1 << o[0], c2 = c1 | (1 << o[1]);
    t.corners[std::size_t(k)] = {0, std::uint8_t(c1), std::uint8_t(c2), 7};
    for (int m = 1; m < 15; ++m) {
      int in[4] = {}, out[4] = {}, ni = 0, no = 0;
      for (int q = 0; q < 4; ++q) {
        const int c = t.corners[std::size_t(k)][std::size_t(q)];
        if ((m >> q) & 1)
          in[ni++] = c;
        else
          out[no++] = c;
      }
      TetCase tc;
      if (ni == 2) {
        // Quad through the four edges joining an inside corner to an outside one, in cycle order.
        const int a = in[0], b = in[1], c = out[0], d = out[1];
        tc.n = 4;
        tc.e = {tet_edge(a, c), tet_edge(a, d), tet_edge(b, d), tet_edge(b, c)};
      } else {
        // The lone corner (inside or outside) and the three edges from it.
        const int lone = ni == 1 ? in[0] : out[0];
        const int* rest = ni == 1 ? out : in;
        tc.n = 3;
        tc.e = {tet_edge(lone, rest[0]), tet_edge(lone, rest[1]), tet_edge(lone, rest[2]), TetEdge{}};
      }
      // -> Vec3d: an Eigen expression returned by `auto` would refer to the destroyed corner_pos() temporaries.
      auto mid = [](const TetEdge& e) -> Vec3d { return 0.5 * (corner_pos(e.lo) + corner_pos(e.lo | e.dir)); };
      Vec3d towards_outside = Vec3d::Zero();
      for (int q = 0; q < no; ++q) towards_outside += corner_pos(out[q]) / double(no);
      for (int q = 0; q < ni; ++q) towards_outside -= corner_pos(in[q]) / double(ni);
      const Vec3d normal = (mid(tc.e[1]) - mid(tc.e[0])).cross(mid(tc.e[2]) - mid(tc.e[0]));
      if (normal.dot(towards_outside) < 0.0) std::swap(tc.e[1], tc.e[tc.n - 1]);  // reverse the cycle
      t.cases[std::size_t(k)][std::size_t(m)] = tc;
    }
  }
  return t;
}

const TetTable& tet_table() {
  static const TetTable table = build_table();
  return table;
}

// Pass 2 for block b: its cells' triangles, six tetrahedra per cube, edge vertices looked up in their owning blocks
// (`pos` their positions); `broken` is set when one is missing.
void triangulate_block(const SparseField& field, const TetTable& table, std::int64_t b, const Edges& edges,
                       const std::vector<std::array<std::int64_t, 8>>& up, const std::vector<Vec3f>& pos,
                       std::vector<std::array<Index, 3>>& bt, std::atomic<bool>& broken) {
  const float iso = field.iso;
  const float* v = field.values[std::size_t(b)].data();
  auto vertex_of = [&](int i, int j, int k, const TetEdge& te) -> Index {
    const std::int64_t id = cell_edge_vertex(edges, up[std::size_t(b)], i, j, k, te.lo,
                                             [&](const int* n) { return node_edge(n[0], n[1], n[2], te.dir); });
    if (id < 0) {
      broken = true;
      return 0;
    }
    return Index(id);
  };
  for (int k = 0; k < kB; ++k)
    for (int j = 0; j < kB; ++j)
      for (int i = 0; i < kB; ++i) {
        int mask = 0;
        for (int c = 0; c < 8; ++c)
          mask |= int(v[SparseField::local(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))] > iso) << c;
        if (mask == 0 || mask == 255) continue;
        // Up to 19 edges of the cube (12 cube edges, 6 face diagonals, the main diagonal) are shared by its
        // tetrahedra: look each up once. Slot lo · 8 + dir.
        std::array<Index, 64> ref{};
        std::uint64_t have = 0;
        auto vertex = [&](const TetEdge& te) {
          const int slot = te.lo * 8 + te.dir;
          if (!((have >> slot) & 1)) {
            ref[std::size_t(slot)] = vertex_of(i, j, k, te);
            have |= std::uint64_t(1) << slot;
          }
          return ref[std::size_t(slot)];
        };
        for (int t = 0; t < 6; ++t) {
          const auto& tc4 = table.corners[std::size_t(t)];
          int m = 0;
          for (int q = 0; q < 4; ++q) m |= ((mask >> tc4[std::size_t(q)]) & 1) << q;
          const TetCase& tc = table.cases[std::size_t(t)][std::size_t(m)];
          if (tc.n == 0) continue;
          Index r[4];
          for (int q = 0; q < tc.n; ++q) r[q] = vertex(tc.e[std::size_t(q)]);
          if (broken.load(std::memory_order_relaxed)) return;
          if (tc.n == 3) {
            bt.push_back({r[0], r[1], r[2]});
          } else if ((pos[r[1]] - pos[r[3]]).squaredNorm() < (pos[r[0]] - pos[r[2]]).squaredNorm()) {
            // The quad's shorter diagonal: better shaped triangles (either is inside the tetrahedron).
            bt.push_back({r[1], r[2], r[3]});
            bt.push_back({r[1], r[3], r[0]});
          } else {
            bt.push_back({r[0], r[1], r[2]});
            bt.push_back({r[0], r[2], r[3]});
          }
        }
      }
}

}  // namespace

Result<McMesh> marching_tetrahedra(const SparseField& field) {
  const auto nb = std::int64_t(field.keys.size());
  const TetTable& table = tet_table();

  // Kept neighbours at +x, +y, +z and their combinations (index = dx + 2 dy + 4 dz), −1 when absent.
  const std::vector<std::array<std::int64_t, 8>> up = field.upper_neighbors();

  // --- pass 1: which owned edges are crossed (the 7 edges from each node [0, 8)³ of the block) ---------------------
  Edges edges(field.keys.size());
  const std::uint64_t vertices = mark_crossed_edges(field, kSteps, edges);
  if (vertices >= (std::uint64_t(1) << 31))
    return numerical_error(fmt::format("surface: {} marching-tetrahedra vertices exceed 2^31", vertices));

  McMesh out;
  out.mesh.vertices.resize(vertices);
  out.cluster.resize(vertices);

  // --- pass 1b: vertex positions and regularisation cells (Treece et al.'s nearer node), in bit order -------------
  place_crossed_vertices(field, kSteps, edges, out.mesh.vertices, out.cluster);

  // --- pass 2: triangles per block, vertices looked up in the owning block --------------------------------------
  std::vector<std::vector<std::array<Index, 3>>> tris(field.keys.size());
  std::atomic<bool> broken{false};
  for_each_block(nb, [&](std::int64_t b) {
    triangulate_block(field, table, b, edges, up, out.mesh.vertices, tris[std::size_t(b)], broken);
  });
  if (broken)
    return numerical_error("surface: marching tetrahedra found an edge missing from its block (internal error)");

  // --- concatenate in block order --------------------------------------------------------------------------------
  std::size_t total = 0;
  for (const auto& bt : tris) total += bt.size();
  out.mesh.triangles.reserve(total);
  for (auto& bt : tris) {
    out.mesh.triangles.insert(out.mesh.triangles.end(), bt.begin(), bt.end());
    std::vector<std::array<Index, 3>>().swap(bt);
  }
  return out;
}

}  // namespace ff::surface
