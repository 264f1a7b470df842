// The scene writer and the key table against the reader: one field list per struct drives all three, so a scene
// written out reads back as the same scene, and the table of keys in docs/scene-keys.md is what `fluidform keys` prints.
#include "scene/scene.h"
#include "support/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace ff::scene {
namespace {
using nlohmann::json;

// Every block, non-default values of each kind: numbers, integers, vectors, a scalar scale, enums, lists of objects,
// nested objects, a second controller's block.
constexpr const char* kRich = R"({
  "solver": {"particle_radius": 0.02, "iterations": 5, "gravity": [0, -9.81, 0.5], "viscosity": 0.02},
  "domain": {"min": [-2, 0, -2], "max": [2, 3, 2]},
  "fluid": [{"shape": "box", "min": [-0.3, 0, -0.3], "max": [0.3, 0.6, 0.3]},
            {"shape": "sphere", "center": [0, 1.2, 0], "radius": 0.2, "velocity": [0, -1, 0]}],
  "targets": [{"mesh": "bunny.obj", "scale": 2, "rotate": [0, 90, 0], "translate": [0.1, 0, 0], "start": 0.5,
               "keyframes": [{"time": 3}, {"time": 5, "translate": [1, 0, 0], "rotate": [0, 45, 0], "scale": 1.5}],
               "interpolation": "smooth", "morph": [{"time": 8, "mesh": "sub/dragon.obj"}]}],
  "sampling": {"method": "voxel", "spacing": 0.03, "seed": 7, "auto_count": 5000,
               "sparse": {"drop_fraction": 0.1, "drop_boxes": [{"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}]}},
  "controller": {"name": "pbfc", "pbfc": {"alpha": 2}, "adaptive": {"gather": false, "bond_radius": "paper"}},
  "output": {"fps": 30, "frames": 50, "checkpoint_every": 0, "velocity": false}
})";

TEST(SceneWriter, WrittenSceneReadsBackTheSame) {
  auto a = parse_scene(kRich, "/base");
  ASSERT_TRUE(a) << a.error().message;
  const json written = scene_to_json(*a);
  auto b = parse_scene(written.dump(), "/elsewhere");  // mesh paths are absolute: the folder no longer matters
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_EQ(scene_to_json(*b), written);
  EXPECT_EQ(b->targets[0].swaps[0].mesh, std::filesystem::path("/base/sub/dragon.obj"));
  EXPECT_EQ(b->sampling.sparse.drop_boxes.size(), 1u);
  EXPECT_EQ(b->sampling.method, sampling::Method::Voxel);
  EXPECT_FLOAT_EQ(b->controller.get<control::PbfcParams>().alpha, 2.0f);
  EXPECT_FALSE(b->controller.get<control::AdaptiveParams>().gather);
  EXPECT_EQ(b->targets[0].transform.scale, Vec3f::Constant(2.0f));
  EXPECT_FALSE(b->auto_radius || b->auto_domain || b->auto_frames);
  // Every block and every key of each block is written, not only the ones the scene gave.
  EXPECT_TRUE(written["solver"].contains("scorr_dq"));
  EXPECT_TRUE(written["controller"].contains("lcat"));
  EXPECT_TRUE(written["sampling"].contains("relax_steps"));
}

TEST(SceneWriter, AutomaticRunLengthStaysAutomatic) {
  auto a = parse_scene(R"({"targets": [{"mesh": "a.obj"}]})", "/base");
  ASSERT_TRUE(a) << a.error().message;
  const json written = scene_to_json(*a);
  EXPECT_FALSE(written["output"].contains("frames"));
  EXPECT_FALSE(written.contains("fluid")) << "a fluid made from the targets stays automatic";
  auto b = parse_scene(written.dump(), "/");
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_TRUE(b->auto_frames);
}

TEST(SceneKeys, EveryFieldHasARowAndTheReadmeShowsThem) {
  const auto rows = scene_keys();
  const auto has = [&](const std::string& k) {
    for (const auto& r : rows)
      if (r.key == k) return true;
    return false;
  };
  for (const char* k : {"solver.particle_radius", "fluid[].radius", "targets[].keyframes[].time", "targets[].morph[].mesh",
                        "sampling.sparse.drop_boxes[].min", "controller.name", "controller.adaptive.alpha",
                        "controller.lcat.density", "output.frames"})
    EXPECT_TRUE(has(k)) << k;
  std::ifstream in(test::source_dir() / "docs" / "scene-keys.md");
  ASSERT_TRUE(in.is_open()) << "docs/scene-keys.md is missing";
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string page = ss.str(), begin = "<!-- fluidform keys: begin -->\n", end = "<!-- fluidform keys: end -->";
  const auto b = page.find(begin), e = page.find(end);
  ASSERT_NE(b, std::string::npos) << "docs/scene-keys.md has no '<!-- fluidform keys: begin -->' line";
  ASSERT_NE(e, std::string::npos) << "docs/scene-keys.md has no '<!-- fluidform keys: end -->' line";
  EXPECT_EQ(page.substr(b + begin.size(), e - b - begin.size()), scene_keys_markdown())
      << "docs/scene-keys.md's table of scene keys is out of date: paste `fluidform keys` between its markers";
}

TEST(SceneReader, FieldListErrors) {
  const auto error_of = [](const std::string& text) {
    auto r = parse_scene(text, "/base");
    return r ? std::string() : r.error().message;
  };
  EXPECT_EQ(error_of(R"({"targets": [{"scale": 1}]})"), "targets[0]: \"mesh\" is required");
  EXPECT_EQ(error_of(R"({"targets": [{"mesh": "a.obj", "keyframes": {"time": 1}}]})"),
            "targets[0].keyframes: expected a list, got object");
  EXPECT_EQ(error_of(R"({"targets": [{"mesh": "a.obj"}], "sampling": {"method": "poisson"}})"),
            "sampling.method = \"poisson\" is not one of: blue-noise, voxel, surface");
  EXPECT_EQ(error_of(R"({"targets": [{"mesh": "a.obj"}], "sampling": {"seed": -1}})"), "sampling.seed = -1 must not be negative");
  EXPECT_EQ(error_of(R"({"targets": [{"mesh": "a.obj"}], "sampling": {"sparse": {"drop_boxes": [{"min": [0, 0, 0]}]}}})"),
            "sampling.sparse.drop_boxes[0]: \"max\" is required");
  EXPECT_EQ(error_of(R"({"fluid": [{"shape": "box", "min": [0, 0, 0]}]})"), "fluid[0]: a box needs \"min\" and \"max\"");
  EXPECT_EQ(error_of(R"({"targets": [{"mesh": "a.obj", "morph": [{"time": 2, "mesh": "b.obj"}, {"time": 1, "mesh": "c.obj"}]}]})"),
            "targets[0].morph[1].time = 1 must be later than the swap before it (2)");
  EXPECT_EQ(error_of(R"({"targets": [{"mesh": "a.obj"}], "solver": {"iterations": 8, "max_iterations": 5}})"),
            "solver.max_iterations = 5 is outside [8, 1000] (at least iterations)");
  EXPECT_NE(error_of(R"({"targets": [{"mesh": "a.obj"}], "controller": {"pbfc": {"alpha": NaN}}})").find("invalid JSON"),
            std::string::npos);
}

}  // namespace
}  // namespace ff::scene

namespace ff::scene {
namespace {

// Issue 46 item 6: `fluidform run bunny.obj` runs the smallest scene around the mesh instead of failing on its JSON.
TEST(SceneFiles, AMeshFileIsTheSmallestSceneAroundIt) {
  auto s = load_scene(test::data_dir() / "tetra.obj");
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->targets.size(), 1u);
  EXPECT_EQ(s->targets[0].mesh, std::filesystem::absolute(test::data_dir() / "tetra.obj").lexically_normal());
  EXPECT_FALSE(s->targets[0].animation.active());
  EXPECT_TRUE(s->auto_fluid && s->auto_radius && s->auto_domain && s->auto_resolution);
  // The same mesh as PLY and STL (the extension is what decides, case-insensitively).
  for (const char* name : {"tetra.ply", "tetra.stl", "tetra.off"}) {
    auto t = load_scene(test::data_dir() / name);
    ASSERT_TRUE(t) << name << ": " << t.error().message;
    EXPECT_EQ(t->targets.size(), 1u) << name;
  }
  const auto dir = test::temp_dir("mesh_scene");
  std::filesystem::copy_file(test::data_dir() / "tetra.obj", dir / "TETRA.OBJ");
  EXPECT_TRUE(load_scene(dir / "TETRA.OBJ")) << "upper-case extension";
}

TEST(SceneFiles, ASkinnedMeshFilePlaysItsFirstClip) {
  const std::filesystem::path x = "/usr/share/assimp/models/X/anim_test.x";  // Debian's assimp-testmodels
  ASSERT_TRUE(std::filesystem::exists(x)) << "install assimp-testmodels";
  auto s = load_scene(x);
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->targets.size(), 1u);
  EXPECT_EQ(s->targets[0].animation.clip, "0");
}

TEST(SceneFiles, AFileThatIsNeitherSaysWhatWasExpected) {
  const auto dir = test::temp_dir("neither");
  std::ofstream(dir / "notes.md") << "# not a scene\n";
  auto r = load_scene(dir / "notes.md");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("neither a scene file (JSON) nor a mesh file"), std::string::npos) << r.error().message;
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
  // A .json file keeps the parser's own message (where it broke), and a broken mesh names itself.
  std::ofstream(dir / "scene.json") << "{\"fluid\": [";
  auto j = load_scene(dir / "scene.json");
  ASSERT_FALSE(j);
  EXPECT_NE(j.error().message.find("invalid JSON"), std::string::npos) << j.error().message;
  auto e = load_scene(test::data_dir() / "empty.obj");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().message.find("empty.obj"), std::string::npos) << e.error().message;
  // A scene under another name still reads as a scene: no extension, upper case, and a name Assimp claims (.xml).
  for (const char* name : {"my.scene", "myscene", "SCENE.JSON", "scene.xml"}) {
    std::ofstream(dir / name) << R"(  // a comment first
      {"fluid":[{"shape":"box","min":[0,0,0],"max":[0.5,0.5,0.5]}]})";
    auto m = load_scene(dir / name);
    EXPECT_TRUE(m) << name << ": " << (m ? "" : m.error().message);
  }
  // A broken scene under any name keeps the parser's message (where it broke).
  std::ofstream(dir / "broken") << "{\"fluid\": [";
  auto b = load_scene(dir / "broken");
  ASSERT_FALSE(b);
  EXPECT_NE(b.error().message.find("invalid JSON"), std::string::npos) << b.error().message;
}

}  // namespace
}  // namespace ff::scene
