// fluidform command line (DESIGN.md "The CLI and output contract").
// Exit codes: 0 ok, 2 bad input or usage, 1 runtime failure. Errors are one line on stderr.
#include "app/progress_bar.h"
#include "app/run_pipeline.h"
#include "io/scene.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

int fail(const ff::Error& e) {
  std::string msg = e.message;
  for (char& c : msg)
    if (c == '\n' || c == '\r') c = ' ';
  fmt::print(stderr, "fluidform: error: {}\n", msg);
  return e.is_input() ? 2 : 1;
}

// The bundled default scene: next to the binary's source tree (build/<preset>/src/app → examples/),
// or where the build was configured from.
fs::path default_scene() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    for (fs::path p = exe.parent_path(); !p.empty() && p != p.root_path(); p = p.parent_path()) {
      const fs::path cand = p / "examples" / "default_scene.json";
      if (fs::exists(cand)) return cand;
    }
  }
  return fs::path(FF_SOURCE_DIR) / "examples" / "default_scene.json";
}

int cmd_run(const fs::path& scene_file, const ff::app::RunOptions& opt) {
  auto scene = ff::io::load_scene(scene_file);
  if (!scene) return fail(scene.error());
  spdlog::info("scene {} -> {}", scene_file.string(), opt.out_dir.string());
  ff::app::ProgressBar bar(stderr);
  auto sum = ff::app::run_scene(*scene, opt, bar);
  if (!sum) return fail(sum.error());
  spdlog::info("done: {} particles, {} frames, {:.2f} ms per frame (simulation only), peak memory {:.0f} MiB -> {}",
               sum->particles, sum->frames_written, 1e3 * sum->mean_frame_seconds, sum->peak_memory_mib,
               opt.out_dir.string());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  auto logger = spdlog::stderr_color_mt("fluidform");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern(::isatty(2) ? "%^%l%$: %v" : "[%H:%M:%S] %l: %v");

  CLI::App app{"fluidform: editable mesh animations from controllable particles"};
  app.set_version_flag("--version", FF_VERSION);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "only warnings and errors");
  app.fallthrough();  // global flags such as -q also work after the subcommand

  fs::path scene_file;
  ff::app::RunOptions run_opt;
  int frames = 0;
  auto* run = app.add_subcommand("run", "simulate a scene file into an output folder");
  run->add_option("scene", scene_file, "scene file (JSON)")->required();
  run->add_option("-o,--out", run_opt.out_dir, "output folder")->capture_default_str();
  run->add_option("--frames", frames, "output frames to simulate (overrides output.frames)")->check(CLI::Range(1, 10'000'000));
  run->add_flag("--resume", run_opt.resume, "continue a killed run from OUT/checkpoint/");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string msg = e.what();
    return fail(ff::param_error(msg + " (see fluidform --help)"));
  }
  if (quiet) spdlog::set_level(spdlog::level::warn);
  if (frames > 0) run_opt.frames = frames;

  if (*run) return cmd_run(scene_file, run_opt);
  // No sub-command: the bundled default scene into ./fluidform-out.
  return cmd_run(default_scene(), ff::app::RunOptions{});
}
