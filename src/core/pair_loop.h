#pragma once
// Pair loops over neighbour lists, four neighbours at a time (core/simd.h): indices are decoded in batches of
// 64, the last group of a batch is padded with the particle itself and masked off.
#include "core/neighbor_grid.h"
#include "core/simd.h"

#include <algorithm>

namespace ff::core {

/// Calls f(const Index* j, __m128 lanes) for each group of four neighbours of particle `self`;
/// `lanes` masks the real entries of the group (j[k] == self for the padding).
template <class F>
inline void for_neighbors4(const core::NeighborRange& r, Index self, F&& f) {
  constexpr std::size_t kBatch = 64;
  Index batch[kBatch];
  for (std::size_t from = 0; from < r.size(); from += kBatch) {
    const std::size_t m = std::min(kBatch, r.size() - from);
    r.decode(from, m, batch);
    for (std::size_t k = m; k % 4; ++k) batch[k] = self;
    for (std::size_t k = 0; k < m; k += 4) f(batch + k, core::simd::first_lanes(m - k));
  }
}

}  // namespace ff::core
