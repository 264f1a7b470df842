# Opens GLBs with vertex colours or a texture (a liquid with its target's look, `appearance` tint or target) in Blender the way an
# artist does, and reports what came in as one JSON line prefixed "FLUIDFORM_COLOUR ": per mesh object, its colour
# attributes, the mean of the first one (linear RGB, as Blender stores COLOR_0) and whether its material's shader
# reads that attribute (a Color Attribute / Vertex Color node wired in), its UV layers and the size of the image a
# wired Image Texture node shows (a liquid in its target's texture). One line per file. Run headless (Debian's 3.4):
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P scripts/blender_colour_check.py -- --glb A.glb [--glb B.obj …]
import json
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
files = [args[i + 1] for i, a in enumerate(args) if a == "--glb"]


def look_of(glb):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if glb.lower().endswith(".obj"):  # an OBJ with its MTL (map_Kd: the texture beside it)
        bpy.ops.wm.obj_import(filepath=glb)
    else:
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
        image = None  # the size of the image a linked Image Texture node shows
        for slot in obj.material_slots:
            mat = slot.material
            if mat and mat.use_nodes:
                for node in mat.node_tree.nodes:
                    linked = any(o.is_linked for o in node.outputs)
                    if node.bl_idname in ("ShaderNodeVertexColor", "ShaderNodeAttribute") and linked:
                        reads = True
                    if node.bl_idname == "ShaderNodeTexImage" and linked and node.image:
                        image = list(node.image.size)
        meshes.append({"name": obj.name, "vertices": len(me.vertices), "colour_attributes": attrs, "mean": mean,
                       "material_reads_colours": reads, "uv_layers": len(me.uv_layers), "image": image})
    return {"file": glb, "meshes": meshes}


for glb in files:
    print("FLUIDFORM_COLOUR " + json.dumps(look_of(glb)))
