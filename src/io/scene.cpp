#include "io/scene.h"

#include "core/params.h"
#include "io/json_reader.h"

#include <fmt/format.h>

#include <fstream>
#include <sstream>

namespace ff::io {
namespace fs = std::filesystem;
using nlohmann::json;

Status OutputParams::validate(std::string_view p) const {
  FF_CHECK(core::check_range(p, "fps", fps, 1.0, 1000.0));
  FF_CHECK(core::check_range(p, "frames", frames, 1, 1e7));
  FF_CHECK(core::check_range(p, "checkpoint_every", checkpoint_every, 0, 1e7));
  return {};
}

Status Scene::validate() const {
  FF_CHECK(solver.validate());
  FF_CHECK(domain.validate(solver.particle_radius));
  FF_CHECK(output.validate());
  FF_CHECK(sampling.validate());
  for (std::size_t i = 0; i < fluid.size(); ++i) FF_CHECK(fluid[i].validate(fmt::format("fluid[{}]", i)));
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const auto p = fmt::format("targets[{}]", i);
    FF_CHECK(core::check_vec(p, "scale", targets[i].transform.scale, 1e-9, 1e9));
    FF_CHECK(core::check_vec(p, "rotate", targets[i].transform.rotate_deg, -1e6, 1e6));
    FF_CHECK(core::check_vec(p, "translate", targets[i].transform.translate, -1e9, 1e9));
    FF_CHECK(core::check_range(p, "start", targets[i].start, 0.0, 1e6));
    FF_CHECK((control::TargetMotion{targets[i].keyframes, targets[i].smooth, Vec3f::Zero()}.validate(p)));
  }
  FF_CHECK(controller.validate());
  if (fluid.empty() && targets.empty())
    return param_error("scene has no fluid: add a \"fluid\" list with at least one box or sphere source");
  return {};
}

namespace {

Status read_solver(const json& j, sim::SolverParams& s) {
  JsonObject o(j, "solver");
  FF_CHECK(o.check_object());
  FF_CHECK(o.get("particle_radius", s.particle_radius));
  FF_CHECK(o.get("support_factor", s.support_factor));
  FF_CHECK(o.get("iterations", s.iterations));
  FF_CHECK(o.get("max_iterations", s.max_iterations));
  FF_CHECK(o.get("max_density_error", s.max_density_error));
  FF_CHECK(o.get("max_dt", s.max_dt));
  FF_CHECK(o.get("cfl", s.cfl));
  FF_CHECK(o.get("max_substeps", s.max_substeps));
  FF_CHECK(o.get("gravity", s.gravity));
  FF_CHECK(o.get("rest_density", s.rest_density));
  FF_CHECK(o.get("viscosity", s.viscosity));
  FF_CHECK(o.get("vorticity", s.vorticity));
  FF_CHECK(o.get("epsilon", s.epsilon));
  FF_CHECK(o.get("scorr_k", s.scorr_k));
  FF_CHECK(o.get("scorr_n", s.scorr_n));
  FF_CHECK(o.get("scorr_dq", s.scorr_dq));
  FF_CHECK(o.get("surface_tension", s.surface_tension));
  FF_CHECK(o.get("surface_tension_samples", s.surface_tension_samples));
  FF_CHECK(o.get("drag", s.drag));
  FF_CHECK(o.get("air_density", s.air_density));
  return o.finish();
}

Status read_domain(const json& j, sim::Domain& d) {
  JsonObject o(j, "domain");
  FF_CHECK(o.check_object());
  FF_CHECK(o.get("min", d.min));
  FF_CHECK(o.get("max", d.max));
  return o.finish();
}

Status read_fluid(const json& j, std::vector<sim::FluidSource>& out) {
  if (!j.is_array()) return param_error(fmt::format("fluid: expected a list of sources, got {}", j.type_name()));
  for (std::size_t i = 0; i < j.size(); ++i) {
    JsonObject o(j[i], fmt::format("fluid[{}]", i));
    FF_CHECK(o.check_object());
    std::string shape = "box";
    FF_CHECK(o.get("shape", shape));
    sim::FluidSource s;
    if (shape == "box") {
      s.shape = sim::FluidSource::Shape::Box;
      if (!o.has("min") || !o.has("max")) return param_error(fmt::format("fluid[{}]: a box needs \"min\" and \"max\"", i));
      FF_CHECK(o.get("min", s.min));
      FF_CHECK(o.get("max", s.max));
    } else if (shape == "sphere") {
      s.shape = sim::FluidSource::Shape::Sphere;
      if (!o.has("center") || !o.has("radius"))
        return param_error(fmt::format("fluid[{}]: a sphere needs \"center\" and \"radius\"", i));
      FF_CHECK(o.get("center", s.center));
      FF_CHECK(o.get("radius", s.radius));
    } else {
      return param_error(fmt::format("fluid[{}].shape = \"{}\" is not one of: box, sphere", i, shape));
    }
    FF_CHECK(o.get("velocity", s.velocity));
    FF_CHECK(o.finish());
    out.push_back(s);
  }
  return {};
}

Status read_targets(const json& j, const fs::path& base, std::vector<TargetSpec>& out) {
  if (!j.is_array()) return param_error(fmt::format("targets: expected a list of targets, got {}", j.type_name()));
  for (std::size_t i = 0; i < j.size(); ++i) {
    JsonObject o(j[i], fmt::format("targets[{}]", i));
    FF_CHECK(o.check_object());
    TargetSpec t;
    std::string mesh;
    FF_CHECK(o.get("mesh", mesh));
    if (mesh.empty()) return param_error(fmt::format("targets[{}].mesh: a mesh file is required", i));
    t.mesh = fs::path(mesh).is_absolute() ? fs::path(mesh) : base / mesh;
    FF_CHECK(o.get("scale", t.transform.scale, /*allow_scalar=*/true));
    FF_CHECK(o.get("rotate", t.transform.rotate_deg));
    FF_CHECK(o.get("translate", t.transform.translate));
    FF_CHECK(o.get("start", t.start));
    std::string interp;
    FF_CHECK(o.get("interpolation", interp));
    if (!interp.empty() && interp != "linear" && interp != "smooth")
      return param_error(fmt::format("targets[{}].interpolation = \"{}\" is not one of: linear, smooth", i, interp));
    t.smooth = interp == "smooth";
    if (const json* keys = o.child("keyframes")) {
      if (!keys->is_array()) return param_error(fmt::format("targets[{}].keyframes: expected a list of keyframes", i));
      for (std::size_t k = 0; k < keys->size(); ++k) {
        JsonObject ko((*keys)[k], fmt::format("targets[{}].keyframes[{}]", i, k));
        FF_CHECK(ko.check_object());
        control::Keyframe key;
        if (!ko.has("time")) return param_error(fmt::format("targets[{}].keyframes[{}]: \"time\" is required", i, k));
        FF_CHECK(ko.get("time", key.time));
        FF_CHECK(ko.get("translate", key.translate));
        FF_CHECK(ko.get("rotate", key.rotate_deg));
        FF_CHECK(ko.get("scale", key.scale));
        FF_CHECK(ko.finish());
        t.keyframes.push_back(key);
      }
    }
    if (const json* morph = o.child("morph")) {
      if (!morph->is_array()) return param_error(fmt::format("targets[{}].morph: expected a list of {{\"time\", \"mesh\"}}", i));
      for (std::size_t k = 0; k < morph->size(); ++k) {
        JsonObject mo((*morph)[k], fmt::format("targets[{}].morph[{}]", i, k));
        FF_CHECK(mo.check_object());
        TargetSpec::Swap sw;
        std::string m;
        if (!mo.has("time") || !mo.has("mesh"))
          return param_error(fmt::format("targets[{}].morph[{}]: \"time\" and \"mesh\" are required", i, k));
        FF_CHECK(mo.get("time", sw.time));
        FF_CHECK(mo.get("mesh", m));
        FF_CHECK(mo.finish());
        if (!(sw.time >= 0.0 && sw.time <= 1e6) || (!t.swaps.empty() && !(sw.time > t.swaps.back().time)))
          return param_error(fmt::format("targets[{}].morph[{}].time = {} must be in [0, 1e6] and later than the swap before it", i, k, sw.time));
        sw.mesh = fs::path(m).is_absolute() ? fs::path(m) : base / m;
        t.swaps.push_back(std::move(sw));
      }
    }
    FF_CHECK(o.finish());
    out.push_back(std::move(t));
  }
  return {};
}

Status read_sampling(const json& j, sampling::SamplingParams& p) {
  JsonObject o(j, "sampling");
  FF_CHECK(o.check_object());
  std::string method;
  FF_CHECK(o.get("method", method));
  if (!method.empty()) {
    const auto m = sampling::parse_method(method);
    if (!m)
      return param_error(fmt::format("sampling.method = \"{}\" is not one of blue-noise, voxel, surface", method));
    p.method = *m;
  }
  FF_CHECK(o.get("spacing", p.spacing));
  std::int64_t count = static_cast<std::int64_t>(p.auto_count), seed = static_cast<std::int64_t>(p.seed),
               max_samples = static_cast<std::int64_t>(p.max_samples);
  FF_CHECK(o.get("auto_count", count));
  FF_CHECK(o.get("seed", seed));
  FF_CHECK(o.get("max_samples", max_samples));
  if (count < 0 || seed < 0 || max_samples < 0)
    return param_error("sampling: auto_count, seed and max_samples must not be negative");
  p.auto_count = static_cast<std::size_t>(count);
  p.seed = static_cast<std::uint64_t>(seed);
  p.max_samples = static_cast<std::size_t>(max_samples);
  FF_CHECK(o.get("relax_steps", p.relax_steps));
  FF_CHECK(o.get("support_factor", p.support_factor));
  FF_CHECK(o.get("phi_offset", p.phi_offset));
  if (const json* sp = o.child("sparse")) {
    JsonObject so(*sp, "sampling.sparse");
    FF_CHECK(so.check_object());
    FF_CHECK(so.get("drop_fraction", p.sparse.drop_fraction));
    if (const json* boxes = so.child("drop_boxes")) {
      if (!boxes->is_array()) return param_error("sampling.sparse.drop_boxes: expected a list of {\"min\", \"max\"} boxes");
      for (std::size_t i = 0; i < boxes->size(); ++i) {
        JsonObject bo((*boxes)[i], fmt::format("sampling.sparse.drop_boxes[{}]", i));
        FF_CHECK(bo.check_object());
        Aabb b;
        b.min = b.max = Vec3f::Zero();
        FF_CHECK(bo.get("min", b.min));
        FF_CHECK(bo.get("max", b.max));
        FF_CHECK(bo.finish());
        p.sparse.drop_boxes.push_back(b);
      }
    }
    FF_CHECK(so.finish());
  }
  return o.finish();
}

/// A baseline's parameter object ("controller": {"pbfc": {...}}): every field its struct lists, unknown keys refused.
template <class P>
Status read_fields(JsonObject& parent, std::string_view key, P& params) {
  const json* j = parent.child(key);
  if (!j) return {};
  JsonObject o(*j, fmt::format("controller.{}", key));
  FF_CHECK(o.check_object());
  Status st;
  P::fields(params, [&](std::string_view k, float& v, double, double) {
    if (st.ok()) st = o.get(k, v);
  });
  FF_CHECK(st);
  return o.finish();
}

Status read_controller(const json& j, control::ControllerSpec& c) {
  JsonObject o(j, "controller");
  FF_CHECK(o.check_object());
  FF_CHECK(o.get("name", c.name));
  if (!control::find_controller(c.name))
    return param_error(fmt::format("controller.name = \"{}\" is not one of: {}", c.name, control::controller_names()));
  if (const json* a = o.child("adaptive")) {
    JsonObject ao(*a, "controller.adaptive");
    auto& p = c.adaptive;
    FF_CHECK(ao.check_object());
    FF_CHECK(ao.get("weights", p.weights));
    FF_CHECK(ao.get("boundary_correction", p.boundary_correction));
    FF_CHECK(ao.get("bond_breaking", p.bond_breaking));
    std::string br;
    FF_CHECK(ao.get("bond_radius", br));
    if (!br.empty()) {
      const auto b = control::parse_bond_radius(br);
      if (!b) return param_error(fmt::format("controller.adaptive.bond_radius = \"{}\" is not one of: over-full, paper", br));
      p.bond_radius = *b;
    }
    FF_CHECK(ao.get("gather", p.gather));
    FF_CHECK(ao.get("kinematic", p.kinematic));
    FF_CHECK(ao.get("max_speed", p.max_speed));
    FF_CHECK(ao.get("alpha", p.alpha));
    FF_CHECK(ao.get("epsilon", p.epsilon));
    FF_CHECK(ao.get("clamp", p.clamp));
    FF_CHECK(ao.get("gamma", p.gamma));
    FF_CHECK(ao.get("normal_threshold", p.normal_threshold));
    FF_CHECK(ao.get("gather_fill", p.gather_fill));
    FF_CHECK(ao.get("gather_speed", p.gather_speed));
    FF_CHECK(ao.get("gather_time", p.gather_time));
    FF_CHECK(ao.finish());
  }
  FF_CHECK(read_fields(o, "thuerey", c.thuerey));
  FF_CHECK(read_fields(o, "pbfc", c.pbfc));
  FF_CHECK(read_fields(o, "weighted", c.weighted));
  FF_CHECK(read_fields(o, "rscf", c.rscf));
  FF_CHECK(read_fields(o, "lcat", c.lcat));
  return o.finish();
}

Status read_output(const json& j, OutputParams& p) {
  JsonObject o(j, "output");
  FF_CHECK(o.check_object());
  FF_CHECK(o.get("fps", p.fps));
  FF_CHECK(o.get("frames", p.frames));
  FF_CHECK(o.get("checkpoint_every", p.checkpoint_every));
  FF_CHECK(o.get("velocity", p.velocity));
  return o.finish();
}

}  // namespace

Result<Scene> parse_scene(std::string_view text, const fs::path& base_dir, std::string_view source_name) {
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false, /*ignore_comments=*/true);
  if (j.is_discarded()) {
    // Re-parse with exceptions only to get the position of the syntax error for the message.
    try {
      [[maybe_unused]] const json again = json::parse(text, nullptr, true, true);
    } catch (const json::parse_error& e) {
      std::string what = e.what();
      const auto colon = what.find("parse error");
      return param_error(fmt::format("{}: invalid JSON: {}", source_name, colon == std::string::npos ? what : what.substr(colon)));
    }
    return param_error(fmt::format("{}: invalid JSON", source_name));
  }
  Scene s;
  JsonObject root(j, "");
  FF_CHECK(root.check_object());
  if (const json* v = root.child("solver")) {
    FF_CHECK(read_solver(*v, s.solver));
    s.auto_radius = !(v->is_object() && v->contains("particle_radius"));
  }
  if (const json* v = root.child("domain")) {
    FF_CHECK(read_domain(*v, s.domain));
    s.auto_domain = false;
  }
  if (const json* v = root.child("fluid")) FF_CHECK(read_fluid(*v, s.fluid));
  if (const json* v = root.child("targets")) FF_CHECK(read_targets(*v, base_dir, s.targets));
  if (const json* v = root.child("output")) {
    FF_CHECK(read_output(*v, s.output));
    s.auto_frames = !(v->is_object() && v->contains("frames"));
  }
  if (const json* v = root.child("sampling")) FF_CHECK(read_sampling(*v, s.sampling));
  if (const json* v = root.child("controller")) FF_CHECK(read_controller(*v, s.controller));
  FF_CHECK(root.finish());
  FF_CHECK(s.validate());
  // The resume hash covers everything that shapes the simulation; the frame count may change between runs.
  json h = j;
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

Result<Scene> load_scene(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) return input_error(fmt::format("{}: no such scene file", file.string()));
  if (fs::is_directory(file, ec)) return input_error(fmt::format("{}: is a folder, not a scene file", file.string()));
  std::ifstream in(file, std::ios::binary);
  if (!in) return input_error(fmt::format("{}: cannot read the scene file", file.string()));
  std::stringstream ss;
  ss << in.rdbuf();
  const fs::path base = file.has_parent_path() ? file.parent_path() : fs::path(".");
  FF_TRY(Scene s, parse_scene(ss.str(), base, file.string()));
  s.file = file;
  return s;
}

}  // namespace ff::io
