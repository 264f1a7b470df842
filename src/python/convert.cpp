#include "python/convert.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <utility>

namespace ff::python {

Exceptions& exceptions() {
  // Held for the interpreter's life: the module object keeps the same references (m.attr), so this is never the
  // last one; leaked on purpose at exit (destroying Python objects after finalisation would crash).
  static Exceptions* e = new Exceptions();
  return *e;
}

void register_exceptions(py::module_& m) {
  auto make = [&](const char* name, py::handle bases, const char* doc) {
    py::object t = py::reinterpret_steal<py::object>(
        PyErr_NewExceptionWithDoc((std::string("fluidform.") + name).c_str(), doc, bases.ptr(), nullptr));
    if (!t) throw py::error_already_set();
    m.attr(name) = t;
    return t;
  };
  Exceptions& e = exceptions();
  e.error = make("Error", PyExc_Exception, "Base of every fluidform error; str() is the CLI's one-line message.");
  e.input = make("InputError", py::make_tuple(e.error, py::handle(PyExc_ValueError)),
                 "Bad input: a file, a mesh, an array, a scene value (the CLI's exit code 2).");
  e.param = make("ParamError", py::make_tuple(e.error, py::handle(PyExc_ValueError)),
                 "A parameter out of range or unknown (the CLI's exit code 2).");
  e.io = make("IoError", py::make_tuple(e.error, py::handle(PyExc_OSError)),
              "The file system refused (the CLI's exit code 1).");
  e.numerical = make("NumericalError", e.error, "The simulation blew up (the CLI's exit code 1).");
  e.cancelled = make("Cancelled", e.error, "A progress callback returned False (or raised) and the work stopped.");
}

void raise(const Error& err) {
  const Exceptions& e = exceptions();
  py::handle type = e.error;
  switch (err.kind) {
    case Error::Kind::Input: type = e.input; break;
    case Error::Kind::Param: type = e.param; break;
    case Error::Kind::Io: type = e.io; break;
    case Error::Kind::Numerical: type = e.numerical; break;
    case Error::Kind::Cancelled: type = e.cancelled; break;
  }
  PyErr_SetString(type.ptr(), err.message.c_str());
  throw py::error_already_set();
}

namespace {

[[noreturn]] void raise_input(const std::string& m) { raise(input_error(m)); }

py::array_t<float, py::array::c_style | py::array::forcecast> as_float_rows(const py::handle& a, const char* what) {
  if (a.is_none()) raise_input(fmt::format("{}: expected an (N, 3) array, got None", what));
  auto arr = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!arr) {
    PyErr_Clear();
    raise_input(fmt::format("{}: expected an (N, 3) array of numbers", what));
  }
  if (arr.ndim() != 2 || arr.shape(1) != 3)
    raise_input(fmt::format("{}: expected an (N, 3) array, got shape {}", what,
                            arr.ndim() == 1 ? fmt::format("({},)", arr.shape(0))
                                            : fmt::format("with {} dimensions", arr.ndim())));
  return arr;
}

}  // namespace

std::vector<Vec3f> points_from_array(const py::handle& a, const char* what) {
  auto arr = as_float_rows(a, what);
  const auto n = static_cast<std::size_t>(arr.shape(0));
  std::vector<Vec3f> out(n);
  const float* d = arr.data();
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = Vec3f(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
    if (!out[i].allFinite())
      raise_input(fmt::format("{}: row {} is not finite ({}, {}, {})", what, i, out[i].x(), out[i].y(), out[i].z()));
  }
  return out;
}

io::TriangleMesh mesh_from_arrays(const py::handle& vertices, const py::handle& faces) {
  io::TriangleMesh mesh;
  mesh.vertices = points_from_array(vertices, "mesh vertices");
  if (mesh.vertices.empty()) raise_input("mesh vertices: the array is empty");
  if (mesh.vertices.size() > std::size_t{kInvalidIndex} - 1)
    raise_input(fmt::format("mesh vertices: {} are more than a mesh may have", mesh.vertices.size()));
  auto f = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(faces);
  if (!f) {
    PyErr_Clear();
    raise_input("mesh faces: expected an (F, 3) array of vertex indices");
  }
  if (f.ndim() != 2 || f.shape(1) != 3) raise_input("mesh faces: expected an (F, 3) array of vertex indices (triangles)");
  const auto nf = static_cast<std::size_t>(f.shape(0));
  if (nf == 0) raise_input("mesh faces: the array is empty");
  const std::int64_t* d = f.data();
  const auto nv = static_cast<std::int64_t>(mesh.vertices.size());
  mesh.triangles.reserve(nf);
  for (std::size_t i = 0; i < nf; ++i) {
    std::array<Index, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const std::int64_t v = d[3 * i + k];
      if (v < 0 || v >= nv)
        raise_input(fmt::format("mesh faces: face {} names vertex {}, not one of the {} vertices", i, v, nv));
      t[k] = static_cast<Index>(v);
    }
    mesh.triangles.push_back(t);
  }
  return mesh;
}

py::array_t<float> points_to_array(std::span<const Vec3f> p) {
  py::array_t<float> a({static_cast<py::ssize_t>(p.size()), py::ssize_t{3}});
  float* d = a.mutable_data();
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) d[3 * i + k] = p[i][k];
  return a;
}

py::array_t<float> floats_to_array(std::span<const float> v) {
  py::array_t<float> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

py::tuple mesh_to_arrays(const io::TriangleMesh& mesh) {
  py::array_t<std::uint32_t> f({static_cast<py::ssize_t>(mesh.triangles.size()), py::ssize_t{3}});
  std::uint32_t* d = f.mutable_data();
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) d[3 * i + k] = mesh.triangles[i][k];
  return py::make_tuple(points_to_array(mesh.vertices), f);
}

nlohmann::json to_json(const py::handle& o) {
  if (o.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(o)) return o.cast<bool>();
  if (py::isinstance<py::int_>(o)) return o.cast<long long>();
  if (py::isinstance<py::float_>(o)) return o.cast<double>();
  if (py::isinstance<py::str>(o)) return o.cast<std::string>();
  if (py::hasattr(o, "__fspath__")) return py::str(o.attr("__fspath__")()).cast<std::string>();
  if (py::isinstance<py::dict>(o)) {
    nlohmann::json j = nlohmann::json::object();
    for (auto [k, v] : o.cast<py::dict>()) j[py::str(k).cast<std::string>()] = to_json(v);
    return j;
  }
  if (py::isinstance<py::array>(o)) return to_json(o.attr("tolist")());
  if (py::isinstance<py::sequence>(o)) {
    nlohmann::json j = nlohmann::json::array();
    for (auto v : o.cast<py::sequence>()) j.push_back(to_json(v));
    return j;
  }
  // NumPy scalars and other numbers.
  if (py::hasattr(o, "__float__")) return o.attr("__float__")().cast<double>();
  raise(param_error(fmt::format("a value of type {} cannot be a parameter",
                                py::str(py::type::handle_of(o).attr("__name__")).cast<std::string>())));
}

py::object from_json(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return py::none();
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(j.get<long long>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<unsigned long long>());
    case nlohmann::json::value_t::number_float: return py::float_(j.get<double>());
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const auto& v : j) l.append(from_json(v));
      return l;
    }
    case nlohmann::json::value_t::object: {
      py::dict d;
      for (const auto& [k, v] : j.items()) d[py::str(k)] = from_json(v);
      return d;
    }
    default: return py::none();
  }
}

PyProgress::~PyProgress() {
  // The callback and a stored exception are Python objects: release them with the GIL held.
  py::gil_scoped_acquire gil;
  error_.reset();
  callback_ = py::object();
}

void PyProgress::begin(std::string_view what, std::size_t total) {
  what_ = std::string(what);
  total_ = total;
  (void)call(0);  // a False here stops the operation at its first tick (begin cannot refuse)
}

bool PyProgress::tick(std::size_t done) { return call(done); }

bool PyProgress::call(std::size_t done) {
  py::gil_scoped_acquire gil;
  if (error_ || cpp_error_) return false;
  if (PyErr_CheckSignals() != 0) {  // Ctrl-C while C++ runs: stop, and raise KeyboardInterrupt afterwards
    error_.emplace();
    return false;
  }
  if (callback_.is_none()) return true;
  // Called from C++ frames (OpenMP workers among them): nothing may be thrown from here.
  try {
    const py::object r = callback_(what_, done, total_);
    if (r.is_none()) return true;
    const int truth = PyObject_IsTrue(r.ptr());  // any object: its truth value, as `if r:` would
    if (truth < 0) {
      error_.emplace();
      return false;
    }
    if (truth == 0) refused_ = true;
    return truth != 0;
  } catch (py::error_already_set& e) {
    error_.emplace(std::move(e));
    return false;
  } catch (...) {
    cpp_error_ = std::current_exception();
    return false;
  }
}

void PyProgress::rethrow_if_any() {
  if (cpp_error_) std::rethrow_exception(std::exchange(cpp_error_, nullptr));
  if (!error_) {
    if (refused_) raise(Error{Error::Kind::Cancelled, "cancelled"});
    return;
  }
  py::error_already_set e = std::move(*error_);
  error_.reset();
  throw std::move(e);
}

}  // namespace ff::python
