#pragma once
// The skinned tests' common start: one target from a skinned file playing a clip, the scene completed and its samples
// set up (weighted and skinned) exactly as a run does it.
#include "pipeline/auto_scene.h"
#include "pipeline/scene_setup.h"

#include <filesystem>
#include <string>

namespace ff::test {

struct SkinnedSetup {
  scene::Scene scene;
  pipeline::TargetSetup setup;
  const pipeline::TargetShapes::Skinned& skinned() const { return *setup.shapes[0].skinned; }
};

/// `mesh` scaled by `scale`, playing `clip`, ~`auto_count` samples (cached under `dir`). Errors as the pipeline's.
inline Result<SkinnedSetup> skinned_setup(const std::filesystem::path& mesh, const std::string& clip, float scale,
                                          const std::filesystem::path& dir, std::size_t auto_count = 4000) {
  SkinnedSetup s;
  scene::TargetSpec t;
  t.mesh = mesh;
  t.transform.scale = Vec3f::Constant(scale);
  t.animation.clip = clip;
  s.scene.targets.push_back(t);
  s.scene.auto_radius = true;
  s.scene.sampling.auto_count = auto_count;
  FF_TRY(auto geometry, pipeline::load_target_meshes(s.scene));
  FF_CHECK(pipeline::complete_scene(s.scene, geometry));
  FF_TRY(s.setup, pipeline::setup_targets(s.scene, geometry, dir / "cache", dir, core::null_progress()));
  if (!s.setup.shapes[0].skinned) return input_error(mesh.string() + ": not skinned");
  return s;
}

}  // namespace ff::test
