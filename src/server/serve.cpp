#include "server/serve.h"

#include "pipeline/live_scene.h"
#include "pipeline/mesh_export.h"
#include "pipeline/front_doors.h"
#include "core/timer.h"
#include "io/particle_frames.h"
#include "scene/scene.h"
#include "io/write_ply.h"
#include "server/frame_codec.h"
#include "server/messages.h"
#include "server/static_files.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <fstream>
#include <mutex>
#include <thread>

namespace ff::server {
namespace fs = std::filesystem;
using nlohmann::json;

Status ServeOptions::validate() const {
  FF_CHECK(server.validate());
  if (!(exit_after >= 0.0 && exit_after <= 1e7)) return param_error("--exit-after must be in [0, 1e7] s");
  if (!(max_fps >= 0.0 && max_fps <= 1000.0)) return param_error("--max-fps must be in [0, 1000] (0: no cap)");
  return {};
}

Result<fs::path> find_web_dir(const fs::path& hint) {
  auto ok = [](const fs::path& d) { return fs::is_regular_file(d / "index.html") && fs::is_directory(d / "src"); };
  if (!hint.empty()) {
    if (!ok(hint)) return input_error(fmt::format("--web {}: no index.html and src/ there", hint.string()));
    return hint;
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
    for (fs::path p = exe.parent_path(); !p.empty() && p != p.root_path(); p = p.parent_path())
      if (ok(p / "web")) return p / "web";
  const fs::path src = fs::path(FF_SOURCE_DIR) / "web";
  if (ok(src)) return src;
  return input_error("the viewer's files (web/index.html) were not found; pass --web DIR");
}

namespace {

json vec(const Vec3f& v) { return json::array({v.x(), v.y(), v.z()}); }

json pose_json(std::size_t t, const pipeline::LivePose& p, double time) {
  return {{"type", "pose"},           {"target", t},          {"translate", vec(p.translate)},
          {"rotate", vec(p.rotate_deg)}, {"scale", p.scale}, {"time", time}};
}

// Frames per second of wall time over about the last second (the HUD's simulation rate).
class RateMeter {
 public:
  float tick() {
    const double now = clock_.seconds();
    stamps_.push_back(now);
    while (stamps_.size() > 2 && now - stamps_.front() > 1.0) stamps_.pop_front();
    const double span = stamps_.back() - stamps_.front();
    return span > 0 ? static_cast<float>(double(stamps_.size() - 1) / span) : 0.0f;
  }
  void reset() { stamps_.clear(); }

 private:
  core::Stopwatch clock_;
  std::deque<double> stamps_;
};

// Commands from the I/O thread to the simulation thread, applied between two frames.
class CommandQueue {
 public:
  void push(Command c) {
    std::lock_guard lock(mu_);
    if (q_.size() < 1024) q_.push_back(std::move(c));  // a flood of drags must not grow without bound
    cv_.notify_all();
  }
  std::deque<Command> take() {
    std::lock_guard lock(mu_);
    return std::exchange(q_, {});
  }
  /// Waits up to `seconds` for a command or a stop.
  void wait(double seconds, const std::atomic<bool>& stop) {
    std::unique_lock lock(mu_);
    cv_.wait_for(lock, std::chrono::duration<double>(seconds), [&] { return !q_.empty() || stop.load(); });
  }
  void wake() { cv_.notify_all(); }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Command> q_;
};

// What the simulation thread needs: the scene or the recorded frames, and where frames go.
struct Shared {
  WsServer* server = nullptr;
  CommandQueue commands;
  std::atomic<bool> stop{false};
  std::atomic<bool> paused{false};
  bool surface = false;  // live surface on (a viewer shows the mesh); the simulation thread's only
  std::mutex hello_mu;
  json hello;  // the current hello (controller, poses and meshes change it), under hello_mu
  void set_hello(json h) {
    std::lock_guard lock(hello_mu);
    hello = std::move(h);
  }
  std::string hello_text() {
    std::lock_guard lock(hello_mu);
    return hello.dump();
  }
};

json live_hello(const pipeline::LiveScene& s, bool paused, bool surface) {
  json targets = json::array();
  for (std::size_t t = 0; t < s.targets().size(); ++t) {
    const auto& lt = s.targets()[t];
    targets.push_back({{"mesh", lt.mesh},
                       {"pivot", vec(lt.pivot)},
                       {"box", {{"min", vec(lt.box.min)}, {"max", vec(lt.box.max)}}},
                       {"pose", pose_json(t, lt.pose, s.time())}});
  }
  json meshes = json::array();
  for (const auto& m : s.meshes()) meshes.push_back(m.filename().string());
  json controllers = json::array();
  for (const auto& name : pipeline::controller_list()) controllers.push_back(name);
  const auto& d = s.scene().domain;
  return {{"type", "hello"},
          {"mode", "live"},
          {"fps", s.fps()},
          {"radius", s.scene().solver.particle_radius},
          {"particles", s.particles().size()},
          {"controller", s.controller_name()},
          {"controllers", controllers},
          {"device", s.device()},
          {"meshes", meshes},
          {"targets", targets},
          {"domain", {{"min", vec(d.min)}, {"max", vec(d.max)}}},
          {"paused", paused},
          {"surface", surface},
          {"animation", nullptr}};
}

// The live surface: the current particles reconstructed (LiveScene::surface, the scene's surface defaults) into
// the mesh the viewer shows. Made on the simulation thread between frames, at most every kSurfaceEvery seconds of
// wall time: 10k particles take ~0.1 s, so the simulation keeps most of its time.
constexpr double kSurfaceEvery = 0.5;
// The HUD's shape metrics are measured at most this often (s of wall time), the last ones shown in between: a number
// read by a person needs no more than a few updates a second, and a skinned target's exact posed metrics cost ~23 ms
// on top of an ~80 ms frame at 9k particles (bench/RESULTS.md "Animated characters, fifth part").
constexpr double kMeasureEvery = 0.25;

void publish_surface(Shared& sh, const pipeline::LiveScene& scene) {
  core::Stopwatch clock;
  if (scene.particles().size() == 0) return;
  auto mesh = scene.surface();
  if (!mesh) {
    spdlog::warn("serve: live surface: {}", mesh.error().message);
    return;
  }
  const SurfaceInfo info{static_cast<std::uint32_t>(scene.frame()), scene.time(), static_cast<float>(1e3 * clock.seconds())};
  sh.server->publish_surface(std::make_shared<const std::vector<std::uint8_t>>(encode_surface(info, *mesh)));
}

void publish(Shared& sh, const FrameInfo& info, std::span<const Vec3f> x, std::span<const std::uint8_t> targets) {
  sh.server->publish_frame(std::make_shared<const std::vector<std::uint8_t>>(encode_frame(info, x, targets)));
}

// Frames at most at `fps` (real time): after each frame, the wait until the next is due. A frame that took longer
// than its share moves the schedule on rather than being made up with a burst.
class Pacer {
 public:
  explicit Pacer(double fps) : dt_(1.0 / fps) {}
  /// Seconds to wait after the frame just published (≤ 0: none).
  double wait() {
    next_due_ = std::max(next_due_ + dt_, clock_.seconds() - dt_);
    return next_due_ - clock_.seconds();
  }
  /// Paused: the schedule restarts from now.
  void hold() { next_due_ = clock_.seconds(); }
  double elapsed() const { return clock_.seconds(); }

 private:
  double dt_, next_due_ = 0.0;
  core::Stopwatch clock_;
};

void error_text(Shared& sh, const std::string& what) {
  spdlog::warn("serve: {}", what);
  sh.server->broadcast_text(json{{"type", "error"}, {"message", what}}.dump());
}

// What the live simulation keeps between frames besides the scene: the HUD's rate and last metrics, when the surface
// and the metrics were last made, and the frames' particle-id order buffers.
struct LiveState {
  RateMeter rate;
  double last_surface = -kSurfaceEvery, last_measure = -kMeasureEvery;
  float shown_error = NAN;
  std::uint32_t shown_controlled = 0;
  int surface_frame = -1;
  // The solver keeps its particles in cell order, which changes between frames; the viewer interpolates each
  // particle between two frames, so frames go out in particle-id order (as a run's PLY frames are written).
  std::vector<Vec3f> by_id_x, by_id_v;
  std::vector<std::uint8_t> by_id_t;
};

// The scene's particles published in particle-id order.
void publish_particles(const pipeline::LiveScene& scene, Shared& sh, LiveState& ls, const FrameInfo& info) {
  scene.particles_by_id(ls.by_id_x, ls.by_id_v, ls.by_id_t);
  publish(sh, info, ls.by_id_x, ls.by_id_t);
}

// One client command applied between frames, and everyone told the new state.
void apply_command(Command& c, pipeline::LiveScene& scene, Shared& sh, LiveState& ls, core::Progress& progress) {
  Status st;
  switch (c.kind) {
    case Command::Kind::Play: sh.paused = false; break;
    case Command::Kind::Pause: sh.paused = true; break;
    case Command::Kind::Restart:
      st = scene.restart();
      ls.rate.reset();
      ls.last_measure = -kMeasureEvery, ls.shown_error = NAN, ls.shown_controlled = 0;  // a fresh start: measure at once
      if (st.ok()) publish_particles(scene, sh, ls, FrameInfo{0, 0.0, 0.0f, NAN, 0.0f, 0});
      break;
    case Command::Kind::Controller: st = scene.set_controller(c.name); break;
    case Command::Kind::Pose: {
      auto applied = scene.set_pose(c.target, c.pose);
      if (!applied) st = applied.error();
      else sh.server->broadcast_text(pose_json(c.target, *applied, scene.time()).dump());
      break;
    }
    case Command::Kind::Mesh: st = scene.set_mesh(c.target, c.mesh, progress); break;
    case Command::Kind::Seek: st = input_error("seek: a live simulation cannot seek (restart instead)"); break;
    case Command::Kind::Surface:
      sh.surface = c.on;
      ls.last_surface = -kSurfaceEvery, ls.surface_frame = -1;  // one now, whatever the last one was
      break;
  }
  if (!st.ok()) error_text(sh, st.error().message);
  sh.set_hello(live_hello(scene, sh.paused, sh.surface));
  // Everyone learns the new state (controller, meshes, paused) the way a new client would; a pose has its own
  // message, sent above.
  if (c.kind != Command::Kind::Pose) sh.server->broadcast_text(sh.hello_text());
}

// The live simulation: commands between frames, one frame, publish, and (realtime) wait out the frame's wall time.
void live_loop(pipeline::LiveScene& scene, Shared& sh, const ServeOptions& opt, core::Progress& progress) {
  LiveState ls;
  // Real time paces at the scene's frame rate; --max-fps caps the wall rate below that (or, as fast as possible, alone).
  const double cap = opt.max_fps > 0 ? opt.max_fps : 0.0;
  const bool paced = opt.realtime || cap > 0;
  Pacer pace(opt.realtime ? (cap > 0 ? std::min(cap, scene.fps()) : scene.fps()) : (cap > 0 ? cap : scene.fps()));
  std::uint64_t frames = 0;
  double step_total = 0.0;
  publish_particles(scene, sh, ls, FrameInfo{0, 0.0, 0.0f, NAN, 0.0f, 0});
  while (!sh.stop) {
    for (Command& c : sh.commands.take()) apply_command(c, scene, sh, ls, progress);
    if (sh.surface && scene.frame() != ls.surface_frame && pace.elapsed() - ls.last_surface >= kSurfaceEvery) {
      ls.last_surface = pace.elapsed();
      ls.surface_frame = scene.frame();
      publish_surface(sh, scene);
    }
    if (sh.paused) {
      sh.commands.wait(0.05, sh.stop);
      pace.hold();
      continue;
    }
    const bool measure = pace.elapsed() - ls.last_measure >= kMeasureEvery;
    auto f = scene.step(measure);
    if (!f) {
      error_text(sh, fmt::format("the simulation stopped: {}; restart to go on", f.error().message));
      sh.paused = true;
      sh.set_hello(live_hello(scene, true, sh.surface));
      continue;
    }
    ++frames;
    step_total += f->step_seconds;
    if (measure) {
      ls.last_measure = pace.elapsed();
      ls.shown_error = static_cast<float>(f->error_rate), ls.shown_controlled = static_cast<std::uint32_t>(f->controlled);
    }
    const FrameInfo info{static_cast<std::uint32_t>(f->frame), f->time, static_cast<float>(1e3 * f->step_seconds),
                         ls.shown_error, ls.rate.tick(), ls.shown_controlled};
    publish_particles(scene, sh, ls, info);
    if (paced) {
      // At most real time: the viewer shows the forming at its true speed when the simulation is faster.
      if (const double wait = pace.wait(); wait > 0) sh.commands.wait(wait, sh.stop);
    }
  }
  if (frames)
    spdlog::info("serve: {} frames simulated, {:.1f} ms per frame, {:.1f} frames per second of wall time", frames,
                 1e3 * step_total / double(frames), double(frames) / pace.elapsed());
}

// Playback of a finished run: its particle frames, read one at a time, in a loop at the run's frame rate.
// (pipeline::open_run reads the folder.)
using Recording = pipeline::RunRecording;

json playback_hello(const Recording& r, bool paused) {
  return {{"type", "hello"},     {"mode", "playback"}, {"fps", r.fps},          {"frames", r.frames.size()},
          {"controller", nullptr}, {"controllers", json::array()}, {"meshes", json::array()},
          {"targets", json::array()}, {"paused", paused},
          {"animation", r.animation ? json("/run/animation.glb") : json(nullptr)},
          {"report", r.report ? json("/run/report.html") : json(nullptr)}};
}

void playback_loop(const Recording& rec, Shared& sh, const ServeOptions& opt) {
  Pacer pace(opt.max_fps > 0 ? std::min(opt.max_fps, rec.fps) : rec.fps);
  RateMeter rate;
  std::size_t k = 0;
  bool show_once = false;
  while (!sh.stop) {
    for (Command& c : sh.commands.take()) {
      if (c.kind == Command::Kind::Play) sh.paused = false;
      else if (c.kind == Command::Kind::Pause) sh.paused = true;
      else if (c.kind == Command::Kind::Restart) k = 0;
      else if (c.kind == Command::Kind::Seek) k = std::min(c.frame, rec.frames.size() - 1), show_once = true;
      else error_text(sh, "playback: a recorded run cannot be steered");
      sh.set_hello(playback_hello(rec, sh.paused));
    }
    // Paused: nothing moves, except that a seek shows the frame it asked for (once, without going on).
    if (sh.paused && !show_once) {
      sh.commands.wait(0.05, sh.stop);
      pace.hold();
      continue;
    }
    auto frame = io::read_particles_ply(rec.frames[k]);
    if (!frame) {
      error_text(sh, fmt::format("playback: {}", frame.error().message));
      sh.paused = true;
      continue;
    }
    const FrameInfo info{static_cast<std::uint32_t>(k), double(k) / rec.fps, static_cast<float>(1e3 * rec.step_seconds[k]),
                         static_cast<float>(rec.error_rate[k]), rate.tick(), 0};
    publish(sh, info, frame->positions, frame->targets);
    if (sh.paused) {
      show_once = false;
      pace.hold();
      continue;
    }
    show_once = false;
    k = (k + 1) % rec.frames.size();
    if (const double wait = pace.wait(); wait > 0) sh.commands.wait(wait, sh.stop);
  }
}

// The input: a run's folder is played back (its animation.glb served under /run/), a scene file is simulated live.
Status open_input(const ServeOptions& opt, core::Progress& progress, Shared& sh,
                  std::unique_ptr<pipeline::LiveScene>& live, std::optional<Recording>& rec, std::vector<Mount>& mounts) {
  std::error_code ec;
  if (fs::is_directory(opt.input, ec)) {
    FF_TRY(rec, pipeline::open_run(opt.input));
    if (rec->animation || rec->report) mounts.push_back({"/run/", opt.input});
    spdlog::info("serve: playing back {} frames of {}{}", rec->frames.size(), opt.input.string(),
                 rec->animation ? " and its animation.glb" : "");
    sh.set_hello(playback_hello(*rec, false));
  } else {
    FF_TRY(scene::Scene scene, scene::load_scene(opt.input));
    pipeline::LiveOptions lo;
    lo.cache_dir = opt.cache_dir;
    lo.controller = opt.controller;
    lo.extra_meshes = opt.meshes;
    lo.max_memory_mib = opt.max_memory_mib;
    lo.device = opt.device;
    FF_TRY(live, pipeline::LiveScene::create(scene, lo, progress));
    spdlog::info("serve: {} particles, controller {}, on {}", live->particles().size(), live->controller_name(),
                 live->device());
    sh.set_hello(live_hello(*live, false, false));
  }
  return {};
}

}  // namespace

Status serve(const ServeOptions& opt, core::Progress& progress) {
  FF_CHECK(opt.validate());
  FF_TRY(const fs::path web, find_web_dir(opt.web_dir));
  const fs::path three = web.parent_path() / "node_modules" / "three";
  if (!fs::is_regular_file(three / "build" / "three.module.js"))
    return input_error(fmt::format("{}: three.js is not installed (npm install)", three.string()));

  Shared sh;
  std::unique_ptr<pipeline::LiveScene> live;
  std::optional<Recording> rec;
  std::vector<Mount> mounts{{"/", web}, {"/vendor/three/", three}};
  FF_CHECK(open_input(opt, progress, sh, live, rec, mounts));
  const StaticFiles files(mounts);

  std::mutex done_mu;
  std::condition_variable done_cv;
  auto request_stop = [&] {
    {
      std::lock_guard lock(done_mu);
      sh.stop = true;
    }
    done_cv.notify_all();
    sh.commands.wake();
  };
  WsServer::Callbacks cb;
  cb.hello = [&] { return sh.hello_text(); };
  cb.on_text = [&](const std::string& text) {
    auto c = parse_command(text);
    if (!c) {
      spdlog::warn("serve: ignored a client message: {}", c.error().message);
      return false;
    }
    sh.commands.push(std::move(*c));
    return true;
  };
  cb.on_signal = [&] {
    spdlog::info("serve: stopping (signal)");
    request_stop();
  };
  WsServer server(opt.server, files, cb);
  sh.server = &server;
  FF_CHECK(server.start());
  const std::string host = opt.server.bind.find(':') != std::string::npos ? "[" + opt.server.bind + "]" : opt.server.bind;
  std::printf("serving http://%s:%u/\n", host.c_str(), unsigned(server.port()));
  std::fflush(stdout);

  std::thread sim([&] {
    if (live) live_loop(*live, sh, opt, progress);
    else playback_loop(*rec, sh, opt);
  });
  {
    std::unique_lock lock(done_mu);
    if (opt.exit_after > 0)
      done_cv.wait_for(lock, std::chrono::duration<double>(opt.exit_after), [&] { return sh.stop.load(); });
    else
      done_cv.wait(lock, [&] { return sh.stop.load(); });
  }
  request_stop();
  sim.join();
  const ServerStats st = server.stats();
  server.stop();
  spdlog::info("serve: stopped; {} frames sent, {} skipped for slow clients, {} bad client messages ignored", st.frames_sent,
               st.frames_skipped, st.bad_messages);
  return {};
}

}  // namespace ff::server
