#pragma once
// Scene targets → control particles, through a cache: sampling a target is the slow part of a run's
// start, and the same mesh with the same transform and sampling parameters always gives the same set.
#include "core/error.h"
#include "core/progress.h"
#include "scene/scene.h"
#include "sampling/control_set.h"
#include "sampling/samplers.h"

#include <filesystem>

namespace ff::pipeline {

struct TargetControls {
  sampling::ControlSet set;
  sampling::SampleReport report;  ///< filled when sampled now
  bool from_cache = false;
  std::filesystem::path cache_file;
};

/// Key of one target's sampling inputs: mesh file bytes, transform, sampling parameters, format version.
Result<std::uint64_t> sampling_key(const scene::TargetSpec& target, const sampling::SamplingParams& params);

/// Loads `target`'s controls from `cache_dir` when a file with the same key is there; otherwise loads the
/// mesh, samples it and writes the cache file (atomically; a failed write only costs a warning).
Result<TargetControls> sample_target_cached(const scene::TargetSpec& target, const sampling::SamplingParams& params,
                                      std::uint8_t id, const std::filesystem::path& cache_dir, core::Progress& progress);

}  // namespace ff::pipeline
