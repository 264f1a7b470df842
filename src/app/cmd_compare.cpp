// `fluidform compare SCENE.json`: every controller on one scene, one fresh process each, the paper's Table 3 columns.
#include "app/cli.h"
#include "pipeline/compare.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <memory>

namespace ff::app {

namespace {

struct CompareCli {
  pipeline::CompareOptions compare;
  std::string controllers;  // comma-separated; empty = every registered controller
  int frames = 0;
  double max_memory = 0.0;
};

int run_compare(CompareCli& o) {
  // Every name is checked before anything runs or is written: a typo must not cost a long table.
  if (!o.controllers.empty()) {
    auto names = pipeline::parse_controller_list(o.controllers);
    if (!names) return fail(names.error());
    o.compare.controllers = std::move(*names);
  }
  if (o.frames > 0) o.compare.frames = o.frames;
  if (o.max_memory > 0.0) o.compare.max_memory_mib = o.max_memory;
  auto table = pipeline::run_compare(o.compare);
  if (!table) return fail(table.error());
  fmt::print(stdout, "{}", pipeline::table_markdown(*table));
  spdlog::info("compare: {} and table.csv in {}", (o.compare.out_dir / "table.md").string(), o.compare.out_dir.string());
  return 0;
}

}  // namespace

Command add_compare(CLI::App& app) {
  auto o = std::make_shared<CompareCli>();
  auto* compare = app.add_subcommand(
      "compare", "run controllers on a scene, one fresh process each, and tabulate the paper's Table 3 columns");
  compare->add_option("scene", o->compare.scene_file, "scene file (JSON), or a mesh file: the smallest scene around it")->required();
  compare->add_option("--controllers", o->controllers, "comma-separated controllers to run (default: all, listed below)");
  compare->add_option("-o,--out", o->compare.out_dir,
                      "output folder: table.md, table.csv, table.json and one run folder per controller")
      ->capture_default_str();
  compare->add_option("--frames", o->frames,
                      fmt::format("output frames per controller (default: the scene's output.frames, else {})",
                                  pipeline::kDefaultCompareFrames))
      ->check(CLI::Range(1, 10'000'000));
  compare->add_option("--max-memory", o->max_memory,
                      "MiB each run may need, estimated before anything runs (overrides limits.max_memory_mb)")
      ->check(CLI::Range(1.0, 1e9));
  compare->add_option("--device", o->compare.device, "cpu, gpu or auto, for every run (see fluidform run --help)")
      ->check(CLI::IsMember({"cpu", "gpu", "auto"}))
      ->capture_default_str();
  compare->footer(pipeline::controllers_help());
  return {compare, [o] { return run_compare(*o); }};
}

}  // namespace ff::app
