# Opens fluidform's exports in Blender the way an artist does and reports what happened, as one JSON line
# prefixed "FLUIDFORM_CHECK ". Run headless (Debian's blender 3.4; put /usr/bin first on PATH so that its bundled
# Python is not confused by another python3):
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P scripts/blender_check.py -- \
#       [--obj MESH.obj] [--glb ANIMATION.glb] [--points FRAME0.ply --pc2 CACHE.pc2]
# --obj: imports the mesh, builds a three-bone armature along its height and parents the mesh to it with
#        automatic weights (Bone Heat); reports the operator's warnings and how many vertices got no weight.
# --glb: imports the animation (import_shading='SMOOTH': the default path hits a numpy bug in Debian's build)
#        and reports meshes and actions.
# --points/--pc2: imports the frame-0 point mesh, plays the cache with the Mesh Cache modifier and reports the
#        largest difference between the evaluated points and the cache's last frame.
# --vdb: imports a `--vdb` level set as a volume object (turned upright: fluidform's files are Y-up like Houdini, the
#        object's 90° about x puts them in Blender's Z-up as the OBJ and glTF importers do), reports its grids, and
#        meshes it with the Volume to Mesh modifier at the zero level: faces and world bounds.
import json
import struct
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
opt = {}
for i in range(0, len(args) - 1, 2):
    opt[args[i].lstrip("-")] = args[i + 1]
out = {}


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def check_obj(path):
    reset()
    before = set(bpy.data.objects)
    bpy.ops.wm.obj_import(filepath=path)
    meshes = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    res = {"objects": len(meshes)}
    if not meshes:
        return res
    mesh = meshes[0]
    res["material"] = principled(mesh.active_material)
    res["vertices"] = len(mesh.data.vertices)
    res["faces"] = len(mesh.data.polygons)
    # World-space bounds (the importer turns Y-up into Blender's Z-up).
    co = [mesh.matrix_world @ v.co for v in mesh.data.vertices]
    lo = [min(c[a] for c in co) for a in range(3)]
    hi = [max(c[a] for c in co) for a in range(3)]
    res["bounds"] = [lo, hi]
    # A simple spine: three bones from the bottom to the top of the mesh, through the centre of its box.
    cx, cy = 0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])
    bpy.ops.object.armature_add(enter_editmode=True, location=(0, 0, 0))
    arm = bpy.context.object
    bones = arm.data.edit_bones
    first = bones[0]
    height = hi[2] - lo[2]
    prev = None
    for k in range(3):
        b = first if k == 0 else bones.new(f"bone{k}")
        b.head = (cx, cy, lo[2] + 0.05 * height + k * 0.3 * height)
        b.tail = (cx, cy, lo[2] + 0.05 * height + (k + 1) * 0.3 * height)
        if prev is not None:
            b.parent = prev
            b.use_connect = True
        prev = b
    bpy.ops.object.mode_set(mode="OBJECT")
    bpy.ops.object.select_all(action="DESELECT")
    mesh.select_set(True)
    arm.select_set(True)
    bpy.context.view_layer.objects.active = arm
    result = bpy.ops.object.parent_set(type="ARMATURE_AUTO")
    res["parent_result"] = sorted(result)
    weighted = 0
    for v in mesh.data.vertices:
        if any(g.weight > 0.0 for g in v.groups):
            weighted += 1
    res["weighted_vertices"] = weighted
    res["unweighted_vertices"] = len(mesh.data.vertices) - weighted
    res["vertex_groups"] = len(mesh.vertex_groups)
    return res


def principled(mat):
    """The material's Principled BSDF inputs that make it water (None when it has none)."""
    if mat is None or not mat.use_nodes:
        return None
    for node in mat.node_tree.nodes:
        if node.type == "BSDF_PRINCIPLED":
            return {"name": mat.name, "transmission": node.inputs["Transmission"].default_value,
                    "ior": node.inputs["IOR"].default_value, "roughness": node.inputs["Roughness"].default_value}
    return None


def check_glb(path):
    reset()
    bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    return {
        "meshes": len(meshes),
        "actions": len(bpy.data.actions),
        "frame_range": [list(a.frame_range) for a in bpy.data.actions][:1],
        "material": principled(meshes[-1].active_material) if meshes else None,
    }


def check_pc2(points, cache):
    reset()
    before = set(bpy.data.objects)
    bpy.ops.import_mesh.ply(filepath=points)
    objs = [o for o in bpy.data.objects if o not in before]
    if not objs:
        return {"objects": 0}
    obj = objs[0]
    with open(cache, "rb") as f:
        head = f.read(32)
        _version, npts, start, _rate, samples = struct.unpack("<iiffi", head[12:32])
        f.seek(32 + (samples - 1) * npts * 12)
        last = struct.unpack(f"<{3 * npts}f", f.read(12 * npts))
    mod = obj.modifiers.new("cache", "MESH_CACHE")
    mod.cache_format = "PC2"
    mod.filepath = cache
    # The cache is Y-up (glTF's and fluidform's convention): the modifier turns it into Blender's Z-up, as the
    # OBJ and glTF importers do, so the played points stand upright: (x, y, z) → (x, −z, y). (Measured on Blender
    # 3.4: this modifier's axis pair that gives that map is forward +Z, up −Y.)
    mod.forward_axis = "POS_Z"
    mod.up_axis = "NEG_Y"
    scene = bpy.context.scene
    scene.frame_set(int(start) + samples - 1)
    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg).to_mesh()
    worst = 0.0
    for i, v in enumerate(ev.vertices):
        x, y, z = last[3 * i], last[3 * i + 1], last[3 * i + 2]
        worst = max(worst, abs(v.co[0] - x), abs(v.co[1] + z), abs(v.co[2] - y))
    return {"objects": 1, "points": len(obj.data.vertices), "cache_points": npts, "samples": samples,
            "max_difference_last_frame": worst}


def check_vdb(path):
    reset()
    bpy.ops.object.volume_import(filepath=path, align="WORLD", location=(0, 0, 0))
    vol = bpy.context.object
    if vol is None or vol.type != "VOLUME":
        return {"objects": 0}
    vol.rotation_euler = (1.5707963267948966, 0.0, 0.0)
    grids = vol.data.grids
    loaded = grids.load()
    res = {"objects": 1, "loaded": bool(loaded), "grids": [g.name for g in grids],
           "types": [g.data_type for g in grids], "error": grids.error_message or None}
    if not res["error"]:
        res.pop("error")
    # The level set back to a mesh in Blender: an empty mesh object with Volume to Mesh at the zero crossing.
    me = bpy.data.meshes.new("vdb_mesh")
    obj = bpy.data.objects.new("vdb_mesh", me)
    bpy.context.scene.collection.objects.link(obj)
    obj.rotation_euler = vol.rotation_euler
    mod = obj.modifiers.new("to_mesh", "VOLUME_TO_MESH")
    mod.object = vol
    mod.grid_name = grids[0].name if len(grids) else ""
    mod.threshold = 0.0
    mod.resolution_mode = "GRID"
    bpy.context.view_layer.update()
    dg = bpy.context.evaluated_depsgraph_get()
    ev_obj = obj.evaluated_get(dg)
    ev = ev_obj.to_mesh()
    res["faces"] = len(ev.polygons)
    if len(ev.vertices):
        co = [ev_obj.matrix_world @ v.co for v in ev.vertices]
        res["bounds"] = [[min(c[a] for c in co) for a in range(3)], [max(c[a] for c in co) for a in range(3)]]
    ev_obj.to_mesh_clear()
    return res


try:
    if "vdb" in opt:
        out["vdb"] = check_vdb(opt["vdb"])
    if "obj" in opt:
        out["obj"] = check_obj(opt["obj"])
    if "glb" in opt:
        out["glb"] = check_glb(opt["glb"])
    if "points" in opt and "pc2" in opt:
        out["pc2"] = check_pc2(opt["points"], opt["pc2"])
except Exception as e:  # reported, and the exit code says it failed
    out["error"] = f"{type(e).__name__}: {e}"
print("FLUIDFORM_CHECK " + json.dumps(out), flush=True)
sys.exit(1 if "error" in out else 0)
