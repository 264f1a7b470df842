#include "scene/scene.h"

#include "core/params.h"
#include "core/printable.h"
#include "io/json_reader.h"
#include "io/load_mesh.h"
#include "io/skin.h"
#include "scene/fields_json.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <optional>
#include <sstream>

namespace ff::scene {
namespace fs = std::filesystem;
using io::JsonObject;
using nlohmann::json;

Status TargetSpec::validate(std::string_view p) const {
  FF_CHECK(core::validate_fields(*this, p));
  FF_CHECK((pose::TargetMotion{keyframes, smooth(), Vec3f::Zero()}.validate(p)));
  FF_CHECK(control::StrengthTrack{strength}.validate(p));
  for (std::size_t k = 1; k < swaps.size(); ++k)
    if (!(swaps[k].time > swaps[k - 1].time))
      return param_error(fmt::format("{}.morph[{}].time = {} must be later than the swap before it ({})", p, k,
                                     swaps[k].time, swaps[k - 1].time));
  return {};
}

Status Scene::validate() const {
  FF_CHECK(solver.validate());
  FF_CHECK(domain.validate(solver.particle_radius));
  FF_CHECK(output.validate());
  FF_CHECK(sampling.validate());
  for (std::size_t i = 0; i < fluid.size(); ++i) FF_CHECK(fluid[i].validate(fmt::format("fluid[{}]", i)));
  for (std::size_t i = 0; i < targets.size(); ++i) FF_CHECK(targets[i].validate(fmt::format("targets[{}]", i)));
  FF_CHECK(controller.validate());
  FF_CHECK(limits.validate());
  if (fluid.empty() && targets.empty())
    return param_error("scene has no fluid: add a \"fluid\" list with at least one box or sphere source");
  return {};
}

namespace {

// A fluid source needs the fields of its shape (a box its corners, a sphere its centre and radius); the field list
// cannot say so, as what is required depends on another field.
Status check_fluid_shapes(const json& fluid) {
  if (!fluid.is_array()) return {};
  for (std::size_t i = 0; i < fluid.size(); ++i) {
    const json& f = fluid[i];
    if (!f.is_object()) continue;  // the reader names the type error
    sim::FluidSource src;
    if (f.contains("shape")) {
      if (!f["shape"].is_string()) continue;
      const auto shape = core::find_choice<sim::FluidSource::Shape>(f["shape"].get<std::string>());
      if (!shape) continue;  // the reader names the unknown shape
      src.shape = *shape;
    }
    const auto need = sim::FluidSource::required_for(src.shape);
    if (!f.contains(need[0]) || !f.contains(need[1]))
      return param_error(fmt::format("fluid[{}]: a {} needs \"{}\" and \"{}\"", i, core::choice_name(src.shape), need[0],
                                     need[1]));
  }
  return {};
}

}  // namespace

Result<Scene> parse_scene(std::string_view text, const fs::path& base_dir, std::string_view source_name) {
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false, /*ignore_comments=*/true);
  if (j.is_discarded()) {
    // Re-parse with exceptions only to get the position of the syntax error for the message.
    try {
      [[maybe_unused]] const json again = json::parse(text, nullptr, true, true);
    } catch (const json::exception& e) {  // a parse_error, or an out_of_range for a number like 1e999999
      std::string what = e.what();
      const auto colon = what.find("parse error"), id_end = what.find("] ");
      what = colon != std::string::npos ? what.substr(colon) : id_end != std::string::npos ? what.substr(id_end + 2) : what;
      // The parser quotes what it last read, which may hold any character of the file but a newline.
      return param_error(fmt::format("{}: invalid JSON: {}", source_name, printable(what, 300)));
    }
    return param_error(fmt::format("{}: invalid JSON", source_name));
  }
  Scene s;
  JsonObject root(j, "");
  FF_CHECK(root.check_object());
  if (const auto it = j.find("fluid"); it != j.end()) FF_CHECK(check_fluid_shapes(*it));
  FF_CHECK(read_fields(root, s, base_dir));
  FF_CHECK(root.finish());
  const auto given = [&](const char* block, const char* key) {
    const auto it = j.find(block);
    return it != j.end() && it->is_object() && (key == nullptr || it->contains(key));
  };
  s.auto_radius = !given("solver", "particle_radius");
  s.auto_domain = !given("domain", nullptr);
  s.auto_frames = !given("output", "frames");
  s.auto_fluid = s.fluid.empty() && !s.targets.empty();
  s.auto_resolution = !given("sampling", "auto_count") && !given("sampling", "spacing");
  FF_CHECK(s.validate());
  // The resume hash covers everything that shapes the simulation; the frame count, the limits and the targets'
  // tints and appearances may change between runs.
  json h = j;
  h.erase("limits");
  if (h.contains("targets") && h["targets"].is_array())  // a target's tint and appearance colour the export only
    for (auto& t : h["targets"])
      if (t.is_object()) t.erase("tint"), t.erase("appearance");
  if (h.contains("output") && h["output"].is_object()) {
    h["output"].erase("frames");
    if (h["output"].empty()) h.erase("output");
  }
  const std::string dumped = h.dump();
  std::uint64_t hash = 14695981039346656037ull;
  for (unsigned char c : dumped) hash = (hash ^ c) * 1099511628211ull;
  s.hash = hash;
  return s;
}

json scene_to_json(const Scene& scene) {
  json j = fields_to_json(scene);
  if (scene.auto_frames) j["output"].erase("frames");
  if (scene.auto_fluid) j.erase("fluid");
  return j;
}

std::vector<core::KeyRow> scene_keys() {
  std::vector<core::KeyRow> rows;
  core::key_rows<Scene>("", rows);
  return rows;
}

std::string scene_keys_markdown() {
  std::string s = "| key | type | default | range | what |\n| --- | --- | --- | --- | --- |\n";
  const auto cell = [](std::string c) {  // a '|' inside a cell would end it
    for (std::size_t k = c.find('|'); k != std::string::npos; k = c.find('|', k + 2)) c.replace(k, 1, "\\|");
    return c;
  };
  for (const auto& r : scene_keys())
    s += fmt::format("| `{}` | {} | {} | {} | {} |\n", r.key, cell(r.type), cell(r.default_value), cell(r.range), cell(r.doc));
  return s;
}

namespace {

// The smallest scene around a mesh file: the mesh as the one target, playing its first clip when it has a skin with
// clips, everything else automatic (docs/scenes.md). The file is read here, so that a broken mesh is the same
// one-line error a scene naming it would give, before any output is made.
Result<Scene> mesh_scene(const fs::path& file) {
  json j = {{"targets", json::array({{{"mesh", fs::absolute(file).lexically_normal().string()}}})}};
  // OBJ, PLY, STL and OFF carry no skeleton: asking would only read the file twice.
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  FF_TRY(const io::TriangleMesh mesh, io::load_mesh(file));
  if (ext != ".obj" && ext != ".ply" && ext != ".stl" && ext != ".off") {
    FF_TRY(const std::optional<io::Skin> skin, io::load_skin(file, mesh, io::MeshTransform{}));
    if (skin && !skin->clips.empty()) j["targets"][0]["animation"] = {{"clip", "0"}};
  }
  spdlog::info("{} is a mesh: running the smallest scene around it, {}", file.string(), j.dump());
  return parse_scene(j.dump(), fs::current_path(), file.string());
}

}  // namespace

Result<Scene> load_scene(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) return input_error(fmt::format("{}: no such scene file", file.string()));
  if (fs::is_directory(file, ec)) return input_error(fmt::format("{}: is a folder, not a scene file", file.string()));
  std::ifstream in(file, std::ios::binary);
  if (!in) return input_error(fmt::format("{}: cannot read the scene file", file.string()));
  // A scene is a JSON object: a file that starts with '{' is one whatever its name (Assimp also claims .xml, .scn and
  // other names a scene might have); else a mesh file by its extension is the smallest scene around it. Only the
  // file's head is read to decide (a mesh may be hundreds of MB).
  std::string text(4096, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  const bool object = first != std::string::npos && (text[first] == '{' || text.compare(first, 2, "//") == 0 ||
                                                    text.compare(first, 2, "/*") == 0);  // comments are allowed
  if (!object && io::is_mesh_extension(file)) {
    FF_TRY(Scene s, mesh_scene(file));
    s.file = file;
    return s;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  text += ss.str();
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  // A file that is neither: say what was expected, not where a parser broke on something that was never JSON.
  if (!object && ext != ".json")
    return input_error(fmt::format("{}: neither a scene file (JSON) nor a mesh file fluidform reads (OBJ, FBX, glTF/GLB, "
                                   "PLY, STL, Collada, ...)",
                                   file.string()));
  const fs::path base = file.has_parent_path() ? file.parent_path() : fs::path(".");
  FF_TRY(Scene s, parse_scene(text, base, file.string()));
  s.file = file;
  return s;
}

}  // namespace ff::scene
