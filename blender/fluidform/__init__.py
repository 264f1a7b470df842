# Fluid Form: fluid particles flow into the shape of the selected meshes (fluidform, run in the background).
# Properties → Object → Fluid Form: particle count, controller, duration, start frame; Form; Cancel (or Esc).
bl_info = {
    "name": "Fluid Form",
    "author": "fluidform",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Object > Fluid Form",
    "description": "Liquid that flows into the shape of the selected meshes (runs the fluidform CLI)",
    "category": "Physics",
}

if "bpy" in locals():  # F8 / reload: pick up edited modules
    import importlib

    for _m in (job, motion, targets, result, task, props, operators, ui):  # noqa: F821
        importlib.reload(_m)

import atexit

import bpy
from bpy.app.handlers import persistent

from . import job, motion, targets, result, task, props, operators, ui  # noqa: E401,F401

_modules = (props, operators, ui)


@persistent
def _on_load_pre(*_args):
    task.cancel_all()  # a run never outlives the file it was started from


def register():
    for m in _modules:
        m.register()
    bpy.app.handlers.load_pre.append(_on_load_pre)
    atexit.register(task.cancel_all)


def unregister():
    task.cancel_all()
    atexit.unregister(task.cancel_all)
    if _on_load_pre in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_on_load_pre)
    for m in reversed(_modules):
        m.unregister()
