# Poses a skinned mesh file the way Blender does (its importer, its Armature modifier), independently of fluidform's
# io/skin: imports FILE (glTF/GLB or FBX), plays one action, and at each given time writes the evaluated (deformed)
# mesh of every mesh object, in world space, as one OBJ in the file's Y-up axes (Blender's Z-up mapped back), OUT_i.obj.
# Times become frames as the importers place keys: frame = t · scene fps (fractional frames as subframes). Headless:
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P scripts/blender_pose_export.py -- \
#       --file FILE --out PREFIX [--action NAME-PREFIX] --times T1,T2,...
# Prints one line "FLUIDFORM_POSE {json}": the action played, the fps, and the OBJ files written.
import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_skinned  # noqa: E402  (beside this script)

opt = blender_skinned.options()
path, prefix = opt["file"], opt["out"]
times = [float(t) for t in opt["times"].split(",")]
blender_skinned.import_file(path, "blender_pose_export")
scene = bpy.context.scene
chosen = blender_skinned.choose_action(opt.get("action", ""), "blender_pose_export")
blender_skinned.play(chosen)
meshes = [o for o in bpy.data.objects if o.type == 'MESH']
written = []
for i, t in enumerate(times):
    f = t * scene.render.fps
    scene.frame_set(int(f), subframe=f - int(f))
    dg = bpy.context.evaluated_depsgraph_get()
    lines, base = [], 1
    for o in meshes:
        ev = o.evaluated_get(dg)
        m = ev.to_mesh()
        for v in m.vertices:
            w = ev.matrix_world @ v.co
            lines.append(f"v {w.x:.7g} {w.z:.7g} {-w.y:.7g}")  # Z-up → Y-up: (x, y, z) ← (x, z, −y)
        for p in m.polygons:
            idx = list(p.vertices)
            for k in range(1, len(idx) - 1):  # fan-triangulate
                lines.append(f"f {idx[0] + base} {idx[k] + base} {idx[k + 1] + base}")
        base += len(m.vertices)
        ev.to_mesh_clear()
    out = f"{prefix}_{i}.obj"
    with open(out, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    written.append(out)
print("FLUIDFORM_POSE " + json.dumps({"action": chosen.name, "fps": scene.render.fps, "files": written}))
