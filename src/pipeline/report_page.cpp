#include "pipeline/report_page.h"

#include "pipeline/compare_page.h"  // base64, the pictures' colours

#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "io/load_mesh.h"
#include "io/picture.h"
#include "io/target_look.h"
#include "core/point_tree.h"
#include "pose/target_motion.h"
#include "scene/scene.h"
#include "surface/decimate.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace ff::pipeline {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The page (web/report/report.html with the bundle and the styles inlined), in pieces: see cmake/embed_report_page.cmake.
// Plain pointers, not constexpr string_views: measuring 30 000-character literals at compile time runs past clang's
// constexpr step limit.
const char* const kPage[] = {
#include "report_page.inc"
};

template <class T>
std::string base64_of(const std::vector<T>& v) {
  return base64(reinterpret_cast<const std::uint8_t*>(v.data()), v.size() * sizeof(T));
}

// A mesh for the page: at most kPageTriangles (decimated when it is a clean mesh, else refused with a reason).
Result<io::TriangleMesh> page_mesh(const io::TriangleMesh& in, std::string_view what) {
  if (in.triangles.size() <= kPageTriangles) return in;
  if (!surface::check_mesh(in).ok_allowing_cavities())
    return input_error(fmt::format("{} has {} triangles and cannot be decimated for the page", what, in.triangles.size()));
  surface::DecimateParams p;
  p.max_triangles = kPageTriangles;
  io::TriangleMesh out = surface::decimate(in, p);
  surface::carry_colours(in, out);
  return out;
}

json mesh_json(const io::TriangleMesh& m) {
  std::vector<float> pos;
  pos.reserve(3 * m.vertices.size());
  for (const Vec3f& v : m.vertices) pos.insert(pos.end(), {v.x(), v.y(), v.z()});
  std::vector<std::uint32_t> idx;
  idx.reserve(3 * m.triangles.size());
  for (const auto& t : m.triangles) idx.insert(idx.end(), {t[0], t[1], t[2]});
  json out{{"positions", base64_of(pos)}, {"indices", base64_of(idx)}, {"triangles", m.triangles.size()}};
  if (!m.colours.empty()) {  // linear RGB bytes, as three.js takes vertex colours
    std::vector<std::uint8_t> rgb;
    rgb.reserve(3 * m.colours.size());
    for (const Vec3f& c : m.colours)
      for (int a = 0; a < 3; ++a) rgb.push_back(static_cast<std::uint8_t>(std::lround(std::clamp(c[a], 0.0f, 1.0f) * 255.0f)));
    out["colours"] = base64_of(rgb);
  }
  return out;
}

void append_mesh(io::TriangleMesh& to, const io::TriangleMesh& m) {
  const auto off = static_cast<Index>(to.vertices.size());
  // Colours: when either has them, the one without is drawn in the target colour.
  if (!m.colours.empty() || !to.colours.empty()) {
    const auto lin = [](std::uint8_t c) { return io::srgb_to_linear(c); };
    const Vec3f plain(lin(kTargetColour[0]), lin(kTargetColour[1]), lin(kTargetColour[2]));
    to.colours.resize(to.vertices.size(), plain);
    if (m.colours.empty()) to.colours.insert(to.colours.end(), m.vertices.size(), plain);
    else to.colours.insert(to.colours.end(), m.colours.begin(), m.colours.end());
  }
  to.vertices.insert(to.vertices.end(), m.vertices.begin(), m.vertices.end());
  for (const auto& t : m.triangles) to.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
}

// The still pictures (io/picture.h, as the tests draw them): the target(s) and the formed shape from one view at one
// scale, as PNG data URIs.
json stills(const io::TriangleMesh& targets, const std::optional<io::TriangleMesh>& formed) {
  io::PictureView view;
  for (const Vec3f& v : targets.vertices) view.box.extend(v);
  if (formed)
    for (const Vec3f& v : formed->vertices) view.box.extend(v);
  json out = json::array();
  const auto add = [&](const io::TriangleMesh& m, std::array<std::uint8_t, 3> colour, const char* label) {
    auto png = io::encode_png(io::render_mesh(m, colour, view));
    if (png) out.push_back({{"label", label}, {"png", "data:image/png;base64," + base64_of(*png)}});
  };
  if (!targets.triangles.empty()) add(targets, kTargetColour, "target");
  if (formed) add(*formed, kLiquidColour, "formed");
  return out;
}

// metrics.csv's columns the plots draw, as numbers (null where a field is missing or not a number).
json metric_columns(const fs::path& out_dir) {
  const io::CsvTable t = io::read_csv(out_dir / "metrics.csv");
  json cols = json::object();
  for (const char* name : {"time_s", "error_rate_pct", "inside_fraction", "splash_fraction", "substeps", "step_time_s"}) {
    const std::size_t c = t.column(name);
    json col = json::array();
    for (const auto& row : t.rows) {
      char* end = nullptr;
      const double v = c < row.size() ? std::strtod(row[c].c_str(), &end) : NAN;
      const bool whole = c < row.size() && !row[c].empty() && end == row[c].c_str() + row[c].size();
      col.push_back(whole && std::isfinite(v) ? json(v) : json(nullptr));
    }
    cols[name] = std::move(col);
  }
  return cols;
}

// The lines a reader should not miss: a run that did not finish or form, and walls too thin for the spacing.
json page_warnings(const json& report) {
  json w = json::array();
  if (report.value("status", "ok") != "ok")
    w.push_back(fmt::format("the run stopped early: {}", report.value("error", report.value("status", "?"))));
  const json& t = report.value("totals", json::object());
  if (t.contains("time_to_form_s") && t["time_to_form_s"].is_null())
    w.push_back("not formed: the fluid never stayed ≥ 99 % inside with ≤ 0.5 % splashed");
  const json& targets = report.value("targets", json::array());
  for (std::size_t k = 0; k < targets.size(); ++k) {
    const json& wall = targets[k].value("thinnest_wall", json::object());
    if (wall.contains("spacings") && wall["spacings"].is_number() && wall["spacings"].get<double>() < 2.999)
      w.push_back(fmt::format("target {}: walls {:.3g} m thin are {:.1f} spacings across and may come out with holes", k,
                              wall.value("m", 0.0), wall["spacings"].get<double>()));
  }
  return w;
}

// The targets at their scene transform (the rest pose), from report.json's scene, for the page (`json`) and its
// picture (`merged`); one that cannot be read is left out with a warning.
// Target t as the run left it at `end` (s): the mesh of its morph phase then, moved by its keyframes' pose then (about
// its first mesh's box centre, as the run poses it), in its look when its liquid wears it (for the still picture).
struct EndTarget {
  io::TriangleMesh mesh, painted;
};
Result<EndTarget> target_at_end(const scene::TargetSpec& t, double end) {
  fs::path file = t.mesh;
  for (const auto& swap : t.swaps)
    if (end >= swap.time) file = swap.mesh;
  EndTarget e;
  FF_TRY(e.mesh, io::load_mesh(file, io::LoadOptions{t.transform}));
  e.painted = e.mesh;
  if (t.appearance == scene::Appearance::Target) {
    if (auto look = io::load_target_look(file, t.transform)) {  // each vertex its colour there
      e.painted = look->mesh;
      e.painted.colours.assign(e.painted.vertices.size(), Vec3f::Ones());
      for (Index f = 0; f < e.painted.triangles.size(); ++f)
        for (int c = 0; c < 3; ++c) e.painted.colours[e.painted.triangles[f][c]] = look->colour_at(f, Vec3f::Unit(c));
    }
  }
  if (!t.keyframes.empty()) {
    Aabb box = e.mesh.bounds();
    if (file != t.mesh)
      if (auto first = io::load_mesh(t.mesh, io::LoadOptions{t.transform})) box = first->bounds();
    const pose::TargetMotion motion{t.keyframes, t.smooth(), 0.5f * (box.min + box.max)};
    const pose::Pose pose = motion.at(end);
    for (Vec3f& v : e.mesh.vertices) v = pose.apply(v);
    for (Vec3f& v : e.painted.vertices) v = pose.apply(v);
  }
  return e;
}

// The targets as the run left them (morph phase and keyframed pose at its end; a skinned one at its bind pose, said so),
// from report.json's scene, for the page (`json`) and its picture (`merged`); one that cannot be read is left out with
// a warning.
json page_targets(const json& report, io::TriangleMesh& merged, json& warnings) {
  json out = json::array();
  if (!report.contains("scene")) return out;
  auto scene = scene::parse_scene(report["scene"].dump(), "/", "report.json's scene");
  if (!scene) {
    warnings.push_back(fmt::format("the targets are not shown: {}", scene.error().message));
    return out;
  }
  const json& totals = report.value("totals", json::object());
  const double end = totals.contains("simulated_seconds") && totals["simulated_seconds"].is_number()
                         ? totals["simulated_seconds"].get<double>() : 0.0;
  for (std::size_t k = 0; k < scene->targets.size(); ++k) {
    const auto& t = scene->targets[k];
    auto e = target_at_end(t, end);
    if (!e) {
      warnings.push_back(fmt::format("target {} is not shown: {}", k, e.error().message));
      continue;
    }
    append_mesh(merged, e->painted);  // the still picture takes any mesh, the 3D view at most kPageTriangles
    auto m = page_mesh(e->mesh, fmt::format("target {}", k));
    if (m) out.push_back(mesh_json(*m));
    else warnings.push_back(fmt::format("target {} is not in the 3D view: {}", k, m.error().message));
    if (t.animation.active())
      warnings.push_back(fmt::format("target {} plays a skinned clip: it is shown at its bind pose, the formed shape at "
                                     "the end of the run", k));
  }
  return out;
}

// final.obj's vertex colours (`v x y z r g b`, sRGB; a run whose liquid is not water writes them), through Assimp
// (io/target_look.h reads vertex colours, to linear): `mesh` takes them when the two agree vertex for vertex.
void final_colours(const fs::path& final, io::TriangleMesh& mesh) {
  std::ifstream in(final);
  std::string line;
  bool coloured = false;
  while (std::getline(in, line) && !coloured) coloured = line == "usemtl liquid";
  if (!coloured) return;
  auto look = io::load_target_look(final);
  if (!look || look->colours.size() != look->mesh.vertices.size() || look->mesh.vertices.size() != mesh.vertices.size()) return;
  const core::PointTree tree(look->mesh.vertices);
  mesh.colours.resize(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)  // linear already (an OBJ's colours are read as sRGB)
    mesh.colours[v] = look->colours[tree.original(tree.nearest(mesh.vertices[v]).slot)];
}

// The final mesh (decimated for the page), when the run made one.
std::optional<io::TriangleMesh> page_final(const fs::path& out_dir, json& warnings) {
  const fs::path final = out_dir / "mesh" / "final.obj";
  if (!fs::is_regular_file(final)) return std::nullopt;
  auto mesh = io::load_mesh(final);
  if (mesh) final_colours(final, *mesh);
  auto m = mesh ? page_mesh(*mesh, "the final mesh") : Result<io::TriangleMesh>(mesh.error());
  if (!m) {
    warnings.push_back(fmt::format("the final mesh is not shown: {}", m.error().message));
    return std::nullopt;
  }
  return std::move(*m);
}

}  // namespace

std::string ReportPage::describe(const fs::path& out_dir) const {
  return fmt::format("report: {} ({:.1f} MB{}) -> {}", view ? "summary, plots and the 3D view" : "summary and plots",
                     double(bytes) / 1e6, animation ? ", with the forming's timeline" : "", (out_dir / "report.html").string());
}

Result<ReportPage> write_report_page(const fs::path& out_dir, const PageSources& sources) {
  std::ifstream in(out_dir / "report.json");
  if (!in) return input_error(fmt::format("{}: no report.json (not the output folder of a run)", out_dir.string()));
  std::stringstream ss;
  ss << in.rdbuf();
  json report = json::parse(ss.str(), nullptr, false);
  if (report.is_discarded() || !report.is_object())
    return input_error(fmt::format("{}: report.json is not valid JSON", (out_dir / "report.json").string()));

  ReportPage page;
  json data = {{"report", report}, {"metrics", metric_columns(out_dir)}, {"warnings", page_warnings(report)}};
  io::TriangleMesh targets;
  json meshes = {{"final", nullptr}, {"targets", page_targets(report, targets, data["warnings"])}};
  page.targets = meshes["targets"].size();
  const std::optional<io::TriangleMesh> final =
      sources.final_mesh ? page_final(out_dir, data["warnings"]) : std::optional<io::TriangleMesh>();
  if (final) meshes["final"] = mesh_json(*final), page.view = true;
  data["stills"] = stills(targets, final);
  data["meshes"] = std::move(meshes);
  data["animation"] = nullptr;
  std::error_code ec;
  if (const fs::path glb = out_dir / "animation.glb"; sources.animation && fs::is_regular_file(glb, ec)) {
    // animation.glb itself when it is small enough, else its lighter copy for the page (mesh_export.h).
    const fs::path light = out_dir / kPageAnimationFile;
    const auto size = fs::file_size(glb, ec);
    const bool own = !ec && size <= kPageAnimationBytes;
    std::error_code ec2;
    const bool copy = !own && fs::is_regular_file(light, ec2) && fs::file_size(light, ec2) <= kPageAnimationBytes && !ec2;
    if (own || copy) {
      std::ifstream g(own ? glb : light, std::ios::binary);
      const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(g)), std::istreambuf_iterator<char>());
      data["animation"] = base64_of(bytes), page.animation = true;
      if (copy)
        data["animation_note"] = fmt::format("the timeline plays {}, a lighter copy of animation.glb ({:.1f} MB) made for "
                                             "this page", kPageAnimationFile, double(size) / 1e6);
    } else if (!ec) {
      data["animation_note"] = fmt::format("the meshed forming is in animation.glb ({:.1f} MB, more than the {:.0f} MB "
                                           "this page carries)", double(size) / 1e6, double(kPageAnimationBytes) / (1 << 20));
    }
  }
  // Inside <script>, "</script" ends the element and "<!--" changes how it is read: every '<' (only ever inside a JSON
  // string) is written as its escape.
  std::string text = data.dump(-1, ' ', false, json::error_handler_t::replace);
  for (std::size_t k = text.find('<'); k != std::string::npos; k = text.find('<', k + 6)) text.replace(k, 1, "\\u003c");
  std::string html;
  for (const char* piece : kPage) html += piece;
  const std::size_t at = html.find("/*FF_DATA*/");
  if (at == std::string::npos) return io_error("the embedded report page has no data placeholder");
  html.replace(at, std::string_view("/*FF_DATA*/").size(), text);
  FF_CHECK(io::write_file_atomic(out_dir / "report.html", html));
  page.bytes = html.size();
  return page;
}

}  // namespace ff::pipeline
