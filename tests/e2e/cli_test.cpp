// End-to-end tests of the fluidform binary: outputs, exit codes, one-line errors, no partial files,
// thread-count independence and kill -9 + --resume.
#include "e2e/cli_support.h"
#include "io/load_mesh.h"
#include "io/write_ply.h"
#include "sampling/control_io.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <chrono>
#include <cmath>
#include <csignal>
#include <fcntl.h>
#include <fstream>
#include <iterator>
#include <spawn.h>
#include <sstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace ff {
namespace {
namespace fs = std::filesystem;
using namespace e2e;

// ~670 particles, a small dam break.
const std::string kSmallScene = R"({
  "solver": {"particle_radius": 0.02},
  "domain": {"min": [0, 0, 0], "max": [0.8, 0.6, 0.32]},
  "fluid": [{"shape": "box", "min": [0, 0, 0], "max": [0.28, 0.48, 0.32]}],
  "output": {"frames": 12, "checkpoint_every": 4}
})";

TEST(Cli, RunWritesFramesReportAndMetrics) {
  const auto dir = test::temp_dir("run");
  const auto scene = write_scene(dir, kSmallScene);
  const auto r = run({"run", scene.string(), "-o", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  for (int f = 0; f <= 12; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.ply", f);
    auto frame = io::read_particles_ply(dir / "out" / "particles" / name);
    ASSERT_TRUE(frame.has_value()) << name;
    EXPECT_EQ(frame->positions.size(), frame->velocities.size());
    EXPECT_EQ(frame->positions.size(), 672u) << "7 x 12 x 8 lattice";
  }
  const std::string csv = read_file(dir / "out" / "metrics.csv");
  EXPECT_EQ(csv.rfind("frame,time_s,particles,step_time_s,substeps,iterations,density_error_mean,density_error_max,peak_memory_mb", 0), 0u);
  EXPECT_EQ(count_lines(csv), 14u) << "header + frames 0..12";
  const std::string rep = read_file(dir / "out" / "report.json");
  EXPECT_NE(rep.find("\"status\": \"ok\""), std::string::npos);
  EXPECT_NE(rep.find("\"mean_step_time_s\""), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "out" / "checkpoint" / "state.ffck"));
  // The mesh animation of every 4th frame (0, 4, 8, 12) and the point cache, without per-frame OBJs; with
  // --no-animation only final.obj.
  EXPECT_TRUE(fs::exists(dir / "out" / "mesh" / "final.obj"));
  EXPECT_TRUE(fs::exists(dir / "out" / "animation.glb"));
  EXPECT_TRUE(fs::exists(dir / "out" / "particles.pc2"));
  EXPECT_FALSE(fs::exists(dir / "out" / "mesh" / "frame_00004.obj"));
  EXPECT_NE(r.err.find("mesh: 4 frame(s)"), std::string::npos) << r.err;
  expect_no_temp_files(dir / "out");
  const auto bare = run({"-q", "run", scene.string(), "-o", (dir / "bare").string(), "--no-animation"});
  ASSERT_EQ(bare.code, 0) << bare.err;
  EXPECT_TRUE(fs::exists(dir / "bare" / "mesh" / "final.obj"));
  EXPECT_FALSE(fs::exists(dir / "bare" / "animation.glb"));
  EXPECT_FALSE(fs::exists(dir / "bare" / "particles.pc2"));
}

TEST(Cli, OneAndTwoThreadsGiveBitIdenticalFrames) {
  const auto dir = test::temp_dir("threads");
  const auto scene = write_scene(dir, kSmallScene);
  ASSERT_EQ(run({"-q", "run", scene.string(), "-o", (dir / "t1").string()}, 1).code, 0);
  ASSERT_EQ(run({"-q", "run", scene.string(), "-o", (dir / "t2").string()}, 2).code, 0);
  for (int f : {1, 6, 12}) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.ply", f);
    const auto a = read_file(dir / "t1" / "particles" / name), b = read_file(dir / "t2" / "particles" / name);
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << name << " differs between 1 and 2 threads";
  }
}

TEST(Cli, KillNineThenResumeGivesTheSameFinalFrame) {
  const auto dir = test::temp_dir("resume");
  const std::string scene_json = R"({
    "solver": {"particle_radius": 0.015},
    "domain": {"min": [0, 0, 0], "max": [0.9, 0.6, 0.3]},
    "fluid": [{"shape": "box", "min": [0, 0, 0], "max": [0.3, 0.5, 0.3]}],
    "output": {"frames": 400, "checkpoint_every": 5}
  })";
  // Long enough (~2 s) that the kill lands mid-run however fast the solver gets.
  const auto scene = write_scene(dir, scene_json);
  ASSERT_EQ(run({"-q", "run", scene.string(), "-o", (dir / "full").string()}).code, 0);

  const fs::path out = dir / "killed";
  Proc p = start({"-q", "run", scene.string(), "-o", out.string()});
  const fs::path ckpt = out / "checkpoint" / "state.ffck";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(ckpt) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(fs::exists(ckpt)) << "no checkpoint appeared";
  // Die between checkpoints: frames 6–9 are written after the checkpoint of frame 5 and before that of frame 10.
  while (!fs::exists(out / "particles" / "frame_00007.ply") && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  ASSERT_EQ(::kill(p.pid, SIGKILL), 0);
  const auto killed = wait(p);
  ASSERT_EQ(killed.code, 128 + SIGKILL) << "the run finished before it could be killed; make the scene longer";
  ASSERT_FALSE(fs::exists(out / "particles" / "frame_00400.ply"));

  const auto resumed = run({"run", scene.string(), "-o", out.string(), "--resume"});
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("resuming from frame"), std::string::npos) << resumed.err;
  const auto a = read_file(dir / "full" / "particles" / "frame_00400.ply");
  const auto b = read_file(out / "particles" / "frame_00400.ply");
  ASSERT_FALSE(a.empty());
  EXPECT_TRUE(a == b) << "resumed final frame differs from the uninterrupted run";
  // metrics.csv is complete after the resume: header + frames 0..400.
  EXPECT_EQ(count_lines(read_file(out / "metrics.csv")), 402u);
  expect_no_temp_files(out);
}

// Checkpoints keep the one before: a truncated newest checkpoint (a disk that filled, a copy cut short) resumes
// from the previous one, with a warning, and the run still ends identical to an uninterrupted one.
TEST(Cli, ACorruptNewestCheckpointResumesFromThePreviousOne) {
  const auto dir = test::temp_dir("resume-prev");
  const auto scene = write_scene(dir, kSmallScene);  // 12 frames, a checkpoint every 4
  ASSERT_EQ(run({"-q", "run", scene.string(), "-o", (dir / "full").string(), "--no-mesh"}).code, 0);
  const fs::path out = dir / "o", ck = out / "checkpoint" / "state.ffck", prev = out / "checkpoint" / "state.prev.ffck";
  ASSERT_EQ(run({"-q", "run", scene.string(), "-o", out.string(), "--frames", "8", "--no-mesh"}).code, 0);
  ASSERT_TRUE(fs::exists(ck));
  ASSERT_TRUE(fs::exists(prev)) << "the frame-4 checkpoint is kept beside the frame-8 one";
  fs::resize_file(ck, fs::file_size(ck) / 2);
  const auto r = run({"run", scene.string(), "-o", out.string(), "--resume", "--no-mesh"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("resuming from the checkpoint before it"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("resuming from frame 5"), std::string::npos) << r.err;
  EXPECT_TRUE(read_file(dir / "full" / "particles" / "frame_00012.ply") == read_file(out / "particles" / "frame_00012.ply"));
  EXPECT_EQ(count_lines(read_file(out / "metrics.csv")), 14u);
  // The newest gone (killed between keeping the old one and writing the new one): the previous one alone is enough.
  fs::remove(ck);
  const auto r2 = run({"run", scene.string(), "-o", out.string(), "--resume", "--no-mesh"});
  ASSERT_EQ(r2.code, 0) << r2.err;
  EXPECT_NE(r2.err.find("resuming from the checkpoint before it"), std::string::npos) << r2.err;
  EXPECT_NE(r2.err.find("resuming from frame 9"), std::string::npos) << r2.err;
  // Neither readable: one line naming the file, exit 2.
  fs::resize_file(ck, fs::file_size(ck) / 3);
  fs::resize_file(prev, fs::file_size(prev) / 3);
  const auto bad = run({"-q", "run", scene.string(), "-o", out.string(), "--resume", "--no-mesh"});
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("state.prev.ffck"), std::string::npos) << bad.err;
  expect_no_temp_files(out);
}

TEST(Cli, ResumeRefusesAChangedScene) {
  const auto dir = test::temp_dir("resume2");
  const auto scene = write_scene(dir, kSmallScene);
  ASSERT_EQ(run({"-q", "run", scene.string(), "-o", (dir / "o").string()}).code, 0);
  std::string changed = kSmallScene;
  changed.replace(changed.find("0.02"), 4, "0.03");
  write_scene(dir, changed);
  const auto r = run({"-q", "run", scene.string(), "-o", (dir / "o").string(), "--resume"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("different scene"), std::string::npos) << r.err;
}

struct BadCase {
  std::string name, scene_json;     // scene_json empty: args are used as they are
  std::vector<std::string> args;    // "{scene}" and "{out}" are replaced
  int code;
  std::string must_contain;
};

TEST(Cli, EveryBadInputExitsNonZeroWithOneLineAndNoPartialOutput) {
  const auto dir = test::temp_dir("bad");
  const std::string fluid = R"("fluid":[{"shape":"box","min":[0,0,0],"max":[0.2,0.2,0.2]}])";
  std::vector<BadCase> cases = {
      {"broken json", R"({"fluid": [ )", {"run", "{scene}", "-o", "{out}"}, 2, "invalid JSON"},
      {"unknown key", "{\"solver\":{\"iteratons\":3}," + fluid + "}", {"run", "{scene}", "-o", "{out}"}, 2,
       "did you mean 'iterations'"},
      {"negative radius", "{\"solver\":{\"particle_radius\":-1}," + fluid + "}", {"run", "{scene}", "-o", "{out}"}, 2,
       "solver.particle_radius = -1"},
      {"nan value", "{\"solver\":{\"viscosity\":NaN}," + fluid + "}", {"run", "{scene}", "-o", "{out}"}, 2, "invalid JSON"},
      {"missing scene", "", {"run", "/nonexistent/scene.json", "-o", "{out}"}, 2, "no such scene file"},
      {"scene is a folder", "", {"run", "/tmp", "-o", "{out}"}, 2, "is a folder"},
      {"unwritable output", "{" + fluid + "}", {"run", "{scene}", "-o", "/proc/fluidform-out"}, 1, "/proc/fluidform-out"},
      {"output is a file", "{" + fluid + "}", {"run", "{scene}", "-o", "{scene}"}, 1, "not a folder"},
      {"missing target mesh", "{\"targets\":[{\"mesh\":\"nope.obj\"}]," + fluid + "}", {"run", "{scene}", "-o", "{out}"},
       2, "nope.obj"},
      {"empty target mesh", "{\"targets\":[{\"mesh\":\"" + (test::data_dir() / "empty.obj").string() + "\"}]," + fluid + "}",
       {"run", "{scene}", "-o", "{out}"}, 2, "empty.obj"},
      {"nan target mesh", "{\"targets\":[{\"mesh\":\"" + (test::data_dir() / "nan_vertex.obj").string() + "\"}]," + fluid + "}",
       {"run", "{scene}", "-o", "{out}"}, 2, "nan_vertex.obj"},
      {"point-only mesh", "{\"targets\":[{\"mesh\":\"" + (test::data_dir() / "points_only.obj").string() + "\"}]," + fluid + "}",
       {"run", "{scene}", "-o", "{out}"}, 2, "points_only.obj"},
      {"malformed mesh", "{\"targets\":[{\"mesh\":\"/usr/share/assimp/models/invalid/malformed.obj\"}]," + fluid + "}",
       {"run", "{scene}", "-o", "{out}"}, 2, "malformed.obj"},
      // Assimp 5.2.5 writes past its vertex array on this file and glibc aborts at a later free: in its own process.
      {"mesh that crashes Assimp",
       "{\"targets\":[{\"mesh\":\"" + (test::data_dir() / "obj_lines_overflow.obj").string() + "\"}]," + fluid + "}",
       {"run", "{scene}", "-o", "{out}"}, 2, "obj_lines_overflow.obj"},
      {"fluid outside domain", R"({"fluid":[{"shape":"box","min":[5,5,5],"max":[6,6,6]}]})", {"run", "{scene}", "-o", "{out}"},
       2, "fluid[0]"},
      {"too many particles", R"({"solver":{"particle_radius":0.0002},"domain":{"min":[0,0,0],"max":[2,2,2]},)" + fluid + "}",
       {"run", "{scene}", "-o", "{out}"}, 2, "more than the limit"},
      {"tiny particles on a target",
       "{\"targets\":[{\"mesh\":\"" + (test::data_dir() / "tetra.obj").string() + "\"}],\"solver\":{\"particle_radius\":0.0002}}",
       {"run", "{scene}", "-o", "{out}"}, 2, "sampling.max_samples"},
      {"zero scale", "{\"targets\":[{\"mesh\":\"" + (test::data_dir() / "tetra.obj").string() + "\",\"scale\":[1,0,1]}]}",
       {"run", "{scene}", "-o", "{out}"}, 2, "targets[0].scale"},
      {"over the memory budget", "{" + fluid + "}", {"run", "{scene}", "-o", "{out}", "--max-memory", "1"}, 2,
       "more than the limit of 1 MiB"},
      {"compare over the memory budget",
       "{\"targets\":[{\"mesh\":\"" + (test::data_dir() / "tetra.obj").string() + "\"}]}",
       {"compare", "{scene}", "-o", "{out}", "--controllers", "pbfc", "--max-memory", "1"}, 2, "more than the limit of 1 MiB"},
      {"serve over the memory budget",
       "{\"targets\":[{\"mesh\":\"" + (test::data_dir() / "tetra.obj").string() + "\"}]}",
       {"serve", "{scene}", "--port", "0", "--cache", "{out}", "--max-memory", "1"}, 2, "more than the limit of 1 MiB"},
      {"unknown option", "", {"run", "x.json", "--bogus"}, 2, "bogus"},
      {"frames zero", "{" + fluid + "}", {"run", "{scene}", "-o", "{out}", "--frames", "0"}, 2, "frames"},
      {"no scene argument", "", {"run"}, 2, "scene"},
      {"unknown sampling key", "{\"sampling\":{\"spacng\":0.1}," + fluid + "}", {"run", "{scene}", "-o", "{out}"}, 2,
       "did you mean 'spacing'"},
      {"bad sampling method", "{\"sampling\":{\"method\":\"grid\"}," + fluid + "}", {"run", "{scene}", "-o", "{out}"}, 2,
       "sampling.method"},
  };
  int k = 0;
  for (const auto& c : cases) {
    const fs::path sub = dir / std::to_string(k++);
    fs::create_directories(sub);
    const fs::path scene = c.scene_json.empty() ? sub / "none.json" : write_scene(sub, c.scene_json);
    const fs::path out = sub / "out";
    std::vector<std::string> args;
    for (auto a : c.args) {
      if (a == "{scene}") a = scene.string();
      if (a == "{out}") a = out.string();
      args.push_back(a);
    }
    args.insert(args.begin(), "-q");
    const auto r = run(args);
    EXPECT_EQ(r.code, c.code) << c.name << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << c.name << ": stderr must be one line, got:\n" << r.err;
    EXPECT_EQ(r.err.rfind("fluidform: error: ", 0), 0u) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.must_contain), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out / "particles" / "frame_00001.ply")) << c.name;
    // compare and serve check everything before they write: not even their folders are made.
    if (c.args[0] == "compare" || c.args[0] == "serve") {
      EXPECT_FALSE(fs::exists(out)) << c.name;
    }
    expect_no_temp_files(sub);
  }
}

TEST(Cli, AFailedRunKeepsWhatItWroteBefore) {
  // A first good run, then a bad scene into the same folder: the earlier frames stay intact.
  const auto dir = test::temp_dir("keep");
  const auto scene = write_scene(dir, kSmallScene);
  ASSERT_EQ(run({"-q", "run", scene.string(), "-o", (dir / "o").string()}).code, 0);
  const auto before = read_file(dir / "o" / "particles" / "frame_00012.ply");
  write_scene(dir, R"({"fluid": [ )", "bad.json");
  EXPECT_EQ(run({"-q", "run", (dir / "bad.json").string(), "-o", (dir / "o").string()}).code, 2);
  EXPECT_EQ(read_file(dir / "o" / "particles" / "frame_00012.ply"), before);
}

TEST(Cli, SampleWritesControlParticlesWithWeights) {
  const auto dir = test::temp_dir("sample");
  test::write_obj(dir / "box.obj", test::box_mesh(Vec3f(0, 0, 0), Vec3f(1, 0.5f, 0.5f)));
  const auto r = run({"sample", (dir / "box.obj").string(), "--spacing", "0.1", "--method", "voxel", "-o",
                      (dir / "c.ply").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  auto set = sampling::read_controls_ply(dir / "c.ply");
  ASSERT_TRUE(set.has_value()) << set.error().message;
  EXPECT_EQ(set->size(), 10u * 5u * 5u);
  EXPECT_FLOAT_EQ(set->spacing, 0.1f);
  for (float w : set->weight) EXPECT_TRUE(w > 0.0f && w <= 1.0f);
  for (float p : set->phi) EXPECT_TRUE(p >= 0.05f - 1e-6f && p <= 1.05f + 1e-6f);

  // Blue noise (the default) with the automatic spacing: about --count samples.
  const auto b = run({"sample", (dir / "box.obj").string(), "--count", "2000", "-o", (dir / "b.ply").string()});
  ASSERT_EQ(b.code, 0) << b.err;
  auto blue = sampling::read_controls_ply(dir / "b.ply");
  ASSERT_TRUE(blue.has_value());
  EXPECT_NEAR(double(blue->size()), 2000.0, 100.0);

  // An open sheet: a shell, a warning, exit 0.
  io::TriangleMesh sheet;
  sheet.vertices = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(1, 0, 1), Vec3f(0, 0, 1)};
  sheet.triangles = {{0, 1, 2}, {0, 2, 3}};
  test::write_obj(dir / "sheet.obj", sheet);
  const auto s = run({"sample", (dir / "sheet.obj").string(), "--spacing", "0.1", "-o", (dir / "s.ply").string()});
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_NE(s.err.find("encloses no volume"), std::string::npos) << s.err;
  EXPECT_TRUE(fs::exists(dir / "s.ply"));
}

TEST(Cli, SampleBadInputIsOneLineAndWritesNothing) {
  const auto dir = test::temp_dir("sample_bad");
  test::write_obj(dir / "box.obj", test::box_mesh(Vec3f(0, 0, 0), Vec3f(1, 1, 1)));
  struct Case {
    std::string name;
    std::vector<std::string> args;
    std::string must_contain;
  };
  const std::string out = (dir / "c.ply").string();
  const std::vector<Case> cases = {
      {"missing mesh", {"sample", "/nonexistent.obj", "-o", out}, "nonexistent.obj"},
      {"empty mesh", {"sample", (test::data_dir() / "empty.obj").string(), "-o", out}, "empty.obj"},
      {"bad method", {"sample", (dir / "box.obj").string(), "--method", "lattice", "-o", out}, "lattice"},
      {"too many samples", {"sample", (dir / "box.obj").string(), "--spacing", "0.0001", "-o", out}, "more than the limit"},
      {"negative spacing", {"sample", (dir / "box.obj").string(), "--spacing", "-1", "-o", out}, "spacing"},
      {"drop fraction 1", {"sample", (dir / "box.obj").string(), "--drop-fraction", "1", "-o", out}, "drop_fraction"},
      {"no output", {"sample", (dir / "box.obj").string()}, "out"},
  };
  for (const auto& c : cases) {
    auto args = c.args;
    args.insert(args.begin(), "-q");
    const auto r = run(args);
    EXPECT_EQ(r.code, 2) << c.name << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.must_contain), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
  expect_no_temp_files(dir);
}

// report.json's scene is the whole scene the run used: run again, it gives the same frames. Two targets, everything
// else automatic (radius, fluid, domain), the length from --frames: the cases where the written scene must say what
// the run filled in or was told.
TEST(Cli, TheReportsSceneRunAgainGivesTheSameFrames) {
  const auto dir = test::temp_dir("reproduce");
  test::write_obj(dir / "ball.obj", test::sphere_mesh(0.2f, 3));
  test::write_obj(dir / "box.obj", test::box_mesh(Vec3f(-0.15f, 0.0f, -0.1f), Vec3f(0.15f, 0.3f, 0.1f)));
  const auto scene = write_scene(dir, R"({"targets": [{"mesh": "ball.obj", "translate": [-0.3, 0.4, 0]},
                                                      {"mesh": "box.obj", "translate": [0.35, 0.2, 0], "start": 0.1}],
                                         "sampling": {"auto_count": 600}, "controller": {"adaptive": {"alpha": 0.6}}})");
  const auto first = run({"-q", "run", scene.string(), "-o", (dir / "first").string(), "--frames", "30", "--no-mesh"});
  ASSERT_EQ(first.code, 0) << first.err;
  const auto rep = nlohmann::json::parse(read_file(dir / "first" / "report.json"));
  ASSERT_TRUE(rep["scene"]["controller"]["adaptive"]["alpha"].is_number()) << rep["scene"].dump();
  EXPECT_EQ(rep["scene"]["output"]["frames"], 30);
  const fs::path again = dir / "elsewhere" / "again.json";  // another folder: the mesh paths must be absolute
  fs::create_directories(again.parent_path());
  std::ofstream(again) << rep["scene"].dump(2);
  const auto second = run({"-q", "run", again.string(), "-o", (dir / "second").string(), "--no-mesh"});
  ASSERT_EQ(second.code, 0) << second.err;
  for (int f : {1, 15, 30}) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.ply", f);
    const auto a = read_file(dir / "first" / "particles" / name), b = read_file(dir / "second" / "particles" / name);
    ASSERT_FALSE(a.empty()) << name;
    EXPECT_TRUE(a == b) << name << " differs when the report's scene is run again";
  }
  const auto rep2 = nlohmann::json::parse(read_file(dir / "second" / "report.json"));
  EXPECT_EQ(rep2["scene"], rep["scene"]);
}

TEST(Cli, RunSamplesTargetsOnceThenUsesTheCache) {
  const auto dir = test::temp_dir("cache");
  test::write_obj(dir / "box.obj", test::box_mesh(Vec3f(0.3f, 0.1f, 0.05f), Vec3f(0.5f, 0.3f, 0.25f)));
  const auto scene = write_scene(dir, R"({
    "solver": {"particle_radius": 0.02},
    "domain": {"min": [0, 0, 0], "max": [0.8, 0.6, 0.32]},
    "fluid": [{"shape": "box", "min": [0, 0, 0], "max": [0.2, 0.2, 0.2]}],
    "targets": [{"mesh": "box.obj"}],
    "output": {"frames": 2}
  })");
  const auto first = run({"run", scene.string(), "-o", (dir / "out").string()});
  ASSERT_EQ(first.code, 0) << first.err;
  std::string rep = read_file(dir / "out" / "report.json");
  EXPECT_NE(rep.find("\"cached\": false"), std::string::npos) << rep;
  EXPECT_NE(rep.find("\"control_particles\": "), std::string::npos);
  const auto second = run({"run", scene.string(), "-o", (dir / "out").string()});
  ASSERT_EQ(second.code, 0) << second.err;
  rep = read_file(dir / "out" / "report.json");
  EXPECT_NE(rep.find("\"cached\": true"), std::string::npos) << rep;
  EXPECT_NE(second.err.find("from the cache"), std::string::npos) << second.err;
  // A changed mesh is sampled again.
  test::write_obj(dir / "box.obj", test::box_mesh(Vec3f(0.3f, 0.1f, 0.05f), Vec3f(0.55f, 0.3f, 0.25f)));
  const auto third = run({"run", scene.string(), "-o", (dir / "out").string()});
  ASSERT_EQ(third.code, 0) << third.err;
  EXPECT_NE(read_file(dir / "out" / "report.json").find("\"cached\": false"), std::string::npos);
}

// A scene of only a target: spacing, fluid, domain and controller come from the defaults; the run writes
// the shape metrics per frame and per target, and the totals.
TEST(Cli, RunWithOnlyATargetFormsItAndReportsShapeMetrics) {
  const auto dir = test::temp_dir("target");
  test::write_obj(dir / "ball.obj", test::sphere_mesh(0.3f, 3));
  const auto scene = write_scene(dir, R"({"targets": [{"mesh": "ball.obj", "translate": [0, 0.5, 0]}],
                                         "sampling": {"auto_count": 400}})");
  const auto r = run({"run", scene.string(), "-o", (dir / "out").string(), "--frames", "90"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rep = nlohmann::json::parse(read_file(dir / "out" / "report.json"));
  const auto& t = rep["totals"];
  EXPECT_EQ(t["controller"], "adaptive");
  ASSERT_TRUE(t["error_rate_pct"].is_number()) << t.dump();
  EXPECT_LT(t["error_rate_pct"].get<double>(), 10.0) << t.dump();
  EXPECT_GT(t["inside_fraction"].get<double>(), 0.8) << t.dump();
  EXPECT_EQ(t["per_target"].size(), 1u);
  const auto csv = read_file(dir / "out" / "metrics_targets.csv");
  EXPECT_EQ(count_lines(csv), 92u);  // header + frames 0..90
  EXPECT_NE(read_file(dir / "out" / "metrics.csv").find("error_rate_pct"), std::string::npos);

  const auto bad = run({"run", scene.string(), "-o", (dir / "out2").string(), "--controller", "magic"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("adaptive, none"), std::string::npos) << bad.err;
  EXPECT_EQ(count_lines(bad.err), 1u) << bad.err;
}

// Issue 46 item 6: a mesh in place of the scene file runs the smallest scene around it (the default ~10k count; two
// frames here), and report.json's scene is that scene; a file that is neither is one line saying what was expected.
TEST(Cli, AMeshFileRunsAsTheSmallestSceneAroundIt) {
  const auto dir = test::temp_dir("mesh_as_scene");
  test::write_obj(dir / "ball.obj", test::sphere_mesh(0.3f, 3));
  const auto r = run({"run", (dir / "ball.obj").string(), "-o", (dir / "out").string(), "--frames", "2", "--no-mesh"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("is a mesh: running the smallest scene around it"), std::string::npos) << r.err;
  const auto rep = nlohmann::json::parse(read_file(dir / "out" / "report.json"));
  ASSERT_EQ(rep["scene"]["targets"].size(), 1u) << rep["scene"].dump();
  EXPECT_EQ(rep["scene"]["targets"][0]["mesh"], (dir / "ball.obj").string());
  EXPECT_GT(rep["totals"]["particles"].get<double>(), 5000.0) << rep["totals"].dump();  // the default count

  std::ofstream(dir / "notes.txt") << "hello\n";
  const auto bad = run({"run", (dir / "notes.txt").string(), "-o", (dir / "out2").string()});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("neither a scene file (JSON) nor a mesh file"), std::string::npos) << bad.err;
  EXPECT_EQ(count_lines(bad.err), 1u) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out2"));
}

// A target in other units (a character exported in centimetres is hundreds of "metres" tall) runs with the defaults:
// its derived radius is far above any absolute limit a hand-written scene would need, and one line suggests the scale.
TEST(Cli, ATargetHundredsOfMetresTallRunsAndSuggestsTheUnitScale) {
  const auto dir = test::temp_dir("huge");
  test::write_obj(dir / "ball.obj", test::sphere_mesh(150.0f, 3));  // 300 m across
  const auto scene = write_scene(dir, R"({"targets": [{"mesh": "ball.obj"}], "sampling": {"auto_count": 400}})");
  const auto r = run({"run", scene.string(), "-o", (dir / "out").string(), "--frames", "2", "--no-mesh"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("300 m across, far outside human scale: if the file is in centimetres, add \"scale\": 0.01"),
            std::string::npos) << r.err;
  const auto rep = nlohmann::json::parse(read_file(dir / "out" / "report.json"));
  const double radius = rep["scene"]["solver"]["particle_radius"].get<double>();
  EXPECT_GT(radius, 10.0);  // the old absolute limit
  EXPECT_LT(radius, 30.0);  // ~400 samples in a 300 m ball: d ≈ 30 m
  // Its thinnest wall is its diameter (sampling/thickness.h), ~4.6 spacings: no thin-wall line.
  const auto& wall = rep["targets"][0]["thinnest_wall"];
  EXPECT_NEAR(wall["m"].get<double>(), 300.0, 9.0) << wall.dump();
  EXPECT_NEAR(wall["spacings"].get<double>(), 300.0 / (2.0 * radius), 0.5) << wall.dump();
  EXPECT_EQ(r.err.find("may come out with holes"), std::string::npos) << r.err;
  // A human-sized target gets no such line.
  const auto small = write_scene(dir, R"({"targets": [{"mesh": "small.obj"}], "sampling": {"auto_count": 400}})");
  test::write_obj(dir / "small.obj", test::sphere_mesh(0.5f, 3));
  const auto q = run({"run", small.string(), "-o", (dir / "out2").string(), "--frames", "2", "--no-mesh"});
  ASSERT_EQ(q.code, 0) << q.err;
  EXPECT_EQ(q.err.find("human scale"), std::string::npos) << q.err;
}

// A thin-walled target (a 2 cm plate at ~400 particles: d ≈ 3.7 cm) gets one line naming its thin walls and the count
// that would resolve them, and report.json records them; a bad input still fails with one line, before it.
TEST(Cli, ThinWallsAreMeasuredAndNamed) {
  const auto dir = test::temp_dir("thin");
  test::write_obj(dir / "plate.obj", test::box(Vec3f(0.5f, 0.01f, 0.5f), 8));
  const auto scene = write_scene(dir, R"({"targets": [{"mesh": "plate.obj"}], "sampling": {"auto_count": 400}})");
  const auto r = run({"run", scene.string(), "-o", (dir / "out").string(), "--frames", "1", "--no-mesh"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::size_t lines = 0;
  for (std::size_t at = 0; (at = r.err.find("may come out with holes", at)) != std::string::npos; ++at) ++lines;
  EXPECT_EQ(lines, 1u) << r.err;
  EXPECT_NE(r.err.find("target 0: walls 0.0"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("particles (sampling.auto_count)"), std::string::npos) << r.err;
  const auto rep = nlohmann::json::parse(read_file(dir / "out" / "report.json"));
  const auto& wall = rep["targets"][0]["thinnest_wall"];
  EXPECT_NEAR(wall["m"].get<double>(), 0.02, 0.002) << wall.dump();
  EXPECT_LT(wall["spacings"].get<double>(), 1.0) << wall.dump();
  const auto bad = run({"-q", "run", scene.string(), "-o", (dir / "out2").string(), "--max-memory", "1"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_EQ(count_lines(bad.err), 1u) << bad.err;
}

// A mirrored target (a negative scale, as artists mirror models) forms as well as the original, and sampling,
// control, metrics and export agree on it: the samples, the fluid and the final mesh are the mirror image's.
TEST(Cli, AMirroredBunnyFormsLikeTheOriginal) {
  const auto dir = test::temp_dir("mirror");
  auto bunny = test::stanford_bunny();
  ASSERT_TRUE(bunny.has_value()) << bunny.error().message;
  test::write_obj(dir / "bunny.obj", *bunny);
  struct Out {
    nlohmann::json totals;
    io::TriangleMesh mesh;
  };
  auto form = [&](const char* name, const char* scale) {
    const auto scene = write_scene(dir, fmt::format(R"({{"targets": [{{"mesh": "bunny.obj", "scale": {}}}],
                                                    "sampling": {{"auto_count": 1500}}}})", scale), std::string(name) + ".json");
    const auto r = run({"-q", "run", scene.string(), "-o", (dir / name).string(), "--frames", "150", "--no-animation"});
    EXPECT_EQ(r.code, 0) << r.err;
    Out o;
    o.totals = nlohmann::json::parse(read_file(dir / name / "report.json"))["totals"];
    auto m = io::load_mesh(dir / name / "mesh" / "final.obj");
    EXPECT_TRUE(m.has_value());
    if (m) o.mesh = std::move(*m);
    return o;
  };
  const Out plain = form("plain", "0.1"), mirrored = form("mirrored", "[-0.1, 0.1, 0.1]");
  ASSERT_FALSE(plain.mesh.triangles.empty());
  ASSERT_FALSE(mirrored.mesh.triangles.empty());
  // Sampling: as many samples as the original.
  const double n0 = plain.totals["control_particles"].get<double>(), n1 = mirrored.totals["control_particles"].get<double>();
  EXPECT_NEAR(n1, n0, 0.03 * n0);
  // Control and metrics: the mirrored shape forms as well (inside the mirrored mesh, not the original).
  EXPECT_LT(mirrored.totals["error_rate_pct"].get<double>(), 1.5) << mirrored.totals.dump();
  EXPECT_GT(mirrored.totals["inside_fraction"].get<double>(), 0.98) << mirrored.totals.dump();
  EXPECT_LT(mirrored.totals["error_rate_pct"].get<double>(), 2.0 * plain.totals["error_rate_pct"].get<double>() + 0.2);
  // Export: a closed mesh facing out, whose box is the original's mirrored in x.
  EXPECT_GT(io::signed_volume(mirrored.mesh), 0.9 * io::signed_volume(plain.mesh));
  Aabb b0, b1;
  for (const auto& v : plain.mesh.vertices) b0.extend(v);
  for (const auto& v : mirrored.mesh.vertices) b1.extend(v);
  const float d = 0.1f * (b0.max - b0.min).maxCoeff();
  EXPECT_NEAR(b1.min.x(), -b0.max.x(), d);
  EXPECT_NEAR(b1.max.x(), -b0.min.x(), d);
  EXPECT_NEAR(b1.min.y(), b0.min.y(), d);
  EXPECT_NEAR(b1.max.z(), b0.max.z(), d);
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {
// A skinned, animated target (issue 19): the run follows the clip, measures against the posed target, and writes
// rigged.glb, the formed mesh in bind pose with the file's skeleton and clip, which the Khronos validator passes and
// three.js plays: posed at three times of the clip it covers the simulated fluid at those times within 2 d, and at the
// run's last time the formed final.obj.
TEST(Cli, ASkinnedTargetRunWritesARiggedGlbThatPlaysTheFormedShape) {
  using nlohmann::json;
  const auto dir = test::temp_dir("rigged-run");
  const auto scene = e2e::write_scene(dir, R"({
    "targets": [{"mesh": "/usr/share/assimp/models/X/anim_test.x", "scale": 0.3,
                 "animation": {"clip": "cylinder_test", "speed": 0.5}}],
    "sampling": {"auto_count": 3000},
    "output": {"frames": 234}
  })");
  const fs::path out = dir / "out";
  const auto r = e2e::run({"run", scene.string(), "-o", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("skinned, "), std::string::npos) << r.err;
  ASSERT_TRUE(fs::exists(out / "rigged.glb")) << r.err;
  const json report = json::parse(e2e::read_file(out / "report.json"));
  const double radius = report["scene"]["solver"]["particle_radius"].get<double>(), spacing = 2.0 * radius;
  // The 1 s clip ends 16.5 % of the cylinder's size from where it starts, so the run played it back and forth
  // (animation.wrap auto), and rigged.glb carries that as its second clip, "cylinder_test pingpong" (2 s). Formed by
  // ~3 s; frames 204, 219, 234 (t = 3.4, 3.65, 3.9 s) at speed 0.5 are in the clip's second, backwards play: times
  // 1.7, 1.825, 1.95 s of the baked clip, 0.3, 0.175, 0.05 s of the file's.
  const std::vector<int> frames{204, 219, 234};
  const auto tau = [](int f) { return std::fmod(0.5 * f / 60.0, 2.0); };
  const std::string times = fmt::format("{},{},{}", tau(frames[0]), tau(frames[1]), tau(frames[2]));
  if (test::shell("node --version").first != 0) GTEST_SKIP() << "node is not installed (scripts/setup installs it)";
  const auto [rc, o] = test::shell("node '" + (test::source_dir() / "scripts" / "check_rigged_glb.mjs").string() + "' '" +
                                   (out / "rigged.glb").string() + "' --clip 1 --times " + times);
  ASSERT_EQ(rc, 0) << o;
  const json j = json::parse(o.substr(o.rfind("\n{") == std::string::npos ? 0 : o.rfind("\n{") + 1), nullptr, false);
  ASSERT_FALSE(j.is_discarded()) << o;
  EXPECT_EQ(j["errors"], 0) << o;
  EXPECT_EQ(j["three"]["skinned_meshes"], 1) << o;
  ASSERT_EQ(j["three"]["clips"].size(), 2u) << o;
  EXPECT_EQ(j["three"]["clips"][1]["name"], "cylinder_test pingpong") << o;
  EXPECT_EQ(j["three"]["clips"][1]["duration"], 2) << o;
  ASSERT_EQ(j["three"]["poses"].size(), frames.size()) << o;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    // The fluid's surface lies about r beyond its particles' centres.
    auto frame = io::read_particles_ply(out / "particles" / fmt::format("frame_{:05d}.ply", frames[k]));
    ASSERT_TRUE(frame.has_value()) << frame.error().message;
    Aabb fluid;
    for (const Vec3f& x : frame->positions) fluid.extend(x);
    const auto& pose = j["three"]["poses"][k];
    double worst = 0.0;
    for (int a = 0; a < 3; ++a)
      worst = std::max({worst, std::abs(pose["min"][a].get<double>() - (fluid.min[a] - radius)),
                        std::abs(pose["max"][a].get<double>() - (fluid.max[a] + radius))});
    std::printf("frame %d (clip time %.3f s): three.js's skinned bounds vs the fluid's, worst side %.4f m = %.2f d\n",
                frames[k], tau(frames[k]), worst, worst / spacing);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(pose["min"][a].get<double>(), fluid.min[a] - radius, 2.0 * spacing) << "frame " << frames[k] << ", axis " << a;
      EXPECT_NEAR(pose["max"][a].get<double>(), fluid.max[a] + radius, 2.0 * spacing) << "frame " << frames[k] << ", axis " << a;
    }
  }
  auto formed = io::load_mesh(out / "mesh" / "final.obj");
  ASSERT_TRUE(formed.has_value());
  const Aabb b = formed->bounds();
  const auto& last = j["three"]["poses"][frames.size() - 1];
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(last["min"][a].get<double>(), b.min[a], 2.0 * spacing) << "axis " << a << ": " << o;
    EXPECT_NEAR(last["max"][a].get<double>(), b.max[a], 2.0 * spacing) << "axis " << a << ": " << o;
  }
}
}  // namespace
}  // namespace ff

namespace ff {
namespace {
// What scripts/fault_inject found: a `mesh` (or `compare`, or a fresh `run`) killed mid-write leaves its temporary
// files, and the rerun must clear them (a writer still running keeps its own: the pid in the name is alive).
TEST(Cli, RerunsClearTheTemporaryFilesAKilledCommandLeft) {
  const auto dir = test::temp_dir("stale");
  const auto scene = e2e::write_scene(dir, R"({
    "solver": {"particle_radius": 0.02},
    "domain": {"min": [0, 0, 0], "max": [0.8, 0.6, 0.32]},
    "fluid": [{"shape": "box", "min": [0, 0, 0], "max": [0.28, 0.48, 0.32]}],
    "output": {"frames": 8, "checkpoint_every": 4}
  })");
  const fs::path out = dir / "o";
  ASSERT_EQ(e2e::run({"-q", "run", scene.string(), "-o", out.string(), "--no-mesh"}).code, 0);
  // A pid that cannot be running (above the kernel's pid_max of 2^22), and this process's own (alive: kept).
  const std::string dead = ".tmp.99999999", alive = ".tmp." + std::to_string(::getpid());
  const auto plant = [](const fs::path& p) { std::ofstream(p) << "half"; };
  fs::create_directories(out / "mesh");
  plant(out / "mesh" / ("frame_00004.obj" + dead));
  plant(out / ("animation.glb" + dead));
  plant(out / ("particles.pc2" + alive));
  ASSERT_EQ(e2e::run({"-q", "mesh", out.string(), "-o", out.string()}).code, 0);
  EXPECT_FALSE(fs::exists(out / "mesh" / ("frame_00004.obj" + dead)));
  EXPECT_FALSE(fs::exists(out / ("animation.glb" + dead)));
  EXPECT_TRUE(fs::exists(out / ("particles.pc2" + alive))) << "a live writer's file must be kept";
  fs::remove(out / ("particles.pc2" + alive));
  // A fresh run (not --resume) into the folder clears them too.
  plant(out / "particles" / ("frame_00003.ply" + dead));
  ASSERT_EQ(e2e::run({"-q", "run", scene.string(), "-o", out.string(), "--no-mesh"}).code, 0);
  EXPECT_FALSE(fs::exists(out / "particles" / ("frame_00003.ply" + dead)));
  e2e::expect_no_temp_files(out);
}
// A target modelled a few centimetres small (the Collada duck at scale 0.01, 1.6 cm) is as slow as real water that
// small: surface tension's capillary sub-step alone wants more sub-steps than solver.max_substeps, and the run says so
// (and what to do) in one line instead of blaming the particles' speed; with the capillary condition off it does not.
TEST(Cli, ATinySceneSaysSurfaceTensionWantsTheSubSteps) {
  const fs::path dir = test::temp_dir("cli-tiny");
  const std::string duck = "/usr/share/assimp/models/Collada/duck.dae";
  const auto scene = [&](const std::string& solver) {
    return R"({"targets": [{"mesh": ")" + duck + R"(", "scale": 0.01}], "sampling": {"auto_count": 1500, "max_auto_count": 1500})" +
           solver + "}";
  };
  const auto r = e2e::run({"run", write_scene(dir, scene("")).string(), "-o", (dir / "out").string(), "--frames", "2", "--no-mesh"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("surface tension at this spacing"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("solver.capillary_cfl = 0"), std::string::npos) << r.err;
  const auto off = e2e::run({"run", write_scene(dir, scene(R"(, "solver": {"capillary_cfl": 0})"), "off.json").string(), "-o",
                             (dir / "off").string(), "--frames", "2", "--no-mesh"});
  ASSERT_EQ(off.code, 0) << off.err;
  EXPECT_EQ(off.err.find("surface tension at this spacing"), std::string::npos) << off.err;
}
}  // namespace
}  // namespace ff
