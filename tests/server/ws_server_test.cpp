// The HTTP + WebSocket server on a real port: files and refusals over raw HTTP (paths sent verbatim), the hello and
// frames over a WebSocket, garbage and oversized messages that are ignored (the client stays), the client limit, a slow
// client that gets the newest frame rather than a queue, and a stop that frees the port.
#include "server/frame_codec.h"
#include "server/messages.h"
#include "server/static_files.h"
#include "server/ws_server.h"
#include "support/test_support.h"
#include "server/raw_client.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <thread>

namespace ff::server {
namespace {
namespace fs = std::filesystem;
using test::RawWebSocket;
using test::raw_get;

class WsServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::temp_dir("ws-server");
    fs::create_directories(dir_ / "web");
    std::ofstream(dir_ / "web" / "index.html") << "<html>viewer</html>";
    std::ofstream(dir_ / "secret.txt") << "secret";
    files_ = std::make_unique<StaticFiles>(std::vector<Mount>{{"/", dir_ / "web"}});
  }
  void TearDown() override {
    server_.reset();
    fs::remove_all(dir_);
  }
  void start(int max_clients = 8) {
    ServerOptions o;
    o.port = 0;
    o.max_clients = max_clients;
    WsServer::Callbacks cb;
    cb.hello = [] { return std::string(R"({"type":"hello"})"); };
    cb.on_text = [this](const std::string& t) {
      const bool ok = parse_command(t).has_value();
      (ok ? good_ : bad_).fetch_add(1);
      return ok;
    };
    server_ = std::make_unique<WsServer>(o, *files_, cb);
    const auto st = server_->start();
    ASSERT_TRUE(st.ok()) << st.error().message;
    port_ = server_->port();
    ASSERT_NE(port_, 0);
  }
  static std::shared_ptr<const std::vector<std::uint8_t>> frame(std::uint32_t k, std::size_t n = 1000) {
    std::vector<Vec3f> x(n, Vec3f(float(k), 0, 0));
    return std::make_shared<const std::vector<std::uint8_t>>(encode_frame(FrameInfo{k, k / 60.0, 1, NAN, 0, 0}, x, {}));
  }
  // Waits until `pred` or ~10 s.
  template <class P>
  static bool eventually(P pred) {
    for (int i = 0; i < 1000; ++i) {
      if (pred()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  }

  fs::path dir_;
  std::unique_ptr<StaticFiles> files_;
  std::unique_ptr<WsServer> server_;
  std::uint16_t port_ = 0;
  std::atomic<int> good_{0}, bad_{0};
};

TEST_F(WsServerTest, FilesAndRefusals) {
  start();
  auto [status, body] = raw_get(port_, "/");
  EXPECT_EQ(status, 200);
  EXPECT_EQ(body, "<html>viewer</html>");
  for (const char* bad : {"/../secret.txt", "/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/..%2f..%2fetc%2fpasswd",
                          "/%2e%2e%2fsecret.txt", "/.%2e/secret.txt", "/..\\..\\etc\\passwd", "/nothing.js"}) {
    auto [s, b] = raw_get(port_, bad);
    EXPECT_TRUE(s == 403 || s == 404 || s == 400) << bad << " -> " << s;
    EXPECT_EQ(b.find("secret"), std::string::npos) << bad;
    EXPECT_EQ(b.find("root:"), std::string::npos) << bad;
  }
  // Not a GET: refused; a WebSocket upgrade anywhere but /ws: not found.
  test::RawSocket s(port_);
  s.send_all("DELETE / HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(s.read_all().substr(0, 12), "HTTP/1.1 405");
}

TEST_F(WsServerTest, HelloFramesAndGarbage) {
  start();
  RawWebSocket ws(port_);
  ASSERT_EQ(ws.status(), 101);
  auto hello = ws.read();
  ASSERT_TRUE(hello);
  EXPECT_EQ(hello->opcode, 1);
  EXPECT_EQ(hello->payload, R"({"type":"hello"})");
  ASSERT_TRUE(eventually([&] { return server_->clients() == 1; }));
  // Garbage of every kind: logged and ignored, the connection stays.
  ws.send(1, "garbage{");
  ws.send(1, R"({"type":"pose","target":"x"})");
  ws.send(2, std::string("\x00\x01\x02", 3));
  ws.send(1, R"({"type":"pause"})");
  ASSERT_TRUE(eventually([&] { return good_ == 1 && bad_ == 2; }));
  EXPECT_TRUE(eventually([&] { return server_->stats().bad_messages == 3; }));
  server_->publish_frame(frame(5));
  auto m = ws.read();
  ASSERT_TRUE(m);
  EXPECT_EQ(m->opcode, 2);
  auto d = decode_frame(std::span(reinterpret_cast<const std::uint8_t*>(m->payload.data()), m->payload.size()));
  ASSERT_TRUE(d);
  EXPECT_EQ(d->info.frame, 5u);
  // An oversized message (here 1 MiB, in one frame, over the 16 KiB limit) is counted and ignored: that client stays
  // connected and its next message is read as usual.
  {
    RawWebSocket big(port_);
    ASSERT_EQ(big.status(), 101);
    ASSERT_TRUE(big.read());  // hello
    const auto bad_before = server_->stats().bad_messages;
    ASSERT_TRUE(big.send(1, std::string(1 << 20, 'x')));
    EXPECT_TRUE(eventually([&] { return server_->stats().bad_messages == bad_before + 1; }));
    ASSERT_TRUE(big.send(1, R"({"type":"play"})"));
    EXPECT_TRUE(eventually([&] { return good_ == 2; }));
    EXPECT_EQ(server_->stats().bad_messages, bad_before + 1);
    server_->publish_frame(frame(7));
    auto r = big.read();
    ASSERT_TRUE(r);
    EXPECT_EQ(r->opcode, 2) << "the client that sent the oversized message is still served";
    m = ws.read();  // the first client got frame 7 too
    ASSERT_TRUE(m);
  }
  // Bytes that are not a WebSocket frame at all (unmasked client frame, reserved bits).
  {
    RawWebSocket raw(port_);
    ASSERT_EQ(raw.status(), 101);
    raw.send_raw(std::string("\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff", 10));
  }
  server_->publish_frame(frame(6));
  m = ws.read();
  ASSERT_TRUE(m);
  EXPECT_EQ(m->opcode, 2);
  EXPECT_EQ(raw_get(port_, "/").first, 200);
  RawWebSocket again(port_);
  EXPECT_EQ(again.status(), 101);
}

TEST_F(WsServerTest, ClientLimit) {
  start(1);
  RawWebSocket a(port_);
  ASSERT_EQ(a.status(), 101);
  ASSERT_TRUE(a.read());  // hello: the session is registered
  RawWebSocket b(port_);
  EXPECT_EQ(b.status(), 503);
}

TEST_F(WsServerTest, SlowClientGetsTheNewestFrameNotAQueue) {
  start();
  RawWebSocket ws(port_);
  ASSERT_EQ(ws.status(), 101);
  ASSERT_TRUE(ws.read());  // hello
  // 60 frames of 1.4 MB (more than the socket buffers hold) while the client reads nothing; then it reads until
  // the last one.
  const std::uint32_t frames = 60;
  for (std::uint32_t k = 1; k <= frames; ++k) server_->publish_frame(frame(k, 200'000));
  int got = 0;
  std::uint32_t last = 0;
  while (last != frames) {
    auto m = ws.read();
    ASSERT_TRUE(m) << "the last frame never came";
    auto d = decode_frame(std::span(reinterpret_cast<const std::uint8_t*>(m->payload.data()), m->payload.size()));
    ASSERT_TRUE(d);
    EXPECT_GT(d->info.frame, last);  // in order, never an old one after a newer
    last = d->info.frame;
    ++got;
  }
  EXPECT_LT(got, int(frames)) << "every frame was queued";
  EXPECT_GT(server_->stats().frames_skipped, 0u);
}

// A live surface has its own slot: a stream of frames does not push it out, and it arrives beside them.
TEST_F(WsServerTest, SurfaceArrivesBesideTheFrames) {
  start();
  RawWebSocket ws(port_);
  ASSERT_EQ(ws.status(), 101);
  ASSERT_TRUE(ws.read());  // hello
  io::TriangleMesh mesh;
  mesh.vertices = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)};
  mesh.triangles = {{0, 1, 2}};
  server_->publish_frame(frame(1, 200'000));
  server_->publish_surface(std::make_shared<const std::vector<std::uint8_t>>(encode_surface(SurfaceInfo{1, 0.5, 3.0f}, mesh)));
  for (std::uint32_t k = 2; k <= 20; ++k) server_->publish_frame(frame(k, 200'000));
  bool surface = false;
  std::uint32_t last = 0;
  while (last != 20 || !surface) {
    auto m = ws.read();
    ASSERT_TRUE(m) << "the surface or the last frame never came";
    const std::span bytes(reinterpret_cast<const std::uint8_t*>(m->payload.data()), m->payload.size());
    if (auto s = decode_surface(bytes)) {
      EXPECT_FALSE(surface) << "one surface was published";
      EXPECT_EQ(s->mesh.triangles.size(), 1u);
      surface = true;
    } else {
      auto d = decode_frame(bytes);
      ASSERT_TRUE(d);
      last = d->info.frame;
    }
  }
}

TEST_F(WsServerTest, StopFreesThePort) {
  start();
  {
    RawWebSocket ws(port_);
    ASSERT_EQ(ws.status(), 101);
    server_->stop();
  }
  ServerOptions o;
  o.port = port_;
  WsServer again(o, *files_, {});
  const auto st = again.start();
  EXPECT_TRUE(st.ok()) << st.error().message;
  EXPECT_EQ(raw_get(port_, "/").first, 200);
}

TEST(ServerOptions, Validate) {
  ServerOptions o;
  EXPECT_TRUE(o.validate().ok());
  o.bind = "not an address";
  EXPECT_FALSE(o.validate().ok());
  o.bind = "::1";
  EXPECT_TRUE(o.validate().ok());
  o.max_clients = 0;
  EXPECT_FALSE(o.validate().ok());
}

}  // namespace
}  // namespace ff::server
