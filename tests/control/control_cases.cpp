#include "control/control_cases.h"

#include "sampling/samplers.h"
#include "support/shapes.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace ff::test {

Case sphere_case() {
  Case c;
  c.mesh = translate(uv_sphere(0.25f, 32), Vec3f(0.0f, 0.45f, 0.0f));
  c.sp.particle_radius = 0.025f;
  sampling::SamplingParams smp;
  smp.spacing = c.sp.spacing();
  smp.method = sampling::Method::Voxel;
  auto set = sampling::sample_target(c.mesh, smp);
  EXPECT_TRUE(set.has_value()) << (set ? "" : set.error().message);
  c.set = std::move(*set);
  c.dom = {Vec3f(-0.6f, 0.0f, -0.6f), Vec3f(0.6f, 1.6f, 0.6f)};
  const float side = 0.3f, h = static_cast<float>(4.0 / 3.0 * 3.14159265 * 0.25 * 0.25 * 0.25 / (side * side));
  sim::FluidSource src;
  src.min = Vec3f(-0.5f * side, 0.75f, -0.5f * side);
  src.max = Vec3f(0.5f * side, 0.75f + h, 0.5f * side);
  c.fluid.push_back(src);
  return c;
}

Outcome simulate(const Case& c, const control::ControllerSpec& spec, int frames, const pose::TargetMotion& motion,
                 const std::vector<std::pair<double, sampling::ControlSet>>& swaps, const Case* measure_against,
                 const control::StrengthTrack& strength) {
  Outcome o;
  sim::ParticleSet p;
  EXPECT_TRUE(sim::fill_sources(c.fluid, c.dom, c.sp.particle_radius, p).ok());
  std::fill(p.target.begin(), p.target.end(), std::uint8_t{0});
  sim::PbfSolver solver(c.sp, c.dom);
  control::ControlContext ctx{c.sp.particle_radius, solver.particle_mass(), c.sp.rest_density, c.sp.gravity, c.dom,
                              c.sp.support()};
  std::vector<control::ControlTarget> targets(1);
  targets[0].set = c.set;
  targets[0].motion = motion;
  targets[0].swaps = swaps;
  targets[0].strength = strength;
  o.control_count = c.set.size();
  auto ctl = control::make_controller(spec, std::move(targets), ctx);
  EXPECT_TRUE(ctl.has_value()) << (ctl ? "" : ctl.error().message);
  if (!ctl) return o.ok = false, o;
  for (int f = 0; f < frames; ++f) {
    auto st = solver.advance(p, f / 60.0, 1.0 / 60.0, **ctl);
    EXPECT_TRUE(st.has_value()) << spec.name << ": " << (st ? "" : st.error().message);
    if (!st) return o.ok = false, o;
  }
  const Case& m = measure_against ? *measure_against : c;
  auto shape = metrics::TargetShape::build(m.mesh, m.set.position, m.set.spacing);
  EXPECT_TRUE(shape.has_value());
  std::vector<std::uint8_t> controlled(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) controlled[i] = p.bound_control[i] != kInvalidIndex;
  const pose::Pose pose = motion.at(frames / 60.0);
  o.m = metrics::measure(*shape, 0, p.position, p.target, controlled, c.sp.particle_radius, pose.rest_from_world(),
                         pose.scale);
  std::vector<std::uint8_t> t;
  sim::sorted_by_id(p, o.x, o.v, t);
  o.bound.assign(p.size(), kInvalidIndex);
  for (std::size_t i = 0; i < p.size(); ++i) o.bound[p.id[i]] = p.bound_control[i];
  return o;
}

}  // namespace ff::test
