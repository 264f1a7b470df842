#pragma once
// Scene files (JSON) → a tree of every stage's parameter structs (docs/scenes.md), and back.
//
// {
//   "solver":  { SolverParams fields },                       see sim/solver_params.h
//   "domain":  { "min": [x,y,z], "max": [x,y,z] },            metres
//   "fluid":   [ {"shape": "box", "min": [..], "max": [..], "velocity": [..]},
//                {"shape": "sphere", "center": [..], "radius": R, "velocity": [..]} ],
//   "targets": [ {"mesh": PATH, "scale": S or [sx,sy,sz], "rotate": [deg x,y,z], "translate": [..], "start": T,
//                 "keyframes": [...], "interpolation": "linear", "morph": [{"time": T, "mesh": PATH}]} ],
//   "output":  { "fps": 60, "frames": 120, "checkpoint_every": 10, "velocity": true },
//   "sampling": { SamplingParams fields },                    see sampling/sampling_params.h
//   "controller": { "name": "adaptive", "adaptive": { AdaptiveParams fields }, ... }   see control/registry.h
// }
// Every struct's keys come from its one field list (core/fields.h); `fluidform keys` prints them all with their
// defaults and ranges. A scene with targets may leave out the particle radius, the domain and the fluid: the
// pipeline then sizes them from the targets (pipeline/auto_scene.h), which is what the `auto_*` flags record.
// Unknown keys are errors naming the JSON path and the closest valid key; out-of-range values name the key, the
// value and the range. Mesh paths are relative to the scene file.
#include "control/registry.h"
#include "pose/skinning.h"
#include "control/strength.h"
#include "pose/target_motion.h"
#include "core/error.h"
#include "core/fields.h"
#include "io/load_mesh.h"
#include "sampling/sampling_params.h"
#include "sim/solver_params.h"

#include <nlohmann/json_fwd.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::scene {

enum class Interpolation { Linear, Smooth };
constexpr std::array<core::Choice<Interpolation>, 2> field_choices(Interpolation) {
  return {{{Interpolation::Linear, "linear"}, {Interpolation::Smooth, "smooth"}}};
}

/// How a target's liquid looks in the exported meshes (targets[].appearance, docs/outputs.md):
/// water: a clear, refracting liquid absorbing towards `tint` (GLB: transmission + volume; OBJ: the water MTL);
/// tint: an opaque liquid of the colour `tint`; target: opaque, each vertex the colour of the nearest point of the
/// target's surface (its base-colour texture at that point's UV, else its vertex colours, else its material colour).
/// Tint and target are written as vertex colours (GLB COLOR_0, OBJ `v x y z r g b`).
enum class Appearance { Water, Tint, Target };
constexpr std::array<core::Choice<Appearance>, 3> field_choices(Appearance) {
  return {{{Appearance::Water, "water"}, {Appearance::Tint, "tint"}, {Appearance::Target, "target"}}};
}

/// One target mesh of the scene.
struct TargetSpec {
  std::filesystem::path mesh;  ///< resolved against the scene file's folder
  io::MeshTransform transform; ///< scale, rotate (degrees), translate — applied in that order
  float start = 0.0f;          ///< s, when the target starts to attract fluid. [0, 1e6]
  /// Keyframed motion after the transform (translate/rotate/scale about the target's centre), see
  /// pose/target_motion.h: [{"time": T, "translate": [..], "rotate": [..], "scale": S}, ...].
  std::vector<pose::Keyframe> keyframes;
  Interpolation interpolation = Interpolation::Linear;  ///< between keyframes: linear, or smoothstep ("smooth")
  /// Linear RGB this target's liquid absorbs towards in the exported GLB (its water material's attenuationColor).
  Vec3f tint{0.16f, 0.48f, 0.85f};
  Appearance appearance = Appearance::Water;  ///< the look of its liquid in the exported meshes (see Appearance)
  /// Mesh swaps, "morph": [{"time": T, "mesh": PATH}, ...]: from T on the target is that mesh (same transform).
  struct Swap {
    double time = 0.0;
    std::filesystem::path mesh;
    template <class S, class F>
    static void fields(S& s, F&& f) {
      f("time", s.time, core::required(core::closed(0.0, 1e6, "s; later than the swap before it")));
      f("mesh", s.mesh, core::required(core::plain("the mesh the target becomes")));
    }
  };
  std::vector<Swap> swaps;
  /// A skinned mesh file's clip (pose/skinning.h): {"clip": NAME|INDEX, "speed", "loop", "wrap", "start",
  /// "skinning", "weights", "follow"}. Without a clip the target is not animated, as a mesh without a skin.
  pose::AnimationSpec animation;
  /// Control strength over time (control/strength.h): [{"time": T, "value": S}, ...], S in [0, 1]; none: 1.
  std::vector<control::StrengthKey> strength;

  bool smooth() const { return interpolation == Interpolation::Smooth; }
  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("mesh", s.mesh, required(plain("the target mesh (OBJ, PLY, STL, glTF, FBX, ...), relative to the scene")));
    f("scale", s.transform.scale,
      scalar_ok(either_sign(closed(1e-9, 1e9, "per-axis factor, or one for all three; a negative one mirrors"))));
    f("rotate", s.transform.rotate_deg, closed(-1e6, 1e6, "degrees about x, y, z (in that order)"));
    f("translate", s.transform.translate, closed(-1e9, 1e9, "m"));
    f("start", s.start, closed(0.0, 1e6, "s, when the target starts to attract fluid"));
    f("keyframes", s.keyframes, plain("keyframed motion about the target's centre"));
    f("interpolation", s.interpolation, plain("between keyframes"));
    f("morph", s.swaps, plain("mesh swaps: from each time on the target is that mesh"));
    f("tint", s.tint, closed(0.0, 1.0, "linear RGB its liquid absorbs towards (water), or its colour (tint)"));
    f("appearance", s.appearance, plain("its liquid's look: water (clear), tint (opaque, the tint), target (its colours)"));
    f("animation", s.animation, plain("a skinned mesh file's clip the target plays (its samples follow the skin)"));
    f("strength", s.strength, plain("control strength keyframes: 1 holds, 0 releases the fluid, between softens"));
  }
  Status validate(std::string_view path) const;
};

struct OutputParams {
  double fps = 60.0;          ///< output frames per simulated second. [1, 1000]
  int frames = 120;           ///< output frames to simulate (frame 0 is the initial state). [1, 10^7]
  int checkpoint_every = 10;  ///< write a checkpoint every K frames; 0 = never. [0, 10^7]
  bool velocity = true;       ///< write vx vy vz into the particle PLY files
  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("fps", s.fps, closed(1.0, 1000.0, "output frames per simulated second"));
    f("frames", s.frames, closed(1, 1e7, "frames to simulate (default with targets: until formed)"));
    f("checkpoint_every", s.checkpoint_every, closed(0, 1e7, "a checkpoint every K frames; 0 = never"));
    f("velocity", s.velocity, plain("write vx vy vz into the particle PLY files"));
  }
  Status validate(std::string_view path = "output") const { return core::validate_fields(*this, path); }
};

/// Resource limits, checked before anything is allocated (pipeline/run_budget.h).
struct LimitsParams {
  double max_memory_mb = 0.0;  ///< refuse a run whose memory estimate is larger, MiB; 0 = 80 % of the machine's. [0, 1e9]
  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("max_memory_mb", s.max_memory_mb, core::closed(0.0, 1e9, "MiB a run may need (estimated first); 0 = 80 % of the machine's"));
  }
  Status validate(std::string_view path = "limits") const { return core::validate_fields(*this, path); }
};

/// How the automatic particle count was chosen (pipeline::complete_scene): for report.json and the summary.
struct AutoSizing {
  double count_for_volume = 0.0;  ///< sampling.auto_count: the count for a solid without thin parts
  double count_for_walls = 0.0;   ///< the count that puts 3 spacings across the thinnest wall (0: none thinner)
  double count = 0.0;             ///< the count the spacing was chosen for
  /// "" or what held the count back: "sampling.max_auto_count", "memory", or "skinned" (a scene with a skinned
  /// target keeps auto_count: its liquid follows fast limbs worse at higher counts)
  std::string limited_by;
  int target = -1;                ///< the target with the thinnest wall (-1: none measured)
  double wall = 0.0;              ///< its thickness, m
};

struct Scene {
  std::filesystem::path file;        ///< the scene file ("" when built in code)
  sim::SolverParams solver;
  sim::Domain domain;
  std::vector<sim::FluidSource> fluid;
  std::vector<TargetSpec> targets;
  OutputParams output;
  sampling::SamplingParams sampling;  ///< how targets become control particles (spacing 0 = the fluid spacing d)
  control::ControllerSpec controller; ///< the shape controller ("adaptive" by default)
  LimitsParams limits;                ///< resource limits (not part of the resume hash)
  bool auto_radius = true;            ///< solver.particle_radius was not given: size it from the targets
  bool auto_domain = true;            ///< domain was not given
  bool auto_frames = true;            ///< output.frames was not given: with targets, run until formed (within a cap)
  bool auto_fluid = false;            ///< targets and no fluid list: the fluid is made from the targets
  /// The scene file gave neither sampling.auto_count nor sampling.spacing: the automatic count may rise for thin
  /// walls. False for a scene built in code (its count is what the code set).
  bool auto_resolution = false;
  AutoSizing sizing;                  ///< filled by complete_scene when the radius is automatic
  std::uint64_t hash = 0;            ///< content hash of the simulation-relevant settings (for --resume)

  /// The scene file's top-level keys, each a struct with its own field list.
  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("solver", s.solver, plain("the PBF solver (sim/solver_params.h)"));
    f("domain", s.domain, plain("the box the fluid lives in"));
    f("fluid", s.fluid, plain("fluid sources: boxes and spheres on the particle lattice (default: from the targets)"));
    f("targets", s.targets, plain("the target meshes"));
    f("output", s.output, plain("what the run writes"));
    f("sampling", s.sampling, plain("targets → control particles (sampling/sampling_params.h)"));
    f("controller", s.controller, plain("the shape controller (control/registry.h)"));
    f("limits", s.limits, plain("resource limits, checked before anything is allocated"));
  }
  /// Cross-field checks (every struct's validate(), fluid present, sources in the domain).
  Status validate() const;
};

/// Parses scene JSON text. `base_dir` resolves relative mesh paths.
Result<Scene> parse_scene(std::string_view json_text, const std::filesystem::path& base_dir,
                          std::string_view source_name = "scene");
/// Reads and parses a scene file. Errors name the file.
Result<Scene> load_scene(const std::filesystem::path& file);

/// The scene as a scene file: every key of every struct (mesh paths absolute), so that parsing it again gives the
/// same scene from any folder. What the scene left automatic and the pipeline filled in (particle radius, domain) is
/// written as filled in; an automatic fluid and run length stay automatic (fluid and output.frames left out): the
/// fluid made from the targets is shared out by the volume their samples stand for, a given one by mesh volume.
nlohmann::json scene_to_json(const Scene& scene);

/// Every scene key with its type, default, range and one line ("fluidform keys", the table in docs/scene-keys.md).
std::vector<core::KeyRow> scene_keys();
/// scene_keys() as a Markdown table.
std::string scene_keys_markdown();

}  // namespace ff::scene
