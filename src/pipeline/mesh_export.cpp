#include "pipeline/mesh_export.h"

#include "io/particle_frames.h"

#include "core/neighbor_grid.h"
#include "core/timer.h"
#include "io/atomic_file.h"
#include "io/picture.h"
#include "io/write_mesh.h"
#include "io/write_ply.h"
#include "io/write_vdb.h"
#include "surface/decimate.h"
#include "surface/mesh_check.h"
#include "pipeline/report_page.h"
#include "surface/reconstruct.h"

#include <fmt/format.h>
#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <string_view>

namespace ff::pipeline {
namespace fs = std::filesystem;

namespace {

constexpr const char* kMtlName = "water.mtl";  // beside the OBJs in OUT/mesh
constexpr const char* kTextureName = "liquid_texture.png";  // the liquid's texture, when it has UVs (MTL map_Kd)

// "spacing D" in a particle PLY's header comments (written by `run`), or 0.
float spacing_from_comments(const io::ParticleFrame& f) {
  for (const auto& c : f.comments) {
    if (c.rfind("spacing ", 0) != 0) continue;
    try {
      const float d = std::stof(c.substr(8));
      if (d > 0.0f && std::isfinite(d)) return d;
    } catch (...) {
    }
  }
  return 0.0f;
}

}  // namespace

Status MeshOptions::validate() const {
  FF_CHECK(params.validate("surface"));
  if (!(spacing >= 0.0f) || !std::isfinite(spacing)) return param_error(fmt::format("mesh: spacing {} must be ≥ 0", spacing));
  if (every < 1) return param_error(fmt::format("mesh: --every {} must be ≥ 1", every));
  if (!(fps > 0.0) || !std::isfinite(fps)) return param_error(fmt::format("mesh: fps {} must be > 0", fps));
  if (!(max_memory_mib >= 0.0 && max_memory_mib <= 1e9))
    return param_error(fmt::format("mesh: --max-memory {} must be in [1, 1e9] MiB", max_memory_mib));
  return {};
}

Result<float> estimate_spacing(std::span<const Vec3f> points) {
  if (points.size() < 2) return input_error("cannot estimate the particle spacing from fewer than 2 particles; give --spacing");
  Aabb box;
  for (const auto& p : points) box.extend(p);
  const Vec3f ext = box.max - box.min;
  // A radius that certainly holds a neighbour in a fluid: twice the spacing of the points spread over their box.
  const double vol = std::max<double>(double(ext.x()) * ext.y() * ext.z(), 1e-30);
  float r = static_cast<float>(2.0 * std::cbrt(vol / double(points.size())));
  r = std::max(r, 1e-6f * std::max(1.0f, ext.maxCoeff()));
  std::vector<Vec3f> probe;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / 4096);
  for (std::size_t i = 0; i < points.size(); i += stride) probe.push_back(points[i]);
  for (int attempt = 0; attempt < 4; ++attempt, r *= 2.0f) {
    core::NeighborGrid grid(r);
    grid.build(points);
    core::NeighborList nl;
    grid.query(points, probe, r, nl);
    std::vector<float> nn;
    for (std::size_t q = 0; q < probe.size(); ++q) {
      float best = INFINITY;
      for (Index j : nl.of(q)) {
        const float d2 = (points[j] - probe[q]).squaredNorm();
        if (d2 > 0.0f) best = std::min(best, d2);
      }
      if (std::isfinite(best)) nn.push_back(std::sqrt(best));
    }
    if (nn.size() * 2 >= probe.size()) {
      std::nth_element(nn.begin(), nn.begin() + static_cast<std::ptrdiff_t>(nn.size() / 2), nn.end());
      return nn[nn.size() / 2];
    }
  }
  return input_error("cannot estimate the particle spacing (the particles are too scattered); give --spacing");
}

namespace {

// The frames to mesh: every k-th and the last, or only the last.
std::vector<std::size_t> chosen_frames(std::size_t count, const MeshOptions& o) {
  std::vector<std::size_t> chosen;
  if (o.final_only) {
    chosen.push_back(count - 1);
  } else {
    for (std::size_t k = 0; k < count; k += static_cast<std::size_t>(o.every)) chosen.push_back(k);
    if (chosen.back() != count - 1) chosen.push_back(count - 1);
  }
  return chosen;
}

// The spacing: given, else from the last frame's header, else estimated from it.
Result<float> frame_spacing(const io::ParticleFrame& last, const fs::path& file, const MeshOptions& o, MeshSummary& sum) {
  float d = o.spacing;
  if (d == 0.0f) d = spacing_from_comments(last);
  if (d == 0.0f) {
    auto est = estimate_spacing(last.positions);
    if (!est) return Error{est.error().kind, fmt::format("{}: {}", file.string(), est.error().message)};
    d = *est;
    sum.spacing_estimated = true;
    spdlog::info("mesh: particle spacing estimated from the particles: {:.4g} m (give --spacing to set it)", d);
  }
  return d;
}

// Reconstructs the chosen frames (and writes their VDBs; the OBJs are written once the look is chosen), several at
// once, one thread each: reconstruct() is deterministic for any thread count, so the meshes do not depend on how
// frames are spread.
// Per triangle, the target of the particle nearest to its centre (within 2d; farther, or free fluid: the target of
// the nearest targeted particle within that range, else 0), for per-target materials.
std::vector<std::uint8_t> triangle_targets(const io::TriangleMesh& m, const io::ParticleFrame& f, float d,
                                           std::size_t targets) {
  std::vector<std::uint8_t> out(m.triangles.size(), 0);
  if (f.targets.size() != f.positions.size() || m.triangles.empty()) return out;
  std::vector<Vec3f> centres(m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    centres[t] = (m.vertices[m.triangles[t][0]] + m.vertices[m.triangles[t][1]] + m.vertices[m.triangles[t][2]]) / 3.0f;
  const float r = 2.0f * d;
  core::NeighborGrid grid(r);
  grid.build(f.positions);
  core::NeighborList nl;
  grid.query(f.positions, centres, r, nl);
  for (std::size_t t = 0; t < centres.size(); ++t) {
    float best = INFINITY;
    for (Index j : nl.of(t)) {
      if (f.targets[j] >= targets) continue;  // free fluid (255) has no tint of its own
      const float d2 = (f.positions[j] - centres[t]).squaredNorm();
      if (d2 < best) best = d2, out[t] = f.targets[j];
    }
  }
  return out;
}

Result<std::vector<io::TriangleMesh>> reconstruct_frames(std::span<const fs::path> frames, std::span<const std::size_t> chosen,
                                                         const fs::path& out, float d, const MeshOptions& o,
                                                         surface::SurfaceStats& last_stats,
                                                         std::vector<std::vector<std::uint8_t>>& labels,
                                                         core::Progress& progress) {
  std::vector<io::TriangleMesh> meshes(chosen.size());
  const bool label = o.target_tints.size() > 1 && o.glb && !o.final_only;  // only the GLB has per-target materials
  if (label) labels.assign(chosen.size(), {});
  std::vector<Error> errors(chosen.size());
  std::vector<char> failed(chosen.size(), 0);
  std::vector<surface::SurfaceStats> stats(chosen.size());
  std::vector<double> colouring(chosen.size(), 0.0), uv_seconds(chosen.size(), 0.0);  // s per frame on the look (UVs)
  progress.begin("meshing", chosen.size());
  std::atomic<std::size_t> done{0};
  std::atomic<bool> cancelled{false};
  const int threads = std::min<int>(omp_get_max_threads(), static_cast<int>(chosen.size()));
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    if (cancelled.load()) continue;
    const fs::path& file = frames[chosen[c]];
    auto f = io::read_particles_ply(file);
    Result<io::TriangleMesh> mesh = f ? surface::reconstruct(f->positions, d, o.params, &stats[c], o.max_memory_mib) : Result<io::TriangleMesh>(f.error());
    if (!mesh) {
      failed[c] = 1;
      errors[c] = Error{mesh.error().kind, fmt::format("{}: {}", file.string(), mesh.error().message)};
    } else {
      meshes[c] = std::move(*mesh);
      if (label) labels[c] = triangle_targets(meshes[c], *f, d, o.target_tints.size());
      const long k = io::frame_number(file);
      if (o.looks != nullptr && o.looks->coloured()) {
        const std::size_t n = o.looks->targets.size();
        const std::vector<std::uint8_t> vt =
            n > 1 ? vertex_targets(meshes[c], f->positions, f->targets, d, n) : std::vector<std::uint8_t>();
        const double time = double(k >= 0 ? k : static_cast<long>(chosen[c])) / o.fps;
        const core::Stopwatch watch;
        meshes[c].colours = liquid_colours(*o.looks, meshes[c], vt, time);
        const double coloured = watch.seconds();
        meshes[c].corner_uv = liquid_uvs(*o.looks, meshes[c], time);  // kept or dropped by pick_look
        if (!meshes[c].corner_uv.empty()) meshes[c].texture = o.looks->targets[0].texture;
        colouring[c] = watch.seconds(), uv_seconds[c] = colouring[c] - coloured;
      }
      if (o.vdb) {
        // The level set at the meshing grid's resolution (cell_size spacings), a band of 3 voxels each side.
        io::VdbOptions v;
        v.voxel_size = o.params.cell_size * d;
        const fs::path p = out / "vdb" / fmt::format("frame_{:05d}.vdb", k >= 0 ? k : static_cast<long>(chosen[c]));
        if (meshes[c].triangles.empty()) {
          // No surface (spray only): no grid; the frame's number is simply missing from OUT/vdb.
        } else if (auto st = io::write_level_set_vdb(p, meshes[c], v); !st.ok()) {
          failed[c] = 1, errors[c] = st.error();
        }
      }
    }
    const std::size_t now = ++done;
#pragma omp critical(ff_mesh_progress)
    if (!progress.tick(now)) cancelled = true;
  }
  progress.end();
  if (cancelled) return Error{Error::Kind::Cancelled, "mesh: cancelled"};
  for (std::size_t c = 0; c < chosen.size(); ++c)
    if (failed[c]) return errors[c];
  last_stats = stats.back();
  if (o.looks != nullptr && o.looks->coloured())
    spdlog::info("mesh: the liquid's look on {} frame(s) in {:.2f} s (summed over frames; its UVs {:.2f} s)",
                 chosen.size(), std::accumulate(colouring.begin(), colouring.end(), 0.0),
                 std::accumulate(uv_seconds.begin(), uv_seconds.end(), 0.0));
  return meshes;
}

// Vertex colours or UVs (pipeline/liquid_look.h): measured on the final mesh; the UVs of every frame are dropped
// unless they keep clearly more of the target's look there.
LookMeasure pick_look(std::vector<io::TriangleMesh>& meshes, const MeshOptions& o, double final_time) {
  LookMeasure m;
  if (o.looks != nullptr && !meshes.empty() && !meshes.back().corner_uv.empty())
    m = measure_look(*o.looks, meshes.back(), final_time);
  const bool uvs = m.uvs_win();  // not measured (no UVs, or a last frame with no surface): no frame keeps UVs
  if (m.points > 0)
    spdlog::info("mesh: the liquid's look as {} (against the target's colour between the vertices of the final mesh: "
                 "UVs {:.2f}, vertex colours {:.2f} sRGB steps, mean over {} points)",
                 uvs ? "UVs into its target's texture" : "vertex colours", m.uvs, m.vertex_colours, m.points);
  if (!uvs)
    for (io::TriangleMesh& mesh : meshes) mesh.corner_uv.clear(), mesh.texture.reset();
  return m;
}

// The material every OBJ names (OUT/mesh/water.mtl; Blender's OBJ importer reads it into a Principled BSDF) and, when
// the meshes have UVs, their texture beside it (OUT/mesh/liquid_texture.png, which an earlier export may have left
// otherwise). Returns the PNG's size (the same bytes animation.glb embeds), 0 without one. Written once the meshes are
// made, so a failed export leaves an earlier one's OBJs and material together.
Result<std::size_t> write_obj_material(const fs::path& out, const io::MeshTexture* t) {
  if (t == nullptr) {
    std::error_code gone;
    fs::remove(out / "mesh" / kTextureName, gone);
    FF_CHECK(io::write_file_atomic(out / "mesh" / kMtlName, io::encode_mtl(io::WaterMaterial{})));
    return std::size_t{0};
  }
  FF_TRY(const std::vector<std::uint8_t> png, io::encode_png(t->image));
  FF_CHECK(io::write_file_atomic(out / "mesh" / kTextureName, png));
  FF_CHECK(io::write_file_atomic(out / "mesh" / kMtlName, io::encode_mtl(io::WaterMaterial{}, kTextureName, t->factor)));
  return png.size();
}

// The chosen frames' OBJs (OUT/mesh/frame_NNNNN.obj), several at once.
Status write_frame_objs(std::span<const fs::path> frames, std::span<const std::size_t> chosen,
                        const std::vector<io::TriangleMesh>& meshes, const fs::path& out) {
  std::vector<Status> status(chosen.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    const fs::path& file = frames[chosen[c]];
    const long k = io::frame_number(file);
    const fs::path p = out / "mesh" / fmt::format("frame_{:05d}.obj", k >= 0 ? k : static_cast<long>(chosen[c]));
    status[c] = io::write_obj(p, meshes[c], true, fmt::format("fluidform mesh of {}", file.filename().string()), kMtlName);
  }
  for (const Status& st : status) FF_CHECK(st);
  return {};
}

// Every particle frame, in order, as one PC2 point cache and its frame-0 point mesh. Particles are written sorted
// by id, so entry i is the same particle in every frame; a frame with fewer particles (an emitter still filling)
// is padded with the last frame's positions of the missing ones.
Status write_point_cache(std::span<const fs::path> frames, const io::ParticleFrame& last, const fs::path& out) {
  const std::size_t n = last.positions.size();
  io::Pc2Writer pc2;
  FF_CHECK(pc2.open(out / "particles.pc2", n, 0.0f));
  for (std::size_t k = 0; k < frames.size(); ++k) {
    auto f = io::read_particles_ply(frames[k]);
    if (!f) return f.error();
    std::vector<Vec3f> x = std::move(f->positions);
    if (x.size() > n)
      return input_error(fmt::format("{}: {} particles, more than the last frame's {}: particles were removed, a point "
                                     "cache cannot follow",
                                     frames[k].string(), x.size(), n));
    for (std::size_t i = x.size(); i < n; ++i) x.push_back(last.positions[i]);
    if (k == 0) {
      io::ParticleFrameView v;
      v.positions = x;
      v.comment = "fluidform particles: frame-0 point mesh for particles.pc2 (Blender: Mesh Cache modifier, PC2)";
      FF_CHECK(io::write_particles_ply(out / "particles_frame0.ply", v));
    }
    FF_CHECK(pc2.add(x));
  }
  return pc2.finish();
}

// The page's lighter copy of an animation.glb over kPageAnimationBytes (report_page.h): at most kPageFrames frames
// (every k-th, and the last), each decimated to an equal share of a triangle budget sized from the full file's bytes
// per triangle (70 % of the page's limit), colours carried. Decimation cannot always reach its budget (a pass that
// would pinch the surface is refused, and a liquid full of tunnels refuses many: measured on the duck's forming, some
// frames stayed at 2–3× the budget): a frame still over twice its share is left out of the copy (the timeline skips
// it), and so is a frame with per-triangle materials or that is not a clean mesh; then the largest frames (never the
// last) are left out until the estimate fits. A copy that still does not fit is not written, and the page says the
// animation is too large.
constexpr std::size_t kPageFrames = 30;
Status write_page_animation(const fs::path& out, const std::vector<io::TriangleMesh>& meshes, const io::GlbOptions& g,
                            std::size_t full_bytes) {  // without the bytes of an embedded texture (the copy has none)
  const core::Stopwatch watch;
  std::size_t triangles = 0;
  for (const auto& m : meshes) triangles += m.triangles.size();
  const std::size_t step = (meshes.size() + kPageFrames - 1) / kPageFrames;
  std::vector<std::size_t> keep;
  for (std::size_t k = 0; k < meshes.size(); k += step) keep.push_back(k);
  if (keep.back() != meshes.size() - 1) keep.push_back(meshes.size() - 1);
  const double per_triangle = double(full_bytes) / double(std::max<std::size_t>(triangles, 1));
  const auto budget = static_cast<std::size_t>(0.7 * double(kPageAnimationBytes) / per_triangle / double(keep.size()));
  std::vector<io::TriangleMesh> light;
  io::GlbOptions lg = g;
  lg.times.clear(), lg.triangle_material.clear();
  for (const std::size_t k : keep) {
    const io::TriangleMesh& m = meshes[k];
    io::TriangleMesh d;
    if (m.triangles.size() <= budget) {
      d = m;
    } else if (g.triangle_material.empty() && surface::check_mesh(m).ok_allowing_cavities()) {
      surface::DecimateParams p;
      p.max_triangles = std::max<std::size_t>(budget, 200);
      p.allow_cavities = true;
      d = surface::decimate(m, p);
      surface::carry_colours(m, d);
    }
    d.corner_uv.clear(), d.texture.reset();  // the page's copy is light: vertex colours, no texture image
    if (d.triangles.empty() != m.triangles.empty() || d.triangles.size() > 2 * std::max<std::size_t>(budget, 200)) continue;
    lg.times.push_back(g.times.empty() ? double(k) / g.fps : g.times[k]);
    if (!g.triangle_material.empty()) lg.triangle_material.push_back(g.triangle_material[k]);
    light.push_back(std::move(d));
  }
  std::size_t total = 0;
  for (const auto& m : light) total += m.triangles.size();
  while (light.size() > 1 && double(total) * per_triangle > 0.9 * double(kPageAnimationBytes)) {
    const auto big = std::max_element(light.begin(), light.end() - 1, [](const auto& a, const auto& b) {
      return a.triangles.size() < b.triangles.size();
    });
    const auto at = big - light.begin();
    total -= big->triangles.size();
    light.erase(big), lg.times.erase(lg.times.begin() + at);
    if (!lg.triangle_material.empty()) lg.triangle_material.erase(lg.triangle_material.begin() + at);
  }
  if (light.empty()) return {};
  FF_TRY(const std::vector<std::uint8_t> bytes, io::encode_glb(light, lg));
  if (bytes.size() > kPageAnimationBytes) {
    spdlog::info("mesh: no lighter animation for report.html ({:.1f} MB even decimated)", double(bytes.size()) / 1e6);
    return {};
  }
  FF_CHECK(io::write_file_atomic(out / kPageAnimationFile, bytes));
  spdlog::info("mesh: {} for report.html: {} of {} frames, {} triangles, {:.1f} MB, in {:.2f} s", kPageAnimationFile,
               light.size(), meshes.size(), total, double(bytes.size()) / 1e6, watch.seconds());
  return {};
}

}  // namespace

Result<MeshSummary> export_meshes(std::span<const fs::path> frames, const fs::path& out, const MeshOptions& o,
                                  core::Progress& progress) {
  FF_CHECK(o.validate());
  if (frames.empty()) return input_error("mesh: no particle frames");
  core::Stopwatch watch;
  MeshSummary sum;
  sum.frames_read = frames.size();
  FF_CHECK(io::ensure_writable_dir(out));
  FF_CHECK(io::ensure_writable_dir(out / "mesh"));
  // A mesh killed mid-write (kill -9) left its temporary files: the rerun clears them (writers still running keep
  // theirs).
  if (const auto n = io::remove_stale_temp_files(out)) spdlog::info("mesh: removed {} partial file(s) left in {}", n, out.string());
  if (o.vdb) {
    if (!io::vdb_available()) return param_error("--vdb: this build has no OpenVDB (install libopenvdb-dev and rebuild)");
    FF_CHECK(io::ensure_writable_dir(out / "vdb"));
  }

  const std::vector<std::size_t> chosen = chosen_frames(frames.size(), o);
  auto last = io::read_particles_ply(frames.back());
  if (!last) return last.error();
  FF_TRY(const float d, frame_spacing(*last, frames.back(), o, sum));
  sum.spacing = d;

  surface::SurfaceStats last_stats;
  std::vector<std::vector<std::uint8_t>> labels;
  FF_TRY(std::vector<io::TriangleMesh> meshes, reconstruct_frames(frames, chosen, out, d, o, last_stats, labels, progress));
  sum.frames_meshed = chosen.size();
  const long last_k = io::frame_number(frames.back());
  sum.look = pick_look(meshes, o, double(last_k >= 0 ? last_k : static_cast<long>(frames.size() - 1)) / o.fps);
  FF_TRY(const std::size_t texture_bytes, write_obj_material(out, meshes.back().corner_uv.empty() ? nullptr : meshes.back().texture.get()));
  if (o.frame_objs && !o.final_only) FF_CHECK(write_frame_objs(frames, chosen, meshes, out));

  const io::TriangleMesh& fin = meshes.back();
  const auto check = surface::check_mesh(fin);
  sum.final_triangles = fin.triangles.size();
  sum.final_vertices = fin.vertices.size();
  sum.mc_triangles_final = last_stats.mc_triangles;
  sum.final_ok = check.ok();
  sum.final_genus = check.genus;
  sum.final_components = check.components;
  if (fin.triangles.empty())
    spdlog::warn("mesh: the last frame made no surface (too few particles close together); final.obj is empty");
  FF_CHECK(io::write_obj(out / "mesh" / "final.obj", fin, true,
                         fmt::format("fluidform editable mesh of {}\nspacing {:.6g} m; {}", frames.back().filename().string(), d,
                                     check.summary()),
                         kMtlName));

  if (o.glb && !o.final_only) {
    io::GlbOptions g;
    g.fps = o.fps;
    g.quantize = o.quantize;
    std::vector<io::WaterMaterial> materials;
    if (o.looks != nullptr && o.looks->targets.size() == o.target_tints.size()) {
      materials = o.looks->materials();
    } else {
      for (const Vec3f& tint : o.target_tints) materials.emplace_back().tint = tint;
    }
    if (materials.size() == 1) g.material = materials[0];
    if (materials.size() > 1) g.materials = materials, g.triangle_material = labels;
    for (std::size_t c : chosen) {
      const long k = io::frame_number(frames[c]);
      g.times.push_back(double(k >= 0 ? k : static_cast<long>(c)) / o.fps);
    }
    FF_TRY(const std::vector<std::uint8_t> glb, io::encode_glb(meshes, g));
    FF_CHECK(io::write_file_atomic(out / "animation.glb", glb));
    // The page's copy is derived from this animation.glb: an earlier run's is removed first.
    std::error_code ec;
    fs::remove(out / kPageAnimationFile, ec);
    if (glb.size() > kPageAnimationBytes) FF_CHECK(write_page_animation(out, meshes, g, glb.size() - std::min(glb.size(), texture_bytes)));
  }
  if (o.pc2 && !o.final_only) FF_CHECK(write_point_cache(frames, *last, out));
  sum.seconds = watch.seconds();
  return sum;
}

}  // namespace ff::pipeline
