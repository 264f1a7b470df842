#pragma once
// Scene files (JSON) → a tree of every stage's parameter structs (DESIGN.md "Scene").
//
// {
//   "solver":  { SolverParams fields },                       see sim/solver_params.h
//   "domain":  { "min": [x,y,z], "max": [x,y,z] },            metres
//   "fluid":   [ {"shape": "box", "min": [..], "max": [..], "velocity": [..]},
//                {"shape": "sphere", "center": [..], "radius": R, "velocity": [..]} ],
//   "targets": [ {"mesh": PATH, "scale": S or [sx,sy,sz], "rotate": [deg x,y,z], "translate": [..], "start": T} ],
//   "output":  { "fps": 60, "frames": 120, "checkpoint_every": 10, "velocity": true },
//   "sampling": { SamplingParams fields },                    see sampling/sampling_params.h
//   "controller": { "name": "adaptive", "adaptive": { AdaptiveParams fields } }   see control/
// }
// A scene with targets may leave out the particle radius, the domain and the fluid: the app then sizes
// them from the targets (app/auto_scene.h), which is what the `auto_*` flags record.
// Every key has a default; unknown keys are errors naming the JSON path and the closest valid key;
// out-of-range values name the key, the value and the range. Mesh paths are relative to the scene file.
#include "core/error.h"
#include "io/load_mesh.h"
#include "control/registry.h"
#include "sampling/sampling_params.h"
#include "sim/solver_params.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::io {

/// One target mesh of the scene (control of targets arrives with the sampling and controller stages).
struct TargetSpec {
  std::filesystem::path mesh;  ///< resolved against the scene file's folder
  MeshTransform transform;     ///< scale, rotate (degrees), translate — applied in that order
  float start = 0.0f;          ///< s, when the target starts to attract fluid. [0, 1e6]
  /// Keyframed motion after the transform (translate/rotate/scale about the target's centre), see
  /// control/target_motion.h: [{"time": T, "translate": [..], "rotate": [..], "scale": S}, ...].
  std::vector<control::Keyframe> keyframes;
  bool smooth = false;         ///< "interpolation": "smooth" (smoothstep) or "linear" (default)
  /// Mesh swaps, "morph": [{"time": T, "mesh": PATH}, ...]: from T on the target is that mesh (same transform).
  struct Swap {
    double time = 0.0;
    std::filesystem::path mesh;
  };
  std::vector<Swap> swaps;
};

struct OutputParams {
  double fps = 60.0;          ///< output frames per simulated second. [1, 1000]
  int frames = 120;           ///< output frames to simulate (frame 0 is the initial state). [1, 10^7]
  int checkpoint_every = 10;  ///< write a checkpoint every K frames; 0 = never. [0, 10^7]
  bool velocity = true;       ///< write vx vy vz into the particle PLY files
  Status validate(std::string_view path = "output") const;
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
  bool auto_radius = true;            ///< solver.particle_radius was not given: size it from the targets
  bool auto_domain = true;            ///< domain was not given
  bool auto_frames = true;            ///< output.frames was not given: with targets, run until formed (within a cap)
  std::uint64_t hash = 0;            ///< content hash of the simulation-relevant settings (for --resume)

  /// Cross-field checks (every struct's validate(), fluid present, sources in the domain).
  Status validate() const;
};

/// Parses scene JSON text. `base_dir` resolves relative mesh paths.
Result<Scene> parse_scene(std::string_view json_text, const std::filesystem::path& base_dir,
                          std::string_view source_name = "scene");
/// Reads and parses a scene file. Errors name the file.
Result<Scene> load_scene(const std::filesystem::path& file);

}  // namespace ff::io
