// The general spatial indexes (core/point_tree.h, core/point_grid.h): exact nearest-point answers against brute force.
#include "core/point_grid.h"
#include "core/point_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <span>
#include <vector>

namespace ff::core {
namespace {

double brute_nearest(const Vec3f& q, const std::vector<Vec3f>& set) {
  float best = std::numeric_limits<float>::infinity();
  for (const Vec3f& p : set) best = std::min(best, (p - q).squaredNorm());
  return std::sqrt(double(best));
}

TEST(PointTree, DuplicatesAndEmpty) {
  const PointTree empty(std::span<const Vec3f>{});
  EXPECT_TRUE(std::isinf(empty.nearest(Vec3f::Zero()).distance2));
  // 100 copies of one point (no split can separate them) plus one other point.
  std::vector<Vec3f> x(100, Vec3f(1, 2, 3));
  x.push_back(Vec3f(-1, 0, 0));
  const PointTree tree(x);
  const auto a = tree.nearest(Vec3f(1, 2, 3.5f));
  EXPECT_FLOAT_EQ(a.distance2, 0.25f);
  EXPECT_EQ(tree.nearest(Vec3f(-1, 0, 0)).distance2, 0.0f);
  EXPECT_EQ(tree.original(tree.nearest(Vec3f(-1, 0, 0)).slot), 100u);
}

// The grid answers only when it can prove the answer: every answer equals brute force, including with
// points left outside its region, and near queries are answered.
TEST(PointGrid, AnswersAreExactOrAbsent) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Vec3f> x(3000);
  for (Vec3f& p : x) p = Vec3f(u(rng), u(rng), u(rng));
  for (int k = 0; k < 200; ++k) x.push_back(Vec3f(u(rng), u(rng), u(rng)) * 20.0f);  // sparse, far
  Aabb half;  // leaves out every point with x > 0.3 and the far ones
  half.min = Vec3f::Constant(-1.0f);
  half.max = Vec3f(0.3f, 1.0f, 1.0f);
  for (const bool whole : {true, false}) {
    const PointGrid grid(x, 0.1f, whole ? Aabb{Vec3f::Constant(-20.0f), Vec3f::Constant(20.0f)} : half);
    EXPECT_EQ(grid.complete(), whole);
    int answered = 0, near = 0;
    for (int k = 0; k < 2000; ++k) {
      const bool far = k % 4 == 0;
      const Vec3f q = Vec3f(u(rng), u(rng), u(rng)) * (far ? 10.0f : 1.0f);
      const float d2 = grid.nearest2(q);
      if (!std::isnan(d2)) {
        EXPECT_EQ(std::sqrt(double(d2)), brute_nearest(q, x)) << q.transpose();
      }
      near += far ? 0 : 1;
      answered += !far && !std::isnan(d2) ? 1 : 0;
    }
    if (whole) {
      EXPECT_GT(answered, near * 95 / 100) << "queries inside the cloud are answered by the grid";
    }
  }
  EXPECT_TRUE(std::isinf(PointGrid(std::span<const Vec3f>{}, 0.1f, {}).nearest2(Vec3f::Zero())));
}

}  // namespace
}  // namespace ff::core
