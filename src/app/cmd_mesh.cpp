// `fluidform mesh INPUT -o OUT`: particle frames reconstructed into meshes, a GLB animation and a Blender point cache.
#include "app/cli.h"
#include "app/progress_bar.h"
#include "io/particle_frames.h"
#include "pipeline/front_doors.h"
#include "pipeline/mesh_export.h"

#include <spdlog/spdlog.h>

#include <memory>

namespace ff::app {
namespace fs = std::filesystem;

namespace {

struct MeshCli {
  fs::path input, out;
  pipeline::MeshOptions mesh;
  bool no_glb = false, no_pc2 = false, no_frames = false, final_only = false, no_quantize = false;
  std::string extraction = "mc";
};

int run_mesh(MeshCli& o) {
  o.mesh.glb = !o.no_glb, o.mesh.pc2 = !o.no_pc2, o.mesh.frame_objs = !o.no_frames, o.mesh.final_only = o.final_only;
  o.mesh.quantize = !o.no_quantize;
  if (auto st = pipeline::set_extraction(o.mesh.params, o.extraction); !st.ok()) return fail(st.error());
  if (auto st = o.mesh.validate(); !st.ok()) return fail(st.error());
  auto frames = io::particle_frames(o.input);
  if (!frames) return fail(frames.error());
  // A run's output folder: its targets' water tints from the run's report (one material per target in the GLB).
  o.mesh.target_tints = pipeline::run_target_tints(o.input);
  // ... and their looks (targets[].appearance), read again from the targets' files.
  const auto looks = pipeline::run_target_looks(o.input);
  if (looks) o.mesh.looks = &looks->looks;
  spdlog::info("mesh: {} particle frame(s) from {} -> {}", frames->size(), o.input.string(), o.out.string());
  ProgressBar bar(stderr);
  auto sum = pipeline::export_meshes(*frames, o.out, o.mesh, bar);
  if (!sum) return fail(sum.error());
  spdlog::info("mesh: {} frame(s) meshed in {:.2f} s at spacing {:.4g} m; final.obj: {} triangles, {} vertices ({} from "
               "{}), {}, genus {}, {} component(s) -> {}",
               sum->frames_meshed, sum->seconds, sum->spacing, sum->final_triangles, sum->final_vertices,
               sum->mc_triangles_final,
               pipeline::extraction_words(o.mesh.params),
               sum->final_ok ? "watertight and manifold" : "NOT watertight/manifold", sum->final_genus,
               sum->final_components, (o.out / "mesh" / "final.obj").string());
  return sum->final_ok ? 0 : fail(numerical_error("mesh: the final mesh failed its checks"));
}

}  // namespace

Command add_mesh(CLI::App& app) {
  auto o = std::make_shared<MeshCli>();
  auto* mesh = app.add_subcommand("mesh", "reconstruct particle frames into meshes, a GLB animation and a Blender point cache");
  mesh->add_option("input", o->input, "a particle PLY, a folder of frame_NNNNN.ply, or a run's output folder")->required();
  mesh->add_option("-o,--out", o->out, "output folder (mesh/, animation.glb, particles.pc2)")->required();
  mesh->add_option("--every", o->mesh.every, "mesh every k-th frame (and the last)")->capture_default_str();
  mesh->add_flag("--final-only", o->final_only, "mesh only the last frame (mesh/final.obj)");
  mesh->add_flag("--vdb", o->mesh.vdb, "also write each meshed frame's level set: OUT/vdb/frame_NNNNN.vdb (OpenVDB)");
  mesh->add_option("--spacing", o->mesh.spacing, "particle spacing d in metres (default: from the frames' header, or estimated)");
  mesh->add_option("--triangles", o->mesh.params.max_triangles, "triangle budget per mesh (0: none)")->capture_default_str();
  mesh->add_option("--cell", o->mesh.params.cell_size, "grid cell size in spacings")->capture_default_str();
  mesh->add_option("--smoothing", o->mesh.params.smoothing_passes, "smoothing passes (paper eq. 20-21)")->capture_default_str();
  mesh->add_option("--extraction", o->extraction,
                   "iso-surface extraction: mc (marching cubes) or rmt (regularised marching tetrahedra)")
      ->capture_default_str();
  mesh->add_option("--fps", o->mesh.fps, "frames per second of the animation")->capture_default_str();
  mesh->add_option("--max-memory", o->mesh.max_memory_mib,
                   "MiB one frame's field grid may need, checked before it is filled (default: 80 % of the machine's)")
      ->check(CLI::Range(1.0, 1e9));
  mesh->add_flag("--no-glb", o->no_glb, "do not write animation.glb");
  mesh->add_flag("--no-pc2", o->no_pc2, "do not write particles.pc2 / particles_frame0.ply");
  mesh->add_flag("--no-frames", o->no_frames, "do not write mesh/frame_NNNNN.obj");
  mesh->add_flag("--no-quantize", o->no_quantize, "store float positions and normals in the GLB");
  return {mesh, [o] { return run_mesh(*o); }};
}

}  // namespace ff::app
