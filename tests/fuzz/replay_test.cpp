// Every input the fuzzers were seeded with (fuzz/corpus/<name>/) and every crash they ever found (fuzz/crashes/<name>/,
// kept after the fix) goes through its fuzz target again: the same fuzz/fuzz_<name>.cpp, compiled here with
// FF_FUZZ_REPLAY, with its own checks (fuzz/fuzz_target.h). A case that crashes takes the test down; the last line
// of its output names the file.
#include "../../fuzz/fuzz_target.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

namespace ff::fuzz {
std::vector<Registered>& registry() {
  static std::vector<Registered> r;
  return r;
}
}  // namespace ff::fuzz

namespace {
namespace fs = std::filesystem;

fs::path fuzz_dir() { return ff::test::source_dir() / "fuzz"; }

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && e.path().filename().string().front() != '.') files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::string> target_names() {
  std::vector<std::string> names;
  for (const auto& r : ff::fuzz::registry()) names.emplace_back(r.name);
  std::sort(names.begin(), names.end());
  return names;
}

ff::fuzz::TargetFn target(const std::string& name) {
  for (const auto& r : ff::fuzz::registry())
    if (name == r.name) return r.fn;
  return nullptr;
}

class FuzzReplay : public ::testing::TestWithParam<std::string> {};

TEST_P(FuzzReplay, CorpusAndCrashesReturnNormally) {
  const std::string name = GetParam();
  const auto fn = target(name);
  ASSERT_NE(fn, nullptr);
  const auto corpus = files_in(fuzz_dir() / "corpus" / name);
  EXPECT_FALSE(corpus.empty()) << "fuzz/corpus/" << name << " has no seed";
  auto all = corpus;
  const auto crashes = files_in(fuzz_dir() / "crashes" / name);
  all.insert(all.end(), crashes.begin(), crashes.end());
  for (const auto& file : all) {
    std::fprintf(stderr, "replay %s\n", file.lexically_relative(ff::test::source_dir()).c_str());
    std::ifstream in(file, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_TRUE(in.eof() || in.good()) << file;
    EXPECT_EQ(fn(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), 0) << file;
  }
  std::fprintf(stderr, "%s: %zu seeds, %zu crashes replayed\n", name.c_str(), corpus.size(), crashes.size());
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzReplay, ::testing::ValuesIn(target_names()),
                         [](const auto& param_info) { return param_info.param; });

// Every fuzz/fuzz_<name>.cpp is compiled in (tests/CMakeLists.txt lists them), and a folder in fuzz/corpus or
// fuzz/crashes without a target (a renamed target) would never be replayed.
TEST(FuzzReplayFolders, EveryFolderHasATarget) {
  const auto names = target_names();
  const std::set<std::string> known(names.begin(), names.end());
  for (const auto& e : fs::directory_iterator(fuzz_dir())) {
    const std::string file = e.path().filename().string();
    if (file.starts_with("fuzz_") && file.ends_with(".cpp")) {
      EXPECT_TRUE(known.count(file.substr(5, file.size() - 9))) << "fuzz/" << file << " is not in fuzz_replay_test";
    }
  }
  for (const char* kind : {"corpus", "crashes"}) {
    std::error_code ec;
    if (!fs::is_directory(fuzz_dir() / kind, ec)) continue;
    for (const auto& e : fs::directory_iterator(fuzz_dir() / kind))
      if (e.is_directory()) {
        EXPECT_TRUE(known.count(e.path().filename().string())) << "fuzz/" << kind << "/" << e.path().filename();
      }
  }
}

}  // namespace
