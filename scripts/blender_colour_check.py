# Opens a GLB with vertex colours (a liquid with its target's look, `appearance` tint or target) in Blender the way an
# artist does, and reports what came in as one JSON line prefixed "FLUIDFORM_COLOUR ": per mesh object, its colour
# attributes, the mean of the first one (linear RGB, as Blender stores COLOR_0) and whether its material's shader
# reads that attribute (a Color Attribute / Vertex Color node wired in). Run headless (Debian's blender 3.4):
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P scripts/blender_colour_check.py -- --glb FILE.glb
import json
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
glb = args[args.index("--glb") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
# Shading "SMOOTH": Blender 3.4's default path calls numpy.bool, which Debian's numpy no longer has.
bpy.ops.import_scene.gltf(filepath=glb, import_shading="SMOOTH")

meshes = []
for obj in bpy.data.objects:
    if obj.type != "MESH":
        continue
    me = obj.data
    attrs = [a.name for a in me.color_attributes]
    mean = None
    if me.color_attributes:
        a = me.color_attributes[0]
        n = len(a.data)
        if n:
            mean = [sum(d.color[c] for d in a.data) / n for c in range(3)]
    reads = False
    for slot in obj.material_slots:
        mat = slot.material
        if mat and mat.use_nodes:
            for node in mat.node_tree.nodes:
                if node.bl_idname in ("ShaderNodeVertexColor", "ShaderNodeAttribute") and any(o.is_linked for o in node.outputs):
                    reads = True
    meshes.append({"name": obj.name, "vertices": len(me.vertices), "colour_attributes": attrs, "mean": mean,
                   "material_reads_colours": reads})
print("FLUIDFORM_COLOUR " + json.dumps({"meshes": meshes}))
