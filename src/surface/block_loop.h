#pragma once
// Parallel loop over grid blocks (or other coarse work items). core::parallel_for is tuned for cheap
// per-particle bodies (static schedule, serial below 2048 items); a block costs thousands of kernel
// evaluations and blocks near the surface cost more than empty ones, so here every item is worth a thread
// and items are handed out dynamically. Each item writes only its own outputs, so the result does not depend
// on the thread count or on which thread ran which item.
#include <cstdint>

namespace ff::surface {

template <class F>
void for_each_block(std::int64_t n, F&& f) {
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)
  for (std::int64_t i = 0; i < n; ++i) f(i);
}

}  // namespace ff::surface
