#pragma once
// The liquid's look in the exported meshes (issue 46 item 3, scene key targets[].appearance, docs/outputs.md):
// water (the clear material, no vertex colours), tint (every vertex of its liquid the target's `tint`), or target
// (every vertex the colour of the nearest point of its target's surface, posed at the frame's time).
//
// Which target a vertex belongs to: the target of the particle nearest to it within 2 spacings (the particle PLYs
// carry it); a vertex with none there (free fluid) takes the target whose surface is nearest. A vertex of a water
// target is white, so its GLB material (water, COLOR_0 multiplies a white base colour) looks as without colours.
//
// Posed. A keyframed target maps the vertex into its rest frame (the inverse of its pose at the frame's time, as the
// metrics do); a skinned one poses its look's triangles at that time (each look vertex follows the skinned vertex at
// its exact position, as load_mesh welded them); a morphing one uses the look of the mesh it is at that time.
//
// Vertex colours, or UVs into the target's own texture. Vertex colours carry textures, vertex colours and material
// colours alike, for several targets in one mesh, but keep no detail finer than the formed mesh's vertices. A target
// whose whole look is one texture (one target in the scene, one mesh, UVs, no vertex colours) also gets UVs: each
// corner the UV of its nearest target point; a formed triangle whose corners land across a UV seam of the target
// (they disagree with the UV map of the target triangle nearest to its centre, extended over it) takes that one map's
// UVs for all three corners, so it shows its side of the seam instead of sweeping the texture between the charts.
// Which of the two is written is measured on the final mesh (measure_look): UVs when they keep more of the texture
// (bench/RESULTS.md, "Results people look at, third part").
#include "core/error.h"
#include "io/target_look.h"
#include "io/triangle_mesh.h"
#include "io/write_mesh.h"
#include "pipeline/auto_scene.h"
#include "pose/target_motion.h"
#include "sampling/mesh_field.h"
#include "scene/scene.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace ff::pipeline {

struct LiquidLooks {
  struct Phase {
    double from = 0.0;  ///< s: from when the target is this mesh (the first phase: −∞)
    io::TargetLook look;
    std::optional<sampling::MeshField> field;  ///< closest points on the look's triangles, rest pose
    std::vector<Index> skin_vertex;            ///< skinned first phase: per look vertex, its vertex of the skinned mesh
  };
  struct Target {
    scene::Appearance appearance = scene::Appearance::Water;
    Vec3f tint{0.16f, 0.48f, 0.85f};
    std::vector<Phase> phases;  ///< appearance target only
    pose::TargetMotion motion;
    std::shared_ptr<const pose::TargetSkin> skin;  ///< a skinned target's skin (its first phase follows it)
    const io::TriangleMesh* skin_mesh = nullptr;   ///< the mesh the skin's weights belong to (TargetGeometry::mesh)
    /// Its look's one texture, when UVs into it can be written (see above); null: vertex colours only.
    std::shared_ptr<const io::MeshTexture> texture;
  };
  std::vector<Target> targets;
  std::vector<std::string> warnings;  ///< textures that could not be used, looks that could not be read

  /// Whether the meshes get vertex colours: some target is not water.
  bool coloured() const;
  /// The GLB/OBJ material of each target: its water material, or the opaque vertex-coloured one.
  std::vector<io::WaterMaterial> materials() const;
};

/// The looks of `scene`'s targets (`geometry` from load_target_meshes, `motions` from setup_targets, each
/// per target). A look that cannot be read (or a texture) is a warning: that target's liquid takes its material
/// colour, or its tint when nothing of the file can be read. Cost: one Assimp import per mesh of a target whose
/// appearance is "target".
LiquidLooks load_liquid_looks(const scene::Scene& scene, const std::vector<TargetGeometry>& geometry,
                              const std::vector<pose::TargetMotion>& motions);

/// The colour of every vertex of `mesh`, a frame of the liquid at `time` (s). `vertex_target`: per vertex the
/// target of its liquid (≥ the target count: none nearby, the nearest target surface decides); empty: all target 0.
std::vector<Vec3f> liquid_colours(const LiquidLooks& looks, const io::TriangleMesh& mesh,
                                  std::span<const std::uint8_t> vertex_target, double time);

/// Per triangle of `mesh` (a frame of the liquid at `time`), its corners' UVs into the texture of the scene's one target
/// (LiquidLooks::Target::texture); empty when there is none.
std::vector<std::array<io::Vec2f, 3>> liquid_uvs(const LiquidLooks& looks, const io::TriangleMesh& mesh, double time);

/// How close a mesh's look comes to its target's, between its vertices: `points` spread uniformly over its triangles,
/// each compared with the target's colour at its nearest target point (what every vertex is given); mean |difference|
/// per channel in sRGB steps (0–255), through the vertex colours interpolated, and through the UVs into the texture.
struct LookMeasure {
  std::size_t points = 0;
  double vertex_colours = 0.0, uvs = 0.0;
  /// UVs keep clearly more of the target's look (a quarter less difference).
  bool uvs_win() const { return points > 0 && uvs < 0.75 * vertex_colours; }
};
/// `mesh` has colours (liquid_colours) and UVs (liquid_uvs) of the scene's one target; 0 points otherwise.
LookMeasure measure_look(const LiquidLooks& looks, const io::TriangleMesh& mesh, double time, std::size_t points = 20000);

/// Per vertex of `mesh`, the target of the particle nearest to it within `2 d` (`targets`: per particle, ≥ `count`
/// for free fluid); 255 when no targeted particle is that close.
std::vector<std::uint8_t> vertex_targets(const io::TriangleMesh& mesh, std::span<const Vec3f> particles,
                                         std::span<const std::uint8_t> targets, float d, std::size_t count);

}  // namespace ff::pipeline
