#pragma once
// The bookkeeping marching cubes (3 owned edges per node) and marching tetrahedra (7) share: which owned grid edges
// of each kept block φ crosses, one bit per edge, and the welded vertex of each. A vertex's index is its block's
// offset plus the crossed edges before it in the block's bit order, so every cell that uses an edge finds the same
// vertex without a hash map, and the order (hence the mesh) does not depend on the thread count.
#include "surface/block_loop.h"
#include "surface/sparse_field.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

namespace ff::surface {

template <int kEdgesPerNode>
struct CrossedEdges {
  static constexpr int kB = SparseField::kBlockCells;
  static constexpr int kWords = kB * kB * kB * kEdgesPerNode / 64;
  static_assert(kB * kB * kB * kEdgesPerNode % 64 == 0);
  static_assert(kB * kB * kB * kEdgesPerNode < 65536);  // prefix counts fit the uint16 ranks

  std::vector<std::uint64_t> bits;    // per block: kWords words of crossed-edge bits
  std::vector<std::uint16_t> rank;    // per block and word: crossed edges before the word
  std::vector<std::uint64_t> offset;  // per block: index of its first vertex; offset.back() = vertex count

  explicit CrossedEdges(std::size_t blocks) : bits(blocks * kWords, 0), rank(blocks * kWords, 0), offset(blocks + 1, 0) {}

  std::uint64_t* block_bits(std::int64_t b) { return &bits[std::size_t(b) * kWords]; }
  static void mark(std::uint64_t* w, int e) { w[e / 64] |= std::uint64_t(1) << (e % 64); }

  /// Once every block's bits are set: the ranks and offsets. Returns the number of vertices.
  std::uint64_t index() {
    const auto nb = std::int64_t(offset.size() - 1);
    std::vector<std::uint32_t> count(offset.size() - 1, 0);
    for_each_block(nb, [&](std::int64_t b) {
      std::uint32_t total = 0;
      for (int q = 0; q < kWords; ++q) {
        rank[std::size_t(b) * kWords + std::size_t(q)] = std::uint16_t(total);
        total += std::uint32_t(std::popcount(bits[std::size_t(b) * kWords + std::size_t(q)]));
      }
      count[std::size_t(b)] = total;
    });
    for (std::size_t b = 0; b + 1 < offset.size(); ++b) offset[b + 1] = offset[b] + count[b];
    return offset.back();
  }

  /// Calls f(e, id) for every crossed edge e of block b, in bit order, with its vertex index.
  template <class F>
  void for_each_crossed(std::int64_t b, F&& f) const {
    const std::uint64_t* w = &bits[std::size_t(b) * kWords];
    std::uint64_t id = offset[std::size_t(b)];
    for (int q = 0; q < kWords; ++q)
      for (std::uint64_t word = w[q]; word; word &= word - 1) f(q * 64 + std::countr_zero(word), id++);
  }

  /// The vertex on edge e of block `owner`, or −1 when that edge is not crossed.
  std::int64_t vertex(std::int64_t owner, int e) const {
    const std::uint64_t word = bits[std::size_t(owner) * kWords + std::size_t(e / 64)];
    if (!((word >> (e % 64)) & 1)) return -1;
    const std::uint64_t below = word & ((std::uint64_t(1) << (e % 64)) - 1);
    return std::int64_t(offset[std::size_t(owner)] + rank[std::size_t(owner) * kWords + std::size_t(e / 64)] +
                        std::uint64_t(std::popcount(below)));
  }
};

/// The block that owns node n of block b's cells (a coordinate may be kB: the node is then the first of the next
/// block): n is wrapped into that block, whose index is returned (−1 when it was not kept).
inline std::int64_t owner_block(const std::array<std::int64_t, 8>& up, int n[3]) {
  int s = 0;
  for (int a = 0; a < 3; ++a)
    if (n[a] == SparseField::kBlockCells) {
      s |= 1 << a;
      n[a] = 0;
    }
  return up[s];
}

/// The vertex on the grid edge that leaves corner `corner` (bits x, y, z) of cell (i, j, k) of a block whose upper
/// neighbours are `up`; `edge_of(n)` numbers the edge at node n of its owner block. −1 when the owner was not kept
/// or the edge is not crossed.
template <class Edges, class EdgeOf>
std::int64_t cell_edge_vertex(const Edges& edges, const std::array<std::int64_t, 8>& up, int i, int j, int k,
                              int corner, EdgeOf&& edge_of) {
  int n[3] = {i + (corner & 1), j + ((corner >> 1) & 1), k + ((corner >> 2) & 1)};
  const std::int64_t owner = owner_block(up, n);
  return owner < 0 ? -1 : edges.vertex(owner, edge_of(n));
}

/// Where φ crosses iso on the grid edge from local node l of the block at block coordinates c to l + step
/// (step ∈ {0, 1}³): the position, kept 1 % of the edge away from either node, and the global id of the nearer
/// node (the vertex's regularisation cell).
inline void place_edge_vertex(const SparseField& f, const std::array<std::int64_t, 3>& c, const int l[3],
                              const int step[3], float v0, float v1, Vec3f& position, std::uint64_t& cell) {
  const float t = std::clamp((f.iso - v0) / (v1 - v0), 0.01f, 0.99f);
  const auto nd = f.node_dims();
  std::int64_t g[3];
  Vec3d p;
  for (int ax = 0; ax < 3; ++ax) {
    g[ax] = c[ax] * SparseField::kBlockCells + l[ax];
    p[ax] = f.origin[ax] + f.cell * (double(g[ax]) + (step[ax] ? double(t) : 0.0));
  }
  if (t >= 0.5f)  // the nearer node owns the vertex
    for (int ax = 0; ax < 3; ++ax) g[ax] += step[ax];
  position = p.cast<float>();
  cell = std::uint64_t((g[2] * nd[1] + g[1]) * nd[0] + g[0]);
}

/// Pass 1 of both extractions: marks in `edges` the owned edges of every kept block that φ crosses, then indexes
/// them. Edge q of node (i, j, k) (edge id node · N + q) runs to the node one step further along each axis whose bit
/// is set in steps[q]. Returns the number of crossed edges (vertices).
template <std::size_t N>
std::uint64_t mark_crossed_edges(const SparseField& field, const std::array<int, N>& steps,
                                 CrossedEdges<int(N)>& edges) {
  constexpr int kB = SparseField::kBlockCells;
  const float iso = field.iso;
  for_each_block(std::int64_t(field.keys.size()), [&](std::int64_t b) {
    const float* v = field.values[std::size_t(b)].data();
    std::uint64_t* w = edges.block_bits(b);
    for (int k = 0; k < kB; ++k)
      for (int j = 0; j < kB; ++j)
        for (int i = 0; i < kB; ++i) {
          const bool in0 = v[SparseField::local(i, j, k)] > iso;
          for (int q = 0; q < int(N); ++q) {
            const int s = steps[std::size_t(q)];
            if (in0 != (v[SparseField::local(i + (s & 1), j + ((s >> 1) & 1), k + ((s >> 2) & 1))] > iso))
              CrossedEdges<int(N)>::mark(w, ((k * kB + j) * kB + i) * int(N) + q);
          }
        }
  });
  return edges.index();
}

/// Pass 1b of both: every crossed edge's vertex position and regularisation cell (the nearer node), in bit order,
/// into positions[id] and cells[id].
template <std::size_t N>
void place_crossed_vertices(const SparseField& field, const std::array<int, N>& steps,
                            const CrossedEdges<int(N)>& edges, std::vector<Vec3f>& positions,
                            std::vector<std::uint64_t>& cells) {
  constexpr int kB = SparseField::kBlockCells;
  for_each_block(std::int64_t(field.keys.size()), [&](std::int64_t b) {
    const float* v = field.values[std::size_t(b)].data();
    const auto c = field.block_coords(field.keys[std::size_t(b)]);
    edges.for_each_crossed(b, [&](int e, std::uint64_t id) {
      const int s = steps[std::size_t(e % int(N))], node = e / int(N);
      const int l[3] = {node % kB, (node / kB) % kB, node / (kB * kB)};
      const int step[3] = {s & 1, (s >> 1) & 1, (s >> 2) & 1};
      place_edge_vertex(field, c, l, step, v[SparseField::local(l[0], l[1], l[2])],
                        v[SparseField::local(l[0] + step[0], l[1] + step[1], l[2] + step[2])], positions[id], cells[id]);
    });
  });
}

}  // namespace ff::surface
