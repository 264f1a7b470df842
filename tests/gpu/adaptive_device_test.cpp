// The adaptive controller on the device (gpu/adaptive_device.h) against the CPU controller (control/adaptive.h) on
// the controller tests' sphere (tests/control/control_cases.h): fluid that has flowed into the target, one frame
// from the same state on both, positions and which particles are controlled (and by which sample); lavapipe in CI,
// validation layer on.
#include "control/adaptive.h"
#include "control/control_cases.h"
#include "control/registry.h"
#include "gpu/adaptive_device.h"
#include "gpu/context.h"
#include "gpu/pbf_device.h"
#include "sampling/samplers.h"
#include "support/shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

namespace ff::gpu {
namespace {

struct Scene {
  test::Case c = test::sphere_case();
  control::AdaptiveParams params;
  control::ControlContext ctx;
  Scene() {
    c.sp.surface_tension = 0.0f, c.sp.vorticity = 0.0f;  // the controller's passes alone (tested apart)
    c.sp.max_iterations = c.sp.iterations;                                    // a fixed sweep count on both
    params.gather = false;  // the gather steering's tests turn it on (GatherFormsTheSphereAsTheCpuDoes and on)
  }
  /// The column of fluid above the sphere, every particle of target 0.
  sim::ParticleSet column() const {
    sim::ParticleSet p;
    EXPECT_TRUE(sim::fill_sources(c.fluid, c.dom, c.sp.particle_radius, p).ok());
    std::fill(p.target.begin(), p.target.end(), std::uint8_t{0});
    return p;
  }
  /// The controllers' context with `solver`'s particle mass.
  void use(const sim::PbfSolver& solver) {
    ctx = {c.sp.particle_radius, solver.particle_mass(), c.sp.rest_density, c.sp.gravity, c.dom, c.sp.support()};
  }
  std::vector<control::ControlTarget> targets() const {
    std::vector<control::ControlTarget> t(1);
    t[0].set = c.set;
    return t;
  }
};

// |a_i − b_i| / d for every particle, in ascending order (its median and percentiles are what the tests compare).
std::vector<double> sorted_apart(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b, float d) {
  std::vector<double> out(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) out[i] = (a[i] - b[i]).norm() / d;
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<Vec3f> by_id(const sim::ParticleSet& p, std::span<const Vec3f> v) {
  std::vector<Vec3f> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[p.id[i]] = v[i];
  return out;
}

// The column after `frames` frames of a CPU controller of `s`'s targets and parameters, from time 0: the state a test's
// frames start from (`s.use(solver)` done); nullopt, with the failure added, when a frame fails.
std::optional<sim::ParticleSet> cpu_state(const Scene& s, sim::PbfSolver& solver, int frames) {
  sim::ParticleSet p = s.column();
  auto ctl = control::AdaptiveController::create(s.targets(), s.ctx, s.params);
  if (!ctl) return ADD_FAILURE() << ctl.error().message, std::nullopt;
  for (int f = 0; f < frames; ++f)
    if (!solver.advance(p, f / 60.0, 1.0 / 60.0, **ctl)) return ADD_FAILURE() << "CPU frame " << f, std::nullopt;
  return p;
}

// A device (validation layer on) with `start`'s fluid on it and the controller of `targets` with `params`. Members in
// the order they must outlive each other.
struct OnDevice {
  std::unique_ptr<Context> ctx;
  std::unique_ptr<PbfDevice> fluid;
  std::unique_ptr<AdaptiveDevice> ctl;
};
Result<OnDevice> on_device(const Scene& s, const sim::PbfSolver& solver, const sim::ParticleSet& start,
                           std::vector<control::ControlTarget> targets, const control::AdaptiveParams& params) {
  OnDevice d;
  FF_TRY(d.ctx, Context::create({.device = -1, .validation = true}));
  FF_TRY(const GridSpec grid, GridSpec::for_support(s.c.dom.min, s.c.dom.max, solver.lambda_consts().h));
  FF_TRY(d.fluid, PbfDevice::create(*d.ctx, start.size(), grid));
  FF_CHECK(d.fluid->set_state(start.position, start.velocity));
  FF_CHECK(d.fluid->set_ids(start.id));
  FF_TRY(d.ctl, AdaptiveDevice::create(*d.fluid, std::move(targets), s.ctx, params));
  FF_CHECK(d.ctl->set_fluid_targets(start.target));
  d.fluid->set_controller(d.ctl.get());
  return d;
}

TEST(GpuAdaptive, OneFrameTracksTheCpuController) {
  Scene s;
  sim::ParticleSet p = s.column();
  sim::PbfSolver solver(s.c.sp, s.c.dom);
  solver.set_cluster_kernels(true);
  s.use(solver);
  auto cpu_ctl = control::AdaptiveController::create(s.targets(), s.ctx, s.params);
  ASSERT_TRUE(cpu_ctl.has_value()) << cpu_ctl.error().message;
  // The column falls into the sphere: after 40 frames most of it is held.
  for (int f = 0; f < 40; ++f) ASSERT_TRUE(solver.advance(p, f / 60.0, 1.0 / 60.0, **cpu_ctl).has_value());
  const sim::ParticleSet start = p;
  std::size_t held = 0;
  for (Index b : start.bound_control) held += b != kInvalidIndex;
  ASSERT_GT(held, start.size() / 2) << "the fluid should have reached the target";

  ASSERT_TRUE(solver.advance(p, 40 / 60.0, 1.0 / 60.0, **cpu_ctl).has_value());

  auto ctx = Context::create({.device = -1, .validation = true});
  ASSERT_TRUE(ctx.has_value()) << ctx.error().message;
  const GridSpec grid = GridSpec::for_support(s.c.dom.min, s.c.dom.max, solver.lambda_consts().h).value();
  std::vector<Vec3f> free_x;  // the same frame without the controller: what the control changes
  for (const bool controlled : {true, false}) {
    auto dev = PbfDevice::create(**ctx, start.size(), grid);
    ASSERT_TRUE(dev.has_value()) << dev.error().message;
    ASSERT_TRUE((*dev)->set_state(start.position, start.velocity).ok());
    auto ctl = AdaptiveDevice::create(**dev, s.targets(), s.ctx, s.params);
    ASSERT_TRUE(ctl.has_value()) << ctl.error().message;
    ASSERT_TRUE((*ctl)->set_fluid_targets(start.target).ok());
    if (controlled) (*dev)->set_controller(ctl->get());
    auto frame = (*dev)->advance(solver, 40 / 60.0, 1.0 / 60.0);
    ASSERT_TRUE(frame.has_value()) << frame.error().message;
    std::vector<Vec3f> x, v;
    ASSERT_TRUE((*dev)->get_state(x, v).ok());
    const auto gx = by_id(start, x);
    if (!controlled) {
      free_x = gx;
      continue;
    }
    const auto cx = by_id(p, p.position);
    std::vector<double> dx(gx.size());
    for (std::size_t i = 0; i < gx.size(); ++i) dx[i] = (gx[i] - cx[i]).norm() / s.c.sp.spacing();
    std::sort(dx.begin(), dx.end());
    std::vector<Index> bound;
    ASSERT_TRUE((*ctl)->get_bound(bound).ok());
    std::vector<Index> gb(bound.size()), cb(bound.size());
    for (std::size_t i = 0; i < bound.size(); ++i) gb[start.id[i]] = bound[i], cb[p.id[i]] = p.bound_control[i];
    std::size_t same_set = 0, same_sample = 0, controlled_cpu = 0;
    for (std::size_t i = 0; i < gb.size(); ++i) {
      same_set += (gb[i] == kInvalidIndex) == (cb[i] == kInvalidIndex);
      same_sample += gb[i] == cb[i];
      controlled_cpu += cb[i] != kInvalidIndex;
    }
    std::printf("%zu particles (%zu controlled), %d sub-steps: GPU − CPU |Δx|/d median %.2e, 90th %.2e, largest %.2e; "
                "controlled alike %zu, same nearest sample %zu\n",
                gx.size(), controlled_cpu, frame->substeps, dx[dx.size() / 2], dx[dx.size() * 9 / 10], dx.back(), same_set,
                same_sample);
    EXPECT_LT(dx[dx.size() / 2], 1e-3);
    EXPECT_LT(dx[dx.size() * 9 / 10], 1e-2);
    EXPECT_GE(same_set, gb.size() - gb.size() / 200);        // ≥ 99.5 %
    EXPECT_GE(same_sample, gb.size() - gb.size() / 50);      // ≥ 98 %: a near tie may go either way
  }
  // The control moves the fluid far more than the two paths differ.
  const auto cx = by_id(p, p.position);
  std::vector<double> diff(cx.size());
  for (std::size_t i = 0; i < cx.size(); ++i) diff[i] = (free_x[i] - cx[i]).norm() / s.c.sp.spacing();
  std::sort(diff.begin(), diff.end());
  const double moved = diff[diff.size() / 2];
  std::printf("without the controller the frame ends |Δx|/d median %.2e from the CPU's controlled frame\n", moved);
  EXPECT_GT(moved, 1e-2);
  for (const std::string& m : (*ctx)->messages()) ADD_FAILURE() << "validation: " << m;
}

// The gather steering from the start: the column above the sphere is steered into it. The seed field is the nearest
// seed to each cell's centre up to a cell's size; the forming holds as much of the fluid as the CPU's after 40 frames.
TEST(GpuAdaptive, GatherFormsTheSphereAsTheCpuDoes) {
  Scene s;
  s.params.gather = true;
  sim::ParticleSet p = s.column();
  const sim::ParticleSet start = p;
  sim::PbfSolver solver(s.c.sp, s.c.dom);
  s.use(solver);
  auto cpu_ctl = control::AdaptiveController::create(s.targets(), s.ctx, s.params);
  ASSERT_TRUE(cpu_ctl.has_value()) << cpu_ctl.error().message;
  constexpr int kFrames = 40;
  for (int f = 0; f < kFrames; ++f) ASSERT_TRUE(solver.advance(p, f / 60.0, 1.0 / 60.0, **cpu_ctl).has_value());
  std::size_t cpu_held = 0;
  for (Index b : p.bound_control) cpu_held += b != kInvalidIndex;

  auto ctx = Context::create({.device = -1, .validation = true});
  ASSERT_TRUE(ctx.has_value()) << ctx.error().message;
  auto dev = PbfDevice::create(**ctx, start.size(),
                               GridSpec::for_support(s.c.dom.min, s.c.dom.max, solver.lambda_consts().h).value());
  ASSERT_TRUE(dev.has_value()) << dev.error().message;
  ASSERT_TRUE((*dev)->set_state(start.position, start.velocity).ok());
  auto ctl = AdaptiveDevice::create(**dev, s.targets(), s.ctx, s.params);
  ASSERT_TRUE(ctl.has_value()) << ctl.error().message;
  ASSERT_TRUE((*ctl)->set_fluid_targets(start.target).ok());
  (*dev)->set_controller(ctl->get());
  // The field after the first frame, against the nearest seed by brute force.
  ASSERT_TRUE((*dev)->advance(solver, 0.0, 1.0 / 60.0).has_value());
  std::vector<Index> seeds;
  std::vector<float> fill;
  ASSERT_TRUE((*ctl)->get_seeds(seeds).ok());
  ASSERT_TRUE((*ctl)->get_fill(fill).ok());
  const GridSpec& field = (*ctl)->field();
  const float diag = field.cell * std::sqrt(3.0f);
  std::size_t cells = 0, worse = 0, seeded = 0;
  for (int z = 0; z < field.dims[2]; ++z)
    for (int y = 0; y < field.dims[1]; ++y)
      for (int x = 0; x < field.dims[0]; ++x, ++cells) {
        const Vec3f centre = field.lo + field.cell * Vec3f(float(x) + 0.5f, float(y) + 0.5f, float(z) + 0.5f);
        float best = INFINITY;
        for (std::size_t i = 0; i < fill.size(); ++i)
          if (fill[i] < s.params.gather_fill) best = std::min(best, (s.c.set.position[i] - centre).norm());
        const Index got = seeds[cells];
        ASSERT_EQ(got == kInvalidIndex, !std::isfinite(best)) << "cell " << cells;
        if (got == kInvalidIndex) continue;
        ++seeded;
        ASSERT_LT(fill[got], s.params.gather_fill);
        const float d = (s.c.set.position[got] - centre).norm();
        worse += d > best + 1e-6f;
        EXPECT_LE(d, best + diag) << "cell " << cells;
      }
  std::printf("seed field: %zu cells, %zu with a seed, %zu not the nearest (all within a cell's diagonal)\n", cells,
              seeded, worse);
  EXPECT_GT(seeded, 0u);
  for (int f = 1; f < kFrames; ++f) ASSERT_TRUE((*dev)->advance(solver, f / 60.0, 1.0 / 60.0).has_value());
  std::vector<Index> bound;
  ASSERT_TRUE((*ctl)->get_bound(bound).ok());
  std::size_t gpu_held = 0;
  for (Index b : bound) gpu_held += b != kInvalidIndex;
  std::printf("after %d frames with the gather steering: CPU holds %zu of %zu particles, GPU %zu\n", kFrames, cpu_held,
              p.size(), gpu_held);
  EXPECT_GT(cpu_held, p.size() / 2);
  EXPECT_LE(std::abs(double(gpu_held) - double(cpu_held)), 0.05 * double(p.size()));
  for (const std::string& m : (*ctx)->messages()) ADD_FAILURE() << "validation: " << m;
}

// A keyframed target (the sphere gliding sideways and turning) with the gather steering: its samples posed on the
// host every sub-step as the CPU controller poses them, the fluid carried along (follow) and chased (gather_chase).
// One frame from a state formed on the CPU tracks the CPU controller.
TEST(GpuAdaptive, AMovingTargetTracksTheCpuController) {
  Scene s;
  s.params.gather = true;
  pose::TargetMotion motion;
  motion.keys.resize(2);
  motion.keys[1].time = 2.0;
  motion.keys[1].translate = Vec3f(0.4f, 0.0f, 0.0f);
  motion.keys[1].rotate_deg = Vec3f(0.0f, 60.0f, 0.0f);
  motion.pivot = Vec3f(0.0f, 0.45f, 0.0f);
  auto targets = [&] {
    auto t = s.targets();
    t[0].motion = motion;
    return t;
  };
  sim::ParticleSet p = s.column();
  sim::PbfSolver solver(s.c.sp, s.c.dom);
  solver.set_cluster_kernels(true);
  s.use(solver);
  auto cpu_ctl = control::AdaptiveController::create(targets(), s.ctx, s.params);
  ASSERT_TRUE(cpu_ctl.has_value()) << cpu_ctl.error().message;
  for (int f = 0; f < 40; ++f) ASSERT_TRUE(solver.advance(p, f / 60.0, 1.0 / 60.0, **cpu_ctl).has_value());
  const sim::ParticleSet start = p;
  ASSERT_TRUE(solver.advance(p, 40 / 60.0, 1.0 / 60.0, **cpu_ctl).has_value());

  auto ctx = Context::create({.device = -1, .validation = true});
  ASSERT_TRUE(ctx.has_value()) << ctx.error().message;
  auto dev = PbfDevice::create(**ctx, start.size(),
                               GridSpec::for_support(s.c.dom.min, s.c.dom.max, solver.lambda_consts().h).value());
  ASSERT_TRUE(dev.has_value()) << dev.error().message;
  ASSERT_TRUE((*dev)->set_state(start.position, start.velocity).ok());
  ASSERT_TRUE((*dev)->set_ids(start.id).ok());
  auto ctl = AdaptiveDevice::create(**dev, targets(), s.ctx, s.params);
  ASSERT_TRUE(ctl.has_value()) << ctl.error().message;
  ASSERT_TRUE((*ctl)->set_fluid_targets(start.target).ok());
  (*dev)->set_controller(ctl->get());
  auto frame = (*dev)->advance(solver, 40 / 60.0, 1.0 / 60.0);
  ASSERT_TRUE(frame.has_value()) << frame.error().message;
  std::vector<Vec3f> x, v;
  ASSERT_TRUE((*dev)->get_state(x, v).ok());
  const auto gx = by_id(start, x), cx = by_id(p, p.position), sx = by_id(start, start.position);
  const auto dx = sorted_apart(gx, cx, s.c.sp.spacing()), moved = sorted_apart(cx, sx, s.c.sp.spacing());
  std::vector<Index> bound;
  ASSERT_TRUE((*ctl)->get_bound(bound).ok());
  std::size_t same = 0, held = 0;
  for (std::size_t i = 0; i < bound.size(); ++i) {
    same += bound[i] == p.bound_control[std::find(p.id.begin(), p.id.end(), start.id[i]) - p.id.begin()];
    held += bound[i] != kInvalidIndex;
  }
  std::printf("moving target, %zu particles (%zu held), %d sub-steps: the frame moved them |Δx|/d median %.3f; GPU − CPU "
              "median %.2e, 90th %.2e, largest %.2e; same nearest sample %zu\n",
              gx.size(), held, frame->substeps, moved[moved.size() / 2], dx[dx.size() / 2], dx[dx.size() * 9 / 10],
              dx.back(), same);
  EXPECT_GT(held, gx.size() / 2);
  EXPECT_GT(moved[moved.size() / 2], 0.05);  // the target carried its fluid along
  EXPECT_LT(dx[dx.size() / 2], 1e-3);
  EXPECT_LT(dx[dx.size() * 9 / 10], 1e-2);
  EXPECT_GE(same, gx.size() - gx.size() / 50);
  for (const std::string& m : (*ctx)->messages()) ADD_FAILURE() << "validation: " << m;
}

// Strength tracks and late starts (control/strength.h): from a state formed on the CPU, one frame with the target
// softened by a track that falls inside the frame, one with a start inside the frame, and one with a start after it,
// each from a fresh controller on both paths, with the gather steering. Both paths see the same strengths per sub-step.
struct TimedFrame {
  std::vector<Vec3f> x;      // by particle id
  std::vector<Index> bound;  // by particle id
};

TEST(GpuAdaptive, AStrengthTrackAndALateStartTrackTheCpuController) {
  Scene s;
  s.params.gather = true;
  sim::PbfSolver solver(s.c.sp, s.c.dom);
  solver.set_cluster_kernels(true);
  s.use(solver);
  const std::optional<sim::ParticleSet> formed = cpu_state(s, solver, 40);
  ASSERT_TRUE(formed.has_value());
  const sim::ParticleSet& start = *formed;
  const double t0 = 40 / 60.0, frame = 1.0 / 60.0;
  auto ctx = Context::create({.device = -1, .validation = true});
  ASSERT_TRUE(ctx.has_value()) << ctx.error().message;
  const GridSpec grid = GridSpec::for_support(s.c.dom.min, s.c.dom.max, solver.lambda_consts().h).value();
  // One frame from `start` on each path with `targets` (no targets: the device frame without a controller).
  auto cpu_frame = [&](const std::vector<control::ControlTarget>& targets) {
    sim::ParticleSet q = start;
    auto ctl = control::AdaptiveController::create(targets, s.ctx, s.params);
    EXPECT_TRUE(ctl.has_value() && solver.advance(q, t0, frame, **ctl).has_value());
    TimedFrame out{by_id(q, q.position), std::vector<Index>(q.size())};
    for (std::size_t i = 0; i < q.size(); ++i) out.bound[q.id[i]] = q.bound_control[i];
    return out;
  };
  auto gpu_frame = [&](const std::vector<control::ControlTarget>& targets) {
    auto dev = PbfDevice::create(**ctx, start.size(), grid).value();
    EXPECT_TRUE(dev->set_state(start.position, start.velocity).ok() && dev->set_ids(start.id).ok());
    std::unique_ptr<AdaptiveDevice> ctl;
    if (!targets.empty()) {
      ctl = AdaptiveDevice::create(*dev, targets, s.ctx, s.params).value();
      EXPECT_TRUE(ctl->set_fluid_targets(start.target).ok());
      dev->set_controller(ctl.get());
    }
    EXPECT_TRUE(dev->advance(solver, t0, frame).has_value());
    std::vector<Vec3f> x, v;
    EXPECT_TRUE(dev->get_state(x, v).ok());
    TimedFrame out{by_id(start, x), std::vector<Index>(start.size(), kInvalidIndex)};
    std::vector<Index> bound;
    if (ctl && ctl->get_bound(bound).ok())
      for (std::size_t i = 0; i < bound.size(); ++i) out.bound[start.id[i]] = bound[i];
    return out;
  };
  auto median_apart = [&](const TimedFrame& a, const TimedFrame& b, double* largest = nullptr) {
    std::vector<double> d(a.x.size());
    for (std::size_t i = 0; i < d.size(); ++i) d[i] = (a.x[i] - b.x[i]).norm() / s.c.sp.spacing();
    std::sort(d.begin(), d.end());
    if (largest) *largest = d.back();
    return d[d.size() / 2];
  };
  auto timed = [&](double start_time, std::vector<control::StrengthKey> keys) {
    auto t = s.targets();
    t[0].start = start_time;
    t[0].strength.keys = std::move(keys);
    return t;
  };
  const TimedFrame held = cpu_frame(s.targets()), free_gpu = gpu_frame({});
  // Softened from 1 to 0.2 over the frame, and a start a third into it.
  for (const auto& targets : {timed(0.0, {{t0, 1.0f}, {t0 + frame, 0.2f}}), timed(t0 + frame / 3, {})}) {
    const TimedFrame c = cpu_frame(targets), g = gpu_frame(targets);
    double largest = 0;
    const double apart = median_apart(g, c, &largest), changed = median_apart(c, held);
    std::size_t same = 0, controlled = 0;
    for (std::size_t i = 0; i < c.bound.size(); ++i) same += g.bound[i] == c.bound[i], controlled += c.bound[i] != kInvalidIndex;
    std::printf("start %.4f s, %zu keys: %zu of %zu controlled; GPU − CPU |Δx|/d median %.2e, largest %.2e; the timing "
                "moved the CPU's frame by %.2e (median); same nearest sample %zu\n",
                targets[0].start, targets[0].strength.keys.size(), controlled, c.bound.size(), apart, largest, changed,
                same);
    EXPECT_GT(controlled, c.bound.size() / 2);
    EXPECT_LT(apart, 1e-3);
    EXPECT_GT(changed, 10 * apart);  // the strengths changed the frame far more than the two paths differ
    EXPECT_GE(same, c.bound.size() - c.bound.size() / 50);
  }
  // A target that starts after the frame adds exactly nothing: the frame without a controller, bit for bit.
  const TimedFrame later = gpu_frame(timed(t0 + 2 * frame, {}));
  double largest = -1;
  median_apart(later, free_gpu, &largest);
  EXPECT_EQ(largest, 0.0);
  EXPECT_EQ(std::count(later.bound.begin(), later.bound.end(), kInvalidIndex), std::ptrdiff_t(later.bound.size()));
  EXPECT_GT(median_apart(free_gpu, held), 1e-2);
  for (const std::string& m : (*ctx)->messages()) ADD_FAILURE() << "validation: " << m;
}

// A target of 8× the reference's samples (AdaptiveParams::speed_reference) runs its speeds × 2 on both paths: one frame
// while the column is still flowing in (the speed limit, the clamp and the gather steering all act), from a state the
// CPU made at × 2, tracks the CPU controller, and differs from the frame at × 1 far more than the paths do.
TEST(GpuAdaptive, TheSpeedsOfALargeTargetTrackTheCpuController) {
  Scene s;
  s.params.gather = true;
  s.params.speed_reference = static_cast<float>(s.c.set.size()) / 8.0f;
  control::AdaptiveParams as_written = s.params;
  as_written.speed_reference = 0.0f;
  sim::PbfSolver solver(s.c.sp, s.c.dom);
  solver.set_cluster_kernels(true);
  s.use(solver);
  constexpr int kFrames = 12;
  const std::optional<sim::ParticleSet> early = cpu_state(s, solver, kFrames);
  ASSERT_TRUE(early.has_value());
  const sim::ParticleSet& start = *early;
  const double t0 = kFrames / 60.0, frame = 1.0 / 60.0;
  auto cpu_frame = [&](const control::AdaptiveParams& params) {
    sim::ParticleSet q = start;
    auto ctl = control::AdaptiveController::create(s.targets(), s.ctx, params);
    EXPECT_TRUE(ctl.has_value() && solver.advance(q, t0, frame, **ctl).has_value());
    return by_id(q, q.position);
  };
  auto dev = on_device(s, solver, start, s.targets(), s.params);
  ASSERT_TRUE(dev.has_value()) << dev.error().message;
  ASSERT_TRUE(dev->fluid->advance(solver, t0, frame).has_value());
  std::vector<Vec3f> x, v;
  ASSERT_TRUE(dev->fluid->get_state(x, v).ok());
  const auto gx = by_id(start, x), cx = cpu_frame(s.params), wx = cpu_frame(as_written);
  const auto apart = sorted_apart(gx, cx, s.c.sp.spacing()), scaled = sorted_apart(cx, wx, s.c.sp.spacing());
  std::printf("speeds x 2, frame %d: GPU - CPU |dx|/d median %.2e, 90th %.2e, largest %.2e; x 2 - x 1 on the CPU: median "
              "%.2e, 90th %.2e\n",
              kFrames, apart[apart.size() / 2], apart[apart.size() * 9 / 10], apart.back(), scaled[scaled.size() / 2],
              scaled[scaled.size() * 9 / 10]);
  EXPECT_LT(apart[apart.size() / 2], 1e-3);
  EXPECT_LT(apart[apart.size() * 9 / 10], 1e-2);
  EXPECT_GT(scaled[scaled.size() * 9 / 10], 10 * apart[apart.size() * 9 / 10]);
  for (const std::string& m : dev->ctx->messages()) ADD_FAILURE() << "validation: " << m;
}

// A morph (ControlTarget::swaps): the sphere, formed on the CPU, swaps to a flat slab of about its volume a third into
// a frame. That frame from the same state on both paths, with the gather steering and each set's own speed factor:
// the device ends the frame's first submission at the swap's sub-step and takes the slab's samples (and factor)
// there, as the CPU controller does; the frame tracks the CPU's, and the swap moves it far more than the paths
// differ. (Only the one frame: in the next ones the fluid falls ~2 spacings a frame into the slab, and a difference
// of 1e-6 d between two CPU runs grows ~5× a frame. With the sphere's factor kept after the swap, this frame's GPU −
// CPU is 3.4e-3 d median, 4.8e-2 90th.)
TEST(GpuAdaptive, AMorphTracksTheCpuController) {
  Scene s;
  s.params.gather = true;
  s.params.speed_reference = static_cast<float>(s.c.set.size()) / 8.0f;  // speeds × 2 for the sphere, × 1.88 the slab
  sampling::SamplingParams smp;
  smp.spacing = s.c.sp.spacing();
  smp.method = sampling::Method::Voxel;
  auto slab = sampling::sample_target(test::translate(test::box(Vec3f(0.32f, 0.08f, 0.32f)), Vec3f(0.0f, 0.45f, 0.0f)),
                                      smp);
  ASSERT_TRUE(slab.has_value()) << slab.error().message;
  sim::PbfSolver solver(s.c.sp, s.c.dom);
  solver.set_cluster_kernels(true);
  s.use(solver);
  const std::optional<sim::ParticleSet> formed = cpu_state(s, solver, 40);
  ASSERT_TRUE(formed.has_value());
  const sim::ParticleSet& start = *formed;
  const double t0 = 40 / 60.0, frame = 1.0 / 60.0;
  auto morph = s.targets();
  morph[0].swaps.emplace_back(t0 + frame / 3, *slab);
  auto cpu_frame = [&](const std::vector<control::ControlTarget>& targets, std::vector<Index>* bound) {
    sim::ParticleSet q = start;
    auto ctl = control::AdaptiveController::create(targets, s.ctx, s.params);
    EXPECT_TRUE(ctl.has_value() && solver.advance(q, t0, frame, **ctl).has_value());
    if (bound) {
      bound->assign(q.size(), kInvalidIndex);
      for (std::size_t i = 0; i < q.size(); ++i) (*bound)[q.id[i]] = q.bound_control[i];
    }
    return by_id(q, q.position);
  };
  auto dev = on_device(s, solver, start, morph, s.params);
  ASSERT_TRUE(dev.has_value()) << dev.error().message;
  EXPECT_EQ(dev->ctl->samples(), s.c.set.size());
  auto done = dev->fluid->advance(solver, t0, frame);
  ASSERT_TRUE(done.has_value()) << done.error().message;
  EXPECT_GE(done->substeps, 2);  // so the swap falls inside the frame, after its first sub-step
  EXPECT_EQ(dev->ctl->samples(), slab->size());
  std::vector<Vec3f> x, v;
  ASSERT_TRUE(dev->fluid->get_state(x, v).ok());
  std::vector<Index> cpu_bound, gpu_bound, bound;
  const auto gx = by_id(start, x), cx = cpu_frame(morph, &cpu_bound), sx = cpu_frame(s.targets(), nullptr);
  ASSERT_TRUE(dev->ctl->get_bound(bound).ok());
  gpu_bound.assign(bound.size(), kInvalidIndex);
  for (std::size_t i = 0; i < bound.size(); ++i) gpu_bound[start.id[i]] = bound[i];
  const auto apart = sorted_apart(gx, cx, s.c.sp.spacing()), morphed = sorted_apart(cx, sx, s.c.sp.spacing());
  std::size_t same = 0, held = 0;
  for (std::size_t i = 0; i < gpu_bound.size(); ++i)
    same += gpu_bound[i] == cpu_bound[i], held += cpu_bound[i] != kInvalidIndex;
  std::printf("morph sphere (%zu samples) -> slab (%zu) inside the frame (%d sub-steps): GPU - CPU |dx|/d median "
              "%.2e, 90th %.2e, largest %.2e; morphed - unmorphed on the CPU: median %.2e, 90th %.2e; %zu of %zu held, "
              "same nearest sample %zu\n",
              s.c.set.size(), slab->size(), done->substeps, apart[apart.size() / 2],
              apart[apart.size() * 9 / 10], apart.back(), morphed[morphed.size() / 2], morphed[morphed.size() * 9 / 10],
              held, gpu_bound.size(), same);
  EXPECT_GT(held, gpu_bound.size() / 2);
  EXPECT_LT(apart[apart.size() / 2], 1e-3);
  EXPECT_LT(apart[apart.size() * 9 / 10], 1e-2);
  EXPECT_GT(morphed[morphed.size() * 9 / 10], 10 * apart[apart.size() * 9 / 10]);
  EXPECT_GE(same, gpu_bound.size() - gpu_bound.size() / 50);
  for (const std::string& m : dev->ctx->messages()) ADD_FAILURE() << "validation: " << m;
}

// Kinematic corrections (AdaptiveParams::kinematic): the corrections move the fluid without becoming velocity. One
// frame from the formed sphere on both paths with them on: positions and velocities track the CPU's, and the
// velocities differ from the CPU frame without them far more than the paths differ.
TEST(GpuAdaptive, KinematicCorrectionsTrackTheCpuController) {
  Scene s;
  s.params.gather = true;
  sim::PbfSolver solver(s.c.sp, s.c.dom);
  solver.set_cluster_kernels(true);
  s.use(solver);
  const std::optional<sim::ParticleSet> formed = cpu_state(s, solver, 40);
  ASSERT_TRUE(formed.has_value());
  const sim::ParticleSet& start = *formed;
  const double t0 = 40 / 60.0, frame = 1.0 / 60.0;
  control::AdaptiveParams kinematic = s.params;
  kinematic.kinematic = true;
  auto cpu_frame = [&](const control::AdaptiveParams& params, std::vector<Vec3f>& v) {
    sim::ParticleSet q = start;
    auto ctl = control::AdaptiveController::create(s.targets(), s.ctx, params);
    EXPECT_TRUE(ctl.has_value() && solver.advance(q, t0, frame, **ctl).has_value());
    v = by_id(q, q.velocity);
    return by_id(q, q.position);
  };
  auto dev = on_device(s, solver, start, s.targets(), kinematic);
  ASSERT_TRUE(dev.has_value()) << dev.error().message;
  ASSERT_TRUE(dev->fluid->advance(solver, t0, frame).has_value());
  std::vector<Vec3f> x, v, cv, wv;
  ASSERT_TRUE(dev->fluid->get_state(x, v).ok());
  const auto cx = cpu_frame(kinematic, cv);
  cpu_frame(s.params, wv);
  // Velocities in spacings per frame, so that they compare with the positions' spacings.
  const float per_frame = s.c.sp.spacing() / static_cast<float>(frame);
  const auto apart = sorted_apart(by_id(start, x), cx, s.c.sp.spacing());
  const auto v_apart = sorted_apart(by_id(start, v), cv, per_frame), v_kinematic = sorted_apart(cv, wv, per_frame);
  std::printf("kinematic: GPU - CPU |dx|/d median %.2e, 90th %.2e; |dv| in d per frame median %.2e, 90th %.2e; "
              "kinematic - not on the CPU: |dv| median %.2e, 90th %.2e\n",
              apart[apart.size() / 2], apart[apart.size() * 9 / 10], v_apart[v_apart.size() / 2],
              v_apart[v_apart.size() * 9 / 10], v_kinematic[v_kinematic.size() / 2],
              v_kinematic[v_kinematic.size() * 9 / 10]);
  EXPECT_LT(apart[apart.size() / 2], 1e-3);
  EXPECT_LT(apart[apart.size() * 9 / 10], 1e-2);
  EXPECT_LT(v_apart[v_apart.size() * 9 / 10], 1e-2);
  EXPECT_GT(v_kinematic[v_kinematic.size() * 9 / 10], 10 * v_apart[v_apart.size() * 9 / 10]);
  for (const std::string& m : dev->ctx->messages()) ADD_FAILURE() << "validation: " << m;
}

}  // namespace
}  // namespace ff::gpu
