#include "server/load_attacks.h"

#include <fmt/format.h>

#include <algorithm>

namespace ff::test {
namespace {

constexpr auto kPerConnection = std::chrono::seconds(5);  // a refusal or a close takes far less

Clock::time_point soon(Clock::time_point deadline) { return std::min(deadline, Clock::now() + kPerConnection); }

int dial(std::uint16_t port, int rcvbuf = 0) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  timeval tv{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  if (rcvbuf > 0) ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);  // before connect: the window
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// Sends what it can; a server that has already closed (a refused huge header) makes the rest fail, which is fine.
void send_some(int fd, const std::string& bytes) {
  for (std::size_t at = 0; at < bytes.size();) {
    const ssize_t k = ::send(fd, bytes.data() + at, bytes.size() - at, MSG_NOSIGNAL);
    if (k <= 0) return;
    at += std::size_t(k);
  }
}

// Reads until the peer closes or `deadline`: the first 64 KiB of what came, and whether it closed.
std::pair<std::string, bool> read_to_close(int fd, Clock::time_point deadline) {
  std::string got;
  char buf[16384];
  while (Clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    const ssize_t k = ::recv(fd, buf, sizeof buf, MSG_DONTWAIT);
    if (k == 0) return {got, true};
    if (k < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
      return {got, true};  // reset
    }
    if (got.size() < 65536) got.append(buf, std::size_t(k));
  }
  return {got, false};
}

// Reads and drops whatever the server sends on `fd`, on its own thread, until destroyed: a client that pings must
// also read, or the server's pong waits behind a frame write that waits for this client.
class Drain {
 public:
  explicit Drain(int fd) : thread_([this, fd] {
    char sink[65536];
    while (!stop_) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 50) > 0 && ::recv(fd, sink, sizeof sink, MSG_DONTWAIT) == 0) return;
    }
  }) {}
  ~Drain() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The closing handshake: a close frame, then the server's answer and its end of the connection. A client that just
// closed its socket with unread data in it (the server's frames) would send a reset, and the reset makes the
// server's kernel drop what it had received and not yet handed over: the last messages would be lost.
bool close_cleanly(RawWebSocket& ws, Clock::time_point deadline) {
  return ws.send_raw(ws_frame(std::string("\x03\xe8", 2), {.opcode = 8})) && peer_closes(ws.socket().fd(), deadline);
}

struct HttpCase {
  std::string name, bytes;
  int expect;  // the status it must get; 0: any 4xx, or a close without an answer
};

std::string request(const std::string& target) {
  return "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
}

std::vector<HttpCase> http_cases() {
  using namespace std::string_literals;
  std::string many;
  for (int i = 0; i < 3000; ++i) many += fmt::format("X-H{}: v\r\n", i);
  std::string binary;
  for (int i = 0; i < 4096; ++i) binary += static_cast<char>(i * 37);
  std::string segments;
  for (int i = 0; i < 4000; ++i) segments += "/a";
  return {
      {"a 64 KiB header", "GET / HTTP/1.1\r\nHost: x\r\nX-Junk: " + std::string(64 * 1024, 'a') + "\r\n\r\n", 0},
      {"3000 headers", "GET / HTTP/1.1\r\nHost: x\r\n" + many + "\r\n", 0},
      {"no version", "GET /\r\n\r\n", 0},
      {"no version, no path", "GET\r\n\r\n", 0},
      {"blank lines", "\r\n\r\n\r\n\r\n", 0},
      {"binary", binary, 0},
      {"NUL in the request line", "GET /index.html\0.js HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"s, 0},
      {"NUL in a header", "GET / HTTP/1.1\r\nHost: x\0y\r\nConnection: close\r\n\r\n"s, 0},
      {"a header without a colon", "GET / HTTP/1.1\r\nHost x\r\n\r\n", 0},
      {"%00", request("/index.html%00.js"), 403},
      {"%2e%2e", request("/%2e%2e/secret.txt"), 403},
      {"%2E%2E%2F", request("/%2E%2E%2Fsecret.txt"), 403},
      {"%252e%252e (double encoding)", request("/%252e%252e/secret.txt"), 404},
      {"%252e%252e%252f (double encoding)", request("/%252e%252e%252fsecret.txt"), 404},
      {"backslashes", request("/..\\secret.txt"), 403},
      {"%5c", request("/%5c..%5csecret.txt"), 403},
      {"overlong UTF-8 dots", request("/%c0%ae%c0%ae/secret.txt"), 404},
      {"an 8000-byte name", request("/" + std::string(8000, 'a')), 404},
      {"4000 segments", request(segments), 404},
      {"a path over the header limit", request("/" + std::string(20000, 'a')), 0},
      {"absolute form", request("http://127.0.0.1/../secret.txt"), 0},
      {"a bad escape", request("/%zz"), 400},
      {"a cut escape", request("/%"), 400},
      {"a body over the limit", "GET / HTTP/1.1\r\nHost: x\r\nContent-Length: 99999999\r\n\r\n" + std::string(32768, 'b'), 0},
      {"bad chunking", "POST / HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\nzz\r\n", 0},
      {"an unknown method", "FOO / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n", 405},
      {"an upgrade of version 12", "GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                                   "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 12\r\n\r\n", 0},
      {"an upgrade without a key", "GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                                   "Sec-WebSocket-Version: 13\r\n\r\n", 0},
      {"an upgrade elsewhere", "GET /ws/../ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade, close\r\n"
                               "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n", 404},
      {"junk after a good request", "GET / HTTP/1.1\r\nHost: x\r\n\r\nGET /\r\n\r\n", 200},
  };
}

}  // namespace

void Tally::add(const Tally& t) {
  connections += t.connections, frames += t.frames, good += t.good, bad += t.bad;
  failures.insert(failures.end(), t.failures.begin(), t.failures.end());
}

Tally http_junk(std::uint16_t port, int rounds, Clock::time_point deadline) {
  Tally t;
  const auto cases = http_cases();
  for (int r = 0; r < rounds && Clock::now() < deadline; ++r)
    for (const HttpCase& c : cases) {
      const int fd = dial(port);
      if (fd < 0) {
        t.failures.push_back("http junk: cannot connect");
        continue;
      }
      ++t.connections, ++t.frames;
      send_some(fd, c.bytes);
      const auto [got, closed] = read_to_close(fd, soon(deadline));
      ::close(fd);
      const int status = got.rfind("HTTP/1.1 ", 0) == 0 && got.size() >= 12 ? std::atoi(got.c_str() + 9) : 0;
      if (!closed) t.failures.push_back(fmt::format("http junk '{}': the connection stayed open", c.name));
      if (c.expect != 0 && status != c.expect)
        t.failures.push_back(fmt::format("http junk '{}': status {}, expected {}", c.name, status, c.expect));
      if (c.expect == 0 && status != 0 && (status < 400 || status > 499))
        t.failures.push_back(fmt::format("http junk '{}': status {}, expected a 4xx or a close", c.name, status));
      if (got.find("secret") != std::string::npos)
        t.failures.push_back(fmt::format("http junk '{}': a file outside the mount was served", c.name));
    }
  return t;
}

Tally ws_protocol_junk(std::uint16_t port, int rounds, Clock::time_point deadline) {
  const std::vector<std::pair<std::string, std::string>> kinds = {
      {"an unmasked frame", ws_frame(R"({"type":"play"})", {.masked = false})},
      {"opcode 3", ws_frame("x", {.opcode = 3})},
      {"opcode 7", ws_frame("x", {.opcode = 7})},
      {"opcode 11", ws_frame("x", {.opcode = 11})},
      {"opcode 15", ws_frame("x", {.opcode = 15})},
      {"a reserved bit", ws_frame("x", {.rsv = 4})},
      {"a lone continuation", ws_frame("x", {.opcode = 0})},
      {"a text frame inside a fragmented message", ws_frame("ab", {.fin = false}) + ws_frame("cd")},
      {"a 126-byte ping", ws_frame(std::string(126, 'p'), {.opcode = 9})},
      {"a fragmented ping", ws_frame("p", {.opcode = 9, .fin = false})},
      {"a 1-byte close", ws_frame("x", {.opcode = 8})},
      {"close code 999", ws_frame(std::string("\x03\xe7", 2), {.opcode = 8})},
      {"invalid UTF-8", ws_frame("\xff\xfe\xfd", {.opcode = 1})},
      {"garbage bytes", std::string(16, '\xff')},
  };
  Tally t;
  for (int r = 0; r < rounds && Clock::now() < deadline; ++r)
    for (const auto& [name, bytes] : kinds) {
      RawWebSocket ws(port);
      ++t.connections;
      if (ws.status() != 101) {
        t.failures.push_back(fmt::format("ws junk '{}': upgrade answered {}", name, ws.status()));
        continue;
      }
      ws.send_raw(bytes);
      ++t.frames;
      if (!peer_closes(ws.socket().fd(), soon(deadline)))
        t.failures.push_back(fmt::format("ws junk '{}': the server kept the connection", name));
    }
  return t;
}

Tally ws_message_junk(std::uint16_t port, int messages, Clock::time_point deadline) {
  Tally t;
  RawWebSocket ws(port);
  ++t.connections;
  if (ws.status() != 101) {
    t.failures.push_back(fmt::format("ws message junk: upgrade answered {}", ws.status()));
    return t;
  }
  Drain drain(ws.socket().fd());
  for (int i = 0; i < messages && Clock::now() < deadline; ++i) {
    std::string bytes;
    switch (i % 6) {
      case 0: bytes = ws_frame("garbage{"), ++t.bad; break;
      case 1: bytes = ws_frame(std::string("\x00\x01\x02", 3), {.opcode = 2}), ++t.bad; break;
      case 2: bytes = ws_frame(""), ++t.bad; break;
      case 3:  // {"type":"nope"} in three pieces: joined, then refused as an unknown command
        bytes = ws_frame(R"({"ty)", {.fin = false}) + ws_frame(R"(pe":)", {.opcode = 0, .fin = false}) +
                ws_frame(R"("nope"})", {.opcode = 0});
        ++t.bad, t.frames += 2;
        break;
      case 4:  // {"type":"pause"} in two pieces with a ping between them (control frames may interleave)
        bytes = ws_frame(R"({"type":)", {.fin = false}) + ws_frame("p", {.opcode = 9}) +
                ws_frame(R"("pause"})", {.opcode = 0});
        ++t.good, t.frames += 2;
        break;
      default:  // an unsolicited pong (ignored), then a command
        bytes = ws_frame("", {.opcode = 10}) + ws_frame(R"({"type":"play"})");
        ++t.good, ++t.frames;
        break;
    }
    ++t.frames;
    if (!ws.send_raw(bytes)) {
      t.failures.push_back(fmt::format("ws message junk: the server dropped the client after {} messages", i));
      break;
    }
  }
  drain.stop();
  // The close comes after every message sent: the answer waits until the server has read them all.
  if (!close_cleanly(ws, deadline)) t.failures.push_back("ws message junk: no answer to the close");
  return t;
}

Tally ws_oversized(std::uint16_t port, std::size_t bytes, bool fragmented, Clock::time_point deadline) {
  Tally t;
  RawWebSocket ws(port);
  ++t.connections;
  if (ws.status() != 101) {
    t.failures.push_back(fmt::format("oversized: upgrade answered {}", ws.status()));
    return t;
  }
  constexpr std::size_t kChunk = 64 * 1024;  // a multiple of 4: every chunk starts at the key's first byte
  const std::string plain(kChunk, 'x');
  std::string masked = plain;
  for (std::size_t i = 0; i < masked.size(); ++i) masked[i] = static_cast<char>(masked[i] ^ char(kMaskKey[i % 4]));
  bool ok = true;
  if (!fragmented) {
    ok = ws.send_raw(ws_frame("", {.declared = std::int64_t(bytes)}));
    for (std::size_t sent = 0; ok && sent < bytes && Clock::now() < deadline; sent += kChunk)
      ok = ws.send_raw(masked.substr(0, std::min(kChunk, bytes - sent)));
    ++t.frames;
  } else {
    const std::size_t n = (bytes + kChunk - 1) / kChunk;
    for (std::size_t k = 0; ok && k < n && Clock::now() < deadline; ++k, ++t.frames)
      ok = ws.send_raw(ws_frame(plain, {.opcode = k == 0 ? 1 : 0, .fin = k + 1 == n}));
  }
  ++t.bad;
  if (ok) ok = ws.send_raw(ws_frame(R"({"type":"play"})"));
  ++t.good, ++t.frames;
  if (!ok || Clock::now() >= deadline)
    t.failures.push_back(fmt::format("oversized ({} bytes{}): not all sent", bytes, fragmented ? ", fragmented" : ""));
  else if (!close_cleanly(ws, deadline))
    t.failures.push_back("oversized: no answer to the close");
  return t;
}

Tally vanishers(std::uint16_t port, int count, Clock::time_point deadline) {
  Tally t;
  const std::string upgrade = kUpgrade;
  for (int i = 0; i < count && Clock::now() < deadline; ++i) {
    ++t.connections;
    switch (i % 6) {
      case 0: {  // half an upgrade request
        RawSocket s(port, 5);
        s.send_all(upgrade.substr(0, upgrade.size() / 2));
        break;
      }
      case 5: {  // connected, then reset before a byte
        RawSocket s(port, 5);
        reset_close(s.fd());
        break;
      }
      default: {
        RawWebSocket ws(port);
        if (ws.status() != 101) {
          t.failures.push_back(fmt::format("vanisher: upgrade answered {}", ws.status()));
          break;
        }
        if (i % 6 == 1) ws.send_raw("\x81");  // half a frame header
        if (i % 6 == 2) ws.send_raw(ws_frame(std::string(1000, 'v')).substr(0, 506)), reset_close(ws.socket().fd());
        if (i % 6 == 3) (void)ws.socket().read_n(30000), reset_close(ws.socket().fd());  // inside a server frame
        if (i % 6 == 4) ws.send_raw(ws_frame("", {.declared = std::int64_t(1) << 62}) + std::string(65536, 'v'));
        ++t.frames;
      }
    }
  }
  return t;
}

Squatters::Squatters(std::uint16_t port, int websockets, int half_requests) {
  const std::string upgrade = kUpgrade;
  for (int i = 0; i < websockets; ++i)
    if (const int fd = dial(port, 4096); fd >= 0) {
      fds_.push_back(fd);
      send_some(fd, upgrade);
      ++upgraded_;
    }
  for (int i = 0; i < half_requests; ++i)
    if (const int fd = dial(port); fd >= 0) fds_.push_back(fd), send_some(fd, "GET / HTTP/1.1\r\nHost: x\r\n");
}

Squatters::~Squatters() {
  for (int fd : fds_) ::close(fd);
}

}  // namespace ff::test
