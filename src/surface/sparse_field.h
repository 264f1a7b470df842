#pragma once
// The scalar field of the particles on a sparse grid (METHOD.md §a.7 [D]):
//   φ(x) = Σ_p V_p W_poly6(x − x_p, h),   V_p = particle_volume · d³,  h = kernel_radius · d,
// ≈ 1 inside a fluid at rest and 0 away from it; the surface is φ = iso (0.5 by default).
//
// Sparse. Nodes sit on a grid of edge `cell` and are grouped in blocks of 8³ cells. A block stores its
// 9³ nodes (its own 8³ plus the first layer of its +x, +y and +z neighbours), so that marching cubes finds
// every cell corner and every edge it owns inside one block. Only blocks within reach of a particle are
// evaluated, and only blocks the iso-surface passes through (a node on each side) are kept: the memory kept
// grows with the surface, not with the fluid's volume or its bounding box. The evaluation itself visits each
// particle's neighbourhood once (cost O(N (h/cell)³)).
//
// Exactness across blocks. A node shared by two blocks (the apron) is computed by both; marching cubes
// needs the two copies to agree bit for bit, or the two blocks could see a different sign there and leave a
// crack. Both copies sum the same contributions in the same order: particles are visited in one global order
// (by home block, then by index), and each contribution is computed from the same floats (the particle's
// offset inside its home block and the node's integer offset from that block).
#include "core/error.h"
#include "core/types.h"
#include "surface/surface_params.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::surface {

struct SparseField {
  static constexpr int kBlockCells = 8;                ///< cells per block edge
  static constexpr int kBlockNodes = kBlockCells + 1;  ///< nodes per block edge (with the apron)
  static constexpr int kNodesPerBlock = kBlockNodes * kBlockNodes * kBlockNodes;

  Vec3d origin = Vec3d::Zero();              ///< position of global node (0, 0, 0), m
  double cell = 0.0;                         ///< node spacing, m
  float iso = 0.5f;                          ///< the surface is φ = iso; inside means φ > iso
  std::array<std::int64_t, 3> block_dims{};  ///< blocks per axis (the key space; most are never allocated)

  /// Kept (surface) blocks: key (see block_key) in increasing order, and their 9³ values, x fastest.
  std::vector<std::uint64_t> keys;
  std::vector<std::vector<float>> values;

  std::size_t candidate_blocks = 0;  ///< blocks evaluated (within reach of a particle)
  float max_value = 0.0f;            ///< max φ over every evaluated node

  std::uint64_t block_key(std::int64_t bx, std::int64_t by, std::int64_t bz) const {
    return std::uint64_t((bz * block_dims[1] + by) * block_dims[0] + bx);
  }
  std::array<std::int64_t, 3> block_coords(std::uint64_t key) const {
    const auto k = std::int64_t(key);
    return {k % block_dims[0], (k / block_dims[0]) % block_dims[1], k / (block_dims[0] * block_dims[1])};
  }
  /// Calls f(key, dx, dy, dz) for the blocks b + (dx, dy, dz), d ∈ {−1, 0, 1}³, that lie in the grid (b itself
  /// included), in increasing key order.
  template <class F>
  void for_each_block_around(const std::array<std::int64_t, 3>& b, F&& f) const {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const std::int64_t x = b[0] + dx, y = b[1] + dy, z = b[2] + dz;
          if (x < 0 || y < 0 || z < 0 || x >= block_dims[0] || y >= block_dims[1] || z >= block_dims[2]) continue;
          f(block_key(x, y, z), dx, dy, dz);
        }
  }
  /// Index of the kept block with this key, or −1.
  std::int64_t find(std::uint64_t key) const;
  /// Global node count per axis (for node ids).
  std::array<std::int64_t, 3> node_dims() const {
    return {block_dims[0] * kBlockCells + 1, block_dims[1] * kBlockCells + 1, block_dims[2] * kBlockCells + 1};
  }
  static constexpr int local(int i, int j, int k) { return (k * kBlockNodes + j) * kBlockNodes + i; }
  /// φ and its gradient (1/m) at `p` by trilinear interpolation of the kept nodes; false when p's cell lies in
  /// a block that was not kept (or outside the grid).
  bool sample(const Vec3f& p, float* value, Vec3f* gradient) const;
  /// Moves `p` onto φ = iso along the gradient (Newton steps of at most half a cell on the trilinear field);
  /// returns p unchanged where the field is not kept or the steps do not get closer.
  Vec3f project(const Vec3f& p) const;
  /// Bytes held by the kept blocks.
  std::size_t bytes() const;
  /// Per kept block: the kept blocks at +x, +y, +z and their combinations (index dx + 2 dy + 4 dz; entry 0 is the
  /// block itself), −1 where absent. The extractors read the nodes they share with those blocks.
  std::vector<std::array<std::int64_t, 8>> upper_neighbors() const;
};

/// φ of `particles` (m) at fluid spacing `spacing` (d, m) with the field part of `params`.
/// Preconditions (checked by reconstruct()): particles non-empty and finite, spacing > 0, params valid.
/// Errors: Param when the particles span more blocks than params.max_blocks or than a 64-bit key can index.
/// `max_memory_mib` bounds the blocks' memory (every candidate block counted as kept: the worst case), checked
/// before any block is evaluated; 0: 80 % of the machine's memory.
Result<SparseField> sparse_field(std::span<const Vec3f> particles, float spacing, const SurfaceParams& params,
                                 double max_memory_mib = 0.0);

}  // namespace ff::surface
