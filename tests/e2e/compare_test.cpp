// End-to-end tests of `fluidform compare`: one row per controller in table.md / table.csv, the
// controller beats plain PBF, an unknown controller name is refused before anything runs, and the error-rate
// column is the same when the compare is run again.
#include "pipeline/compare.h"
#include "e2e/cli_support.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

namespace ff {
namespace {
namespace fs = std::filesystem;
using namespace e2e;

// A 0.3 m sphere, ~1.5k particles, 60 frames (1 s): seconds per controller.
fs::path tiny_scene(const fs::path& dir) {
  test::write_obj(dir / "sphere.obj", test::uv_sphere(0.3f, 24));
  return write_scene(dir, R"({"targets": [{"mesh": "sphere.obj"}], "sampling": {"auto_count": 1500},
                             "output": {"frames": 60}})");
}

std::vector<std::vector<std::string>> read_csv(const fs::path& p) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(read_file(p));
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

std::size_t column(const std::vector<std::vector<std::string>>& csv, const std::string& name) {
  const auto& head = csv.at(0);
  return static_cast<std::size_t>(std::find(head.begin(), head.end(), name) - head.begin());
}

// The controller name and error-rate column of each row.
std::vector<std::pair<std::string, std::string>> error_column(const fs::path& csv_file) {
  const auto csv = read_csv(csv_file);
  const std::size_t c_name = column(csv, "controller"), c_err = column(csv, "error_rate_pct");
  std::vector<std::pair<std::string, std::string>> out;
  for (std::size_t r = 1; r < csv.size(); ++r) out.emplace_back(csv[r].at(c_name), csv[r].at(c_err));
  return out;
}

class Compare : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test::temp_dir("compare"));
    scene_ = new fs::path(tiny_scene(*dir_));
    first_ = new Outcome(run({"compare", scene_->string(), "--controllers", "adaptive,none", "-o", (*dir_ / "a").string()}));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete first_, delete scene_, delete dir_;
  }
  static fs::path* dir_;
  static fs::path* scene_;
  static Outcome* first_;
};
fs::path* Compare::dir_ = nullptr;
fs::path* Compare::scene_ = nullptr;
Outcome* Compare::first_ = nullptr;

TEST_F(Compare, WritesOneRowPerControllerAndAdaptiveBeatsNone) {
  ASSERT_EQ(first_->code, 0) << first_->err;
  const fs::path out = *dir_ / "a";
  const std::string md = read_file(out / "table.md");
  EXPECT_NE(md.find("| controller | controlled / fluid particles | controlled / control | error rate (%) | per-frame time (s) "
                    "| memory (MB) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| adaptive |"), std::string::npos) << md;
  EXPECT_NE(md.find("| none |"), std::string::npos) << md;
  EXPECT_NE(md.find("60 frames"), std::string::npos) << md;
  const auto csv = read_csv(out / "table.csv");
  ASSERT_EQ(csv.size(), 3u) << "header + two rows";
  const auto errors = error_column(out / "table.csv");
  ASSERT_EQ(errors[0].first, "adaptive");
  ASSERT_EQ(errors[1].first, "none");
  const std::size_t c_status = column(csv, "status");
  EXPECT_EQ(csv[1].at(c_status), "ok");
  EXPECT_EQ(csv[2].at(c_status), "ok");
  EXPECT_LT(std::stod(errors[0].second), std::stod(errors[1].second));
  // Each controller ran in its own folder, without the particle frames the table does not need.
  EXPECT_TRUE(fs::exists(out / "adaptive" / "report.json"));
  EXPECT_FALSE(fs::exists(out / "adaptive" / "particles"));
  expect_no_temp_files(out);
}

// compare.html (issue 46 item 2): the table with a picture of each controller's formed shape beside the target's and
// links to their report.html, sortable; looked at in headless chromium off the network (web/test/compare.test.mjs).
TEST_F(Compare, ThePageShowsEveryRowWithItsPictureAndSorts) {
  ASSERT_EQ(first_->code, 0) << first_->err;
  const fs::path out = *dir_ / "a";
  const std::string html = read_file(out / "compare.html");
  ASSERT_FALSE(html.empty());
  for (const char* name : {"adaptive", "none"}) {
    EXPECT_TRUE(fs::exists(out / name / "formed.png")) << name;
    EXPECT_TRUE(fs::exists(out / name / "report.html")) << name;
    EXPECT_NE(html.find(std::string("<a href=\"") + name + "/report.html\">"), std::string::npos) << name;
  }
  EXPECT_TRUE(fs::exists(out / "target.png"));
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  if (const std::string why = e2e::browser_test_missing(); !why.empty()) GTEST_SKIP() << why;
  const fs::path src = test::source_dir(), browser = e2e::chromium();
  const fs::path artifacts = fs::current_path() / "test-artifacts" / "compare";
  const auto [rc, log] = test::shell("node '" + (src / "web" / "test" / "compare.test.mjs").string() + "' --page '" +
                                     (out / "compare.html").string() + "' --rows 2 --chromium '" + browser.string() +
                                     "' --out '" + artifacts.string() + "'", /*echo=*/true);
  EXPECT_EQ(rc, 0) << log;
}

TEST_F(Compare, SameErrorRatesWhenRunAgain) {
  ASSERT_EQ(first_->code, 0) << first_->err;
  const auto again = run({"compare", scene_->string(), "--controllers", "adaptive,none", "-o", (*dir_ / "b").string()});
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(error_column(*dir_ / "a" / "table.csv"), error_column(*dir_ / "b" / "table.csv"));
}

// A controller that crashes is a failure row and the table goes on (the binary behind a script that kills
// itself with SIGSEGV for `none`).
TEST_F(Compare, CrashOfOneControllerIsAFailureRow) {
  const fs::path script = *dir_ / "crashing-fluidform.sh";
  std::ofstream(script) << "#!/bin/sh\ncase \"$*\" in *\"--controller none\"*) kill -SEGV $$;; esac\nexec '"
                        << test::binary().string() << "' \"$@\"\n";
  fs::permissions(script, fs::perms::owner_all);
  pipeline::CompareOptions o;
  o.scene_file = *scene_;
  o.out_dir = *dir_ / "crash";
  o.controllers = {"none", "adaptive"};
  o.frames = 10;
  o.exe = script;
  auto table = pipeline::run_compare(o);
  ASSERT_TRUE(table.has_value()) << table.error().message;
  ASSERT_EQ(table->rows.size(), 2u);
  EXPECT_FALSE(table->rows[0].ok);
  EXPECT_EQ(table->rows[0].status, "failure (blew up: killed by signal 11 (Segmentation fault))");
  EXPECT_TRUE(table->rows[1].ok) << table->rows[1].status;
  const std::string md = read_file(o.out_dir / "table.md");
  EXPECT_NE(md.find("| none | n/a | n/a | failure |"), std::string::npos) << md;
  EXPECT_NE(md.find("| adaptive |"), std::string::npos) << md;
}

// The refusals need no run: plain tests, so that CTest (one process per test) does not run the fixture's compare.
TEST(CompareCli, UnknownControllerIsRefusedBeforeAnythingRuns) {
  const fs::path dir = test::temp_dir("compare-bad"), out = dir / "bad";
  const auto r = run({"compare", tiny_scene(dir).string(), "--controllers", "adaptive,nosuch", "-o", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("nosuch"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}

TEST(CompareCli, MissingSceneIsAOneLineError) {
  const fs::path dir = test::temp_dir("compare-missing"), out = dir / "missing";
  const auto r = run({"compare", (dir / "nope.json").string(), "-o", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("nope.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ff
