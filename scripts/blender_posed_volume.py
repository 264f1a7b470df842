# The enclosed volume of a skinned file's mesh as Blender poses it (its importer, its Armature modifier), at evenly
# spaced frames of one action: how much of its bind volume linear blend skinning keeps. Independent of fluidform.
# Headless:
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P scripts/blender_posed_volume.py -- \
#       --file FILE [--action NAME-PREFIX] [--steps 10]
# Prints "bind V" and, per frame, "frame F V (P % of bind)", in Blender's units (the importer's scale).
import os
import sys

import bmesh
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_skinned  # noqa: E402  (beside this script)

opt = blender_skinned.options()
path = opt["file"]
steps = int(opt.get("steps", "10"))
blender_skinned.import_file(path, "blender_posed_volume")
scene = bpy.context.scene
chosen = blender_skinned.choose_action(opt.get("action", ""), "blender_posed_volume")
meshes = [o for o in bpy.data.objects if o.type == 'MESH']


def volume(objects, evaluated):
    total = 0.0
    dg = bpy.context.evaluated_depsgraph_get()
    for o in objects:
        ob = o.evaluated_get(dg) if evaluated else o
        m = ob.to_mesh() if evaluated else o.data
        bm = bmesh.new()
        bm.from_mesh(m)
        bm.transform(ob.matrix_world)
        total += bm.calc_volume()
        bm.free()
        if evaluated:
            ob.to_mesh_clear()
    return total


bind = volume(meshes, False)
print(f"bind {bind:.6g}")
blender_skinned.play(chosen)
lo, hi = chosen.frame_range
for k in range(steps + 1):
    f = lo + (hi - lo) * k / steps
    scene.frame_set(int(f), subframe=f - int(f))
    v = volume(meshes, True)
    print(f"frame {f:.2f} {v:.6g} ({100 * v / bind:.1f} % of bind)")
