#pragma once
// The small scene the controller tests share: a sphere target (d = 0.05 m, ~520 samples) floating above the floor
// with a column of its volume on top, and a runner that steps any registered controller on it and measures the
// result against the target (METHOD §d).
#include "control/registry.h"
#include "io/triangle_mesh.h"
#include "metrics/shape_metrics.h"
#include "sim/emitter.h"
#include "sim/pbf_solver.h"

#include <utility>
#include <vector>

namespace ff::test {

struct Case {
  io::TriangleMesh mesh;
  sampling::ControlSet set;
  sim::SolverParams sp;
  sim::Domain dom;
  std::vector<sim::FluidSource> fluid;
};

/// A sphere of radius 0.25 m floating 0.2 m above the floor, and a column of the same volume standing on top of
/// it (the layout the app makes for a scene of only a target).
Case sphere_case();

struct Outcome {
  metrics::FrameMetrics m;
  std::vector<Vec3f> x, v;       ///< sorted by particle id
  std::vector<Index> bound;      ///< bound_control, sorted by particle id
  std::size_t control_count = 0;
  bool ok = true;                ///< every frame stepped without error
};

/// Runs `spec` on the case for `frames` frames of 1/60 s, then measures against `measure_against` (default: c). The
/// target's control strength follows `strength` (no keys: 1).
Outcome simulate(const Case& c, const control::ControllerSpec& spec, int frames, const pose::TargetMotion& motion = {},
                 const std::vector<std::pair<double, sampling::ControlSet>>& swaps = {},
                 const Case* measure_against = nullptr, const control::StrengthTrack& strength = {});

}  // namespace ff::test
