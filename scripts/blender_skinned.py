# What the Blender scripts that play a skinned file's clip share (blender_pose_export.py, blender_posed_volume.py):
# their "--key value" arguments after "--", importing the file with Blender's own importer, and choosing the action.
import sys

import bpy


def options():
    """The "--key value" pairs after "--" on Blender's command line, as a dict."""
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    return {args[i].lstrip("-"): args[i + 1] for i in range(0, len(args) - 1, 2)}


def import_file(path, script):
    """An empty scene with `path` (glTF/GLB or FBX) imported by Blender's importer; `script` names the caller in errors."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.lower().endswith((".glb", ".gltf")):
        bpy.ops.import_scene.gltf(filepath=path, import_shading='SMOOTH')  # SMOOTH: Debian's numpy (see the README)
    elif path.lower().endswith(".fbx"):
        bpy.ops.import_scene.fbx(filepath=path)
    else:
        raise SystemExit(f"{script}: {path}: only glTF/GLB and FBX are imported here")


def choose_action(want, script):
    """The action named `want` (or `want` with the importer's "_ARMATURE" suffix, or else the first, by name, that
    starts with it: rigged.glb may hold both "NAME" and "NAME pingpong"), or the first of all when `want` is empty."""
    actions = sorted(bpy.data.actions, key=lambda a: a.name)
    chosen = None
    if want:
        for test in (lambda n: n == want, lambda n: n.startswith(want + "_"), lambda n: n.startswith(want)):
            chosen = next((a for a in actions if test(a.name)), None)
            if chosen is not None:
                break
    elif actions:
        chosen = actions[0]
    if chosen is None:
        raise SystemExit(f"{script}: no action '{want}' among {[a.name for a in actions]}")
    return chosen


def play(action):
    """Every armature plays `action`."""
    for o in bpy.data.objects:
        if o.type == 'ARMATURE':
            o.animation_data_create()
            o.animation_data.action = action
