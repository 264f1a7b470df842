// `fluidform sample MESH -o CONTROLS.ply`: a mesh sampled into control particles (PLY with density, weight, phi).
#include "app/cli.h"
#include "app/progress_bar.h"
#include "io/atomic_file.h"
#include "io/load_mesh.h"
#include "sampling/control_io.h"
#include "sampling/samplers.h"

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
  const auto m = sampling::parse_method(o.method);
  if (!m)
    return fail(param_error(fmt::format("--method {} is not one of {}", o.method, core::choice_names(o.params.method))));
  o.params.method = *m;
  if (o.drop_box.size() % 6 != 0) return fail(param_error("--drop-box takes 6 numbers per box: min x y z, max x y z"));
  for (std::size_t i = 0; i < o.drop_box.size(); i += 6) {
    sampling::DropBox b;
    b.min = Vec3f(o.drop_box[i], o.drop_box[i + 1], o.drop_box[i + 2]);
    b.max = Vec3f(o.drop_box[i + 3], o.drop_box[i + 4], o.drop_box[i + 5]);
    o.params.sparse.drop_boxes.push_back(b);
  }
  if (auto st = o.params.validate(); !st.ok()) return fail(st.error());
  // Check the output before the (possibly long) sampling.
  const fs::path dir = o.out.has_parent_path() ? o.out.parent_path() : fs::path(".");
  if (auto st = io::ensure_writable_dir(dir); !st.ok()) return fail(st.error());
  auto mesh = io::load_mesh(o.mesh);
  if (!mesh) return fail(mesh.error());
  ProgressBar bar(stderr);
  sampling::SampleReport rep;
  auto set = sampling::sample_target(*mesh, o.params, 0, &rep, bar);
  if (!set) return fail(set.error());
  for (const auto& w : rep.warnings) spdlog::warn("{}", w);
  if (auto st = sampling::write_controls_ply(o.out, *set); !st.ok()) return fail(st.error());
  spdlog::info("{} control particles ({}, spacing {:g} m, volume {:g} m^3, {} dropped) in {:.2f} s -> {}", set->size(),
               sampling::method_name(rep.method), rep.spacing, rep.volume, rep.dropped, rep.seconds, o.out.string());
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
