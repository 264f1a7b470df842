// fluidform command line (docs/cli.md): the global flags, one sub-command per file
// (cmd_*.cpp, app/cli.h), and the default run of the bundled scene when no sub-command is given.
#include "core/simd_target.h"
#include "app/cli.h"

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <vector>

int main(int argc, char** argv) {
  using namespace ff::app;
  auto logger = spdlog::stderr_color_mt("fluidform");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern(::isatty(2) ? "%^%l%$: %v" : "[%H:%M:%S] %l: %v");

  // FF_SIMD pins the instruction set of the Highway kernels (core/simd_target.h); a bad value stops here.
  if (const ff::Status s = ff::core::select_simd_target_from_env(); !s.ok()) {
    spdlog::error("{}", s.error().message);
    return 2;
  }

  CLI::App app{"fluidform: editable mesh animations from controllable particles"};
  app.set_version_flag("--version", FF_VERSION);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "only warnings and errors");
  app.fallthrough();  // global flags such as -q also work after the subcommand
  const std::vector<Command> commands{add_run(app), add_sample(app), add_mesh(app), add_compare(app), add_serve(app),
                                      add_keys(app), add_devices(app), add_report(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return fail(ff::param_error(std::string(e.what()) + " (see fluidform --help)"));
  }
  if (quiet) spdlog::set_level(spdlog::level::warn);
  for (const Command& c : commands)
    if (*c.sub) return c.run();
  return run_default_scene();
}
