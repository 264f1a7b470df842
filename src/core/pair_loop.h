#pragma once
// Pair loops over neighbour lists, four neighbours at a time (core/simd.h): compact indices are decoded in batches
// of 64, wide ones read in place; the last group is padded with the particle itself and masked off.
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
  const std::size_t n = r.size();
  if (const Index* wide = r.wide()) {
    // A wide list is read in place; only its partial last group is copied and padded (copying the whole list
    // in batches cost a `rep movs` per batch, ~8 % of the control-density pass).
    const std::size_t full = n & ~std::size_t(3);
    for (std::size_t k = full; k < full + 4; ++k) batch[k - full] = k < n ? wide[k] : self;
    for (std::size_t k = 0; k < n; k += 4) f(k < full ? wide + k : batch, core::simd::first_lanes(n - k));
    return;
  }
  for (std::size_t from = 0; from < n; from += kBatch) {
    const std::size_t m = std::min(kBatch, n - from);
    r.decode(from, m, batch);
    for (std::size_t k = m; k % 4; ++k) batch[k] = self;
    for (std::size_t k = 0; k < m; k += 4) f(batch + k, core::simd::first_lanes(m - k));
  }
}

}  // namespace ff::core
