# Opens a rigged GLB (io/write_rigged_glb.h, `rigged.glb`) in Blender the way an artist does and reports what came
# in, as one JSON line prefixed "FLUIDFORM_RIG ": armatures and their bones, the actions, the mesh and its Armature
# modifier, and, playing one clip, the evaluated (deformed) mesh's world bounds at the given times, in glTF's Y-up
# axes (the importer turns Y-up into Blender's Z-up: (x, y, z) → (x, −z, y); this maps back). Times become frames as
# the importer places keys: frame = t · scene fps. Run headless (Debian's blender 3.4, /usr/bin first on PATH):
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P scripts/blender_rig_check.py -- \
#       --glb RIGGED.glb [--clip NAME] [--times T1,T2,...]
import json
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
opt = {}
for i in range(0, len(args) - 1, 2):
    opt[args[i].lstrip("-")] = args[i + 1]
out = {}


def bounds_yup(obj):
    dg = bpy.context.evaluated_depsgraph_get()
    ev_obj = obj.evaluated_get(dg)
    ev = ev_obj.to_mesh()
    co = [ev_obj.matrix_world @ v.co for v in ev.vertices]
    ev_obj.to_mesh_clear()
    if not co:
        return None
    pts = [(c[0], c[2], -c[1]) for c in co]
    return [[min(p[a] for p in pts) for a in range(3)], [max(p[a] for p in pts) for a in range(3)]]


def check(path, clip, times):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")
    arms = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    res = {
        "armatures": len(arms),
        "bones": [len(a.data.bones) for a in arms],
        "bone_names": [b.name for a in arms for b in a.data.bones],
        "actions": [{"name": a.name, "frame_range": list(a.frame_range), "fcurves": len(a.fcurves)}
                    for a in bpy.data.actions],
        "meshes": len(meshes),
        "fps": bpy.context.scene.render.fps,
    }
    skinned = [m for m in meshes if any(md.type == "ARMATURE" and md.object is not None for md in m.modifiers)]
    res["skinned_meshes"] = len(skinned)
    if skinned:
        mesh = skinned[0]
        res["vertices"] = len(mesh.data.vertices)
        res["vertex_groups"] = len(mesh.vertex_groups)
    if not arms or not skinned:
        return res
    arm = next(md.object for md in skinned[0].modifiers if md.type == "ARMATURE")
    # The clip: the action named as it (the importer may append the armature's name), made the armature's active
    # action, with any NLA strips muted so that only it plays.
    # An exact name wins over the importer's suffixed one, which wins over a bare prefix: rigged.glb may hold both
    # "NAME" and "NAME pingpong" (the clip baked back and forth), and a bare prefix matches both.
    action = None
    for test in ((lambda n: True) if clip is None else (lambda n: n == clip),
                 lambda n: n.startswith(clip + "_"), lambda n: n.startswith(clip)):
        action = next((a for a in bpy.data.actions if test(a.name)), None)
        if action is not None or clip is None:
            break
    res["played"] = action.name if action else None
    if action is None:
        return res
    ad = arm.animation_data or arm.animation_data_create()
    for track in ad.nla_tracks:
        track.mute = True
    ad.action = action
    fps = bpy.context.scene.render.fps / bpy.context.scene.render.fps_base
    poses = []
    for t in times:
        f = t * fps
        bpy.context.scene.frame_set(int(f), subframe=f - int(f))
        b = bounds_yup(skinned[0])
        poses.append({"t": t, "frame": f, "min": b[0] if b else None, "max": b[1] if b else None})
    res["poses"] = poses
    return res


try:
    times = [float(s) for s in opt.get("times", "").split(",") if s]
    out = check(opt["glb"], opt.get("clip"), times)
except Exception as e:  # reported, and the exit code says it failed
    out["error"] = f"{type(e).__name__}: {e}"
print("FLUIDFORM_RIG " + json.dumps(out), flush=True)
sys.exit(1 if "error" in out else 0)
