#include "pipeline/run_budget.h"

#include "core/memory.h"
#include "sampling/samplers.h"
#include "sampling/sdf_grid.h"
#include "sim/emitter.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace ff::pipeline {

nlohmann::json RunEstimate::to_json() const {
  return {{"fluid_particles", fluid_particles},
          {"control_samples", control_samples},
          {"memory_mib", std::round(memory_mib)},
          {"sdf_grids_mib", std::round(sdf_mib)},
          {"memory_limit_mib", std::round(limit_mib)}};
}

RunEstimate estimate_run(const scene::Scene& scene, const std::vector<TargetGeometry>& targets) {
  RunEstimate e;
  const float d = scene.solver.spacing();
  e.fluid_particles = sim::estimate_particle_count(scene.fluid, scene.domain, d);
  const float dc = scene.sampling.spacing > 0.0f ? scene.sampling.spacing : d;
  double samples = 0.0;
  for (const auto& t : targets) {
    // What the samples stand for: the covered cells once complete_scene has counted them (its fluid is less).
    const double v = t.cells_volume > 0.0 ? t.cells_volume : t.volume;
    samples += sampling::estimate_sample_count(t.volume > 0.0, v, t.area, dc);
  }
  e.control_samples = static_cast<std::size_t>(std::min(samples, 1e18));
  // The targets' SDF grids (sampling/sdf_grid.h, at most kAutoSdfNodes nodes each, the sampler's kSamplerSdfNodes): the metrics keep one per target
  // for the run (4 bytes a node), and sampling builds one at a time (16 bytes a node at the peak of its build).
  // Next to the samples they are small for a solid (~20 nodes per sample); for a thin shape in a large box, or
  // a sheet, they are most of the memory.
  double sdf_bytes = 0.0, sdf_build_peak = 0.0;
  for (const auto& t : targets) {
    const float metric_margin = 3.0f * d, sample_margin = 2.0f * dc;
    sdf_bytes += 4.0 * sampling::sdf_node_count(t.box, sampling::auto_sdf_spacing(t.box, metric_margin, d), metric_margin);
    const float sample_sdf = sampling::auto_sdf_spacing(t.box, sample_margin, dc, sampling::kSamplerSdfNodes);
    sdf_build_peak = std::max(sdf_build_peak, 16.0 * sampling::sdf_node_count(t.box, sample_sdf, sample_margin));
  }
  e.sdf_mib = (sdf_bytes + sdf_build_peak) / (1024.0 * 1024.0);
  e.memory_mib = kBaseMib + (kFluidKib * double(e.fluid_particles) + kSampleKib * samples) / 1024.0 + e.sdf_mib;
  // A million particles or a few GiB: minutes per frame on a laptop, worth saying before it starts.
  e.large = e.fluid_particles + e.control_samples > 1'000'000 || e.memory_mib > 4096.0;
  return e;
}

double memory_limit_mib(const scene::Scene& scene, std::optional<double> override_mib) {
  if (override_mib) return *override_mib;
  if (scene.limits.max_memory_mb > 0.0) return scene.limits.max_memory_mb;
  const double machine = core::machine_memory_mib();
  return machine > 0.0 ? 0.8 * machine : 16384.0;  // unknown machine: 80 % of 20 GiB
}

Result<RunEstimate> check_run_budget(const scene::Scene& scene, const std::vector<TargetGeometry>& targets,
                                     std::optional<double> override_mib) {
  RunEstimate e = estimate_run(scene, targets);
  e.limit_mib = memory_limit_mib(scene, override_mib);
  if (e.memory_mib > e.limit_mib)
    return param_error(fmt::format(
        "the run would need about {:.0f} MiB ({} fluid particles, {} control samples at spacing {:g} m, {:.0f} MiB of "
        "SDF grids), more than the limit of {:.0f} MiB; increase solver.particle_radius, shrink the fluid, or raise "
        "limits.max_memory_mb / --max-memory",
        e.memory_mib, e.fluid_particles, e.control_samples, scene.solver.spacing(), e.sdf_mib, e.limit_mib));
  return e;
}

}  // namespace ff::pipeline
