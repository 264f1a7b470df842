#pragma once
// Helpers of the end-to-end tests: run the fluidform binary (stderr captured, OMP_NUM_THREADS set or cleared),
// read files, check that no partial output is left.
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern char** environ;

namespace ff::e2e {
namespace fs = std::filesystem;

struct Proc {
  pid_t pid = -1;
  fs::path err_file;
};

// Starts the binary with `args`, stderr into a file; `threads` sets OMP_NUM_THREADS when > 0.
inline Proc start(const std::vector<std::string>& args, int threads = 0) {
  static int counter = 0;
  Proc p;
  p.err_file = fs::temp_directory_path() / ("fluidform-e2e-stderr-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::vector<std::string> argv_s{test::binary().string()};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : argv_s) argv.push_back(s.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_s;
  for (char** e = environ; *e; ++e)
    if (std::string(*e).rfind("OMP_NUM_THREADS=", 0) != 0) env_s.emplace_back(*e);
  if (threads > 0) env_s.push_back("OMP_NUM_THREADS=" + std::to_string(threads));
  std::vector<char*> envp;
  for (auto& s : env_s) envp.push_back(s.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 2, p.err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  EXPECT_EQ(posix_spawn(&p.pid, argv[0], &fa, nullptr, argv.data(), envp.data()), 0);
  posix_spawn_file_actions_destroy(&fa);
  return p;
}

struct Outcome {
  int code = -1;
  std::string err;
};

inline Outcome wait(const Proc& p) {
  int status = 0;
  ::waitpid(p.pid, &status, 0);
  std::ifstream in(p.err_file);
  std::string err((std::istreambuf_iterator<char>(in)), {});
  fs::remove(p.err_file);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), err};
}

inline Outcome run(const std::vector<std::string>& args, int threads = 0) { return wait(start(args, threads)); }

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

inline fs::path write_scene(const fs::path& dir, const std::string& json, const std::string& name = "scene.json") {
  std::ofstream(dir / name) << json;
  return dir / name;
}

inline std::size_t count_lines(const std::string& s) {
  std::size_t n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

inline void expect_no_temp_files(const fs::path& dir) {
  if (!fs::exists(dir)) return;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << "partial file left: " << e.path();
}

// Debian's chromium for the browser tests (FF_CHROMIUM overrides), or empty.
inline fs::path chromium() {
  if (const char* c = std::getenv("FF_CHROMIUM")) return c;
  for (const char* c : {"/usr/bin/chromium", "/usr/bin/chromium-browser"})
    if (fs::exists(c)) return c;
  return {};
}

// Why a browser test (node + npm's playwright-core + chromium) cannot run here; empty when it can.
inline std::string browser_test_missing() {
  if (test::shell("node --version").first != 0) return "node is not installed (scripts/setup installs it)";
  if (!fs::exists(test::source_dir() / "node_modules" / "playwright-core" / "package.json"))
    return "playwright-core is not installed: npm install (scripts/setup runs it)";
  if (chromium().empty()) return "Debian's chromium is not installed (apt-get install chromium; scripts/test installs it)";
  return "";
}

}  // namespace ff::e2e
