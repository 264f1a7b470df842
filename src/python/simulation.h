#pragma once
// fluidform.Simulation: a scene stepped one frame at a time from Python (pipeline::LiveScene, the live viewer's
// stepper, which sets a scene up exactly as `fluidform run` does).
#include <pybind11/pybind11.h>

namespace ff::python {

void bind_simulation(pybind11::module_& m);

}  // namespace ff::python
