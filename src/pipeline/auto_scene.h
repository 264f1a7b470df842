#pragma once
// Completes a scene that names only its targets (docs/scenes.md: the smallest scene is {"targets":[{"mesh":...}]}):
//   particle spacing  d = ∛(V / auto_count): the targets hold ~auto_count (10k) control samples and the fluid
//                     kFluidCellShare of as many particles (METHOD §0: d_c = d); when the scene names no count,
//                     more where a target's thinnest wall would be under kWallSpacings spacings across (up to
//                     sampling.max_auto_count);
//   fluid             one column per target, of its fluid's volume, over the middle of its footprint, a spacing
//                     over the targets' highest point under it (its top; a container's floor), so it pours down
//                     through the target's control band (METHOD §a.10: control only reaches H_c);
//   domain            the targets and columns with a margin; the floor one control support below the lowest
//                     target, so the formed shape is held by the control, not by the floor.
// Mesh units are metres whatever the model's size. Given keys are never overridden.
#include "pose/skinning.h"
#include "core/error.h"
#include "scene/scene.h"
#include "io/triangle_mesh.h"
#include "sampling/mesh_field.h"
#include "sampling/thickness.h"
#include "sim/particle_set.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ff::pipeline {

/// Spacings across a target's thinnest wall that the automatic count aims at, and under which a wall is named
/// (issue 44: fewer come out of the simulation and the surface reconstruction with holes).
inline constexpr double kWallSpacings = 3.0;

/// A target mesh in its scene pose, with what the layout needs.
struct TargetGeometry {
  io::TriangleMesh mesh;
  std::optional<sampling::MeshField> field;  ///< inside/outside of `mesh` (built once, for the layout)
  double volume = 0.0;        ///< m³ (0 for an open sheet); after complete_scene with an automatic fluid, its fluid's
  double cells_volume = 0.0;  ///< m³: the lattice cells its solid covers, what its samples stand for (complete_scene)
  double area = 0.0;    ///< m²
  Aabb box;
  /// The skin of a target whose scene gives it an animation clip (io/skin.h; the clip found): null otherwise.
  std::shared_ptr<const pose::TargetSkin> skin;
  /// Its thinnest walls (complete_scene; nullopt for an open sheet): what a spacing must resolve.
  std::optional<sampling::Thickness> thickness;
};

/// The skin of a target with an animation clip, for `mesh` (load_mesh's, the target's transform applied). Errors
/// name the target: a file without bones, an unknown clip (naming the clips there are), a malformed skin.
Result<std::shared_ptr<const pose::TargetSkin>> load_target_skin(const scene::TargetSpec& spec,
                                                                    const io::TriangleMesh& mesh, std::size_t i);

/// The smallest share of its bind volume that `mesh` (world, bind pose, closed) keeps over `skin`'s clip, posed at
/// `samples` clip times spread over the clip: Σ signed tetrahedra of the posed mesh over the bind mesh's (≤ 1; 1
/// when no pose loses volume, or for a mesh without volume). huesitos.fbx: 0.88.
double posed_volume_share(const pose::TargetSkin& skin, const io::TriangleMesh& mesh, int samples = 64);

/// How far `skin`'s clip ends from where it starts: the largest distance between a vertex of `mesh` (world, bind pose)
/// posed at the clip's first and at its last key time, over the bind mesh's box diagonal (0 for a clip that cycles;
/// huesitos.fbx 0.79, X/anim_test.x 0.16). ClipWrap::Auto plays a clip back and forth above kClipSeamTolerance.
double clip_seam(const pose::TargetSkin& skin, const io::TriangleMesh& mesh);

/// Loads every target with its transform (and the skin of an animated one). Errors name the target.
Result<std::vector<TargetGeometry>> load_target_meshes(const scene::Scene& scene);

/// The share of its covered lattice cells (sampling::lattice_cells) a closed target's automatic fluid fills: one rule
/// for every shape and resolution (an open sheet gets one particle per sample). All of them overfill a figure on thin
/// legs: bench_scenes' star at 10k with 100 % of its cells as fluid formed, then drained 3 % out under its feet for
/// good; with 98 % it never formed, with 97 % only at 9.97 s, with 95.5 % at 1.6 s; the thin-walled vase with 101 %
/// never formed. bench/RESULTS.md, "Detail at scale, third part", has the family.
inline constexpr double kFluidCellShare = 0.955;

/// Fills what the scene left out (auto_radius, auto_domain, an empty fluid list) from the targets. With an
/// automatic fluid, each target's `volume` becomes its fluid's: kFluidCellShare of the lattice cells its solid covers
/// at the sampling spacing (sampling::lattice_cells), sparse-sampling drops removed
/// (an open sheet's: one spacing³ per surface sample), which is what the fluid is sized and shared by. An animated
/// target's is that times its posed mesh's smallest share of its bind volume over the clip (posed_volume_share), so
/// that its fluid fits inside it at every pose. Each closed target's thinnest walls are measured into its
/// `thickness`. Each automatic column holds its target's volume to the particle (sim::boxes_for_count on the
/// domain's lattice), stacked above any column before it whose footprint it overlaps, and an automatic domain is
/// raised to keep 2 H_c above the tallest.
Status complete_scene(scene::Scene& scene, std::vector<TargetGeometry>& targets);

/// One line when target k's thinnest walls (TargetGeometry::thickness) are under 3 control spacings (they may come out
/// of the simulation with holes): where, how thin, and the spacing and `sampling.auto_count` that would resolve them.
std::optional<std::string> thin_wall_warning(const scene::Scene& s, std::size_t k, const TargetGeometry& t);

/// Shares the fluid out among the targets by volume (METHOD: "fluid is shared out by volume"): target t gets
/// round(N V_t / ΣV) particles, the ones nearest its centre among those not yet taken, larger targets first.
/// One target: every particle. No targets: all stay free (kFreeFluid).
void assign_targets(sim::ParticleSet& particles, const std::vector<TargetGeometry>& targets);

}  // namespace ff::pipeline
