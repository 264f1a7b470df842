// The adaptive controller (METHOD.md §a.2–§a.6) on a small sphere target: it forms the shape where plain PBF
// does not, it is deterministic for any thread count, and its parameters and registry reject bad input.
#include "control/control_cases.h"
#include "control/registry.h"
#include "metrics/shape_metrics.h"
#include "sampling/samplers.h"
#include "sim/emitter.h"
#include "sim/pbf_solver.h"
#include "support/shapes.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cstdio>

namespace ff {
namespace {

using test::Case;
using test::sphere_case;

test::Outcome simulate(const Case& c, const std::string& controller, int frames, const control::AdaptiveParams& ap = {},
                       const pose::TargetMotion& motion = {},
                       const std::vector<std::pair<double, sampling::ControlSet>>& swaps = {},
                       const Case* measure_against = nullptr, const control::StrengthTrack& strength = {}) {
  control::ControllerSpec spec;
  spec.name = controller;
  spec.get<control::AdaptiveParams>() = ap;
  return test::simulate(c, spec, frames, motion, swaps, measure_against, strength);
}

TEST(Adaptive, FormsASphereThatPlainPbfDoesNot) {
  const Case c = sphere_case();
  const auto none = simulate(c, "none", 150);
  const auto ada = simulate(c, "adaptive", 150);
  // Plain PBF falls through the floating sphere onto the floor; the controller holds the fluid in it.
  // The sphere is only 10 spacings across, so E in % is dominated by the packing noise (two independent
  // packings of spacing d are ~0.45 d apart on average): the criterion is in spacings.
  EXPECT_GT(none.m.error_rate, 3.0 * ada.m.error_rate) << none.m.error_rate << " vs " << ada.m.error_rate;
  EXPECT_LT(ada.m.error_spacings, 0.6) << "E_fwd " << ada.m.e_fwd << " E_bwd " << ada.m.e_bwd;
  EXPECT_GT(ada.m.inside_fraction, 0.97);
  EXPECT_LT(ada.m.splash_fraction, 0.01);
  EXPECT_GT(ada.m.controlled, ada.m.fluid * 9 / 10);
  EXPECT_LT(none.m.inside_fraction, 0.5);
}

TEST(Adaptive, KinematicControlHoldsTheFluidWorse) {
  // The PBD reading (corrections become velocity, with the speed limit) against the kinematic option.
  const Case c = sphere_case();
  const auto ada = simulate(c, "adaptive", 150);
  control::AdaptiveParams kin;
  kin.kinematic = true;
  const auto k = simulate(c, "adaptive", 150, kin);
  EXPECT_GT(k.m.error_rate, ada.m.error_rate);
  EXPECT_LT(k.m.inside_fraction, ada.m.inside_fraction);
  std::printf("sphere, 150 frames: E %.2f %% (%.2f d), inside %.3f; kinematic: E %.2f %%, inside %.3f\n",
              ada.m.error_rate, ada.m.error_spacings, ada.m.inside_fraction, k.m.error_rate, k.m.inside_fraction);
}

TEST(Adaptive, AMovingTargetStaysFormedWhileItMoves) {
  // Formed by 2.5 s, then moved 0.3 m along x in 1.2 s (0.25 m/s: half its diameter per second, the issue's
  // speed) while turning 45° about y; measured mid-motion at 3.5 s in the target's own frame.
  const Case c = sphere_case();
  pose::TargetMotion motion;
  motion.pivot = Vec3f(0.0f, 0.45f, 0.0f);
  motion.keys = {{2.5, Vec3f::Zero(), Vec3f::Zero(), 1.0f}, {3.7, Vec3f(0.3f, 0.0f, 0.0f), Vec3f(0, 45, 0), 1.0f}};
  const auto still = simulate(c, "adaptive", 210);
  const auto moving = simulate(c, "adaptive", 210, {}, motion);
  EXPECT_LT(moving.m.error_spacings, 0.8) << "E " << moving.m.error_rate << " %";
  EXPECT_GT(moving.m.inside_fraction, 0.9);
  EXPECT_LT(moving.m.error_rate, still.m.error_rate + 1.5);
  std::printf("sphere at 3.5 s: still E %.2f %%, moving at 0.25 m/s E %.2f %% (%.2f d), inside %.3f\n", still.m.error_rate,
              moving.m.error_rate, moving.m.error_spacings, moving.m.inside_fraction);
}

TEST(Adaptive, AMeshSwapMorphsTheFormedShape) {
  // The sphere, formed by 2 s, becomes a flat slab of the same volume at 2 s; by 5 s the fluid has the slab's
  // shape: its error against the slab falls well below the unmorphed sphere's error against the slab.
  const Case c = sphere_case();
  Case b = c;
  b.mesh = test::translate(test::box(Vec3f(0.32f, 0.08f, 0.32f)), Vec3f(0.0f, 0.45f, 0.0f));
  sampling::SamplingParams smp;
  smp.spacing = c.sp.spacing();
  smp.method = sampling::Method::Voxel;
  auto set = sampling::sample_target(b.mesh, smp);
  ASSERT_TRUE(set.has_value());
  b.set = std::move(*set);
  const auto sphere_vs_box = simulate(c, "adaptive", 300, {}, {}, {}, &b);
  const auto morphed = simulate(c, "adaptive", 300, {}, {}, {{2.0, b.set}}, &b);
  EXPECT_LT(morphed.m.error_rate, 0.5 * sphere_vs_box.m.error_rate)
      << morphed.m.error_rate << " vs " << sphere_vs_box.m.error_rate;
  EXPECT_GT(morphed.m.inside_fraction, 0.9);
  std::printf("morph sphere -> slab at 2 s, at 5 s: E vs slab %.2f %%, inside %.3f (unmorphed sphere vs slab %.2f %%)\n",
              morphed.m.error_rate, morphed.m.inside_fraction, sphere_vs_box.m.error_rate);
}

// Form, hold, release (issue 19 item 4): formed by 2.5 s and released over 0.25 s, the fluid falls off the floating
// sphere as free liquid, as under plain PBF; "release, then re-form" takes it back from the floor into the shape, where
// E returns to the held run's level.
TEST(Adaptive, AStrengthTrackReleasesTheFluidAndReformsIt) {
  const Case c = sphere_case();
  control::StrengthTrack release, reform, half;
  release.keys = {{2.5, 1.0f}, {2.75, 0.0f}};
  reform.keys = {{2.5, 1.0f}, {2.75, 0.0f}, {3.5, 0.0f}, {3.75, 1.0f}};
  half.keys = {{0.0, 0.5f}};
  const auto held = simulate(c, "adaptive", 300);
  const auto released = simulate(c, "adaptive", 300, {}, {}, {}, nullptr, release);
  const auto reformed = simulate(c, "adaptive", 480, {}, {}, {}, nullptr, reform);
  const auto soft = simulate(c, "adaptive", 300, {}, {}, {}, nullptr, half);
  std::printf("sphere at 5 s: held E %.2f %% inside %.3f; released E %.2f %% inside %.3f, controlled %zu; "
              "released at 2.75 s and re-formed from 3.5 s, at 8 s: E %.2f %% inside %.3f splash %.3f; "
              "strength 0.5: E %.2f %% inside %.3f\n",
              held.m.error_rate, held.m.inside_fraction, released.m.error_rate, released.m.inside_fraction,
              released.m.controlled, reformed.m.error_rate, reformed.m.inside_fraction, reformed.m.splash_fraction,
              soft.m.error_rate, soft.m.inside_fraction);
  // Released: nothing is controlled and most of the fluid has left the shape.
  EXPECT_EQ(released.m.controlled, 0u);
  EXPECT_LT(released.m.inside_fraction, 0.5);
  EXPECT_GT(released.m.error_rate, 3.0 * held.m.error_rate);
  // Re-formed: back in the shape, as close as the held run (within a fifth of a spacing of E) and as full.
  EXPECT_LT(reformed.m.error_spacings, held.m.error_spacings + 0.2);
  EXPECT_GT(reformed.m.inside_fraction, 0.97);
  EXPECT_LT(reformed.m.splash_fraction, 0.01);
  // Half strength softens the control but still holds the fluid in the sphere.
  EXPECT_GT(soft.m.inside_fraction, 0.9);
}

TEST(Adaptive, IsIndependentOfTheThreadCount) {
  const Case c = sphere_case();
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto one = simulate(c, "adaptive", 40);
  omp_set_num_threads(2);
  const auto two = simulate(c, "adaptive", 40);
  omp_set_num_threads(before);
  ASSERT_EQ(one.x.size(), two.x.size());
  for (std::size_t i = 0; i < one.x.size(); ++i) ASSERT_EQ(one.x[i], two.x[i]) << "particle " << i;
}

TEST(Adaptive, SpeedScalesGrowWithTheCubeRootOfATargetsSampleCount) {
  const std::vector<std::uint8_t> target = {0, 1, 1, 1, 1, 1, 1, 1, 1, 2};  // 1, 8 and 1 samples; target 3 has none
  const auto s = control::speed_scales(target, 4, 1.0f);
  ASSERT_EQ(s.size(), 4u);
  EXPECT_FLOAT_EQ(s[0], 1.0f);
  EXPECT_FLOAT_EQ(s[1], 2.0f);
  EXPECT_FLOAT_EQ(s[2], 1.0f);
  EXPECT_FLOAT_EQ(s[3], 1.0f);  // never below 1
  EXPECT_FLOAT_EQ(control::speed_scales(target, 4, 0.125f)[0], 2.0f);
  for (const float f : control::speed_scales(target, 4, 0.0f)) EXPECT_EQ(f, 1.0f);  // 0: off
  for (const float f : control::speed_scales(target, 4, 100.0f)) EXPECT_EQ(f, 1.0f);  // fewer than the reference
}

// A target with 8× the reference's samples runs its three speeds × 2: exactly as those speeds doubled by hand. A target
// below the reference (every test's sphere, ~520 samples, under the default 12 000) runs them as written.
TEST(Adaptive, ALargeTargetRunsItsSpeedsScaledByItsSampleCount) {
  const Case c = sphere_case();
  constexpr int kFrames = 30;
  control::AdaptiveParams scaled;
  scaled.speed_reference = static_cast<float>(c.set.size()) / 8.0f;
  control::AdaptiveParams hand, off;
  hand.speed_reference = off.speed_reference = 0.0f;
  hand.clamp *= 2.0f, hand.max_speed *= 2.0f, hand.gather_speed *= 2.0f;
  const auto a = simulate(c, "adaptive", kFrames, scaled), b = simulate(c, "adaptive", kFrames, hand);
  const auto d = simulate(c, "adaptive", kFrames), o = simulate(c, "adaptive", kFrames, off);
  ASSERT_EQ(a.x.size(), b.x.size());
  for (std::size_t i = 0; i < a.x.size(); ++i) ASSERT_EQ(a.x[i], b.x[i]) << "particle " << i;
  for (std::size_t i = 0; i < d.x.size(); ++i) ASSERT_EQ(d.x[i], o.x[i]) << "particle " << i;
  std::printf("sphere after %d frames: speeds × 1 inside %.3f, controlled %zu; × 2 inside %.3f, controlled %zu\n", kFrames,
              d.m.inside_fraction, d.m.controlled, a.m.inside_fraction, a.m.controlled);
  EXPECT_GT(a.m.controlled, d.m.controlled) << "faster speeds fill the target sooner";
}

// The clamp grows with the factor only up to one spacing: at × 16 the target runs exactly as with the clamp set to 1
// by hand (not 1.6) and the two other speeds × 16.
TEST(Adaptive, TheScaledClampStopsAtOneSpacing) {
  const Case c = sphere_case();
  constexpr int kFrames = 12;
  control::AdaptiveParams scaled;
  scaled.speed_reference = static_cast<float>(c.set.size()) / 4096.0f;  // × 16
  ASSERT_GT(scaled.clamp * 16.0f, 1.0f);
  control::AdaptiveParams hand = scaled;
  hand.speed_reference = 0.0f;
  hand.clamp = 1.0f, hand.max_speed *= 16.0f, hand.gather_speed *= 16.0f;
  const auto a = simulate(c, "adaptive", kFrames, scaled), b = simulate(c, "adaptive", kFrames, hand);
  ASSERT_EQ(a.x.size(), b.x.size());
  for (std::size_t i = 0; i < a.x.size(); ++i) ASSERT_EQ(a.x[i], b.x[i]) << "particle " << i;
}

// A morph's new sample set gets its own factor: the sphere swapped at t = 0 for the slab (432 samples, × 1.88 here)
// runs exactly as the slab from the start, not at the sphere's × 2.
TEST(Adaptive, AMorphsNewSamplesGetTheirOwnSpeedFactor) {
  const Case c = sphere_case();
  Case b = c;
  sampling::SamplingParams smp;
  smp.spacing = c.sp.spacing();
  smp.method = sampling::Method::Voxel;
  auto slab = sampling::sample_target(
      test::translate(test::box(Vec3f(0.32f, 0.08f, 0.32f)), Vec3f(0.0f, 0.45f, 0.0f)), smp);
  ASSERT_TRUE(slab.has_value()) << slab.error().message;
  b.set = *slab;
  control::AdaptiveParams ap;
  ap.speed_reference = static_cast<float>(c.set.size()) / 8.0f;  // the sphere × 2
  const auto scales = [&](const sampling::ControlSet& set) {
    return control::speed_scales(std::vector<std::uint8_t>(set.size(), 0), 1, ap.speed_reference)[0];
  };
  ASSERT_NE(scales(c.set), scales(b.set));
  std::printf("speed factors: sphere (%zu samples) x %.3f, slab (%zu) x %.3f\n", c.set.size(), scales(c.set),
              b.set.size(), scales(b.set));
  constexpr int kFrames = 12;
  const auto morphed = simulate(c, "adaptive", kFrames, ap, {}, {{0.0, b.set}});
  const auto direct = simulate(b, "adaptive", kFrames, ap);
  ASSERT_EQ(morphed.x.size(), direct.x.size());
  for (std::size_t i = 0; i < morphed.x.size(); ++i) ASSERT_EQ(morphed.x[i], direct.x[i]) << "particle " << i;
}

TEST(Adaptive, ParametersAndRegistryRejectBadInput) {
  control::AdaptiveParams ap;
  ap.alpha = 0.0f;
  const auto st = ap.validate();
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("controller.adaptive.alpha"), std::string::npos) << st.error().message;
  ap = {};
  ap.clamp = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(ap.validate().ok());
  control::ControllerSpec spec;
  spec.name = "magic";
  const auto r = control::make_controller(spec, {}, {});
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("adaptive, none"), std::string::npos) << r.error().message;
  spec.name = "adaptive";
  const auto empty = control::make_controller(spec, {}, {});
  ASSERT_FALSE(empty.has_value());
  EXPECT_NE(empty.error().message.find("no targets"), std::string::npos);
  EXPECT_NE(control::find_controller("none"), nullptr);
}

}  // namespace
}  // namespace ff
