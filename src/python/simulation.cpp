#include "python/simulation.h"

#include "python/convert.h"

#include "pipeline/live_scene.h"

#include <fmt/format.h>
#include <pybind11/stl.h>

#include <memory>
#include <mutex>

namespace ff::python {
namespace {
namespace fs = std::filesystem;

/// Owner of the buffers behind the zero-copy arrays handed out since the last step. While such an array is alive
/// (use_count() > 1: each array's base holds a reference), the next step first detaches the particles
/// (LiveScene::detach_particles): the old buffers move here and stay valid, unchanged, for as long as an array
/// needs them; the solver goes on with an equal copy. With no array alive nothing is copied.
struct ViewOwner {
  pipeline::Particles detached;
};

class Simulation {
 public:
  Simulation(const py::object& scene_arg, std::optional<std::string> controller, std::optional<std::string> cache_dir,
             std::optional<double> max_memory, const std::string& device, const py::object& progress) {
    const scene::Scene scene = load_scene_argument(scene_arg);
    pipeline::LiveOptions opt;
    opt.controller = std::move(controller);
    opt.device = device;  // "cpu", "gpu" or "auto": checked by LiveScene::create
    if (cache_dir) opt.cache_dir = *cache_dir;
    if (max_memory) {
      if (!(*max_memory >= 1.0 && *max_memory <= 1e9))
        raise(param_error(fmt::format("max_memory = {} is outside [1, 1e9] MiB", *max_memory)));
      opt.max_memory_mib = max_memory;
    }
    PyProgress bar(progress);
    auto live = [&] {
      py::gil_scoped_release nogil;
      return pipeline::LiveScene::create(scene, opt, bar);
    }();
    bar.rethrow_if_any();
    live_ = unwrap(std::move(live));
  }

  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;
  // Views outlive the simulation when a caller keeps them: hand them the buffers they point into.
  ~Simulation() {
    if (live_) before_change();
  }

  py::dict step(int frames, bool metrics) {
    if (frames < 1) raise(param_error(fmt::format("step: frames = {} must be ≥ 1", frames)));
    auto lock = guard("step");
    before_change();
    pipeline::LiveFrame f;
    Status st;
    double seconds = 0.0;
    int substeps = 0;
    {
      py::gil_scoped_release nogil;
      for (int i = 0; i < frames && st.ok(); ++i) {
        auto r = live_->step(metrics && i + 1 == frames);  // the metrics of the frame returned only
        if (!r) st = r.error();
        else {
          f = *r;
          seconds += f.step_seconds;
          substeps += f.substeps;
        }
      }
    }
    check(st);
    last_ = f;
    py::dict d = frame_dict(f);
    d["step_seconds"] = seconds;
    d["substeps"] = substeps;
    return d;
  }

  void restart() {
    auto lock = guard("restart");
    before_change();
    check(live_->restart());
    last_ = pipeline::LiveFrame{};
  }

  void set_controller(const std::string& name) {
    auto lock = guard("controller");
    check(live_->set_controller(name));
  }

  py::dict set_pose(std::size_t target, const py::object& translate, const py::object& rotate, float scale) {
    auto lock = guard("set_pose");
    pipeline::LivePose p;
    p.translate = vec3(translate, "translate");
    p.rotate_deg = vec3(rotate, "rotate");
    p.scale = scale;
    const pipeline::LivePose q = unwrap(live_->set_pose(target, p));
    py::dict d;
    d["translate"] = py::make_tuple(q.translate.x(), q.translate.y(), q.translate.z());
    d["rotate"] = py::make_tuple(q.rotate_deg.x(), q.rotate_deg.y(), q.rotate_deg.z());
    d["scale"] = q.scale;
    return d;
  }

  // Zero-copy, read-only views of the solver's arrays, in the solver's order (it sorts particles spatially; `ids`
  // says which particle each row is).
  py::array positions() { return view(live_->particles().position, 3, "positions"); }
  py::array velocities() { return view(live_->particles().velocity, 3, "velocities"); }
  py::array target_ids() { return view(live_->particles().target, 1, "target_ids"); }
  py::array ids() { return view(live_->particles().id, 1, "ids"); }

  /// Copies in id order (the order of the run's PLY frames), stable from frame to frame.
  py::dict sorted() {
    auto lock = guard("sorted");
    std::vector<Vec3f> x, v;
    std::vector<std::uint8_t> t;
    live_->particles_by_id(x, v, t);
    py::array_t<std::uint8_t> ta(static_cast<py::ssize_t>(t.size()));
    std::copy(t.begin(), t.end(), ta.mutable_data());
    py::dict d;
    d["positions"] = points_to_array(x);
    d["velocities"] = points_to_array(v);
    d["target_ids"] = ta;
    return d;
  }

  py::dict metrics() const { return frame_dict(last_); }
  py::object scene_dict() const { return from_json(scene::scene_to_json(live_->scene())); }
  const pipeline::LiveScene& live() const { return *live_; }

 private:
  /// The simulation for this call, or a RuntimeError while another thread steps it (with the GIL released): a
  /// blocking wait here would hold the GIL the stepping thread needs to finish.
  std::unique_lock<std::mutex> guard(const char* what) {
    std::unique_lock<std::mutex> lock(busy_, std::try_to_lock);
    if (!lock) throw std::runtime_error(fmt::format("Simulation.{}: another thread is stepping this simulation", what));
    return lock;
  }

  static Vec3f vec3(const py::object& o, const char* what) {
    std::vector<float> s;
    try {
      s = o.cast<std::vector<float>>();
    } catch (const py::cast_error&) {
      raise(param_error(fmt::format("{}: expected 3 numbers", what)));
    }
    if (s.size() != 3) raise(param_error(fmt::format("{}: expected 3 numbers, got {}", what, s.size())));
    return {s[0], s[1], s[2]};
  }

  static py::dict frame_dict(const pipeline::LiveFrame& f) {
    py::dict d;
    d["frame"] = f.frame;
    d["time"] = f.time;
    d["controlled"] = f.controlled;
    d["error_rate"] = f.error_rate;
    d["inside"] = f.inside;
    d["splash"] = f.splash;
    d["e_fwd_all"] = f.e_fwd_all;
    return d;
  }

  void before_change() {
    if (views_ && views_.use_count() > 1) {
      views_->detached = live_->detach_particles();
      views_.reset();
    }
  }

  template <class T>
  py::array view(const std::vector<T>& a, int columns, const char* what) {
    auto lock = guard(what);
    if (!views_) views_ = std::make_shared<ViewOwner>();
    auto* keep = new std::shared_ptr<ViewOwner>(views_);
    py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<ViewOwner>*>(p); });
    using Scalar = std::conditional_t<std::is_same_v<T, Vec3f>, float, T>;
    static_assert(!std::is_same_v<T, Vec3f> || sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be packed");
    const auto n = static_cast<py::ssize_t>(a.size());
    const auto* data = reinterpret_cast<const Scalar*>(a.data());
    py::array out = columns == 3 ? py::array_t<Scalar>({n, py::ssize_t{3}}, data, base)
                                 : py::array_t<Scalar>({n}, data, base);
    py::detail::array_proxy(out.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return out;
  }

  std::unique_ptr<pipeline::LiveScene> live_;
  std::shared_ptr<ViewOwner> views_;
  pipeline::LiveFrame last_;
  std::mutex busy_;
};

}  // namespace

void bind_simulation(py::module_& m) {
  py::class_<Simulation>(m, "Simulation", R"(A scene stepped one frame at a time.

Set up exactly as `fluidform run` sets the scene up (the same particles, samples and controller), so stepping it
gives the run's frames. positions, velocities, target_ids and ids are read-only NumPy views of the solver's arrays
without a copy, in the solver's order (it sorts particles spatially between frames; ids names each row). A view
stays valid and unchanged after later steps (the solver then goes on with a copy). sorted() gives copies in id
order, the order of the run's particle frames.)")
      .def(py::init<const py::object&, std::optional<std::string>, std::optional<std::string>, std::optional<double>,
                    const std::string&, const py::object&>(),
           py::arg("scene"), py::kw_only(), py::arg("controller") = py::none(), py::arg("cache_dir") = py::none(),
           py::arg("max_memory") = py::none(), py::arg("device") = "cpu", py::arg("progress") = py::none(),
           "scene: a scene file path or a dict of scene keys; controller overrides the scene's; cache_dir holds the "
           "control-sample cache (default fluidform-out/cache, as a run's); max_memory: MiB the scene may need, checked "
           "before anything is allocated (as run's); device: 'cpu', 'gpu' or 'auto' (as run's --device); "
           "progress: callback(what, done, total).")
      .def("step", &Simulation::step, py::arg("frames") = 1, py::kw_only(), py::arg("metrics") = true,
           "Advances `frames` frames of 1/fps s; returns the last frame's shape metrics (measured on the last frame "
           "only; metrics=False skips them, NaN) and the solver's wall time of the steps (step_seconds).")
      .def("restart", &Simulation::restart, "Back to t = 0 with a fresh solver and controller.")
      .def("set_pose", &Simulation::set_pose, py::arg("target"), py::kw_only(),
           py::arg("translate") = py::make_tuple(0, 0, 0), py::arg("rotate") = py::make_tuple(0, 0, 0),
           py::arg("scale") = 1.0f,
           "Moves target `target` about its pivot (m, degrees about x, y, z, uniform scale); returns the pose applied "
           "(clamped so the target stays in the domain).")
      .def("sorted", &Simulation::sorted, "Copies of positions, velocities and target_ids in particle-id order.")
      .def("metrics", &Simulation::metrics, "The last step's shape metrics (error_rate %, inside, splash, ...).")
      .def("scene", &Simulation::scene_dict, "The completed scene as a dict of scene keys.")
      .def_property_readonly("positions", &Simulation::positions, "(N, 3) float32 view, metres")
      .def_property_readonly("velocities", &Simulation::velocities, "(N, 3) float32 view, m/s")
      .def_property_readonly("target_ids", &Simulation::target_ids, "(N,) uint8 view; 255: free fluid")
      .def_property_readonly("ids", &Simulation::ids, "(N,) uint32 view: each row's stable particle id")
      .def_property("controller", [](const Simulation& s) { return s.live().controller_name(); },
                    &Simulation::set_controller, "the shape controller's name; assigning switches it")
      .def_property_readonly("device", [](const Simulation& s) { return s.live().device(); },
                             "what steps it: 'cpu', or the GPU's name and driver")
      .def_property_readonly("time", [](const Simulation& s) { return s.live().time(); }, "s simulated")
      .def_property_readonly("frame", [](const Simulation& s) { return s.live().frame(); })
      .def_property_readonly("fps", [](const Simulation& s) { return s.live().fps(); })
      .def_property_readonly("particle_radius",
                             [](const Simulation& s) { return s.live().scene().solver.particle_radius; }, "r, m")
      .def("__len__", [](const Simulation& s) { return s.live().particles().size(); })
      .def("__repr__", [](const Simulation& s) {
        return fmt::format("<fluidform.Simulation {} particles, frame {}, controller {}>", s.live().particles().size(),
                           s.live().frame(), s.live().controller_name());
      });
}

}  // namespace ff::python
