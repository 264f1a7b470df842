#pragma once
// A deliberately dumb HTTP/WebSocket client on plain sockets for the server tests: it sends exactly the bytes it is
// given (browsers and HTTP libraries would normalise "/../" away before the server ever saw it) and speaks just
// enough RFC 6455 to read frames and send masked ones.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace ff::test {

class RawSocket {
 public:
  explicit RawSocket(std::uint16_t port, int timeout_s = 20) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    timeval tv{timeout_s, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ok_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~RawSocket() { ::close(fd_); }
  RawSocket(const RawSocket&) = delete;
  RawSocket& operator=(const RawSocket&) = delete;
  bool ok() const { return ok_; }
  int fd() const { return fd_; }

  bool send_all(const void* data, std::size_t n) {
    const auto* p = static_cast<const char*>(data);
    while (n) {
      const ssize_t k = ::send(fd_, p, n, MSG_NOSIGNAL);
      if (k <= 0) return false;
      p += k, n -= std::size_t(k);
    }
    return true;
  }
  bool send_all(const std::string& s) { return send_all(s.data(), s.size()); }
  /// Exactly n bytes, or nullopt on close/timeout.
  std::optional<std::string> read_n(std::size_t n) {
    while (buf_.size() - pos_ < n) {
      char tmp[65536];
      const ssize_t k = ::recv(fd_, tmp, sizeof tmp, 0);
      if (k <= 0) return std::nullopt;
      buf_.append(tmp, std::size_t(k));
    }
    std::string s = buf_.substr(pos_, n);
    pos_ += n;
    if (pos_ > (1u << 20)) buf_.erase(0, pos_), pos_ = 0;
    return s;
  }
  /// Up to and including "\r\n\r\n".
  std::optional<std::string> read_head() {
    std::string s;
    while (s.size() < 4 || s.compare(s.size() - 4, 4, "\r\n\r\n") != 0) {
      auto c = read_n(1);
      if (!c) return std::nullopt;
      s += *c;
      if (s.size() > 65536) return std::nullopt;
    }
    return s;
  }
  /// Everything until the peer closes (or times out).
  std::string read_all() {
    std::string s = buf_.substr(pos_);
    buf_.clear(), pos_ = 0;
    char tmp[65536];
    for (ssize_t k; (k = ::recv(fd_, tmp, sizeof tmp, 0)) > 0;) s.append(tmp, std::size_t(k));
    return s;
  }

 private:
  int fd_ = -1;
  bool ok_ = false;
  std::string buf_;
  std::size_t pos_ = 0;
};

/// The status code of a raw HTTP/1.1 GET of `target` (sent verbatim), and the body.
inline std::pair<int, std::string> raw_get(std::uint16_t port, const std::string& target) {
  RawSocket s(port);
  if (!s.ok()) return {-1, ""};
  s.send_all("GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
  const std::string r = s.read_all();
  if (r.rfind("HTTP/1.1 ", 0) != 0) return {-1, r};
  const auto body = r.find("\r\n\r\n");
  return {std::stoi(r.substr(9, 3)), body == std::string::npos ? "" : r.substr(body + 4)};
}

struct WsMessage {
  int opcode = 0;  // 1 text, 2 binary, 8 close
  std::string payload;
};

class RawWebSocket {
 public:
  explicit RawWebSocket(std::uint16_t port) : s_(port) {
    if (!s_.ok()) return;
    s_.send_all("GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n");
    const auto head = s_.read_head();
    status_ = head && head->size() > 12 ? std::stoi(head->substr(9, 3)) : -1;
  }
  int status() const { return status_; }
  /// A client frame (masked with a zero key, so the payload goes as it is).
  bool send(int opcode, const std::string& payload) {
    std::string f;
    f += static_cast<char>(0x80 | opcode);
    const std::size_t n = payload.size();
    if (n < 126) {
      f += static_cast<char>(0x80 | n);
    } else if (n < 65536) {
      f += static_cast<char>(0x80 | 126);
      f += static_cast<char>(n >> 8), f += static_cast<char>(n & 0xff);
    } else {
      f += static_cast<char>(0x80 | 127);
      for (int k = 7; k >= 0; --k) f += static_cast<char>((std::uint64_t(n) >> (8 * k)) & 0xff);
    }
    f += std::string(4, '\0');
    return s_.send_all(f) && s_.send_all(payload);
  }
  bool send_raw(const std::string& bytes) { return s_.send_all(bytes); }
  RawSocket& socket() { return s_; }
  /// One message (continuation frames joined).
  std::optional<WsMessage> read() {
    WsMessage m;
    for (bool fin = false; !fin;) {
      const auto h = s_.read_n(2);
      if (!h) return std::nullopt;
      fin = ((*h)[0] & 0x80) != 0;
      if (((*h)[0] & 0x0f) != 0) m.opcode = (*h)[0] & 0x0f;
      std::uint64_t n = static_cast<unsigned char>((*h)[1]) & 0x7f;
      if (n == 126 || n == 127) {
        const auto e = s_.read_n(n == 126 ? 2 : 8);
        if (!e) return std::nullopt;
        n = 0;
        for (char c : *e) n = (n << 8) | static_cast<unsigned char>(c);
      }
      const auto p = s_.read_n(n);
      if (!p) return std::nullopt;
      m.payload += *p;
    }
    return m;
  }

 private:
  RawSocket s_;
  int status_ = -1;
};

}  // namespace ff::test
