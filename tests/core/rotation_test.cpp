// The one rotation from degrees (core/rotation.h), R = Rz · Ry · Rx: what it does to the axes, that it is a rotation,
// and that the viewer's twin (web/src/rotation.js) gives the same matrices on the same angles (node, like the frame
// codec's round trip).
#include "core/rotation.h"

#include "support/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>
#include <random>

namespace ff::core {
namespace {

TEST(RotationFromDegrees, TurnsTheAxesAsRzRyRx) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  EXPECT_TRUE((rotation_from_degrees<double>(Vec3d(0, 0, 90)) * x).isApprox(y, 1e-12));
  EXPECT_TRUE((rotation_from_degrees<double>(Vec3d(90, 0, 0)) * y).isApprox(z, 1e-12));
  EXPECT_TRUE((rotation_from_degrees<double>(Vec3d(0, 90, 0)) * z).isApprox(x, 1e-12));
  // x first: 90° about x takes y to z, then 90° about z leaves z where it is; the other order would give x.
  EXPECT_TRUE((rotation_from_degrees<double>(Vec3d(90, 0, 90)) * y).isApprox(z, 1e-12));
  EXPECT_TRUE((rotation_from_degrees<double>(Vec3d(90, 0, 90)) * x).isApprox(y, 1e-12));
}

TEST(RotationFromDegrees, IsARotation) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-720.0, 720.0);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Matrix3d r = rotation_from_degrees<double>(Vec3d(u(rng), u(rng), u(rng)));
    EXPECT_TRUE((r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  }
  // The float instantiation (a keyframed target's pose) is the same rotation to float precision.
  const Vec3f deg(30.0f, -45.0f, 100.0f);
  EXPECT_TRUE(rotation_from_degrees<float>(deg).cast<double>().isApprox(rotation_from_degrees<double>(deg.cast<double>()), 1e-6));
}

TEST(RotationFromDegrees, TheViewersTwinAgrees) {
  if (std::system("node --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "node is not installed (scripts/setup installs it)";
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-360.0, 360.0);
  nlohmann::json cases = nlohmann::json::array();
  std::vector<Vec3d> angles = {{0, 0, 0}, {90, 0, 0}, {0, 90, 0}, {0, 0, 90}, {30, 45, 60}, {-170, 89.5, 400}};
  for (int k = 0; k < 20; ++k) angles.emplace_back(u(rng), u(rng), u(rng));
  for (const Vec3d& deg : angles) {
    const Eigen::Matrix3d r = rotation_from_degrees<double>(deg);
    nlohmann::json m = nlohmann::json::array();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m.push_back(r(i, j));
    cases.push_back({{"deg", {deg.x(), deg.y(), deg.z()}}, {"matrix", m}});
  }
  const auto file = test::temp_dir("rotation") / "angles.json";
  std::ofstream(file) << cases.dump();
  const auto [code, out] = test::shell("node '" + (test::source_dir() / "web" / "test" / "rotation_twin.mjs").string() +
                                       "' '" + file.string() + "'");
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("rotation twin ok: 26 angle sets"), std::string::npos) << out;
}

}  // namespace
}  // namespace ff::core
