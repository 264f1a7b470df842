#pragma once
// Clients for the server's load test (load_test.cpp): a lean viewer that reads the frame stream on its own thread
// (only each frame's number is kept, the payload is skipped through one fixed buffer, so 64 of them cost the test
// little memory), raw WebSocket frames built byte by byte (masked or not, any opcode, FIN and reserved bits, a
// declared length that lies), a check that the server closed a connection, and the process's heap in use.
// Every socket has a receive and send timeout and every loop a deadline: nothing here can wait forever.
#include "server/raw_client.h"

#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
// From the sanitizer runtime (<sanitizer/allocator_interface.h>, which gcc does not ship).
extern "C" std::size_t __sanitizer_get_current_allocated_bytes();
#else
#include <malloc.h>
#endif

namespace ff::test {

using Clock = std::chrono::steady_clock;

/// Bytes of heap in use by the whole process. The sanitizers have their own allocator (glibc's counters would read
/// ~0 there), and RSS would count their shadow memory: the allocator's own count is the figure that compares.
inline std::size_t heap_bytes() {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  return __sanitizer_get_current_allocated_bytes();
#else
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
#endif
}

/// A field of /proc/self/status in KiB ("VmRSS", "VmHWM"); 0 if absent.
inline std::size_t proc_status_kib(const std::string& field) {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return 0;
  char line[256];
  std::size_t kib = 0;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, field.c_str(), field.size()) == 0 && line[field.size()] == ':')
      kib = std::strtoull(line + field.size() + 1, nullptr, 10);
  std::fclose(f);
  return kib;
}

struct WsFrameSpec {
  int opcode = 1;        ///< 0 continuation, 1 text, 2 binary, 8 close, 9 ping, 10 pong; others are reserved
  bool fin = true;
  bool masked = true;    ///< a client must mask; an unmasked client frame is a protocol error
  int rsv = 0;           ///< reserved bits (0–7); non-zero without an extension is a protocol error
  std::int64_t declared = -1;  ///< the length the header claims (−1: the payload's true length)
};

/// The masking key of every frame ws_frame builds.
inline constexpr unsigned char kMaskKey[4] = {0x37, 0xfa, 0x21, 0x3d};

/// One client WebSocket frame, masked with a non-zero key (so the server's unmasking is exercised).
inline std::string ws_frame(const std::string& payload, WsFrameSpec f = {}) {
  std::string out;
  out += static_cast<char>((f.fin ? 0x80 : 0) | ((f.rsv & 7) << 4) | (f.opcode & 0x0f));
  const std::uint64_t n = f.declared >= 0 ? std::uint64_t(f.declared) : payload.size();
  const char mask_bit = f.masked ? char(0x80) : char(0);
  if (n < 126) {
    out += static_cast<char>(mask_bit | char(n));
  } else if (n < 65536) {
    out += static_cast<char>(mask_bit | 126);
    out += static_cast<char>(n >> 8), out += static_cast<char>(n & 0xff);
  } else {
    out += static_cast<char>(mask_bit | 127);
    for (int k = 7; k >= 0; --k) out += static_cast<char>((n >> (8 * k)) & 0xff);
  }
  if (f.masked) out.append(reinterpret_cast<const char*>(kMaskKey), 4);
  for (std::size_t i = 0; i < payload.size(); ++i)
    out += f.masked ? static_cast<char>(payload[i] ^ static_cast<char>(kMaskKey[i % 4])) : payload[i];
  return out;
}

inline constexpr const char* kUpgrade =
    "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
    "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";

/// True when the peer closes `fd` (FIN or reset) before `deadline`; whatever it sends meanwhile is read and dropped.
inline bool peer_closes(int fd, Clock::time_point deadline) {
  char sink[65536];
  while (Clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    const int left = int(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
    if (::poll(&p, 1, std::max(left, 1)) <= 0) continue;
    const ssize_t k = ::recv(fd, sink, sizeof sink, MSG_DONTWAIT);
    if (k == 0) return true;
    if (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return true;  // reset
  }
  return false;
}

/// Closes with a reset (SO_LINGER 0) instead of a FIN: a client that vanishes.
inline void reset_close(int fd) {
  linger l{1, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_LINGER, &l, sizeof l);
}

/// A viewer that behaves: upgrades, then reads every message on its own thread until stop() or its deadline,
/// keeping the number and arrival time of each particle frame (magic "FFP1") and nothing else.
class Viewer {
 public:
  struct Frame {
    std::uint32_t number;
    Clock::time_point at;
  };

  Viewer(std::uint16_t port, Clock::time_point deadline) : deadline_(deadline) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    timeval tv{0, 200'000};  // short: the reading loop looks at stop_ and the deadline between waits
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    timeval snd{5, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &snd, sizeof snd);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return;
    const std::string req = kUpgrade;
    if (::send(fd_, req.data(), req.size(), MSG_NOSIGNAL) != ssize_t(req.size())) return;
    std::string head;
    unsigned char c = 0;
    while (head.size() < 4096 && (head.size() < 4 || head.compare(head.size() - 4, 4, "\r\n\r\n") != 0) && read(&c, 1))
      head += char(c);
    upgraded_ = head.rfind("HTTP/1.1 101", 0) == 0;
    if (upgraded_) thread_ = std::thread([this] { loop(); });
  }
  ~Viewer() {
    stop();
    ::close(fd_);
  }
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  bool upgraded() const { return upgraded_; }
  std::uint64_t count() const { return count_.load(); }
  std::uint32_t newest() const { return newest_.load(); }
  bool closed() const { return closed_.load(); }
  /// Ends the reading thread: the shutdown wakes its receive at once (and the server sees the viewer leave).
  void stop() {
    stop_ = true;
    ::shutdown(fd_, SHUT_RDWR);
    if (thread_.joinable()) thread_.join();
  }
  /// The frames it got (call after stop()).
  const std::vector<Frame>& frames() const { return frames_; }

 private:
  // Exactly n bytes into dst (nullptr: skipped); false on close, error, stop or the deadline.
  bool read(unsigned char* dst, std::size_t n) {
    while (n) {
      if (pos_ == len_) {
        const ssize_t k = ::recv(fd_, buf_.data(), buf_.size(), 0);
        if (k == 0) return false;
        if (k < 0) {
          if ((errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) && !stop_ && Clock::now() < deadline_) continue;
          return false;
        }
        pos_ = 0, len_ = std::size_t(k);
      }
      const std::size_t take = std::min(n, len_ - pos_);
      if (dst) std::memcpy(dst, buf_.data() + pos_, take), dst += take;
      pos_ += take, n -= take;
    }
    return true;
  }
  void loop() {
    for (;;) {
      unsigned char h[2];
      if (!read(h, 2)) break;
      const int opcode = h[0] & 0x0f;
      std::uint64_t n = h[1] & 0x7f;
      if (n >= 126) {
        unsigned char e[8];
        const std::size_t k = n == 126 ? 2 : 8;
        if (!read(e, k)) break;
        n = 0;
        for (std::size_t i = 0; i < k; ++i) n = (n << 8) | e[i];
      }
      unsigned char head[12] = {};
      const std::size_t first = std::min<std::uint64_t>(n, sizeof head);
      if (!read(head, first) || !read(nullptr, n - first)) break;
      if (opcode == 8) break;  // the server closed
      std::uint32_t magic = 0, number = 0;
      std::memcpy(&magic, head, 4), std::memcpy(&number, head + 8, 4);
      if (opcode == 2 && first == 12 && magic == 0x31504646u) {
        if (frames_.size() < 100'000) frames_.push_back({number, Clock::now()});
        newest_ = std::max(newest_.load(), number);
        count_.fetch_add(1);
      }
    }
    closed_ = true;
  }

  int fd_ = -1;
  Clock::time_point deadline_;
  bool upgraded_ = false;
  std::array<unsigned char, 65536> buf_{};
  std::size_t pos_ = 0, len_ = 0;
  std::vector<Frame> frames_;  // the reading thread's, until it is joined
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::uint32_t> newest_{0};
  std::atomic<bool> stop_{false}, closed_{false};
  std::thread thread_;
};

}  // namespace ff::test
