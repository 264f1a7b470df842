#pragma once
// The memory budget of a run, checked before the fluid, the samples or any grid is allocated: a scene whose sizes
// (particle spacing, fluid sources, targets) would need more memory than the machine has fails with one line that
// names the estimate, the limit and the knob, instead of dying in the allocator; a large one says so up front.
#include "core/error.h"
#include "pipeline/auto_scene.h"
#include "scene/scene.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <vector>

namespace ff::pipeline {

/// What a run will hold, before it starts.
struct RunEstimate {
  std::size_t fluid_particles = 0;   ///< from the fluid sources on the lattice (sim::estimate_particle_count)
  std::size_t control_samples = 0;   ///< the targets' volume (or area, for sheets) at the sampling spacing
  double sdf_mib = 0.0;              ///< of which the targets' SDF grids
  double memory_mib = 0.0;           ///< estimated peak resident memory
  double limit_mib = 0.0;            ///< the limit it was checked against
  bool large = false;                ///< worth a word before the run starts
  nlohmann::json to_json() const;
};

/// Peak memory model, from the default bunny's measured peaks (10k particles + 10k samples: 40 MiB; 99k + 100k:
/// 269 MiB) and the solver's own 170 bytes per particle (bench_pbf_step): a base, then per fluid particle
/// (solver, frame writing, checkpoint) and per control sample (its fluid pairs within H_c, the bond lists).
inline constexpr double kBaseMib = 15.0, kFluidKib = 0.6, kSampleKib = 2.0;

/// The estimate of a completed scene (after complete_scene) with `targets` its geometry.
RunEstimate estimate_run(const scene::Scene& scene, const std::vector<TargetGeometry>& targets);

/// The limit in MiB: `override_mib` (--max-memory) if given, else scene.limits.max_memory_mb if > 0, else 80 % of
/// the machine's memory.
double memory_limit_mib(const scene::Scene& scene, std::optional<double> override_mib);

/// The estimate, checked against the limit: a Param error naming both and the knobs when it is over.
Result<RunEstimate> check_run_budget(const scene::Scene& scene, const std::vector<TargetGeometry>& targets,
                                     std::optional<double> override_mib);

}  // namespace ff::pipeline
