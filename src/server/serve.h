#pragma once
// `fluidform serve SCENE.json | OUT/`: the live viewer. A scene runs live in a background thread and every
// frame goes to the browsers as a binary message (server/frame_codec.h); a finished run's folder is played back
// (its particle frames through the same stream, its animation.glb as a file for the viewer). The viewer's files are
// web/ and three.js from node_modules/three, served as they are (web/index.html maps "three" with an import map).
#include "core/error.h"
#include "core/progress.h"
#include "server/ws_server.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace ff::server {

struct ServeOptions {
  std::filesystem::path input;   ///< a scene file, or the output folder of a run
  ServerOptions server;
  std::filesystem::path web_dir; ///< the viewer (web/); empty: found next to the binary or in the source tree
  std::filesystem::path cache_dir = "fluidform-out/cache";  ///< control-particle cache (live mode)
  std::optional<std::string> controller;  ///< overrides the scene's controller
  std::vector<std::filesystem::path> meshes;  ///< more meshes for the viewer's mesh list (live mode)
  bool realtime = true;          ///< at most fps frames per second of wall time (false: as fast as it runs)
  double max_fps = 0.0;          ///< cap on simulated frames per second of wall time (0: none), to share a machine
                                 ///< or make the simulation slower than the display on purpose (the viewer's tests)
  double exit_after = 0.0;       ///< s of wall time, then a clean exit (0: until Ctrl-C); for scripts and tests
  std::optional<double> max_memory_mib;  ///< --max-memory: overrides the scene's limits.max_memory_mb (live mode)
  std::string device = "cpu";    ///< --device cpu|gpu|auto (live mode; pipeline/stepper.h)
  Status validate() const;
};

/// Serves until SIGINT/SIGTERM (or exit_after), then stops cleanly and frees the port. Prints
/// "serving http://ADDRESS:PORT/" on stdout once listening (the port is the real one when --port 0).
Status serve(const ServeOptions& options, core::Progress& progress);

/// The viewer's folder: `hint` if given, else web/ found upwards from the binary, else in FF_SOURCE_DIR.
Result<std::filesystem::path> find_web_dir(const std::filesystem::path& hint);

}  // namespace ff::server
