// Animated characters of liquid (issue 19), end to end with the defaults: `fluidform run` on the walking demo
// character and assimp-testmodels' skinned X, FBX and glTF (an open sheet) files, each playing its clip; after the shape has formed, every
// frame of metrics.csv (measured against the posed target) must hold the issue's figures: E averaged over the
// animation ≤ 1.5 % and ≤ 3 % at every frame, ≥ 98 % of the fluid inside, ≤ 1 % splash. And "release, then re-form"
// (examples/reform.json): let go at 4 s the bunny's fluid leaves the shape, re-formed from 6 s E is back under 1.5 %.
#include "e2e/cli_support.h"
#include "support/test_support.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <ostream>
#include <sstream>

namespace ff {
namespace {
namespace fs = std::filesystem;

struct Row {
  double time, e, inside, splash;
  std::size_t controlled;
};

std::vector<Row> read_metrics(const fs::path& csv) {
  std::istringstream in(e2e::read_file(csv));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> head;
  {
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) head.push_back(c);
  }
  const auto col = [&](const std::string& name) {
    const auto it = std::find(head.begin(), head.end(), name);
    EXPECT_NE(it, head.end()) << name;
    return static_cast<std::size_t>(it - head.begin());
  };
  const std::size_t t = col("time_s"), e = col("error_rate_pct"), in_c = col("inside_fraction"),
                    sp = col("splash_fraction"), ctrl = col("controlled");
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    for (std::string v; std::getline(ss, v, ',');) c.push_back(v);
    if (c.size() != head.size()) continue;
    rows.push_back({std::stod(c[t]), std::stod(c[e]), std::stod(c[in_c]), std::stod(c[sp]),
                    static_cast<std::size_t>(std::stoull(c[ctrl]))});
  }
  return rows;
}

struct CharacterCase {
  std::string name;
  std::string target;  // the scene's target object
  int frames;
  double formed_by;    // s: the figures hold from here on
};

// gtest prints a parameter without a printer as its raw bytes, heap addresses included, and ctest's test name
// carries that print: the name changed with every build, so ctest's timing of the test was never found again.
void PrintTo(const CharacterCase& c, std::ostream* os) { *os << c.name; }

std::string character_glb() {
  static const std::string file = [] {
    const fs::path out = test::temp_dir("e2e-character") / "character.glb";
    const std::string cmd = fmt::format("/usr/bin/python3 {}/scripts/make_character.py --out {} > /dev/null",
                                        test::source_dir().string(), out.string());
    return std::system(cmd.c_str()) == 0 ? out.string() : std::string();
  }();
  return file;
}

class AnimatedCharacter : public ::testing::TestWithParam<CharacterCase> {};

TEST_P(AnimatedCharacter, FormsAndFollowsThePosedTargetWithTheDefaults) {
  const CharacterCase& c = GetParam();
  std::string target = c.target;
  if (c.name == "character") {
    ASSERT_FALSE(character_glb().empty()) << "scripts/make_character.py failed";
    target = fmt::format(R"({{"mesh": "{}", "animation": {{"clip": "walk"}}}})", character_glb());
  }
  const auto dir = test::temp_dir("e2e-animated-" + c.name);
  const auto scene = e2e::write_scene(dir, fmt::format(R"({{"targets": [{}], "output": {{"frames": {}}}}})", target, c.frames));
  const fs::path out = dir / "out";
  const auto r = e2e::run({"-q", "run", scene.string(), "-o", out.string(), "--no-mesh"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_metrics(out / "metrics.csv");
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(c.frames) + 1);
  double sum = 0, worst_e = 0, worst_in = 1, worst_splash = 0;
  std::size_t n = 0;
  for (const Row& row : rows) {
    if (row.time < c.formed_by - 1e-9) continue;
    sum += row.e, ++n;
    worst_e = std::max(worst_e, row.e), worst_in = std::min(worst_in, row.inside), worst_splash = std::max(worst_splash, row.splash);
  }
  ASSERT_GT(n, 0u);
  std::printf("%s, from %.1f s (%zu frames): E mean %.3f %%, max %.3f %%; inside min %.2f %%; splash max %.2f %%\n",
              c.name.c_str(), c.formed_by, n, sum / double(n), worst_e, 100 * worst_in, 100 * worst_splash);
  EXPECT_LE(sum / double(n), 1.5);
  EXPECT_LE(worst_e, 3.0);
  EXPECT_GE(worst_in, 0.98);
  EXPECT_LE(worst_splash, 0.01);
}

INSTANTIATE_TEST_SUITE_P(
    Files, AnimatedCharacter,
    ::testing::Values(
        CharacterCase{"character", "", 360, 3.0},
        CharacterCase{"anim_test",
                      R"({"mesh": "/usr/share/assimp/models/X/anim_test.x", "scale": 0.1, "animation": {"clip": "0"}})", 360,
                      3.0},
        // huesitos' limbs swing at up to 32 m/s. Fluid they shed is steered back at least at the seed's own speed
        // (adaptive.gather_chase): formed by ~1 s. At the approach speed alone (2.3 m/s) a fifth of the fluid chased a
        // limb for the whole run (bench/RESULTS.md, "Animated characters, seventh part"). Its clip ends far from where
        // it starts, so it plays back and forth (animation.wrap auto): from 2 s the window holds three turns (3.1,
        // 4.7, 6.2 s). Repeated, the clip jumps at each of them (the one at 7.8 s threw 84 % of the fluid out).
        CharacterCase{"huesitos",
                      R"({"mesh": "/usr/share/assimp/models/FBX/huesitos.fbx", "scale": 0.01, "animation": {"clip": "0"}})",
                      420, 2.0},
        // An open sheet (10 vertices, 2 joints, a 5.5 s bend): its fluid is one particle per surface sample, poured
        // from above onto the strip's top edge, so it forms later; from 10 s the figures cover a whole play of the clip.
        // Its samples ride the posed triangles (pose::MeshAnchors): skinned by their own weights they followed
        // the bones' smooth blend while the 10-vertex sheet cuts the bend's corner, and 96.9 % of the fluid was inside.
        CharacterCase{"simple_skin",
                      R"({"mesh": "/usr/share/assimp/models/glTF2/simple_skin/simple_skin.gltf", "animation": {"clip": "0"}})",
                      960, 10.0}),
    [](const ::testing::TestParamInfo<CharacterCase>& p) { return p.param.name; });

TEST(StrengthTrack, ReleaseThenReformTheBunny) {
  const auto dir = test::temp_dir("e2e-reform");
  const fs::path out = dir / "out";
  const auto r = e2e::run({"-q", "run", (test::source_dir() / "examples" / "reform.json").string(), "-o", out.string(),
                           "--no-mesh"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_metrics(out / "metrics.csv");
  ASSERT_FALSE(rows.empty());
  const auto at = [&](double t) {
    for (const Row& row : rows)
      if (row.time >= t - 1e-9) return row;
    return rows.back();
  };
  const Row held = at(4.0), released = at(5.9), reformed = at(8.0), end = rows.back();
  std::printf("bunny: held E %.3f %% inside %.3f; released (5.9 s) E %.2f %% inside %.3f controlled %zu; re-formed (8 s) "
              "E %.3f %% inside %.3f; end (%.1f s) E %.3f %%\n", held.e, held.inside, released.e, released.inside,
              released.controlled, reformed.e, reformed.inside, end.time, end.e);
  EXPECT_LT(held.e, 1.5);
  EXPECT_EQ(released.controlled, 0u);
  EXPECT_LT(released.inside, 0.5);
  EXPECT_GT(released.e, 5.0);
  EXPECT_LT(reformed.e, 1.5);
  EXPECT_GE(reformed.inside, 0.98);
  EXPECT_LT(end.e, 1.5);
}

}  // namespace
}  // namespace ff
