#pragma once
// What the load test (load_test.cpp) throws at the server, one function per kind of misbehaving client, each bounded
// in count and in time (a deadline per connection and one for the whole attack). None uses gtest: they run on the
// attack's own threads and hand back a tally, with a line per thing the server got wrong, for the test to assert.
#include "server/load_clients.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ff::test {

struct Tally {
  int connections = 0;  ///< opened
  int frames = 0;       ///< WebSocket frames or HTTP requests sent
  int good = 0;         ///< valid viewer commands among them (the server's on_text must see exactly these)
  int bad = 0;          ///< messages the server must count as bad (ServerStats::bad_messages)
  std::vector<std::string> failures;  ///< what the server did wrong, one line each
  double seconds = 0;   ///< how long it took (for the log)
  void add(const Tally& t);
};

/// HTTP junk, each request on its own connection: huge headers, request lines without a version, %2e%2e, double
/// encoding (%252e), backslashes, NUL bytes, very long paths, bodies on a GET, bad chunking, bad upgrades. The
/// server must answer with a 4xx or close, within a few seconds, and never with `secret` (a file outside the mount).
Tally http_junk(std::uint16_t port, int rounds, Clock::time_point deadline);

/// WebSocket frames that break the protocol (unmasked, reserved opcodes and bits, a lone continuation, a control
/// frame too long or fragmented, invalid UTF-8, a text frame inside a fragmented message), each on a fresh
/// connection: the server must close that connection.
Tally ws_protocol_junk(std::uint16_t port, int rounds, Clock::time_point deadline);

/// `messages` junk messages on one connection that the server must ignore while keeping the client: garbage text,
/// binary, empty text, garbage split into continuation frames, and valid commands split into continuation frames
/// with a ping between the pieces. The connection is drained meanwhile (a pong waits for the server's writes).
Tally ws_message_junk(std::uint16_t port, int messages, Clock::time_point deadline);

/// One text message of `bytes` (far over max_message), in one frame or in 64 KiB continuation frames, streamed from
/// one buffer (so the test itself holds no copy), then a valid command that must still be read.
Tally ws_oversized(std::uint16_t port, std::size_t bytes, bool fragmented, Clock::time_point deadline);

/// `count` clients that vanish mid-message: half an upgrade request, half a frame header, a frame header and half
/// its payload, a frame that claims 2^62 bytes, part of one of the server's frames read, each then closed or reset.
Tally vanishers(std::uint16_t port, int count, Clock::time_point deadline);

/// Clients that hold a connection and never read it: upgraded WebSockets with a tiny receive buffer (the server's
/// writes stall at once), and HTTP connections with half a request (slowloris). Closed by the destructor.
class Squatters {
 public:
  Squatters(std::uint16_t port, int websockets, int half_requests);
  ~Squatters();
  Squatters(const Squatters&) = delete;
  Squatters& operator=(const Squatters&) = delete;
  int upgraded() const { return upgraded_; }

 private:
  std::vector<int> fds_;
  int upgraded_ = 0;
};

}  // namespace ff::test
