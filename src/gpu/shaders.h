#pragma once
// The compute shaders of shaders/*.comp as SPIR-V words, compiled by glslc at build time (src/gpu/CMakeLists.txt).
#include <cstdint>
#include <span>

namespace ff::gpu::shaders {

std::span<const std::uint32_t> grid_count();
std::span<const std::uint32_t> grid_scan();
std::span<const std::uint32_t> grid_scatter();
std::span<const std::uint32_t> grid_order();
std::span<const std::uint32_t> pbf_lambda();
std::span<const std::uint32_t> pbf_delta();
std::span<const std::uint32_t> pbf_force();
std::span<const std::uint32_t> pbf_update();
std::span<const std::uint32_t> frame_check();
std::span<const std::uint32_t> pbf_copy();
std::span<const std::uint32_t> density_error();
std::span<const std::uint32_t> density_decide();
std::span<const std::uint32_t> st_estimate();
std::span<const std::uint32_t> st_smooth();
std::span<const std::uint32_t> vort_omega();
std::span<const std::uint32_t> vort_apply();
std::span<const std::uint32_t> pbf_predict();
std::span<const std::uint32_t> ctl_fill();
std::span<const std::uint32_t> ctl_bonds();
std::span<const std::uint32_t> ctl_accel();
std::span<const std::uint32_t> ctl_spring();
std::span<const std::uint32_t> ctl_lambda();
std::span<const std::uint32_t> ctl_correct();
std::span<const std::uint32_t> ctl_seed_init();
std::span<const std::uint32_t> ctl_seed_flood();
std::span<const std::uint32_t> ctl_gather();

}  // namespace ff::gpu::shaders
