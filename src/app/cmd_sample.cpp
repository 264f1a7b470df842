// `fluidform sample MESH -o CONTROLS.ply`: a mesh sampled into control particles (PLY with density, weight, phi).
#include "app/cli.h"
#include "app/progress_bar.h"
#include "pipeline/front_doors.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <memory>

namespace ff::app {
namespace fs = std::filesystem;

namespace {

struct SampleCli {
  fs::path mesh, out;
  std::string method = "blue-noise";
  std::vector<float> drop_box;  // 6 numbers per box
  sampling::SamplingParams params;
};

int run_sample(SampleCli& o) {
  if (auto st = pipeline::set_sampler(o.params, o.method, o.drop_box); !st.ok()) return fail(st.error());
  ProgressBar bar(stderr);
  auto s = pipeline::sample_mesh_file(o.mesh, o.out, o.params, bar);
  if (!s) return fail(s.error());
  for (const auto& w : s->report.warnings) spdlog::warn("{}", w);
  const auto& rep = s->report;
  spdlog::info("{} control particles ({}, spacing {:g} m, volume {:g} m^3, {} dropped) in {:.2f} s -> {}", s->set.size(),
               pipeline::sampler_name(rep.method), rep.spacing, rep.volume, rep.dropped, rep.seconds, o.out.string());
  // Where the time went (SampleReport's stages), so a slow sampling says which stage to blame.
  spdlog::info("  stages: mesh field {:.2f} s, SDF grid {:.2f} s, candidates + elimination {:.2f} s, relaxation {:.2f} s, "
               "spacing repair {:.2f} s (+{} -{}), weights {:.2f} s",
               rep.t_field, rep.t_sdf, rep.t_init, rep.t_relax, rep.t_repair, rep.repaired_added, rep.repaired_dropped,
               rep.t_weights);
  return 0;
}

}  // namespace

Command add_sample(CLI::App& app) {
  auto o = std::make_shared<SampleCli>();
  auto* sample = app.add_subcommand("sample", "sample a mesh into control particles (PLY with density, weight, phi)");
  sample->add_option("mesh", o->mesh, "mesh file (any format Assimp reads)")->required();
  sample->add_option("-o,--out", o->out, "output PLY file")->required();
  sample->add_option("--spacing", o->params.spacing, "sample spacing d in metres (default: about --count samples)");
  sample->add_option("--count", o->params.auto_count, "samples aimed at when --spacing is not given")->capture_default_str();
  sample->add_option("--method", o->method, core::choice_names(o->params.method))->capture_default_str();
  sample->add_option("--seed", o->params.seed, "random seed")->capture_default_str();
  sample->add_option("--relax-steps", o->params.relax_steps, "blue-noise relaxation steps")->capture_default_str();
  sample->add_option("--max-samples", o->params.max_samples, "refuse to make more samples")->capture_default_str();
  sample->add_option("--drop-fraction", o->params.sparse.drop_fraction,
                     "sparse sampling: remove this fraction of the samples at random");
  sample->add_option("--drop-box", o->drop_box, "sparse sampling: remove the samples in the box x0 y0 z0 x1 y1 z1 (repeatable)")
      ->expected(6)
      ->allow_extra_args(false);
  return {sample, [o] { return run_sample(*o); }};
}

}  // namespace ff::app
