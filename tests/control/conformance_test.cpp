// The conformance suite every registered controller passes, run over the registry so a new
// controller is covered the moment it is listed: `none` is plain PBF bit for bit; no NaN after a few hundred
// sub-steps; bindings in range; the same bits for 1 and 2 threads; unknown or out-of-range parameters are a clear
// error; every real controller ends closer to the target than `none`. Then one focused test per baseline of the
// behaviour METHOD.md §b documents for it.
#include "control/control_cases.h"
#include "control/lcat.h"
#include "control/registry.h"
#include "scene/scene.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>

namespace ff {
namespace {

std::vector<std::string> registered(bool with_none = true) {
  std::vector<std::string> names;
  for (const auto& e : control::registry())
    if (with_none || e.name != "none") names.emplace_back(e.name);
  return names;
}

control::ControllerSpec spec_of(const std::string& name) {
  control::ControllerSpec s;
  s.name = name;
  return s;
}

// One 200-frame run per controller (≥ 400 sub-steps), shared by the tests that only read its end state.
const test::Outcome& long_run(const std::string& name) {
  static std::map<std::string, test::Outcome> cache;
  static const test::Case c = test::sphere_case();
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, test::simulate(c, spec_of(name), 200)).first;
  return it->second;
}

class Conformance : public ::testing::TestWithParam<std::string> {};

TEST_P(Conformance, StaysFiniteForHundredsOfSubSteps) {
  const auto& o = long_run(GetParam());
  ASSERT_TRUE(o.ok);
  for (std::size_t i = 0; i < o.x.size(); ++i)
    ASSERT_TRUE(o.x[i].allFinite() && o.v[i].allFinite()) << GetParam() << ": particle " << i;
}

TEST_P(Conformance, BindsOnlyToExistingControlParticles) {
  const auto& o = long_run(GetParam());
  ASSERT_TRUE(o.ok);
  std::size_t bound = 0;
  for (Index b : o.bound) {
    if (b == kInvalidIndex) continue;
    ASSERT_LT(b, o.control_count) << GetParam();
    ++bound;
  }
  if (GetParam() == "none") EXPECT_EQ(bound, 0u);
  else EXPECT_GT(bound, 0u) << GetParam() << " controls nothing";
}

// Every controller but the reference.
class RealController : public ::testing::TestWithParam<std::string> {};

TEST_P(RealController, EndsCloserToTheTargetThanNone) {
  const auto& o = long_run(GetParam());
  const auto& none = long_run("none");
  ASSERT_TRUE(o.ok && none.ok);
  EXPECT_LT(o.m.error_rate, none.m.error_rate) << GetParam();
  std::printf("%-9s E %6.2f %%  inside %.3f  splash %.3f  controlled %zu of %zu (none: E %.2f %%)\n", GetParam().c_str(),
              o.m.error_rate, o.m.inside_fraction, o.m.splash_fraction, o.m.controlled, o.m.fluid, none.m.error_rate);
}

TEST_P(Conformance, IsIndependentOfTheThreadCount) {
  const test::Case c = test::sphere_case();
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto one = test::simulate(c, spec_of(GetParam()), 30);
  omp_set_num_threads(2);
  const auto two = test::simulate(c, spec_of(GetParam()), 30);
  omp_set_num_threads(before);
  ASSERT_EQ(one.x.size(), two.x.size());
  for (std::size_t i = 0; i < one.x.size(); ++i) {
    ASSERT_EQ(one.x[i], two.x[i]) << GetParam() << ": particle " << i;
    ASSERT_EQ(one.bound[i], two.bound[i]) << GetParam() << ": particle " << i;
  }
}

// Strength 0 releases the fluid (issue 19 item 4): the controller then contributes exactly nothing, so every
// registered controller given a target at strength 0 throughout steps the same bits as `none` (plain PBF), and binds
// nothing.
TEST_P(Conformance, AtStrengthZeroAddsExactlyNothing) {
  const test::Case c = test::sphere_case();
  control::StrengthTrack off;
  off.keys = {{0.0, 0.0f}};
  const auto none = test::simulate(c, spec_of("none"), 40);
  const auto o = test::simulate(c, spec_of(GetParam()), 40, {}, {}, nullptr, off);
  ASSERT_TRUE(o.ok && none.ok);
  ASSERT_EQ(o.x.size(), none.x.size()) << GetParam();
  for (std::size_t i = 0; i < o.x.size(); ++i) {
    ASSERT_EQ(o.x[i], none.x[i]) << GetParam() << ": particle " << i;
    ASSERT_EQ(o.v[i], none.v[i]) << GetParam() << ": particle " << i;
    ASSERT_EQ(o.bound[i], kInvalidIndex) << GetParam() << ": particle " << i;
  }
}

TEST_P(Conformance, UnknownOrOutOfRangeParametersAreAClearError) {
  const std::string name = GetParam();
  // An unknown key inside the controller's own parameter object (or, for `none`, which has none, the object itself).
  const std::string text = name == "none" ? R"({"controller": {"name": "none", "none": {"x": 1}}})"
                                          : R"({"controller": {"name": ")" + name + R"(", ")" + name + R"(": {"bogus_key": 1}}})";
  auto s = scene::parse_scene(text, ".", "scene.json");
  ASSERT_FALSE(s.has_value()) << name;
  const std::string want = name == "none" ? "controller.none" : "controller." + name + ".bogus_key";
  EXPECT_NE(s.error().message.find(want), std::string::npos) << s.error().message;
  EXPECT_EQ(s.error().message.find('\n'), std::string::npos);
  if (name == "none") return;
  // The first parameter of each baseline set far outside its range.
  // The first number of the controller's own parameters (the table's row for `name`), far outside its range, then NaN.
  for (const bool nan : {false, true}) {
    auto spec = spec_of(name);
    std::string first;
    std::apply([&](auto&... params) {
      const auto visit = [&](auto& p) {
        if (p.info.name != name) return;
        std::remove_reference_t<decltype(p)>::fields(p, [&](std::string_view k, auto& v, const core::FieldInfo& info) {
          if constexpr (std::is_floating_point_v<std::remove_reference_t<decltype(v)>>)
            if (first.empty() && info.ranged()) first = std::string(k), v = nan ? std::nanf("") : static_cast<float>(info.hi * 10 + 1);
        });
      };
      (visit(params), ...);
    }, spec.params);
    ASSERT_FALSE(first.empty()) << name << " has no ranged number to test";
    const auto st = spec.validate();
    ASSERT_FALSE(st.ok()) << name << (nan ? " NaN" : "");
    EXPECT_NE(st.error().message.find("controller." + name + "." + first), std::string::npos) << st.error().message;
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, Conformance, ::testing::ValuesIn(registered()),
                         [](const auto& p) { return p.param; });
INSTANTIATE_TEST_SUITE_P(Registry, RealController, ::testing::ValuesIn(registered(/*with_none=*/false)),
                         [](const auto& p) { return p.param; });

TEST(ConformanceNone, IsBitIdenticalToPlainPbf) {
  // `none` from the registry, given the scene's targets, against the solver's own NoController without any.
  const test::Case c = test::sphere_case();
  const auto reg = test::simulate(c, spec_of("none"), 60);
  sim::ParticleSet p;
  ASSERT_TRUE(sim::fill_sources(c.fluid, c.dom, c.sp.particle_radius, p).ok());
  std::fill(p.target.begin(), p.target.end(), std::uint8_t{0});
  sim::PbfSolver solver(c.sp, c.dom);
  sim::NoController plain;
  for (int f = 0; f < 60; ++f) ASSERT_TRUE(solver.advance(p, f / 60.0, 1.0 / 60.0, plain).has_value());
  std::vector<Vec3f> x, v;
  std::vector<std::uint8_t> t;
  sim::sorted_by_id(p, x, v, t);
  ASSERT_EQ(x.size(), reg.x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    ASSERT_EQ(x[i], reg.x[i]) << "particle " << i;
    ASSERT_EQ(v[i], reg.v[i]) << "particle " << i;
  }
}

}  // namespace
}  // namespace ff
