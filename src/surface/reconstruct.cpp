#include "surface/reconstruct.h"

#include "core/timer.h"
#include "surface/cluster_reduce.h"
#include "surface/components.h"
#include "surface/decimate.h"
#include "surface/marching_cubes.h"
#include "surface/marching_tetrahedra.h"
#include "surface/smooth.h"
#include "surface/sparse_field.h"

#include <fmt/format.h>

#include <cmath>
#include <utility>

namespace ff::surface {
namespace {

// The particles and the spacing a surface can be made from.
Status check_input(std::span<const Vec3f> particles, float spacing, const SurfaceParams& params) {
  FF_CHECK(params.validate());
  if (!(std::isfinite(spacing) && spacing > 0.0f))
    return param_error(fmt::format("surface: particle spacing = {} must be finite and > 0", spacing));
  if (particles.empty()) return input_error("surface: no particles to reconstruct a surface from");
  for (std::size_t i = 0; i < particles.size(); ++i)
    if (!particles[i].allFinite())
      return input_error(fmt::format("surface: particle {} has a non-finite position ({}, {}, {})", i, particles[i].x(),
                                     particles[i].y(), particles[i].z()));
  return {};
}

// What every stage's result must pass (bubbles are allowed only when they are kept on purpose).
bool acceptable(const SurfaceParams& params, const MeshCheck& c) {
  return params.remove_cavities ? c.ok() : c.ok_allowing_cavities();
}

// Tiny components removed from the extracted mesh, its vertices' clusters following the vertices.
void remove_tiny_components(McMesh& mc, const SurfaceParams& params, double d, SurfaceStats& st) {
  core::Stopwatch watch;
  const ComponentCleanup cleanup =
      remove_small_components(mc.mesh, params.min_component_volume * d * d * d, params.remove_cavities);
  if (!cleanup.vertex_map.empty()) {
    std::vector<std::uint64_t> cluster(mc.mesh.vertices.size());
    for (std::size_t v = 0; v < cleanup.vertex_map.size(); ++v)
      if (cleanup.vertex_map[v] != kInvalidIndex) cluster[cleanup.vertex_map[v]] = mc.cluster[v];
    mc.cluster = std::move(cluster);
  }
  st.removed_components = cleanup.removed_components;
  st.removed_triangles = cleanup.removed_triangles;
  st.t_components = watch.seconds();
}

// Cluster reduction, merged vertices put back onto the iso-surface; kept only when the result passes `check` and has
// as many components.
void reduce(io::TriangleMesh& mesh, const McMesh& mc, const SparseField& field, const SurfaceParams& params,
            MeshCheck& check, SurfaceStats& st) {
  core::Stopwatch watch;
  ClusterStats cs;
  io::TriangleMesh reduced = cluster_reduce(
      mesh, mc.cluster, kNoCluster, [&](const Vec3f& p) { return field.project(p); }, &cs);
  st.t_reduce = watch.seconds();
  watch.restart();
  const MeshCheck c = check_mesh(reduced);
  st.t_check += watch.seconds();
  if (acceptable(params, c) && c.components == check.components) {
    mesh = std::move(reduced);
    check = c;
    st.clusters_merged = cs.clusters_merged;
    st.clusters_undone = cs.clusters_undone;
    st.reduced_vertices = mesh.vertices.size();
    st.reduced_triangles = mesh.triangles.size();
  } else {
    st.reduction_undone = true;
  }
}

// Smoothing (eq. 20–21, with a Taubin back-step by default), undone when the result fails its check.
void smooth(io::TriangleMesh& mesh, const SurfaceParams& params, double d, MeshCheck& check, SurfaceStats& st) {
  core::Stopwatch watch;
  std::vector<Vec3f> before = mesh.vertices;
  smooth_weighted(mesh, {params.smoothing_passes, params.smoothing_beta,
                         float(params.smoothing_radius * params.cell_size * d), params.smoothing_inflate});
  st.t_smooth = watch.seconds();
  watch.restart();
  const MeshCheck c = check_mesh(mesh);
  st.t_check += watch.seconds();
  if (acceptable(params, c)) {
    check = c;
  } else {
    mesh.vertices = std::move(before);
    st.smoothing_undone = true;
  }
}

// Decimation (it checks itself pass by pass).
void decimate_mesh(io::TriangleMesh& mesh, const SurfaceParams& params, double d, MeshCheck& check, SurfaceStats& st) {
  core::Stopwatch watch;
  DecimateStats ds;
  mesh = decimate(mesh, {float(params.decimate_error * d), params.max_triangles, !params.remove_cavities}, &ds);
  st.t_decimate = watch.seconds();
  st.decimate_passes = ds.passes;
  st.decimate_rejected = ds.rejected_passes;
  st.decimate_error = ds.error;
  st.budget_met = ds.budget_met;
  if (ds.passes > 0) {
    watch.restart();
    check = check_mesh(mesh);
    st.t_check += watch.seconds();
  }
}

}  // namespace

Result<io::TriangleMesh> reconstruct(std::span<const Vec3f> particles, float spacing, const SurfaceParams& params,
                                     SurfaceStats* stats, double max_memory_mib) {
  SurfaceStats st;
  st.particles = particles.size();
  FF_CHECK(check_input(particles, spacing, params));
  const double d = spacing;

  // --- field and extraction (marching cubes, or the tetrahedra of RMT) -------------------------------------------
  core::Stopwatch watch;
  FF_TRY(SparseField field, sparse_field(particles, spacing, params, max_memory_mib));
  st.t_field = watch.seconds();
  st.candidate_blocks = field.candidate_blocks;
  st.surface_blocks = field.keys.size();
  st.field_bytes = field.bytes();
  st.max_field = field.max_value;

  watch.restart();
  const bool tetrahedra = params.extraction == Extraction::MarchingTetrahedra;
  FF_TRY(McMesh mc, tetrahedra ? marching_tetrahedra(field) : marching_cubes(field));
  st.t_mc = watch.seconds();
  st.mc_vertices = mc.mesh.vertices.size();
  st.mc_triangles = mc.mesh.triangles.size();
  st.mc_centres = mc.centre_vertices;

  // --- tiny components --------------------------------------------------------------------------------------------
  remove_tiny_components(mc, params, d, st);

  watch.restart();
  MeshCheck check = check_mesh(mc.mesh);
  st.t_check += watch.seconds();
  if (!acceptable(params, check))
    return numerical_error(fmt::format("surface: marching {} produced a broken mesh (internal error): {}",
                                       tetrahedra ? "tetrahedra" : "cubes", check.summary()));
  io::TriangleMesh mesh = std::move(mc.mesh);

  // --- reduction, merged vertices put back onto the iso-surface ---------------------------------------------------
  // Before smoothing: the merges are judged on the marching-cubes geometry they were derived from, and the
  // projection needs the unsmoothed surface (projecting after smoothing would bring the noise back).
  st.reduced_vertices = mesh.vertices.size();
  st.reduced_triangles = mesh.triangles.size();
  if (params.reduction == Reduction::Cluster && !mesh.triangles.empty()) reduce(mesh, mc, field, params, check, st);
  field = SparseField{};  // the grid is not needed any more: free it before the remaining stages
  mc.cluster = {};

  // --- smoothing (eq. 20–21, with a Taubin back-step by default) ----------------------------------------------------
  if (params.smoothing_passes > 0 && params.smoothing_beta > 0.0f && !mesh.triangles.empty())
    smooth(mesh, params, d, check, st);

  // --- decimation (checks itself pass by pass) ----------------------------------------------------------------------
  if ((params.decimate_error > 0.0f || params.max_triangles > 0) && !mesh.triangles.empty())
    decimate_mesh(mesh, params, d, check, st);
  st.check = check;
  if (stats) *stats = st;
  return mesh;
}

}  // namespace ff::surface
