#pragma once
// Particle frames → editable meshes and mesh animations (docs/outputs.md): `fluidform mesh` and the meshing at the end of
// `run`. Reads particle PLYs, reconstructs the chosen frames (surface::reconstruct, several frames at once), and
// writes, all atomically:
//   OUT/mesh/frame_NNNNN.obj   one mesh per meshed frame (NNNNN: the particle frame's number)
//   OUT/mesh/final.obj         the last frame's mesh: the editable mesh for Blender, Mixamo, Unity
//   OUT/mesh/water.mtl         the water material the OBJs name (io::WaterMaterial; the GLB carries the same)
//   OUT/mesh/liquid_texture.png  the target's texture the OBJs' UVs index, when the liquid wears it (liquid_look.h)
//   OUT/animation.glb          the meshed frames as one glTF 2.0 mesh animation (io/write_mesh.h)
//   OUT/particles.pc2          every particle frame as a Blender point cache, played by the Mesh Cache modifier
//   OUT/particles_frame0.ply   on this point mesh (the first frame's particles)
//   OUT/vdb/frame_NNNNN.vdb    with `vdb`: each meshed frame's level set (OpenVDB, grid "surface"), for Blender's
//                              volume objects and Houdini
#include "core/error.h"
#include "core/progress.h"
#include "core/types.h"
#include "surface/surface_params.h"
#include "pipeline/liquid_look.h"

#include <filesystem>
#include <span>
#include <vector>

namespace ff::pipeline {

struct MeshOptions {
  surface::SurfaceParams params;
  float spacing = 0.0f;     ///< particle spacing d (m); 0: from the frames' header ("spacing D"), else estimated
  int every = 1;            ///< mesh every k-th frame (and always the last); ≥ 1
  bool final_only = false;  ///< mesh only the last frame (final.obj; no per-frame meshes, no animation)
  bool frame_objs = true;   ///< write mesh/frame_NNNNN.obj
  bool glb = true;          ///< write animation.glb
  bool pc2 = true;          ///< write particles.pc2 and particles_frame0.ply
  bool quantize = true;     ///< KHR_mesh_quantization in the GLB
  bool vdb = false;         ///< write OUT/vdb/frame_NNNNN.vdb for every meshed frame (voxel = the surface cell)
  /// The water tint of each target (scene targets[].tint). One: the GLB's material takes it. Several: one material
  /// per target, each triangle of a frame getting the material of the target of the particle nearest to it.
  std::vector<Vec3f> target_tints;
  /// The targets' looks (pipeline/liquid_look.h); when one is not water, every mesh written gets vertex colours and
  /// the GLB its targets' materials. Null: water, as the tints say. Not owned.
  const LiquidLooks* looks = nullptr;
  double fps = 60.0;        ///< frame rate of the animation and the cache
  double max_memory_mib = 0.0;  ///< bound on one frame's field grid (surface::reconstruct); 0: 80 % of the machine's

  Status validate() const;
};

struct MeshSummary {
  std::size_t frames_read = 0, frames_meshed = 0;
  float spacing = 0.0f;
  bool spacing_estimated = false;
  std::size_t final_triangles = 0, final_vertices = 0, mc_triangles_final = 0;
  bool final_ok = false;     ///< the final mesh is closed, 2-manifold, outward, no degenerate triangles
  int final_genus = 0;
  std::size_t final_components = 0;
  double seconds = 0.0;      ///< wall time of the whole export
  /// Vertex colours or UVs, measured on the final mesh (points 0: the look had no texture to index, or none).
  LookMeasure look;
};

/// Median nearest-neighbour distance of (up to 4096 of) the points: the spacing of a fluid near rest.
Result<float> estimate_spacing(std::span<const Vec3f> points);

Result<MeshSummary> export_meshes(std::span<const std::filesystem::path> frames, const std::filesystem::path& out,
                                  const MeshOptions& options, core::Progress& progress);

}  // namespace ff::pipeline
