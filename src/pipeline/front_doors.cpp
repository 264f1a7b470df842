#include "pipeline/front_doors.h"

#include "control/registry.h"
#include "gpu/context.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "io/load_mesh.h"
#include "io/particle_frames.h"
#include "io/write_mesh.h"
#include "metrics/report.h"
#include "pipeline/mesh_export.h"
#include "sampling/control_io.h"
#include "scene/scene.h"
#include "surface/reconstruct.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>

namespace ff::pipeline {
namespace fs = std::filesystem;
using nlohmann::json;

Status set_sampler(sampling::SamplingParams& params, std::string_view method, std::span<const float> drop_box,
                   std::string_view method_option) {
  const auto m = sampling::parse_method(method);
  if (!m)
    return param_error(
        fmt::format("{} {} is not one of {}", method_option, method, core::choice_names(params.method)));
  params.method = *m;
  if (drop_box.size() % 6 != 0) return param_error("--drop-box takes 6 numbers per box: min x y z, max x y z");
  for (std::size_t i = 0; i < drop_box.size(); i += 6) {
    sampling::DropBox b;
    b.min = Vec3f(drop_box[i], drop_box[i + 1], drop_box[i + 2]);
    b.max = Vec3f(drop_box[i + 3], drop_box[i + 4], drop_box[i + 5]);
    params.sparse.drop_boxes.push_back(b);
  }
  return params.validate();
}

Result<SampledMesh> sample_mesh(const io::TriangleMesh& mesh, const sampling::SamplingParams& params,
                                core::Progress& progress) {
  SampledMesh out;
  FF_TRY(out.set, sampling::sample_target(mesh, params, 0, &out.report, progress));
  return out;
}

Result<SampledMesh> sample_mesh_file(const fs::path& mesh, const fs::path& out, const sampling::SamplingParams& params,
                                     core::Progress& progress) {
  // The output's folder is checked before the (possibly long) sampling.
  FF_CHECK(io::ensure_writable_dir(out.has_parent_path() ? out.parent_path() : fs::path(".")));
  FF_TRY(io::TriangleMesh m, io::load_mesh(mesh));
  FF_TRY(SampledMesh s, sample_mesh(m, params, progress));
  FF_CHECK(sampling::write_controls_ply(out, s.set));
  return s;
}

std::string_view sampler_name(sampling::Method method) { return sampling::method_name(method); }

Result<io::TriangleMesh> mesh_particles(std::span<const Vec3f> points, std::optional<float> spacing,
                                        const surface::SurfaceParams& params) {
  if (spacing) return surface::reconstruct(points, *spacing, params);
  FF_TRY(const float d, estimate_spacing(points));
  return surface::reconstruct(points, d, params);
}

Status set_extraction(surface::SurfaceParams& params, std::string_view name) {
  auto e = surface::parse_extraction(name);
  if (!e) return param_error("--extraction " + e.error().message);
  params.extraction = *e;
  return {};
}

std::string_view extraction_words(const surface::SurfaceParams& params) {
  return params.extraction == surface::Extraction::MarchingTetrahedra ? "marching tetrahedra" : "marching cubes";
}

Result<metrics::FrameMetrics> measure_particles(const io::TriangleMesh& target, std::span<const Vec3f> positions,
                                                std::span<const std::uint8_t> controlled, float radius,
                                                std::optional<std::vector<Vec3f>> samples) {
  float d_c = 2.0f * radius;
  std::vector<Vec3f> controls;
  if (!samples) {
    // As a run does: the target sampled at the fluid spacing d = 2r (METHOD §0: d_c = d).
    sampling::SamplingParams params;
    params.spacing = d_c;
    FF_TRY(sampling::ControlSet set, sampling::sample_target(target, params));
    controls = std::move(set.position);
  } else {
    controls = std::move(*samples);
    if (auto est = estimate_spacing(controls); est) d_c = *est;
  }
  FF_TRY(metrics::TargetShape shape, metrics::TargetShape::build(target, controls, d_c));
  const std::vector<std::uint8_t> ids(positions.size(), 0);
  return metrics::measure(shape, 0, positions, ids, controlled, radius);
}

std::vector<std::string> controller_list() {
  std::vector<std::string> out;
  for (const auto& e : control::registry()) out.emplace_back(e.name);
  return out;
}

std::string controller_names() { return control::controller_names(); }

bool is_controller(std::string_view name) { return control::find_controller(name) != nullptr; }

std::vector<Vec3f> run_target_tints(const fs::path& run_dir) {
  std::vector<Vec3f> tints;
  std::error_code ec;
  if (!fs::is_regular_file(run_dir / "report.json", ec)) return tints;
  std::ifstream in(run_dir / "report.json");
  const auto report = json::parse(in, nullptr, false);
  if (report.is_object() && report.contains("scene") && report["scene"].is_object() &&
      report["scene"].contains("targets") && report["scene"]["targets"].is_array())
    for (const auto& t : report["scene"]["targets"]) {
      Vec3f tint = io::WaterMaterial{}.tint;
      if (t.is_object() && t.contains("tint") && t["tint"].is_array() && t["tint"].size() == 3)
        for (int a = 0; a < 3; ++a)
          if (t["tint"][a].is_number()) tint[a] = std::clamp(t["tint"][a].get<float>(), 0.0f, 1.0f);
      tints.push_back(tint);
    }
  return tints;
}

std::unique_ptr<RunLooks> run_target_looks(const fs::path& run_dir) {
  std::error_code ec;
  if (!fs::is_regular_file(run_dir / "report.json", ec)) return nullptr;
  std::ifstream in(run_dir / "report.json");
  const auto report = json::parse(in, nullptr, false);
  if (!report.is_object() || !report.contains("scene")) return nullptr;
  auto scene = scene::parse_scene(report["scene"].dump(), "/", "report.json's scene");
  if (!scene) return nullptr;
  bool any = false;
  for (const auto& t : scene->targets) any |= t.appearance != scene::Appearance::Water;
  if (!any) return nullptr;
  auto geometry = load_target_meshes(*scene);
  if (!geometry) {
    spdlog::warn("mesh: the targets' looks are not used: {}", geometry.error().message);
    return nullptr;
  }
  auto out = std::make_unique<RunLooks>();
  out->geometry = std::move(*geometry);
  std::vector<pose::TargetMotion> motions;  // as the run posed them: about each target's box centre
  for (std::size_t t = 0; t < scene->targets.size(); ++t)
    motions.push_back({scene->targets[t].keyframes, scene->targets[t].smooth(),
                       0.5f * (out->geometry[t].box.min + out->geometry[t].box.max)});
  out->looks = load_liquid_looks(*scene, out->geometry, motions);
  return out;
}

Result<RunRecording> open_run(const fs::path& out) {
  RunRecording r;
  FF_TRY(r.frames, io::particle_frames(out));
  r.animation = fs::is_regular_file(out / "animation.glb");
  r.report = fs::is_regular_file(out / "report.html");
  std::ifstream rep(out / "report.json");
  if (rep) {
    const json j = json::parse(rep, nullptr, false);
    if (!j.is_discarded() && j.contains("scene") && j["scene"].contains("output") && j["scene"]["output"]["fps"].is_number())
      r.fps = j["scene"]["output"]["fps"].get<double>();
  }
  r.error_rate.assign(r.frames.size(), NAN);
  r.step_seconds.assign(r.frames.size(), 0.0);
  const io::CsvTable csv = io::read_csv(out / "metrics.csv");
  const std::size_t c_frame = csv.column(metrics::column::frame), c_err = csv.column(metrics::column::error_rate),
                    c_step = csv.column(metrics::column::step_time);
  for (const auto& v : csv.rows) {
    if (c_frame >= v.size()) continue;
    const long f = std::strtol(v[c_frame].c_str(), nullptr, 10);
    if (f < 0 || f >= long(r.frames.size())) continue;
    if (c_err < v.size()) r.error_rate[std::size_t(f)] = std::strtod(v[c_err].c_str(), nullptr);
    if (c_step < v.size()) r.step_seconds[std::size_t(f)] = std::strtod(v[c_step].c_str(), nullptr);
  }
  return r;
}

Result<std::vector<GpuDevice>> gpu_devices() {
  FF_TRY(std::vector<gpu::DeviceInfo> found, gpu::list_devices());
  std::vector<GpuDevice> out;
  for (const gpu::DeviceInfo& d : found) out.push_back({d.index, d.name, d.type, d.driver, d.api, d.memory_bytes, d.compute});
  return out;
}

}  // namespace ff::pipeline
