// The server under load (issue 20 item 4): the simulation's rate in the real serve loop with 1 viewer and with 64,
// in one run. `fluidform serve SCENE --as-fast-as-possible` runs in its own process (the LiveScene loop of
// src/server/serve.cpp, unchanged: step, encode, publish, as fast as the machine goes), so its peak memory is its
// own. This program connects the viewers (tests/server/load_clients.h: each reads every message on its own thread
// and keeps only the frame numbers) and alternates phases of 1 and of N viewers, 1, N, N, 1, …, so a drift of the
// machine or of the scene's cost as it forms falls on both alike. A phase's rate is the frames the simulation
// advanced (the newest frame number a viewer holds) over the phase's wall time; the ratio is N viewers' rate over
// 1 viewer's, per round and as the median of the rounds.
//   build/release/bench/bench_serve_load [--scene FILE] [--viewers N] [--rounds R] [--phase SECONDS]
// Defaults: examples/default_scene.json (the bunny, ~10k particles), 64 viewers, 5 rounds, 8 s phases. The viewers
// share the machine with the simulation (as a browser on the same machine would): they cost it what reading the
// frames costs, which is part of what is measured.
#include "server/load_clients.h"
#include "support/test_support.h"

#include <fmt/format.h>

#include <sys/wait.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace ff;
using test::Clock;
using namespace std::chrono_literals;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

// A field of /proc/PID/status in KiB ("VmRSS", "VmHWM").
std::size_t status_kib(pid_t pid, const std::string& field) {
  std::FILE* f = std::fopen(fmt::format("/proc/{}/status", pid).c_str(), "r");
  if (!f) return 0;
  char line[256];
  std::size_t kib = 0;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, field.c_str(), field.size()) == 0 && line[field.size()] == ':')
      kib = std::strtoull(line + field.size() + 1, nullptr, 10);
  std::fclose(f);
  return kib;
}

// `fluidform serve` in a child process; its port from the "serving http://127.0.0.1:PORT/" line.
struct Server {
  pid_t pid = -1;
  std::uint16_t port = 0;
};

Server spawn(const std::vector<std::string>& args, Clock::time_point deadline) {
  int out[2];
  if (::pipe(out) != 0) return {};
  Server s;
  s.pid = ::fork();
  if (s.pid == 0) {
    ::dup2(out[1], 1);
    ::close(out[0]), ::close(out[1]);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    std::_Exit(127);
  }
  ::close(out[1]);
  std::string got;
  while (Clock::now() < deadline && got.find('\n') == std::string::npos) {
    pollfd p{out[0], POLLIN, 0};
    if (::poll(&p, 1, 200) <= 0) continue;
    char buf[256];
    const ssize_t k = ::read(out[0], buf, sizeof buf);
    if (k <= 0) break;
    got.append(buf, std::size_t(k));
  }
  ::close(out[0]);  // serve prints nothing more on stdout
  const auto at = got.rfind(':');
  if (got.rfind("serving http://", 0) == 0 && at != std::string::npos) s.port = std::uint16_t(std::atoi(got.c_str() + at + 1));
  return s;
}

struct Phase {
  int viewers = 0;
  double rate = 0;        // simulated frames per second of wall time
  double viewer_fps = 0;  // frames a second the slowest viewer got
  double rss_mib = 0;     // the server's largest VmRSS seen in the phase
};

// One phase: `extra` more viewers beside the measuring one, connected and each past its first frame before the clock
// starts, for `seconds`.
Phase measure(std::uint16_t port, pid_t pid, test::Viewer& probe, int extra, double seconds) {
  std::vector<std::unique_ptr<test::Viewer>> more;
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds + 120));
  for (int i = 0; i < extra; ++i) more.push_back(std::make_unique<test::Viewer>(port, end));
  for (auto until = Clock::now() + 60s; Clock::now() < until; std::this_thread::sleep_for(20ms))
    if (std::all_of(more.begin(), more.end(), [](auto& v) { return v->count() > 0; })) break;
  std::this_thread::sleep_for(1s);  // connections settled
  Phase p;
  p.viewers = extra + 1;
  std::vector<std::uint64_t> before;
  for (auto& v : more) before.push_back(v->count());
  const std::uint64_t probe_before = probe.count();
  const std::uint32_t f0 = probe.newest();
  const auto t0 = Clock::now();
  for (auto until = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
       Clock::now() < until; std::this_thread::sleep_for(100ms))
    p.rss_mib = std::max(p.rss_mib, double(status_kib(pid, "VmRSS")) / 1024);
  const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
  p.rate = double(probe.newest() - f0) / dt;
  double slowest = double(probe.count() - probe_before);
  for (std::size_t i = 0; i < more.size(); ++i) slowest = std::min(slowest, double(more[i]->count() - before[i]));
  p.viewer_fps = slowest / dt;
  more.clear();
  std::this_thread::sleep_for(1s);  // the server notices them gone before the next phase
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path scene = test::source_dir() / "examples" / "default_scene.json";
  int viewers = 64, rounds = 5;
  double phase = 8.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--scene") scene = argv[i + 1];
    else if (a == "--viewers") viewers = std::max(2, std::atoi(argv[i + 1]));
    else if (a == "--rounds") rounds = std::max(1, std::atoi(argv[i + 1]));
    else if (a == "--phase") phase = std::max(1.0, std::atof(argv[i + 1]));
    else return std::fprintf(stderr, "unknown option %s\n", a.c_str()), 2;
  }
  const fs::path cache = fs::temp_directory_path() / "ff-bench-serve-cache";
  const Server srv = spawn({test::binary().string(), "serve", scene.string(), "--port", "0", "--as-fast-as-possible",
                            "--max-clients", std::to_string(viewers + 8), "--cache", cache.string()},
                           Clock::now() + 600s);
  if (srv.port == 0) {
    std::fprintf(stderr, "bench_serve_load: the server did not start\n");
    if (srv.pid > 0) ::kill(srv.pid, SIGKILL), ::waitpid(srv.pid, nullptr, 0);
    return 1;
  }
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(rounds * 2 * (phase + 70) + 300));
  test::Viewer probe(srv.port, end);
  for (auto until = Clock::now() + 60s; Clock::now() < until && probe.count() == 0;) std::this_thread::sleep_for(20ms);
  std::this_thread::sleep_for(3s);  // the first frames' warm-up (caches, the allocator) out of the figures
  std::printf("| round | viewers | simulated frames/s | slowest viewer's frames/s | server RSS MiB |\n|---|---:|---:|---:|---:|\n");
  std::vector<double> one, many, ratios;
  for (int r = 0; r < rounds; ++r) {
    double rate_one = 0, rate_many = 0;
    for (int k = 0; k < 2; ++k) {
      const bool is_many = (r % 2 == 0) == (k == 1);  // 1, N, N, 1, 1, N, …
      const Phase p = measure(srv.port, srv.pid, probe, is_many ? viewers - 1 : 0, phase);
      std::printf("| %d | %d | %.2f | %.2f | %.0f |\n", r, p.viewers, p.rate, p.viewer_fps, p.rss_mib);
      std::fflush(stdout);
      (is_many ? rate_many : rate_one) = p.rate;
      (is_many ? many : one).push_back(p.rate);
    }
    ratios.push_back(rate_many / rate_one);
  }
  const double hwm = double(status_kib(srv.pid, "VmHWM")) / 1024;
  ::kill(srv.pid, SIGTERM);
  int status = 0;
  for (auto until = Clock::now() + 20s; Clock::now() < until && ::waitpid(srv.pid, &status, WNOHANG) == 0;)
    std::this_thread::sleep_for(50ms);
  if (::waitpid(srv.pid, &status, WNOHANG) == 0) ::kill(srv.pid, SIGKILL), ::waitpid(srv.pid, &status, 0);
  std::printf("\nmedian rate: 1 viewer %.2f frames/s, %d viewers %.2f frames/s; ratio of the medians %.3f, "
              "median of the rounds' ratios %.3f; the server's peak RSS (VmHWM) %.0f MiB\n",
              median(one), viewers, median(many), median(many) / median(one), median(ratios), hwm);
  return 0;
}
