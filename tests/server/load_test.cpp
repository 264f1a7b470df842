// The server under load, on loopback: 64 viewers that read, while clients that never read, clients that vanish
// mid-message, thousands of garbage, fragmented and oversized WebSocket frames and HTTP junk arrive at once, and a
// publisher thread publishes 10k-particle frames at 30 per second. Every viewer must keep getting new frames, each
// piece of junk must be refused or closed, the heap must stay within a stated bound, the client count must return
// to 0, and stop() must come back. Every loop is bounded in count and by a deadline. The rate of the simulation
// under this load is measured by bench/bench_serve_load.cpp, not here (a speed target is not a unit test).
#include "server/frame_codec.h"
#include "server/load_attacks.h"
#include "server/messages.h"
#include "server/static_files.h"
#include "server/ws_server.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <future>

namespace ff::server {
namespace {
namespace fs = std::filesystem;
using test::Clock;
using namespace std::chrono_literals;

constexpr int kViewers = 64;
constexpr std::size_t kParticles = 10'000;  // ~70 KB a frame, as the default scene
constexpr auto kFramePeriod = 33ms;         // ~30 frames a second

// Publishes frame 1, 2, … every kFramePeriod until stopped (or its deadline), as the simulation thread does.
class Publisher {
 public:
  Publisher(WsServer& server, Clock::time_point deadline)
      : thread_([this, &server, deadline] {
          std::vector<Vec3f> x(kParticles);
          for (std::size_t i = 0; i < x.size(); ++i) x[i] = Vec3f(float(i % 100), float(i / 100), 0.0f);
          for (auto next = Clock::now(); !stop_ && Clock::now() < deadline; next += kFramePeriod) {
            const std::uint32_t k = newest_ + 1;
            x[k % kParticles].z() = float(k);  // frames differ, as simulated ones do
            server.publish_frame(std::make_shared<const std::vector<std::uint8_t>>(
                encode_frame(FrameInfo{k, k / 30.0, 1.0f, NAN, 30.0f, 0}, x, {})));
            newest_ = k;
            std::this_thread::sleep_until(next + kFramePeriod);
          }
        }) {}
  ~Publisher() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  std::uint32_t newest() const { return newest_; }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<std::uint32_t> newest_{0};
  std::thread thread_;
};

// Samples the heap in use every 10 ms on its own thread; the largest figure seen.
class HeapPeak {
 public:
  HeapPeak() : thread_([this] {
    while (!stop_) {
      peak_ = std::max(peak_.load(), test::heap_bytes());
      std::this_thread::sleep_for(10ms);
    }
  }) {}
  std::size_t stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    return peak_;
  }
  ~HeapPeak() { stop(); }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<std::size_t> peak_{0};
  std::thread thread_;
};

double secs(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

template <class P>
bool eventually(P pred, Clock::time_point deadline) {
  for (; Clock::now() < deadline; std::this_thread::sleep_for(10ms))
    if (pred()) return true;
  return pred();
}

class LoadTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::temp_dir("server-load");
    fs::create_directories(dir_ / "web");
    std::ofstream(dir_ / "web" / "index.html") << "<html>viewer</html>";
    std::ofstream(dir_ / "secret.txt") << "secret";
    files_ = std::make_unique<StaticFiles>(std::vector<Mount>{{"/", dir_ / "web"}});
  }
  void TearDown() override {
    server_.reset();
    fs::remove_all(dir_);
  }
  void start(int max_clients) {
    ServerOptions o;
    o.port = 0;
    o.max_clients = max_clients;
    WsServer::Callbacks cb;
    cb.hello = [] { return std::string(R"({"type":"hello"})"); };
    cb.on_text = [this](const std::string& t) {
      if (t == "stall") std::this_thread::sleep_for(500ms);  // holds the I/O thread (the burst test)
      const bool ok = parse_command(t).has_value();
      (ok ? good_ : bad_).fetch_add(1);
      return ok;
    };
    server_ = std::make_unique<WsServer>(o, *files_, cb);
    const auto st = server_->start();
    ASSERT_TRUE(st.ok()) << st.error().message;
    port_ = server_->port();
  }

  fs::path dir_;
  std::unique_ptr<StaticFiles> files_;
  std::unique_ptr<WsServer> server_;
  std::uint16_t port_ = 0;
  std::atomic<int> good_{0}, bad_{0};
};

// Bounds, stated: a viewer that gets no frame for 2 s shows a frozen simulation; 4 frames a second is far below the
// 30 published (a viewer that keeps up gets nearly all) but above what a stalled or starved one gets. The heap may
// grow by 32 MiB under the attack, which streams 6 × 16 MiB of oversized messages at once: a server that buffered
// them whole, or queued frames for the clients that never read, goes over.
// Under a sanitizer the one I/O thread runs 10-30 times slower (it takes about 10 messages a second from each junk
// connection here, as it serves every other connection in turn): a fifth of the junk, still hundreds of each kind.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr int kJunkScale = 5;
#else
constexpr int kJunkScale = 1;
#endif
constexpr double kMaxGap = 2.0;  // s
constexpr double kMinViewerFps = 4.0;
constexpr std::size_t kHeapBound = 32u << 20;
constexpr std::size_t kOversized = 16u << 20;

TEST_F(LoadTest, SixtyFourViewersKeepGettingFramesWhileJunkArrives) {
  start(160);  // 64 viewers, 8 that never read, the junk connections at a time, and room to spare
  const auto end = Clock::now() + 240s;  // the whole test's deadline: every wait below is bounded by it
  Publisher publisher(*server_, end);
  std::vector<std::unique_ptr<test::Viewer>> viewers;
  for (int i = 0; i < kViewers; ++i) {
    viewers.push_back(std::make_unique<test::Viewer>(port_, end));
    ASSERT_TRUE(viewers.back()->upgraded()) << "viewer " << i;
  }
  ASSERT_TRUE(eventually([&] { return std::all_of(viewers.begin(), viewers.end(), [](auto& v) { return v->count() > 0; }); },
                         Clock::now() + 30s))
      << "not every viewer got a first frame";
  ASSERT_EQ(server_->clients(), kViewers);

  const std::size_t heap_before = test::heap_bytes();
  HeapPeak heap;
  const auto t0 = Clock::now();
  const std::uint32_t published_before = publisher.newest();
  test::Tally tally;
  {
    test::Squatters squatters(port_, 8, 64);
    const auto attack_end = std::min(end, Clock::now() + 120s);
    std::vector<std::future<test::Tally>> attacks;
    const auto spawn = [&](auto f) {
      attacks.push_back(std::async(std::launch::async, [f, t0] {
        test::Tally t = f();
        t.seconds = secs(Clock::now() - t0);
        return t;
      }));
    };
    spawn([&] { return test::http_junk(port_, 3, attack_end); });
    spawn([&] { return test::ws_protocol_junk(port_, 15 / kJunkScale, attack_end); });
    spawn([&] { return test::vanishers(port_, 240 / kJunkScale, attack_end); });
    for (int k = 0; k < 2; ++k) spawn([&] { return test::ws_message_junk(port_, 1500 / kJunkScale, attack_end); });
    for (int k = 0; k < 6; ++k) spawn([&, k] { return test::ws_oversized(port_, kOversized, k % 2 == 1, attack_end); });
    for (auto& a : attacks) {
      const test::Tally t = a.get();
      std::printf("load: an attack of %d connections, %d frames or requests, done after %.1f s\n", t.connections,
                  t.frames, t.seconds);
      tally.add(t);
    }
    // The attack lasts at least 3 s, so that every viewer is measured over a window of some length.
    std::this_thread::sleep_until(t0 + 3s);
    EXPECT_EQ(test::raw_get(port_, "/").first, 200) << "a file while the squatters hold their connections";
  }
  const auto t1 = Clock::now();
  const std::size_t heap_peak = heap.stop();
  for (const auto& f : tally.failures) ADD_FAILURE() << f;
  EXPECT_GE(tally.frames, 3000 / kJunkScale) << "thousands of junk frames and requests (a fifth under a sanitizer)";

  // Every viewer gets frames as new as the newest published once the junk is over, and every command the junk
  // carried was seen and every bad message counted, no more, no fewer.
  const std::uint32_t newest = publisher.newest();
  for (int i = 0; i < kViewers; ++i)
    EXPECT_TRUE(eventually([&] { return viewers[i]->newest() >= newest; }, std::min(end, Clock::now() + 15s)))
        << "viewer " << i << " is stuck at frame " << viewers[i]->newest() << " of " << newest;
  EXPECT_TRUE(eventually([&] { return good_ == tally.good; }, std::min(end, Clock::now() + 15s)))
      << good_ << " commands seen of " << tally.good;
  EXPECT_TRUE(eventually([&] { return server_->stats().bad_messages == std::uint64_t(tally.bad); },
                         std::min(end, Clock::now() + 15s)))
      << server_->stats().bad_messages << " bad messages counted of " << tally.bad;
  publisher.stop();

  // Over the attack's window [t0, t1]: enough frames for every viewer, never a long gap, and always newer ones.
  const double window = std::chrono::duration<double>(t1 - t0).count();
  std::vector<std::size_t> counts;
  for (int i = 0; i < kViewers; ++i) {
    viewers[i]->stop();
    EXPECT_FALSE(viewers[i]->closed() && viewers[i]->newest() < newest) << "viewer " << i << " was dropped";
    auto last = t0;
    std::uint32_t previous = 0;
    std::size_t in_window = 0;
    for (const auto& f : viewers[i]->frames()) {
      EXPECT_GT(f.number, previous) << "viewer " << i << ": an older frame after a newer one";
      previous = f.number;
      if (f.at < t0 || f.at > t1) continue;
      EXPECT_LE(secs(f.at - last), kMaxGap) << "viewer " << i << " went without a frame for " << secs(f.at - last) << " s";
      last = f.at, ++in_window;
    }
    EXPECT_LE(secs(t1 - last), kMaxGap) << "viewer " << i << " got nothing in the attack's last seconds";
    EXPECT_GE(double(in_window), kMinViewerFps * window) << "viewer " << i;
    counts.push_back(in_window);
  }
  std::sort(counts.begin(), counts.end());
  const std::size_t growth = heap_peak > heap_before ? heap_peak - heap_before : 0;
  std::printf("load: %d viewers, %.1f s of attack, %u frames published, per viewer min %zu median %zu; "
              "%d junk connections, %d frames or requests; heap +%.1f MiB at peak; VmHWM %.0f MiB\n",
              kViewers, window, newest - published_before, counts.front(), counts[counts.size() / 2],
              tally.connections, tally.frames, double(growth) / (1 << 20),
              double(test::proc_status_kib("VmHWM")) / 1024);
  EXPECT_LE(growth, kHeapBound) << "the heap grew by " << growth / (1 << 20) << " MiB";

  // Everyone gone: the count returns to 0, and stop() is prompt.
  viewers.clear();
  EXPECT_TRUE(eventually([&] { return server_->clients() == 0; }, std::min(end, Clock::now() + 15s)))
      << server_->clients() << " clients left";
  const auto stop_at = Clock::now();
  server_->stop();
  EXPECT_LT(secs(Clock::now() - stop_at), 5.0) << "stop() hung";
}

// Upgrades that all arrive at once: the client limit holds for those still in their handshake too. The I/O thread
// is held in a callback while 32 upgrade requests arrive, so that it reads them all in one batch, before any of
// their handshakes has finished.
TEST_F(LoadTest, ClientLimitHoldsForABurstOfUpgrades) {
  start(4);
  test::RawWebSocket staller(port_);
  ASSERT_EQ(staller.status(), 101);
  ASSERT_TRUE(staller.read());  // hello
  std::vector<std::unique_ptr<test::RawSocket>> socks;
  for (int i = 0; i < 32; ++i) socks.push_back(std::make_unique<test::RawSocket>(port_, 10));
  std::this_thread::sleep_for(200ms);  // accepted, each waiting for its request
  staller.send(1, "stall");
  std::this_thread::sleep_for(100ms);  // the I/O thread is in the callback
  for (auto& s : socks) s->send_all(test::kUpgrade);
  int accepted = 0, refused = 0;
  for (auto& s : socks) {
    const auto head = s->read_head();
    if (head && head->rfind("HTTP/1.1 101", 0) == 0) ++accepted;
    if (head && head->rfind("HTTP/1.1 503", 0) == 0) ++refused;
  }
  EXPECT_EQ(accepted, 3) << "the limit is 4, one is connected";
  EXPECT_EQ(refused, 29);
  socks.clear();
  EXPECT_TRUE(eventually([&] { return server_->clients() == 1; }, Clock::now() + 15s));
}

// Frames are never queued: not for clients that never read (each holds the frame being written and the newest), nor
// on the way to the I/O thread. That thread is held in a callback while 100 frames of 1.2 MB are published; a
// server that queued a handler, and a frame with it, per publish would hold all 120 MB when it comes back.
TEST_F(LoadTest, FramesAreNeverQueued) {
  start(8);
  test::Squatters never(port_, 4, 0);
  test::RawWebSocket staller(port_);
  ASSERT_EQ(staller.status(), 101);
  ASSERT_TRUE(staller.read());  // hello
  ASSERT_TRUE(eventually([&] { return server_->clients() == 5; }, Clock::now() + 15s));
  std::vector<Vec3f> x(200'000, Vec3f::Zero());
  const std::vector<std::uint8_t> base = encode_frame(FrameInfo{0, 0, 0, NAN, 0, 0}, x, {});
  x.clear();
  const std::size_t before = test::heap_bytes();
  std::size_t peak = before;
  staller.send(1, "stall");
  std::this_thread::sleep_for(100ms);  // the I/O thread is in the callback
  for (std::uint32_t k = 1; k <= 100; ++k) {
    auto f = std::make_shared<std::vector<std::uint8_t>>(base);
    std::memcpy(f->data() + 8, &k, 4);  // the frame number (frame_codec.h)
    server_->publish_frame(std::move(f));
    peak = std::max(peak, test::heap_bytes());
  }
  for (auto until = Clock::now() + 2s; Clock::now() < until; std::this_thread::sleep_for(10ms))
    peak = std::max(peak, test::heap_bytes());
  // Each of the 5 clients: the frame being written and the newest, and the one waiting for the I/O thread.
  EXPECT_LT(peak - before, std::size_t(16) << 20) << "frames were queued";
  EXPECT_TRUE(eventually([&] { return server_->stats().frames_skipped >= 4 * 95; }, Clock::now() + 15s))
      << server_->stats().frames_skipped;
  // The staller reads on: it gets frame 100, the last, after only a few of the 99 before it (one, the newest when
  // the I/O thread came back; a few more where publishing outlasted the stall, as under a sanitizer).
  std::uint32_t number = 0;
  int frames = 0;
  for (int i = 0; i < 200 && number != 100; ++i) {
    const auto m = staller.read();
    ASSERT_TRUE(m) << "frame 100 never came";
    if (m->opcode != 2 || m->payload.size() <= 12) continue;
    std::memcpy(&number, m->payload.data() + 8, 4);
    ++frames;
  }
  EXPECT_EQ(number, 100u);
  EXPECT_LE(frames, 20) << "frames were queued for the staller";
}

// Continuation frames are joined into one message, with control frames between the pieces; garbage in pieces is
// refused like garbage in one frame; and the client stays through all of it.
TEST_F(LoadTest, FragmentedMessagesAreJoined) {
  start(8);
  test::RawWebSocket ws(port_);
  ASSERT_EQ(ws.status(), 101);
  ASSERT_TRUE(ws.read());  // hello
  ws.send_raw(test::ws_frame(R"({"type":)", {.fin = false}) + test::ws_frame(R"("pause"})", {.opcode = 0}));
  ASSERT_TRUE(eventually([&] { return good_ == 1; }, Clock::now() + 10s)) << "two pieces";
  ws.send_raw(test::ws_frame(R"({"ty)", {.fin = false}) + test::ws_frame("p", {.opcode = 9}) +
              test::ws_frame(R"(pe":"pl)", {.opcode = 0, .fin = false}) + test::ws_frame("", {.opcode = 10}) +
              test::ws_frame(R"(ay"})", {.opcode = 0}));
  ASSERT_TRUE(eventually([&] { return good_ == 2; }, Clock::now() + 10s)) << "three pieces, a ping and a pong between";
  ws.send_raw(test::ws_frame("", {.opcode = 1}) + test::ws_frame(R"({"type":"nope"})", {.fin = false}) +
              test::ws_frame("", {.opcode = 0}));
  ASSERT_TRUE(eventually([&] { return bad_ == 2; }, Clock::now() + 10s)) << "an empty message, an unknown command";
  ws.send_raw(test::ws_frame(R"({"type":"play"})"));
  EXPECT_TRUE(eventually([&] { return good_ == 3; }, Clock::now() + 10s)) << "the client stays";
}

}  // namespace
}  // namespace ff::server
