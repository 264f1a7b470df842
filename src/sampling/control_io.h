#pragma once
// Control particles as PLY (`fluidform sample` output, the run's sample cache): x y z and the float
// properties density (ρ_c), weight (ω), phi (φ̃); the per-target values (spacing, support, mass, centre,
// target, and a cache key) go into header comments "fluidform-controls key=value ...".
#include "core/error.h"
#include "sampling/control_set.h"

#include <cstdint>
#include <filesystem>

namespace ff::sampling {

/// Writes atomically. `key` (0 = none) identifies the inputs the set was made from (the cache checks it).
Status write_controls_ply(const std::filesystem::path& path, const ControlSet& set, std::uint64_t key = 0);

/// Reads a file written by write_controls_ply; `key` receives the stored key (0 when absent).
Result<ControlSet> read_controls_ply(const std::filesystem::path& path, std::uint64_t* key = nullptr);

}  // namespace ff::sampling
