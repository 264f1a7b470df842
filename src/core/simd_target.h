#pragma once
// Which instruction set the pair kernels run on. The kernels (sim/pbf_kernels.cpp, control/adaptive_kernels.cpp)
// are compiled once per x86 target by Google Highway and the best one the CPU has is chosen at run time: AVX-512,
// AVX2 or SSE4 (the floor of the release build, -march=x86-64-v2). Results are bit-identical for any thread count on
// one target; between targets they differ at rounding level (vector width changes the order of the lane sums, and
// AVX2 / AVX-512 fuse multiply-adds). FF_SIMD=sse4|avx2|avx512 pins one, for tests that compare files.
#include "core/error.h"

#include <string>
#include <string_view>
#include <vector>

namespace ff::core {

/// The target the kernels run on now ("AVX2", …).
std::string simd_target();
/// The targets this CPU can run, best first (names as simd_target()).
std::vector<std::string> simd_targets();
/// Pins the kernels to `name` (sse4, avx2, avx512, case-insensitive; "auto" or "" undoes the pin). An unknown name
/// or one this CPU cannot run is an error naming it.
Status select_simd_target(std::string_view name);
/// select_simd_target($FF_SIMD) when the variable is set.
Status select_simd_target_from_env();

}  // namespace ff::core
