#pragma once
// What the viewer may ask of the server: small JSON text messages over the WebSocket (web/src/protocol.js writes
// them). Every message is checked here before it reaches the simulation; anything else is refused with a reason.
//   {"type": "play"} | {"type": "pause"} | {"type": "restart"}
//   {"type": "controller", "name": "none"}
//   {"type": "pose", "target": 0, "translate": [x, y, z], "rotate": [rx, ry, rz], "scale": 1}   (rotate, scale optional)
//   {"type": "mesh", "target": 0, "mesh": 1}      (an index into the hello message's "meshes")
//   {"type": "surface", "on": true}               (live surface: the reconstructed mesh, sent about twice a second)
//   {"type": "seek", "frame": 12}                  (playback of a finished run: go on from that frame)
#include "pipeline/live_scene.h"
#include "core/error.h"

#include <string>
#include <string_view>

namespace ff::server {

inline constexpr std::size_t kMaxClientMessage = 16 * 1024;  ///< bytes; a real command is under 200

struct Command {
  enum class Kind { Play, Pause, Restart, Controller, Pose, Mesh, Surface, Seek } kind = Kind::Play;
  std::size_t target = 0;
  pipeline::LivePose pose;
  std::string name;      ///< Controller
  std::size_t mesh = 0;  ///< Mesh
  std::size_t frame = 0; ///< Seek
  bool on = false;       ///< Surface
};

/// Parses and checks one client message. Input error (one line, no echo of the message) for anything malformed.
Result<Command> parse_command(std::string_view text);

}  // namespace ff::server
