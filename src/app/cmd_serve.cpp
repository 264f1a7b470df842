// `fluidform serve SCENE.json | OUT/`: the live viewer (src/server), a scene run live or a finished run played back.
#include "app/cli.h"
#include "app/progress_bar.h"
#include "server/serve.h"

#include <fmt/format.h>

#include <memory>

namespace ff::app {
namespace fs = std::filesystem;

namespace {

struct ServeCli {
  server::ServeOptions serve;
  std::string controller;
  bool as_fast_as_possible = false;
  double max_memory = 0.0;
};

int run_serve(ServeCli& o) {
  if (!o.controller.empty()) o.serve.controller = o.controller;
  o.serve.realtime = !o.as_fast_as_possible;
  if (o.max_memory > 0.0) o.serve.max_memory_mib = o.max_memory;
  if (!fs::exists(o.serve.input))
    return fail(input_error(fmt::format("{}: no such scene file or run folder", o.serve.input.string())));
  ProgressBar bar(stderr);
  if (auto st = server::serve(o.serve, bar); !st.ok()) return fail(st.error());
  return 0;
}

}  // namespace

Command add_serve(CLI::App& app) {
  auto o = std::make_shared<ServeCli>();
  auto* serve = app.add_subcommand(
      "serve", "live viewer: run a scene (or play back a run's folder) and watch, steer and edit it in a browser or WebXR headset");
  serve->add_option("input", o->serve.input, "scene file (JSON), a mesh file (the smallest scene around it), or the output folder of a finished run")->required();
  serve->add_option("--port", o->serve.server.port, "TCP port (0: any free port, printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  serve->add_option("--bind", o->serve.server.bind,
                    "address to listen on (loopback by default: whoever reaches the page can steer the simulation)")
      ->capture_default_str();
  serve->add_option("--max-clients", o->serve.server.max_clients, "viewers at once")->capture_default_str();
  add_controller_option(serve, o->controller, "");
  serve->add_option("--mesh", o->serve.meshes, "another mesh for the viewer's mesh list (repeatable)");
  serve->add_option("--web", o->serve.web_dir, "the viewer's folder (default: web/ of the source tree)");
  serve->add_option("--cache", o->serve.cache_dir, "control-particle cache folder")->capture_default_str();
  serve->add_option("--exit-after", o->serve.exit_after, "stop after this many seconds (default: at Ctrl-C)");
  serve->add_flag("--as-fast-as-possible", o->as_fast_as_possible,
                  "simulate as fast as the machine can (default: at most real time)");
  serve->add_option("--max-fps", o->serve.max_fps,
                    "at most this many simulated frames per second of wall time (default 0: no cap)");
  serve->add_option("--device", o->serve.device,
                    "cpu, gpu (Vulkan; lavapipe where there is no GPU) or auto (a GPU when there is one and the scene is "
                    "one the GPU path does, else the CPU); docs/gpu.md")
      ->check(CLI::IsMember({"cpu", "gpu", "auto"}))
      ->capture_default_str();
  serve->add_option("--max-memory", o->max_memory,
                    "MiB the live scene may need, estimated before it starts (overrides limits.max_memory_mb)")
      ->check(CLI::Range(1.0, 1e9));
  return {serve, [o] { return run_serve(*o); }};
}

}  // namespace ff::app
