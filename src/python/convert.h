#pragma once
// What every binding file shares: fluidform's errors as Python exceptions, NumPy ⇄ core types, the progress hook
// that calls Python, and parameter structs read from keyword arguments through the scene reader (so a misspelt
// keyword is refused exactly as a misspelt scene key is).
#include "core/error.h"
#include "core/progress.h"
#include "io/triangle_mesh.h"
#include "scene/fields_json.h"
#include "scene/scene.h"

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <exception>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace ff::python {
namespace py = pybind11;

/// The exception types, created once by the module (fluidform.Error and its subclasses).
struct Exceptions {
  py::object error, input, param, io, numerical, cancelled;
};
Exceptions& exceptions();
void register_exceptions(py::module_& m);

/// Raises the Python exception for `e` (InputError, ParamError, IoError, NumericalError, Cancelled), its message
/// the one line the CLI prints.
[[noreturn]] void raise(const Error& e);
template <class T>
T unwrap(Result<T> r) {
  if (!r) raise(r.error());
  return std::move(r).value();
}
inline void check(const Status& st) {
  if (!st.ok()) raise(st.error());
}

/// An (N, 3) float32 array (any real dtype is converted) → points. Errors name `what`.
std::vector<Vec3f> points_from_array(const py::handle& a, const char* what);
/// (vertices (V, 3), faces (F, 3)) → a mesh; indices are checked against V, coordinates for being finite.
io::TriangleMesh mesh_from_arrays(const py::handle& vertices, const py::handle& faces);
/// A copy of the points as an (N, 3) float32 array.
py::array_t<float> points_to_array(std::span<const Vec3f> p);
py::array_t<float> floats_to_array(std::span<const float> v);
/// Mesh → (vertices (V, 3) float32, faces (F, 3) uint32).
py::tuple mesh_to_arrays(const io::TriangleMesh& mesh);

/// Python keyword arguments → JSON (numbers, strings, bools, lists and dicts of them).
nlohmann::json to_json(const py::handle& o);
py::object from_json(const nlohmann::json& j);

/// Reads `kwargs` into a parameter struct through its field list: an unknown key or a value out of range raises
/// ParamError with the scene reader's message (`path` names the struct, e.g. "sampling").
template <core::HasFields P>
void read_kwargs(const py::kwargs& kwargs, const std::string& path, P& params) {
  if (kwargs.size() == 0) return;
  check(scene::read_object(to_json(kwargs), path, params, "."));
}

/// A scene argument: a scene file path (str or os.PathLike) or a dict of scene keys (mesh paths relative to the
/// working directory). Raises the scene reader's errors.
scene::Scene load_scene_argument(const py::handle& scene);

/// core::Progress that calls `callback(what, done, total)` with the GIL held; a callback returning False, raising,
/// or a pending KeyboardInterrupt stops the operation (Error::Kind::Cancelled) and the exception is re-raised by
/// rethrow_if_any() once the C++ call has returned.
class PyProgress final : public core::Progress {
 public:
  explicit PyProgress(py::object callback) : callback_(std::move(callback)) {}
  ~PyProgress() override;
  void begin(std::string_view what, std::size_t total) override;
  bool tick(std::size_t done) override;
  /// With the GIL held: raises the callback's exception (or KeyboardInterrupt) if one stopped the operation, else
  /// Cancelled if the callback returned False (the result of an operation that ran on is then discarded).
  void rethrow_if_any();

 private:
  bool call(std::size_t done);
  py::object callback_;
  std::string what_;
  std::size_t total_ = 0;
  std::optional<py::error_already_set> error_;
  std::exception_ptr cpp_error_;
  bool refused_ = false;  // the callback said stop: Cancelled, even from an operation that does not stop early  // a C++ exception from the callback's conversion (never let one cross C++ frames)
};

}  // namespace ff::python
