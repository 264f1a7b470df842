// Scene files: defaults, unknown keys with "did you mean", ranges naming key/value/range, types.
#include "scene/scene.h"


#include <gtest/gtest.h>

namespace ff::scene {
namespace {

constexpr const char* kMinimal = R"({"fluid":[{"shape":"box","min":[0,0,0],"max":[0.5,0.5,0.5]}]})";

Result<Scene> parse(const std::string& s) { return parse_scene(s, "/base"); }

std::string error_of(const std::string& s) {
  auto r = parse(s);
  EXPECT_FALSE(r.has_value()) << s;
  return r.has_value() ? "" : r.error().message;
}

TEST(Scene, MinimalSceneGetsDocumentedDefaults) {
  auto s = parse(kMinimal);
  ASSERT_TRUE(s.has_value()) << s.error().message;
  EXPECT_FLOAT_EQ(s->solver.particle_radius, 0.025f);
  EXPECT_EQ(s->solver.iterations, 4);
  EXPECT_FLOAT_EQ(s->solver.gravity.y(), -10.0f);
  EXPECT_DOUBLE_EQ(s->output.fps, 60.0);
  ASSERT_EQ(s->fluid.size(), 1u);
  EXPECT_EQ(s->fluid[0].shape, sim::FluidSource::Shape::Box);
}

TEST(Scene, FullSceneParses) {
  auto s = parse(R"({
    // comments are allowed
    "solver": {"particle_radius": 0.01, "iterations": 6, "gravity": [0, -9.81, 0], "vorticity": 0.001},
    "domain": {"min": [-1, 0, -1], "max": [1, 2, 1]},
    "fluid": [{"shape": "sphere", "center": [0, 1, 0], "radius": 0.3, "velocity": [1, 0, 0]}],
    "targets": [{"mesh": "bunny.obj", "scale": 2, "rotate": [0, 90, 0], "translate": [0, 0.1, 0], "start": 0.5}],
    "output": {"fps": 30, "frames": 10, "checkpoint_every": 0, "velocity": false}})");
  ASSERT_TRUE(s.has_value()) << s.error().message;
  EXPECT_EQ(s->solver.iterations, 6);
  EXPECT_FLOAT_EQ(s->fluid[0].radius, 0.3f);
  ASSERT_EQ(s->targets.size(), 1u);
  EXPECT_EQ(s->targets[0].mesh, std::filesystem::path("/base/bunny.obj"));
  EXPECT_EQ(s->targets[0].transform.scale, Vec3f::Constant(2.0f));
  EXPECT_FALSE(s->output.velocity);
}

TEST(Scene, UnknownKeyNamesPathAndClosestKey) {
  EXPECT_EQ(error_of(R"({"solver":{"iteratons":3},"fluid":[]})"), "solver.iteratons: unknown key (did you mean 'iterations'?)");
  EXPECT_EQ(error_of(std::string(R"({"fluidd":1,)") + std::string(kMinimal).substr(1)),
            "fluidd: unknown key (did you mean 'fluid'?)");
  const auto e = error_of(R"({"fluid":[{"shape":"box","min":[0,0,0],"max":[1,1,1],"colour":"red"}]})");
  EXPECT_NE(e.find("fluid[0].colour: unknown key"), std::string::npos) << e;
  const auto far = error_of(R"({"zzzzzzzz":1})");
  EXPECT_NE(far.find("valid keys here"), std::string::npos) << far;
}

TEST(Scene, OutOfRangeNamesKeyValueAndRange) {
  EXPECT_EQ(error_of(std::string(R"({"solver":{"particle_radius":-0.1},)") + std::string(kMinimal).substr(1)),
            "solver.particle_radius = -0.1 is outside (0.0001, 10000]");
  EXPECT_EQ(error_of(std::string(R"({"solver":{"cfl":1.7},)") + std::string(kMinimal).substr(1)),
            "solver.cfl = 1.7 is outside (0, 1]");
  EXPECT_EQ(error_of(std::string(R"({"output":{"fps":0},)") + std::string(kMinimal).substr(1)),
            "output.fps = 0 is outside [1, 1000]");
  const auto e = error_of(R"({"fluid":[{"shape":"sphere","center":[0,1,0],"radius":-1}]})");
  EXPECT_EQ(e, "fluid[0].radius = -1 is outside (0, 1e+06]");
}

TEST(Scene, WrongTypesAndBrokenJsonAreOneLineErrors) {
  EXPECT_EQ(error_of(std::string(R"({"solver":{"iterations":"four"},)") + std::string(kMinimal).substr(1)),
            "solver.iterations: expected an integer, got \"four\"");
  EXPECT_EQ(error_of(std::string(R"({"solver":{"iterations":2.5},)") + std::string(kMinimal).substr(1)),
            "solver.iterations: expected an integer, got 2.5");
  const auto broken = error_of(R"({"fluid": [ )");
  EXPECT_NE(broken.find("invalid JSON"), std::string::npos) << broken;
  EXPECT_EQ(broken.find('\n'), std::string::npos);
  EXPECT_NE(error_of("[1,2]").find("expected a JSON object"), std::string::npos);
  EXPECT_NE(error_of(R"({"fluid":[{"shape":"cone"}]})").find("is not one of: box, sphere"), std::string::npos);
  EXPECT_NE(error_of("{}").find("no fluid"), std::string::npos);
}

TEST(Scene, NanIsRejectedByRangeChecks) {
  sim::SolverParams p;
  p.viscosity = std::nanf("");
  ASSERT_FALSE(p.validate().ok());
  EXPECT_NE(p.validate().error().message.find("solver.viscosity"), std::string::npos);
}

TEST(Scene, TargetOnlySceneControllerKeyframesAndMorphParse) {
  auto s = parse(R"({"targets": [{"mesh": "a.obj", "interpolation": "smooth",
      "keyframes": [{"time": 1, "translate": [0.5, 0, 0]}, {"time": 2, "rotate": [0, 90, 0], "scale": 1.5}],
      "morph": [{"time": 3, "mesh": "b.obj"}]}],
    "controller": {"name": "adaptive", "adaptive": {"gather": false, "bond_radius": "paper"}}})");
  ASSERT_TRUE(s.has_value()) << s.error().message;
  EXPECT_TRUE(s->fluid.empty());
  EXPECT_TRUE(s->auto_radius && s->auto_domain && s->auto_frames);
  ASSERT_EQ(s->targets[0].keyframes.size(), 2u);
  EXPECT_TRUE(s->targets[0].smooth());
  EXPECT_FLOAT_EQ(s->targets[0].keyframes[1].scale, 1.5f);
  ASSERT_EQ(s->targets[0].swaps.size(), 1u);
  EXPECT_EQ(s->targets[0].swaps[0].mesh, std::filesystem::path("/base/b.obj"));
  EXPECT_FALSE(s->controller.get<control::AdaptiveParams>().gather);
  EXPECT_EQ(s->controller.get<control::AdaptiveParams>().bond_radius, control::BondRadius::Paper);
}

TEST(Scene, BadControllerKeyframeAndMorphEntriesAreOneLineErrors) {
  EXPECT_NE(error_of(R"({"targets": [{"mesh": "a.obj"}], "controller": {"name": "magic"}})").find("adaptive, none"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"targets": [{"mesh": "a.obj"}], "controller": {"adaptive": {"alpah": 1}}})").find("alpha"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"targets": [{"mesh": "a.obj"}], "controller": {"adaptive": {"clamp": 5}}})")
                .find("controller.adaptive.clamp"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"targets": [{"mesh": "a.obj", "keyframes": [{"time": 2}, {"time": 1}]}]})").find("later"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"targets": [{"mesh": "a.obj", "keyframes": [{"time": 1, "scale": 0}]}]})").find("scale"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"targets": [{"mesh": "a.obj", "morph": [{"time": 1}]}]})").find("required"), std::string::npos);
  EXPECT_NE(error_of(R"({"targets": [{"mesh": "a.obj", "interpolation": "cubic"}]})").find("linear, smooth"),
            std::string::npos);
  // Neither fluid nor targets: nothing to simulate.
  EXPECT_NE(error_of(R"({"output": {"frames": 3}})").find("no fluid"), std::string::npos);
}

TEST(Scene, HashIgnoresFrameCountButNotPhysics) {
  auto a = parse(kMinimal), b = parse(std::string(R"({"output":{"frames":7},)") + std::string(kMinimal).substr(1));
  auto c = parse(std::string(R"({"solver":{"iterations":5},)") + std::string(kMinimal).substr(1));
  ASSERT_TRUE(a && b && c);
  EXPECT_EQ(a->hash, b->hash);
  EXPECT_NE(a->hash, c->hash);
}

TEST(Scene, MissingFileAndFolderAreInputErrors) {
  auto r = load_scene("/nonexistent/scene.json");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().kind, Error::Kind::Input);
  EXPECT_NE(r.error().message.find("/nonexistent/scene.json"), std::string::npos);
  EXPECT_FALSE(load_scene("/tmp").has_value());
}

}  // namespace
}  // namespace ff::scene
