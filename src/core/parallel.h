#pragma once
// Parallel helpers on OpenMP. Every loop is a gather (each index writes only its own slot), and
// every reduction is summed in a fixed chunk order, so results never depend on the thread count.
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace ff::core {

/// Loops shorter than this run on the calling thread: a parallel region costs microseconds, and far more
/// when the machine is oversubscribed (a barrier then waits for a descheduled thread's time slice).
inline constexpr std::int64_t kMinParallel = 2048;

/// Runs f(i) for i in [0, n) with a static schedule. f must write only data owned by i.
template <class F>
void parallel_for(std::int64_t n, F&& f) {
#pragma omp parallel for schedule(static) if (n >= kMinParallel)
  for (std::int64_t i = 0; i < n; ++i) f(i);
}

/// Runs f(begin, end) over [0, n) in blocks of `block`, handed out dynamically (the cluster kernels: blocks differ
/// in work, and each block writes only its own outputs, so the schedule never changes a result).
template <class F>
void parallel_blocks(std::int64_t n, std::int64_t block, F&& f) {
  const std::int64_t blocks = (n + block - 1) / block;
#pragma omp parallel for schedule(dynamic, 1) if (n * 8 >= kMinParallel)
  for (std::int64_t b = 0; b < blocks; ++b) f(b * block, std::min(n, (b + 1) * block));
}

/// Chunk size of deterministic reductions: fixed, so the summation tree is the same for any thread count.
inline constexpr std::int64_t kReduceChunk = 4096;

/// Σ f(i) for i in [0, n), accumulated in double per fixed-size chunk, chunks added in order.
template <class F>
double deterministic_sum(std::int64_t n, F&& f) {
  const std::int64_t chunks = (n + kReduceChunk - 1) / kReduceChunk;
  std::vector<double> partial(static_cast<std::size_t>(std::max<std::int64_t>(chunks, 1)), 0.0);
#pragma omp parallel for schedule(static) if (chunks > 1)
  for (std::int64_t c = 0; c < chunks; ++c) {
    double s = 0.0;
    const std::int64_t end = std::min(n, (c + 1) * kReduceChunk);
    for (std::int64_t i = c * kReduceChunk; i < end; ++i) s += static_cast<double>(f(i));
    partial[static_cast<std::size_t>(c)] = s;
  }
  double total = 0.0;
  for (double s : partial) total += s;
  return total;
}

/// max f(i) for i in [0, n): max is order-independent, so a plain per-chunk pass is deterministic.
template <class F>
double deterministic_max(std::int64_t n, double init, F&& f) {
  const std::int64_t chunks = (n + kReduceChunk - 1) / kReduceChunk;
  std::vector<double> partial(static_cast<std::size_t>(std::max<std::int64_t>(chunks, 1)), init);
#pragma omp parallel for schedule(static) if (chunks > 1)
  for (std::int64_t c = 0; c < chunks; ++c) {
    double m = init;
    const std::int64_t end = std::min(n, (c + 1) * kReduceChunk);
    for (std::int64_t i = c * kReduceChunk; i < end; ++i) m = std::max(m, static_cast<double>(f(i)));
    partial[static_cast<std::size_t>(c)] = m;
  }
  double total = init;
  for (double m : partial) total = std::max(total, m);
  return total;
}

/// Number of threads OpenMP will use for the next parallel region.
inline int thread_count() { return omp_get_max_threads(); }

}  // namespace ff::core
