// OUT/report.html (issue 46): every run writes one self-contained page (the summary, plots over the run's frames, the
// formed mesh and its target in a three.js view), `fluidform report OUT` writes it again byte for byte, and the page is
// looked at as a person would: opened from disk in Debian's chromium with the network refused (web/test/report.test.mjs:
// no console errors, every plot drawn, the mesh drawn, the target overlay and the timeline working). Its screenshots are
// kept in the build folder (test-artifacts/report/) and the path is printed.
#include "e2e/cli_support.h"
#include "io/picture.h"
#include "support/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>

namespace ff {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

// The run's data the page carries (<script id="ff-data">), parsed.
json page_data(const std::string& html) {
  const std::string open = R"(<script id="ff-data" type="application/json">)";
  const std::size_t a = html.find(open);
  const std::size_t b = a == std::string::npos ? a : html.find("</script>", a);
  if (b == std::string::npos) return json();
  return json::parse(html.substr(a + open.size(), b - a - open.size()), nullptr, false);
}

std::vector<std::uint8_t> base64_decode(const std::string& s) {
  std::vector<std::uint8_t> out;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* at = std::strchr(digits, c);
    if (c == '=' || !at) break;
    acc = (acc << 6) | std::uint32_t(at - digits), bits += 6;
    if (bits >= 8) bits -= 8, out.push_back(std::uint8_t((acc >> bits) & 0xFF));
  }
  return out;
}

// A small bunny run (~1500 particles, 40 frames, meshed every 10 into animation.glb), with or without meshes.
fs::path small_run(const fs::path& dir, const std::string& name, bool mesh) {
  const fs::path bunny = test::source_dir() / "examples" / "bunny.obj";
  e2e::write_scene(dir, R"({"targets": [{"mesh": ")" + bunny.string() +
                            R"(", "scale": 0.1}], "sampling": {"auto_count": 1500}, "output": {"frames": 40}})");
  std::vector<std::string> args{"run", (dir / "scene.json").string(), "-o", (dir / name).string(), "--mesh-every", "10", "-q"};
  if (!mesh) args.push_back("--no-mesh");
  const auto r = e2e::run(args);
  EXPECT_EQ(r.code, 0) << r.err;
  return dir / name;
}

TEST(Report, EveryRunWritesASelfContainedPageAndReportWritesItAgain) {
  ASSERT_TRUE(fs::exists(test::source_dir() / "examples" / "bunny.obj")) << "run scripts/setup (it writes examples/bunny.obj)";
  const fs::path dir = test::temp_dir("report");
  const fs::path out = small_run(dir, "run", true);
  const std::string html = e2e::read_file(out / "report.html");
  ASSERT_FALSE(html.empty());
  EXPECT_LT(html.size(), 5u << 20);
  // Self-contained: no script, style or image fetched from anywhere (the bundle and the data are inline).
  for (const char* outside : {"<script src", "<link rel=\"stylesheet\"", "<img src=\"http", "/*FF_DATA*/", "/*FF_BUNDLE*/"})
    EXPECT_EQ(html.find(outside), std::string::npos) << outside;
  EXPECT_EQ(html.find("built without npm"), std::string::npos) << "the page was built without its bundle";
  const json data = page_data(html);
  ASSERT_TRUE(data.is_object()) << "the page's data is not JSON";
  const json report = json::parse(e2e::read_file(out / "report.json"));
  EXPECT_EQ(data["report"]["totals"]["particles"], report["totals"]["particles"]);
  EXPECT_EQ(data["metrics"]["time_s"].size(), 41u);  // frames 0..40
  EXPECT_EQ(data["metrics"]["error_rate_pct"].size(), 41u);
  ASSERT_TRUE(data["meshes"]["final"].is_object());
  EXPECT_GT(data["meshes"]["final"]["triangles"].get<int>(), 100);
  EXPECT_EQ(data["meshes"]["targets"].size(), 1u);
  EXPECT_TRUE(data["animation"].is_string()) << "a small run's animation.glb is carried";
  // Still pictures of target and formed shape (io/picture.h), each a PNG that shows something.
  ASSERT_EQ(data["stills"].size(), 2u);
  for (const auto& st : data["stills"]) {
    const std::string uri = st["png"].get<std::string>(), head = "data:image/png;base64,";
    ASSERT_EQ(uri.rfind(head, 0), 0u);
    auto pic = io::decode_png(base64_decode(uri.substr(head.size())));
    ASSERT_TRUE(pic) << pic.error().message;
    EXPECT_GT(pic->covered(io::PictureView{}.background), std::size_t(0.02 * pic->width * pic->height)) << st["label"];
  }

  // `fluidform report OUT` makes the same page again; a folder that is not a run's is one line.
  fs::rename(out / "report.html", dir / "first.html");
  const auto again = e2e::run({"report", out.string(), "-q"});
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(e2e::read_file(out / "report.html"), html);
  const auto bad = e2e::run({"report", dir.string()});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("no report.json"), std::string::npos) << bad.err;

  // --no-mesh into the same folder: the summary and the plots; the earlier run's meshes stay (nothing written is lost)
  // but are not shown as this run's.
  const fs::path bare = small_run(dir, "run", false);
  EXPECT_TRUE(fs::exists(bare / "mesh" / "final.obj"));
  const json bare_data = page_data(e2e::read_file(bare / "report.html"));
  ASSERT_TRUE(bare_data.is_object());
  EXPECT_TRUE(bare_data["meshes"]["final"].is_null());
  EXPECT_EQ(bare_data["metrics"]["time_s"].size(), 41u);
  EXPECT_EQ(bare_data["stills"].size(), 1u) << "the target alone";
  EXPECT_TRUE(bare_data["animation"].is_null());
  fs::remove_all(dir);
}

TEST(Report, ThePageInHeadlessChromiumOffTheNetwork) {
  if (const std::string why = e2e::browser_test_missing(); !why.empty()) GTEST_SKIP() << why;
  const fs::path src = test::source_dir(), browser = e2e::chromium();
  const fs::path dir = test::temp_dir("report_page");
  const fs::path artifacts = fs::current_path() / "test-artifacts" / "report";
  fs::create_directories(artifacts);
  const fs::path out = small_run(dir, "run", true), bare = small_run(dir, "bare", false);
  const json report = json::parse(e2e::read_file(out / "report.json"));
  const std::string script = (src / "web" / "test" / "report.test.mjs").string();
  const auto [rc, log] = test::shell("node '" + script + "' --page '" + (out / "report.html").string() + "' --particles " +
                                     std::to_string(report["totals"]["particles"].get<long>()) + " --chromium '" +
                                     browser.string() + "' --out '" + (artifacts / "run").string() + "'", /*echo=*/true);
  EXPECT_EQ(rc, 0) << log;
  const auto [rc2, log2] = test::shell("node '" + script + "' --page '" + (bare / "report.html").string() +
                                       "' --expect-view 0 --chromium '" + browser.string() + "' --out '" +
                                       (artifacts / "no-mesh").string() + "'", /*echo=*/true);
  EXPECT_EQ(rc2, 0) << log2;
  std::printf("report screenshots: %s\n", artifacts.c_str());
  if (rc == 0 && rc2 == 0) fs::remove_all(dir);
}

}  // namespace
}  // namespace ff
