#include "core/parallel.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::core {
namespace {

TEST(Parallel, DeterministicSumIndependentOfThreadCount) {
  const std::int64_t n = 1'000'003;
  auto f = [](std::int64_t i) { return std::sin(double(i)) * 1e-3 + 1e7 * double(i % 3 == 0); };
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const double a = deterministic_sum(n, f);
  omp_set_num_threads(2);
  const double b = deterministic_sum(n, f);
  omp_set_num_threads(3);
  const double c = deterministic_sum(n, f);
  omp_set_num_threads(saved);
  EXPECT_EQ(a, b);  // bit-identical, not just close
  EXPECT_EQ(a, c);
  double serial = 0.0;
  for (std::int64_t i = 0; i < n; ++i) serial += f(i);
  EXPECT_NEAR(a, serial, 1e-6 * std::abs(serial));
}

TEST(Parallel, DeterministicMaxAndEmpty) {
  EXPECT_EQ(deterministic_sum(0, [](std::int64_t) { return 1.0; }), 0.0);
  EXPECT_EQ(deterministic_max(10000, -1.0, [](std::int64_t i) { return double((i * 7919) % 10007); }), 10006.0);
}

}  // namespace
}  // namespace ff::core
