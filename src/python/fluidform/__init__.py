"""fluidform: editable mesh animations from controllable particles.

The C++ pipeline of the `fluidform` CLI as a Python module (NumPy arrays in and out):

    import fluidform as ff
    positions, weights = ff.sample("bunny.obj", count=5000)        # a target's control samples
    summary = ff.run("scene.json", out="out", progress=print)      # `fluidform run`
    sim = ff.Simulation({"targets": [{"mesh": "bunny.obj"}]})      # step it yourself
    sim.step(10); sim.positions                                    # (N, 3) view, no copy
    vertices, faces = ff.reconstruct(sim.positions)                # a closed mesh
    ff.measure(sim.positions, "bunny.obj")["error_rate"]            # METHOD §d metrics

Errors raise fluidform.Error subclasses (InputError and ParamError are ValueErrors, IoError an OSError) with the
CLI's one-line messages.
"""
from ._fluidform import (  # noqa: F401
    Cancelled,
    Error,
    InputError,
    IoError,
    NumericalError,
    ParamError,
    Samples,
    Simulation,
    __version__,
    measure,
    reconstruct,
    run,
    sample,
    set_log_level,
)

__all__ = [
    "Cancelled", "Error", "InputError", "IoError", "NumericalError", "ParamError", "Samples", "Simulation",
    "measure", "reconstruct", "run", "sample", "set_log_level",
]
