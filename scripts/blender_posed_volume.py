# The enclosed volume of a skinned file's mesh as Blender poses it (its importer, its Armature modifier), at evenly
# spaced frames of one action: how much of its bind volume linear blend skinning keeps. Independent of fluidform.
# Headless:
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P scripts/blender_posed_volume.py -- \
#       --file FILE [--action NAME-PREFIX] [--steps 10]
# Prints "bind V" and, per frame, "frame F V (P % of bind)", in Blender's units (the importer's scale).
import sys

import bmesh
import bpy

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
opt = {}
for i in range(0, len(args) - 1, 2):
    opt[args[i].lstrip("-")] = args[i + 1]
path = opt["file"]
steps = int(opt.get("steps", "10"))
bpy.ops.wm.read_factory_settings(use_empty=True)
if path.lower().endswith((".glb", ".gltf")):
    bpy.ops.import_scene.gltf(filepath=path, import_shading='SMOOTH')
elif path.lower().endswith(".fbx"):
    bpy.ops.import_scene.fbx(filepath=path)
else:
    raise SystemExit(f"blender_posed_volume: {path}: only glTF/GLB and FBX are imported here")
scene = bpy.context.scene
actions = sorted(bpy.data.actions, key=lambda a: a.name)
want = opt.get("action", "")
chosen = next((a for a in actions if a.name.startswith(want)), None) if want else (actions[0] if actions else None)
if chosen is None:
    raise SystemExit(f"blender_posed_volume: no action '{want}' among {[a.name for a in actions]}")
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
for o in bpy.data.objects:
    if o.type == 'ARMATURE':
        o.animation_data_create()
        o.animation_data.action = chosen
lo, hi = chosen.frame_range
for k in range(steps + 1):
    f = lo + (hi - lo) * k / steps
    scene.frame_set(int(f), subframe=f - int(f))
    v = volume(meshes, True)
    print(f"frame {f:.2f} {v:.6g} ({100 * v / bind:.1f} % of bind)")
