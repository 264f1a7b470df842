#pragma once
// The entry points the front doors (the CLI in app/, the live viewer's server in server/, the Python module in
// python/) call besides run, the live scene and mesh export: sample a mesh into control particles, reconstruct
// particles into a mesh, measure particles against a target, the controllers by name, and a finished run's folder
// read back. A front end includes pipeline/ and plain types of core/ and io/, never a stage
// (tests/architecture/check_includes.py holds that), so a change to a stage's entry point is made here once.
#include "core/error.h"
#include "core/progress.h"
#include "core/types.h"
#include "io/triangle_mesh.h"
#include "pipeline/auto_scene.h"
#include "pipeline/liquid_look.h"
#include "metrics/shape_metrics.h"
#include "sampling/control_set.h"
#include "sampling/samplers.h"
#include "sampling/sampling_params.h"
#include "surface/surface_params.h"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ff::pipeline {

// ---- Sampling a mesh into control particles (`fluidform sample`, Python's sample) ----

/// `params` with the sampler named `method` ("blue-noise", "voxel", "surface") and the sparse-sampling drop boxes
/// `drop_box` (6 numbers a box: min x y z, max x y z) added, then validated. Errors name the option as the caller
/// spells it: `method_option` ("--method" on the command line, "method" in Python).
Status set_sampler(sampling::SamplingParams& params, std::string_view method, std::span<const float> drop_box = {},
                   std::string_view method_option = "--method");

struct SampledMesh {
  sampling::ControlSet set;
  sampling::SampleReport report;
};
/// Control particles of `mesh` (sampling::sample_target, target id 0).
Result<SampledMesh> sample_mesh(const io::TriangleMesh& mesh, const sampling::SamplingParams& params,
                                core::Progress& progress);
/// The mesh file `mesh` sampled and written as a control PLY (density, weight, phi) to `out`, whose folder is checked
/// to be writable before the (possibly long) sampling.
Result<SampledMesh> sample_mesh_file(const std::filesystem::path& mesh, const std::filesystem::path& out,
                                     const sampling::SamplingParams& params, core::Progress& progress);
/// The sampler's name as the CLI and the Python module print it.
std::string_view sampler_name(sampling::Method method);

// ---- Particles to a mesh (the live viewer's surface, Python's reconstruct) ----

/// `points` reconstructed (surface::reconstruct) at particle spacing `spacing` (none: estimated from the points).
Result<io::TriangleMesh> mesh_particles(std::span<const Vec3f> points, std::optional<float> spacing,
                                        const surface::SurfaceParams& params);
/// The iso-surface extraction by name (mc, rmt) into `params`; errors name the choices.
Status set_extraction(surface::SurfaceParams& params, std::string_view name);
/// The extraction's name (marching cubes or tetrahedra), for a log line.
std::string_view extraction_words(const surface::SurfaceParams& params);

// ---- Measuring particles against a target (Python's measure) ----

/// The shape metrics (METHOD §d) of `positions` (particle radius `radius`; flags: controlled or not) against `target`,
/// whose control samples are `samples` (none: sampled at the fluid spacing 2·radius, as a run does).
Result<metrics::FrameMetrics> measure_particles(const io::TriangleMesh& target, std::span<const Vec3f> positions,
                                                std::span<const std::uint8_t> controlled, float radius,
                                                std::optional<std::vector<Vec3f>> samples);

// ---- Controllers by name (the CLI's --controller, the viewer's list) ----

/// Every registered controller's name, in the registry's order.
std::vector<std::string> controller_list();
/// The same, as one line for a help text ("adaptive, none, ...").
std::string controller_names();
bool is_controller(std::string_view name);

// ---- A finished run's folder (`fluidform mesh RUN`, the viewer's playback) ----

/// The water tint of each target in `run_dir`/report.json (none when there is no report). Read defensively (a report
/// is ours, but may be edited): a target without a readable tint keeps the default, so target k always gets material
/// k; values are clamped to [0, 1].
std::vector<Vec3f> run_target_tints(const std::filesystem::path& run_dir);

/// The targets' looks of the run in `run_dir` (its report.json's scene), for `fluidform mesh` on a run's folder: null
/// when no target's appearance is tint or target, or when the report or a target cannot be read (then with one warning:
/// the meshes take the water material and the tints).
struct RunLooks {
  std::vector<TargetGeometry> geometry;  ///< the skins and meshes `looks` points into
  LiquidLooks looks;
};
std::unique_ptr<RunLooks> run_target_looks(const std::filesystem::path& run_dir);

/// What the viewer plays back from a run's folder: its particle frames, and per frame the error rate and sub-step
/// time from metrics.csv (NaN / 0 when unknown), the frame rate from report.json.
struct RunRecording {
  std::vector<std::filesystem::path> frames;
  std::vector<double> error_rate, step_seconds;
  double fps = 60.0;
  bool animation = false;  ///< the folder has animation.glb
  bool report = false;     ///< the folder has report.html
};
Result<RunRecording> open_run(const std::filesystem::path& run_dir);

// ---- GPU devices (`fluidform devices`) ----

/// One Vulkan device (gpu::DeviceInfo, copied so the front doors need not include the stage).
struct GpuDevice {
  int index = 0;
  std::string name, type, driver, api;  ///< type: "discrete", "integrated", "virtual", "cpu", "other"
  std::uint64_t memory_bytes = 0;       ///< the largest device-local heap
  bool compute = false;
};
/// The Vulkan devices of this machine; an Error (one line) when there is no Vulkan loader or driver.
Result<std::vector<GpuDevice>> gpu_devices();

}  // namespace ff::pipeline
