// The Python module `fluidform` (pybind11): the pipeline library for scripts and notebooks. Each function is a
// thin layer over the stage the CLI calls, so results, defaults and one-line error messages are the CLI's.
//   sample(mesh, ...)          a mesh (file or NumPy arrays) → control samples (pipeline::sample_mesh)
//   reconstruct(points, ...)   particles → (vertices, faces) (pipeline::mesh_particles)
//   measure(positions, mesh)   the shape metrics of METHOD §d (pipeline::measure_particles)
//   run(scene, ...)            `fluidform run` (pipeline::run_scene), with a progress callback that can cancel
//   Simulation(scene)          a scene stepped frame by frame (pipeline::LiveScene), its arrays as NumPy views
// Heavy calls release the GIL; progress callbacks take it back (python/convert.h).
#include "python/convert.h"
#include "python/simulation.h"

#include "io/load_mesh.h"
#include "pipeline/front_doors.h"
#include "pipeline/mesh_export.h"
#include "pipeline/run.h"
#include "scene/scene.h"

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <spdlog/spdlog.h>

#include <filesystem>

namespace ff::python {
namespace {
namespace fs = std::filesystem;

/// A mesh argument: a path (str or os.PathLike) or a (vertices, faces) pair of arrays.
io::TriangleMesh mesh_argument(const py::handle& mesh) {
  if (py::isinstance<py::str>(mesh) || py::hasattr(mesh, "__fspath__")) {
    const std::string path = py::isinstance<py::str>(mesh) ? mesh.cast<std::string>()
                                                           : py::str(mesh.attr("__fspath__")()).cast<std::string>();
    return unwrap([&] {
      py::gil_scoped_release nogil;
      return io::load_mesh(path);
    }());
  }
  if (py::isinstance<py::tuple>(mesh) || py::isinstance<py::list>(mesh)) {
    const auto seq = mesh.cast<py::sequence>();
    if (seq.size() != 2) raise(input_error("mesh: expected a file path or a (vertices, faces) pair of arrays"));
    return mesh_from_arrays(seq[0], seq[1]);
  }
  raise(input_error("mesh: expected a file path or a (vertices, faces) pair of arrays"));
}

struct Samples {
  py::array_t<float> positions, weights, density, phi;
  float spacing = 0, support = 0, mass = 0;
  std::string method;
  double volume = 0, area = 0;
  std::vector<std::string> warnings;
};

Samples sample(const py::object& mesh, std::optional<std::size_t> count, std::optional<float> spacing,
               const std::string& method, std::uint64_t seed, const py::object& progress, const py::kwargs& kwargs) {
  sampling::SamplingParams params;
  read_kwargs(kwargs, "sampling", params);
  check(pipeline::set_sampler(params, method, {}, "method"));
  params.seed = seed;
  if (count && spacing) raise(param_error("sample: give count or spacing, not both"));
  if (count) params.auto_count = *count;
  if (spacing) params.spacing = *spacing;
  check(params.validate());
  const io::TriangleMesh target = mesh_argument(mesh);
  PyProgress bar(progress);
  auto sampled = [&] {
    py::gil_scoped_release nogil;
    return pipeline::sample_mesh(target, params, bar);
  }();
  bar.rethrow_if_any();
  const pipeline::SampledMesh m = unwrap(std::move(sampled));
  const sampling::ControlSet& s = m.set;
  const sampling::SampleReport& rep = m.report;
  Samples out;
  out.positions = points_to_array(s.position);
  out.weights = floats_to_array(s.weight);
  out.density = floats_to_array(s.density);
  out.phi = floats_to_array(s.phi);
  out.spacing = s.spacing, out.support = s.support, out.mass = s.mass;
  out.method = std::string(pipeline::sampler_name(rep.method));
  out.volume = rep.volume, out.area = rep.area;
  out.warnings = rep.warnings;
  return out;
}

py::tuple reconstruct(const py::object& points, std::optional<float> spacing, const py::kwargs& kwargs) {
  surface::SurfaceParams params;
  read_kwargs(kwargs, "surface", params);
  check(params.validate());
  const std::vector<Vec3f> p = points_from_array(points, "points");
  if (p.empty()) raise(input_error("points: the array is empty"));
  auto mesh = [&] {
    py::gil_scoped_release nogil;
    return pipeline::mesh_particles(p, spacing, params);
  }();
  return mesh_to_arrays(unwrap(std::move(mesh)));
}

py::dict measure(const py::object& positions, const py::object& mesh, std::optional<float> particle_radius,
                 const py::object& samples, const py::object& controlled) {
  const std::vector<Vec3f> x = points_from_array(positions, "positions");
  if (x.empty()) raise(input_error("positions: the array is empty"));
  const io::TriangleMesh target = mesh_argument(mesh);
  float r = 0.0f;
  if (particle_radius) {
    r = *particle_radius;
    if (!(std::isfinite(r) && r > 0.0f)) raise(param_error(fmt::format("particle_radius = {} must be > 0", r)));
  } else {
    r = 0.5f * unwrap(pipeline::estimate_spacing(x));
  }
  std::vector<std::uint8_t> flags(x.size(), 1);
  if (!controlled.is_none()) {
    auto c = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(controlled);
    if (!c || c.ndim() != 1 || static_cast<std::size_t>(c.shape(0)) != x.size()) {
      PyErr_Clear();
      raise(input_error(fmt::format("controlled: expected {} flags, one per position", x.size())));
    }
    std::copy(c.data(), c.data() + x.size(), flags.begin());
  }
  std::optional<std::vector<Vec3f>> controls;
  if (!samples.is_none()) controls = points_from_array(samples, "samples");
  auto measured = [&] {
    py::gil_scoped_release nogil;
    return pipeline::measure_particles(target, x, flags, r, std::move(controls));
  }();
  const metrics::FrameMetrics f = unwrap(std::move(measured));
  py::dict d;
  d["error_rate"] = f.error_rate;
  d["e_fwd"] = f.e_fwd;
  d["e_bwd"] = f.e_bwd;
  d["e_fwd_all"] = f.e_fwd_all;
  d["inside"] = f.inside_fraction;
  d["splash"] = f.splash_fraction;
  d["error_spacings"] = f.error_spacings;
  d["fluid"] = f.fluid;
  d["controlled"] = f.controlled;
  d["particle_radius"] = r;
  return d;
}

py::dict run(const py::object& scene_arg, const std::string& out, std::optional<int> frames,
             std::optional<std::string> controller, bool mesh, bool animation, int mesh_every, bool vdb, bool resume,
             std::optional<double> max_memory, const std::string& device, const py::object& progress) {
  scene::Scene scene = load_scene_argument(scene_arg);
  pipeline::RunOptions opt;
  opt.out_dir = out;
  opt.device = device;  // "cpu", "gpu" or "auto": checked by the run, its error names --device
  if (frames) {
    if (*frames < 1) raise(param_error(fmt::format("frames = {} must be ≥ 1", *frames)));
    opt.frames = frames;
  }
  opt.controller = std::move(controller);
  opt.mesh = mesh;
  opt.animation = animation;
  if (mesh_every < 0) raise(param_error(fmt::format("mesh_every = {} must be ≥ 0", mesh_every)));
  opt.mesh_every = mesh_every;
  opt.vdb = vdb;
  opt.resume = resume;
  if (max_memory) {
    if (!(*max_memory >= 1.0 && *max_memory <= 1e9))
      raise(param_error(fmt::format("max_memory = {} is outside [1, 1e9] MiB", *max_memory)));
    opt.max_memory_mib = max_memory;
  }
  PyProgress bar(progress);
  auto sum = [&] {
    py::gil_scoped_release nogil;
    return pipeline::run_scene(scene, opt, bar);
  }();
  bar.rethrow_if_any();
  const pipeline::RunSummary s = unwrap(std::move(sum));
  py::dict d;
  d["out"] = out;
  d["particles"] = s.particles;
  d["frames"] = s.frames_written;
  d["frame_seconds"] = s.mean_frame_seconds;
  d["peak_memory_mib"] = s.peak_memory_mib;
  d["controller"] = s.controller;
  d["device"] = s.device;
  if (s.has_targets) {
    d["control_particles"] = s.control_particles;
    d["controlled"] = s.controlled;
    d["error_rate"] = s.error_rate;
    d["inside"] = s.inside_fraction;
    d["splash"] = s.splash_fraction;
    d["time_to_form"] = s.time_to_form;
    d["e_fwd_all"] = s.e_fwd_all;
    d["error_spacings"] = s.error_spacings;
  }
  if (mesh) {
    d["mesh_triangles"] = s.mesh_triangles;
    d["mesh_frames"] = s.mesh_frames;
    d["mesh_ok"] = s.mesh_ok;
    d["mesh_seconds"] = s.mesh_seconds;
  }
  return d;
}

void set_log_level(const std::string& level) {
  const auto l = spdlog::level::from_str(level);
  if (l == spdlog::level::off && level != "off")
    raise(param_error(fmt::format("log level {} is not one of trace, debug, info, warn, error, critical, off", level)));
  spdlog::set_level(l);
}

}  // namespace

scene::Scene load_scene_argument(const py::handle& scene_arg) {
  if (py::isinstance<py::dict>(scene_arg)) {
    // A scene as a dict: relative mesh paths from the working directory, as for a scene file there.
    const std::string text = to_json(scene_arg).dump();
    return unwrap(scene::parse_scene(text, fs::current_path(), "scene"));
  }
  if (py::isinstance<py::str>(scene_arg) || py::hasattr(scene_arg, "__fspath__")) {
    const std::string path = py::isinstance<py::str>(scene_arg)
                                 ? scene_arg.cast<std::string>()
                                 : py::str(scene_arg.attr("__fspath__")()).cast<std::string>();
    return unwrap(scene::load_scene(path));
  }
  raise(input_error("scene: expected a scene file path or a dict of scene keys"));
}

}  // namespace ff::python

PYBIND11_MODULE(_fluidform, m) {
  namespace py = pybind11;
  using namespace ff::python;
  m.doc() = "fluidform: editable mesh animations from controllable particles (the C++ pipeline, bound by pybind11).";
  m.attr("__version__") = FF_VERSION;
  register_exceptions(m);
  // Scripts want results, not the CLI's progress log: warnings and errors only until set_log_level says otherwise.
  spdlog::set_level(spdlog::level::warn);

  py::class_<Samples>(m, "Samples", "Control samples of one target (positions and their SPH quantities).")
      .def_readonly("positions", &Samples::positions, "(N, 3) float32, metres")
      .def_readonly("weights", &Samples::weights, "(N,) float32: ω, the Shepard self-weight in (0, 1] (eq. 2)")
      .def_readonly("density", &Samples::density, "(N,) float32: ρ_c, kg/m³ (eq. 9)")
      .def_readonly("phi", &Samples::phi, "(N,) float32: φ̃, the normalised distance from the centre (eq. 4)")
      .def_readonly("spacing", &Samples::spacing, "d_c, the sampling spacing, m")
      .def_readonly("support", &Samples::support, "H_c, the control kernel support, m")
      .def_readonly("mass", &Samples::mass, "m_c, the calibrated control mass, kg")
      .def_readonly("method", &Samples::method, "the method used ('surface' when an open sheet forced it)")
      .def_readonly("volume", &Samples::volume, "m³ enclosed by the mesh")
      .def_readonly("area", &Samples::area, "m² of the mesh")
      .def_readonly("warnings", &Samples::warnings)
      .def("__len__", [](const Samples& s) { return s.positions.shape(0); })
      .def("__iter__", [](const Samples& s) { return py::iter(py::make_tuple(s.positions, s.weights)); },
           "positions, weights = sample(...)")
      .def("__repr__", [](const Samples& s) {
        return fmt::format("<fluidform.Samples {} {} samples, spacing {:g} m>", s.positions.shape(0), s.method, s.spacing);
      });

  m.def("sample", &sample, py::arg("mesh"), py::kw_only(), py::arg("count") = py::none(),
        py::arg("spacing") = py::none(), py::arg("method") = "blue-noise", py::arg("seed") = 1,
        py::arg("progress") = py::none(),
        R"(Samples a target mesh into control particles.

mesh: a mesh file (any format Assimp reads) or a (vertices (V, 3), faces (F, 3)) pair of NumPy arrays, metres.
count: about this many samples (default 10000), or spacing: the sample spacing d_c in metres (not both).
method: 'blue-noise' (default), 'voxel' or 'surface'. Further keywords are the scene's "sampling" keys
(relax_steps, support_factor, phi_offset, max_samples, sparse=...); an unknown one raises ParamError.
progress: callback(what, done, total); returning False cancels (raises Cancelled).
Returns Samples: .positions (N, 3) and .weights (N,), unpackable as `positions, weights = sample(...)`.)");

  m.def("reconstruct", &reconstruct, py::arg("points"), py::kw_only(), py::arg("spacing") = py::none(),
        R"(Reconstructs the surface of a particle cloud: a closed, 2-manifold, outward mesh.

points: (N, 3) positions, metres. spacing: the particle spacing d = 2r (default: the median nearest-neighbour
distance). Further keywords are the scene's "surface" keys (iso, smoothing_iterations, max_triangles, ...).
Returns (vertices (V, 3) float32, faces (F, 3) uint32); both empty when the particles make no surface.)");

  m.def("measure", &measure, py::arg("positions"), py::arg("mesh"), py::kw_only(),
        py::arg("particle_radius") = py::none(), py::arg("samples") = py::none(), py::arg("controlled") = py::none(),
        R"(The shape metrics of METHOD §d: how well fluid particles form a target mesh.

positions: (N, 3) fluid positions; mesh: a file or (vertices, faces). particle_radius r (default: half the median
nearest-neighbour spacing). samples: the target's control samples (default: the mesh sampled at d = 2r, as a
run does). controlled: per-particle flags (default: all controlled).
Returns a dict: error_rate (%), e_fwd, e_bwd, e_fwd_all (m), inside, splash (fractions), error_spacings, fluid,
controlled.)");

  m.def("run", &run, py::arg("scene"), py::kw_only(), py::arg("out") = "fluidform-out", py::arg("frames") = py::none(),
        py::arg("controller") = py::none(), py::arg("mesh") = true, py::arg("animation") = true,
        py::arg("mesh_every") = 0, py::arg("vdb") = false, py::arg("resume") = false, py::arg("max_memory") = py::none(),
        py::arg("device") = "cpu", py::arg("progress") = py::none(),
        R"(Runs a scene as `fluidform run` does, into the folder `out` (the same files).

scene: a scene file path or a dict of scene keys (relative mesh paths from the working directory).
frames, controller, mesh, animation, mesh_every, vdb, resume, max_memory (MiB), device ('cpu', 'gpu' or 'auto'):
as the CLI's options.
progress: callback(what, done, total), e.g. ('forming', 60, 600); returning False cancels (raises Cancelled).
Ctrl-C cancels too. Returns the run's summary as a dict (error_rate, inside, splash, frame_seconds, device, ...).)");

  m.def("set_log_level", &set_log_level, py::arg("level"),
        "The library's log level: 'trace', 'debug', 'info' (the CLI's), 'warn' (the module's default), 'error', 'off'.");

  bind_simulation(m);
}
