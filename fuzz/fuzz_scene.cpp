// Scene files (scene/scene.h, through io/json_reader.h and scene/fields_json.h): any bytes as a scene file's text.
// A scene that parses must also survive its own round trip: scene_to_json() is written so that parsing it again
// gives the same scene, and `run` writes it next to its output for exactly that.
#include "fuzz_target.h"
#include "scene/scene.h"

#include <nlohmann/json.hpp>

#include <filesystem>

FF_FUZZ_TARGET(scene) {
  using namespace ff;
  const std::filesystem::path base = "/nonexistent/fuzz";  // mesh paths are resolved, never opened
  auto s = scene::parse_scene(fuzz::as_text(data, size), base, "scene.json");
  if (!s) {
    fuzz::check_refusal(s.error());
    return 0;
  }
  const nlohmann::json j = scene::scene_to_json(*s);
  const std::string text = j.dump();
  auto again = scene::parse_scene(text, base, "scene.json");
  if (!again) std::fprintf(stderr, "round trip refused: %s\n", again.error().message.c_str());
  FF_FUZZ_CHECK(again.has_value());
  FF_FUZZ_CHECK(scene::scene_to_json(*again) == j);
  return 0;
}
