// Kernel properties (SPlisHSPlasH KernelTests idea): every kernel integrates to 1, is non-negative,
// vanishes at the support, and its gradient is antisymmetric; Poly6's lattice sum matches METHOD.md §c.1.
#include "core/kernels.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::core {
namespace {

template <class K>
double integrate(const K& k, float h, int n) {
  // Midpoint rule on an n³ grid over [−h, h]³.
  const double step = 2.0 * h / n;
  double s = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int l = 0; l < n; ++l) {
        const Vec3f r(float(-h + (i + 0.5) * step), float(-h + (j + 0.5) * step), float(-h + (l + 0.5) * step));
        s += k.w(r.norm());
      }
  return s * step * step * step;
}

TEST(Kernels, IntegrateToOne) {
  for (float h : {0.1f, 1.0f, 2.5f}) {
    EXPECT_NEAR(integrate(Poly6(h), h, 80), 1.0, 2e-3) << "poly6 h=" << h;
    EXPECT_NEAR(integrate(Spiky(h), h, 80), 1.0, 2e-3) << "spiky h=" << h;
    EXPECT_NEAR(integrate(CubicSpline(h), h, 80), 1.0, 2e-3) << "cubic h=" << h;
  }
}

TEST(Kernels, ZeroOutsideSupportAndNonNegative) {
  const float h = 0.2f;
  Poly6 p(h);
  Spiky s(h);
  CubicSpline c(h);
  for (float r = 0.0f; r <= 1.5f * h; r += h / 37.0f) {
    EXPECT_GE(p.w(r), 0.0f);
    EXPECT_GE(s.w(r), 0.0f);
    EXPECT_GE(c.w(r), 0.0f);
    if (r >= h) {
      EXPECT_EQ(p.w(r), 0.0f);
      EXPECT_EQ(s.w(r), 0.0f);
      EXPECT_EQ(c.w(r), 0.0f);
    }
  }
  EXPECT_FLOAT_EQ(p.w(0.0f), p.w_zero());
}

TEST(Kernels, GradientsAntisymmetricAndPointInward) {
  const float h = 0.1f;
  Poly6 p(h);
  Spiky s(h);
  CubicSpline c(h);
  for (const Vec3f& r : {Vec3f(0.01f, 0.02f, -0.03f), Vec3f(0.05f, 0.0f, 0.0f), Vec3f(-0.02f, 0.07f, 0.01f)}) {
    EXPECT_TRUE((p.grad(r) + p.grad(-r)).isZero(1e-6f * p.grad(r).norm()));
    EXPECT_TRUE((s.grad(r) + s.grad(-r)).isZero(1e-6f * s.grad(r).norm()));
    EXPECT_TRUE((c.grad(r) + c.grad(-r)).isZero(1e-6f * c.grad(r).norm()));
    // Kernels decrease with distance: the gradient points against r.
    EXPECT_LT(s.grad(r).dot(r), 0.0f);
    EXPECT_LT(p.grad(r).dot(r), 0.0f);
    // The analytic gradient matches a finite difference of the value.
    const float e = 1e-4f;
    const Vec3f u = r.normalized();
    EXPECT_NEAR(s.grad(r).dot(u), (s.w(r.norm() + e) - s.w(r.norm() - e)) / (2 * e), 2e-2f * s.grad(r).norm());
    EXPECT_NEAR(p.grad(r).dot(u), (p.w(r.norm() + e) - p.w(r.norm() - e)) / (2 * e), 2e-2f * p.grad(r).norm());
  }
  EXPECT_TRUE(s.grad(Vec3f::Zero()).isZero());
}

TEST(Kernels, Poly6LatticeSumMatchesMethod) {
  // METHOD.md §c.1: Poly6 lattice sum × d³ is 1.010 for h = 2d and 1.000 for h = 4d.
  auto lattice_sum = [](float d, float h) {
    Poly6 p(h);
    double s = 0.0;
    const int reach = int(std::ceil(h / d));
    for (int i = -reach; i <= reach; ++i)
      for (int j = -reach; j <= reach; ++j)
        for (int k = -reach; k <= reach; ++k) s += p.w_r2(d * d * float(i * i + j * j + k * k));
    return s * d * d * d;
  };
  EXPECT_NEAR(lattice_sum(0.05f, 0.1f), 1.010, 0.0015);
  EXPECT_NEAR(lattice_sum(0.05f, 0.2f), 1.000, 0.0015);
}

}  // namespace
}  // namespace ff::core
