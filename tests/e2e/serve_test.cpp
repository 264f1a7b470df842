// `fluidform serve` end to end: the viewer in Debian's chromium, headless and off the network, driven by
// playwright-core from web/test/viewer.test.mjs against the real server — frames, a screenshot with particles, the
// HUD, dragging a target and the error rate against the moved target, path traversal and garbage messages on the
// real port, rotating and swapping the target, WebXR (VR and AR with a controller drag) on an emulated headset (IWER),
// Ctrl-C freeing the port, and the playback of a finished run with its mesh animation. The script prints
// the speed numbers (simulation steps per second, frames received per second, render FPS); they are echoed here.
#include "e2e/cli_support.h"
#include "io/load_mesh.h"
#include "io/write_mesh.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

namespace ff {
namespace {
namespace fs = std::filesystem;

using test::shell;

TEST(Serve, ViewerInHeadlessChromium) {
  const fs::path src = test::source_dir();
  if (const std::string why = e2e::browser_test_missing(); !why.empty()) GTEST_SKIP() << why;
  const fs::path browser = e2e::chromium();
  ASSERT_TRUE(fs::exists(src / "examples" / "bunny.obj")) << "run scripts/setup (it writes examples/bunny.obj)";

  const fs::path dir = test::temp_dir("serve");
  // The control-particle cache outlives the test: the default bunny is then sampled once per machine, not per run.
  const fs::path cache = fs::temp_directory_path() / "fluidform-serve-test-cache";
  // A finished run to play back: a small bunny, meshed every 10 frames into animation.glb.
  e2e::write_scene(dir, R"({"targets": [{"mesh": ")" + (src / "examples" / "bunny.obj").string() +
                            R"(", "scale": 0.1}], "sampling": {"auto_count": 1500}, "output": {"frames": 40}})");
  const auto r = e2e::run({"run", (dir / "scene.json").string(), "-o", (dir / "run").string(), "--mesh-every", "10", "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(dir / "run" / "animation.glb"));

  // A second mesh for the viewer's mesh list: a sphere of the bunny's volume at the bunny's centre (in the bunny's
  // units: the scene's scale applies to it too), so the swap keeps the fluid volume and the target's place.
  auto bunny = io::load_mesh(src / "examples" / "bunny.obj");
  ASSERT_TRUE(bunny) << bunny.error().message;
  Aabb box;
  for (const Vec3f& v : bunny->vertices) box.extend(v);
  const float radius = static_cast<float>(std::cbrt(3.0 * std::abs(io::signed_volume(*bunny)) / (4.0 * M_PI)));
  ASSERT_TRUE(io::write_obj(dir / "sphere.obj", test::translate(test::uv_sphere(radius, 48), 0.5f * (box.min + box.max))).ok());

  const auto [rc, out] = shell("node '" + (src / "web" / "test" / "viewer.test.mjs").string() + "' --binary '" +
                               test::binary().string() + "' --scene '" + (src / "examples" / "default_scene.json").string() +
                               "' --cache '" + cache.string() + "' --mesh '" + (dir / "sphere.obj").string() +
                               "' --playback '" + (dir / "run").string() + "' --chromium '" +
                               browser.string() + "' --out '" + dir.string() + "'", /*echo=*/true);
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("viewer test ok"), std::string::npos) << out;
  if (rc == 0) fs::remove_all(dir);
}

}  // namespace
}  // namespace ff
