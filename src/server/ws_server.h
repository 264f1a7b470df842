#pragma once
// HTTP + WebSocket on one port for the live viewer: static files (server/static_files.h) for every GET, and the
// frame stream on /ws. One I/O thread owns every connection; other threads only hand it work (publish_frame,
// broadcast_text, stop), so no connection state is shared between threads.
//
// Why Boost.Beast (Debian's libboost-dev, header-only here): one library for HTTP and WebSocket on the same port and
// the same io_context, so the page and its frames share one origin and one address to bind; per-message size
// limits and timeouts built in; asynchronous writes, which is what lets a slow client skip frames instead of
// blocking the simulation. websocketpp would still need a second HTTP stack for the files (cpp-httplib), and two
// servers on two ports for one page. Beast's headers are compiled in ws_server.cpp only (pimpl): they are heavy.
#include "core/error.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ff::server {

class StaticFiles;

struct ServerOptions {
  std::string bind = "127.0.0.1";  ///< loopback unless asked: the viewer can steer the simulation
  std::uint16_t port = 8080;       ///< 0: any free port (see WsServer::port())
  int max_clients = 8;             ///< WebSocket clients at once; more get 503
  std::size_t max_message = 16 * 1024;  ///< bytes of one client message; a larger one is ignored (counted, logged)
  Status validate() const;
};

struct ServerStats {
  std::uint64_t frames_sent = 0;     ///< binary frames written, all clients
  std::uint64_t frames_skipped = 0;  ///< frames replaced by a newer one before a slow client could take them
  std::uint64_t bad_messages = 0;    ///< malformed client messages (logged and ignored)
};

class WsServer {
 public:
  struct Callbacks {
    std::function<std::string()> hello;                   ///< the first text message of every client
    std::function<bool(const std::string&)> on_text;      ///< a client's text message; false: malformed (logged)
    std::function<void()> on_signal;                      ///< SIGINT or SIGTERM arrived
  };
  WsServer(ServerOptions options, const StaticFiles& files, Callbacks callbacks);
  ~WsServer();  ///< stops
  WsServer(const WsServer&) = delete;
  WsServer& operator=(const WsServer&) = delete;

  /// Binds and listens, then serves on its own thread. Errors: the address does not parse, the port is taken.
  Status start();
  std::uint16_t port() const;
  /// The newest frame, for every client (thread-safe). A client still writing the previous one gets only the
  /// latest when it is done: frames in between are skipped, never queued. Nor are they queued on the way to the I/O
  /// thread: a frame published before that thread took the previous one replaces it.
  void publish_frame(std::shared_ptr<const std::vector<std::uint8_t>> frame);
  /// The newest live surface (frame_codec.h), for every client (thread-safe), in its own newest-only slot.
  void publish_surface(std::shared_ptr<const std::vector<std::uint8_t>> surface);
  /// A text message (JSON) for every client, in order (thread-safe).
  void broadcast_text(std::string text);
  /// Closes the listener and every connection and joins the thread; the port is free afterwards. Idempotent.
  void stop();
  ServerStats stats() const;
  int clients() const;

  struct Impl;  ///< opaque (ws_server.cpp): the Beast objects and the sessions

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace ff::server
