# A finished run → Blender, all in one step: a collection "Fluid Form: NAME" holding
#   Points    the particles as a point mesh (particles_frame0.ply) played by a Mesh Cache modifier
#             (particles.pc2), drawn as small spheres by a Geometry Nodes modifier;
#   Sequence  the meshed forming (animation.glb: one mesh per meshed frame, each shown for its frames);
#   Final     the editable final mesh (mesh/final.obj), hidden at first since the sequence ends on the same shape;
# with one water material, and the scene's frame range set to the run. Anything that fails on the way removes
# every datablock the import had created, so a failure leaves nothing half-imported.
import json
import os
import re
import struct

import bpy
import numpy as np

from .targets import RESULT_TAG

# Data collections an import may add to (diffed before/after to undo a failed import).
_DATA = ("objects", "meshes", "materials", "actions", "collections", "node_groups", "images", "textures",
         "cameras", "lights")


def _snapshot():
    return {k: set(getattr(bpy.data, k)[:]) for k in _DATA}


def _remove_new(before):
    """Removes every datablock not in the snapshot `before` (objects first, then their data)."""
    for k in _DATA:
        coll = getattr(bpy.data, k)
        for idb in [i for i in coll[:] if i not in before[k]]:
            try:
                coll.remove(idb)
            except (ReferenceError, RuntimeError):
                pass


def read_point_ply(path):
    """The vertices (n×3 float32) of a binary little-endian PLY point mesh (fluidform's particles_frame0.ply)."""
    types = {"float": "f4", "float32": "f4", "double": "f8", "float64": "f8", "uchar": "u1", "uint8": "u1",
             "char": "i1", "int8": "i1", "short": "i2", "ushort": "u2", "int": "i4", "int32": "i4", "uint": "u4"}
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            raise ValueError(f"{path}: not a PLY file")
        fmt, count, props, in_vertex = None, 0, [], False
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: no end_header")
            words = line.decode("ascii", "replace").split()
            if not words or words[0] == "comment":
                continue
            if words[0] == "format":
                fmt = words[1]
            elif words[0] == "element":
                in_vertex = words[1] == "vertex"
                if in_vertex:
                    count = int(words[2])
            elif words[0] == "property" and in_vertex:
                props.append((words[2], "<" + types[words[1]]))
            elif words[0] == "end_header":
                break
        if fmt != "binary_little_endian":
            raise ValueError(f"{path}: format {fmt} (binary_little_endian expected)")
        data = np.frombuffer(f.read(count * np.dtype(props).itemsize), dtype=np.dtype(props), count=count)
    return np.stack([data["x"], data["y"], data["z"]], axis=1).astype(np.float32)


def read_pc2_header(path):
    with open(path, "rb") as f:
        head = f.read(32)
    if len(head) < 32 or not head.startswith(b"POINTCACHE2"):
        raise ValueError(f"{path}: not a PC2 point cache")
    _version, points, start, rate, samples = struct.unpack("<iiffi", head[12:32])
    return {"points": points, "start": start, "rate": rate, "samples": samples}


def read_mtl(path):
    """Kd, Ni of the first material of an MTL file (defaults when absent)."""
    kd, ni = (0.16, 0.48, 0.85), 1.33
    try:
        with open(path, encoding="utf-8") as f:
            for line in f:
                w = line.split()
                if len(w) >= 4 and w[0] == "Kd":
                    kd = tuple(float(c) for c in w[1:4])
                elif len(w) >= 2 and w[0] == "Ni":
                    ni = float(w[1])
    except OSError:
        pass
    return kd, ni


def water_material(name, tint, ior, attenuation_distance=0.78):
    """Principled BSDF water: transmission 1, the given IOR, roughness 0.05, and an absorbing volume of the tint
    (glTF's KHR_materials_volume as fluidform writes it: the colour light has after `attenuation_distance` m)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = next(n for n in nodes if n.type == "BSDF_PRINCIPLED")
    out = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
    bsdf.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bsdf.inputs["Metallic"].default_value = 0.0
    bsdf.inputs["Roughness"].default_value = 0.05
    bsdf.inputs["Transmission"].default_value = 1.0
    bsdf.inputs["IOR"].default_value = ior
    vol = nodes.new("ShaderNodeVolumeAbsorption")
    vol.location = (bsdf.location[0], bsdf.location[1] - 420)
    vol.inputs["Color"].default_value = (*tint, 1.0)
    vol.inputs["Density"].default_value = 1.0 / max(attenuation_distance, 1e-3)
    links.new(vol.outputs["Volume"], out.inputs["Volume"])
    # EEVEE: refraction through the screen-space pass (scene Render → Screen Space Reflections → Refraction).
    mat.use_screen_refraction = True
    mat.blend_method = "BLEND"
    mat.show_transparent_back = False
    mat.diffuse_color = (*tint, 0.5)  # the solid viewport's colour
    mat[RESULT_TAG] = True
    return mat


def particle_material(name, tint):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = (*tint, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.25
    bsdf.inputs["Specular"].default_value = 0.6
    mat.diffuse_color = (*tint, 1.0)
    mat[RESULT_TAG] = True
    return mat


def sphere_nodes(name, radius, material):
    """Geometry Nodes: an ico sphere of `radius` on every point (renders in EEVEE, Cycles and Workbench)."""
    ng = bpy.data.node_groups.new(name, "GeometryNodeTree")
    ng.inputs.new("NodeSocketGeometry", "Geometry")
    ng.outputs.new("NodeSocketGeometry", "Geometry")
    gin, gout = ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")
    ico = ng.nodes.new("GeometryNodeMeshIcoSphere")
    ico.inputs["Radius"].default_value = radius
    ico.inputs["Subdivisions"].default_value = 1
    smooth = ng.nodes.new("GeometryNodeSetShadeSmooth")
    setmat = ng.nodes.new("GeometryNodeSetMaterial")
    setmat.inputs["Material"].default_value = material
    inst = ng.nodes.new("GeometryNodeInstanceOnPoints")
    for k, n in enumerate((gin, ico, smooth, setmat, inst, gout)):
        n.location = (200 * k - 400, 0)
    ng.links.new(ico.outputs["Mesh"], smooth.inputs["Geometry"])
    ng.links.new(smooth.outputs["Geometry"], setmat.inputs["Geometry"])
    ng.links.new(gin.outputs["Geometry"], inst.inputs["Points"])
    ng.links.new(setmat.outputs["Geometry"], inst.inputs["Instance"])
    ng.links.new(inst.outputs["Instances"], gout.inputs["Geometry"])
    ng[RESULT_TAG] = True
    return ng


def _layer_collection(layer, coll):
    if layer.collection == coll:
        return layer
    for child in layer.children:
        found = _layer_collection(child, coll)
        if found is not None:
            return found
    return None


def _move_to(objs, coll):
    for o in objs:
        for c in list(o.users_collection):
            c.objects.unlink(o)
        coll.objects.link(o)


def _path_for_blend(path):
    """`path` relative to the saved .blend (//...) when it lies below its folder, else absolute."""
    if bpy.data.filepath:
        try:
            rel = bpy.path.relpath(path)
            if not rel.startswith("//.."):
                return rel
        except ValueError:
            pass
    return path


def import_run(context, out_dir, name, start_frame, fps, particle_radius=None):
    """Imports the run in `out_dir` (see the top of this file). Returns the collection; raises (having removed
    everything it created) on failure."""
    scene = context.scene
    view_layer = context.view_layer
    paths = {
        "points": os.path.join(out_dir, "particles_frame0.ply"),
        "pc2": os.path.join(out_dir, "particles.pc2"),
        "glb": os.path.join(out_dir, "animation.glb"),
        "final": os.path.join(out_dir, "mesh", "final.obj"),
        "mtl": os.path.join(out_dir, "mesh", "water.mtl"),
        "report": os.path.join(out_dir, "report.json"),
    }
    for k in ("points", "pc2", "glb", "final"):
        if not os.path.isfile(paths[k]):
            raise RuntimeError(f"the run left no {os.path.relpath(paths[k], out_dir)}")
    report = {}
    if os.path.isfile(paths["report"]):
        with open(paths["report"], encoding="utf-8") as f:
            report = json.load(f)
    if particle_radius is None:
        particle_radius = report.get("scene", {}).get("solver", {}).get("particle_radius", 0.01)
    cache = read_pc2_header(paths["pc2"])
    last_frame = cache["samples"] - 1

    before = _snapshot()
    kept = {
        "frame_range": (scene.frame_start, scene.frame_end),
        "engine": scene.render.engine,
        "active_layer": view_layer.active_layer_collection,
        "selected": [o for o in context.selected_objects],
        "active": view_layer.objects.active,
    }
    try:
        top = bpy.data.collections.new(f"Fluid Form: {name}")
        scene.collection.children.link(top)
        sub = {}
        for part in ("Points", "Sequence", "Final"):
            sub[part] = bpy.data.collections.new(f"{name} {part.lower()}")
            top.children.link(sub[part])
        for c in [top, *sub.values()]:
            c[RESULT_TAG] = name
        kd, ior = read_mtl(paths["mtl"])
        water = water_material(f"{name} water", kd, ior)
        drops = particle_material(f"{name} particles", kd)

        # Points: the frame-0 point mesh, played by the cache (Y-up → Z-up in the modifier, as scripts/blender_check.py).
        pts = read_point_ply(paths["points"])
        if len(pts) != cache["points"]:
            raise RuntimeError(f"particles_frame0.ply has {len(pts)} points, particles.pc2 {cache['points']}")
        mesh = bpy.data.meshes.new(f"{name} points")
        mesh.vertices.add(len(pts))
        mesh.vertices.foreach_set("co", pts.reshape(-1))
        mesh.update()
        points = bpy.data.objects.new(f"{name} points", mesh)
        sub["Points"].objects.link(points)
        mc = points.modifiers.new("Fluid Form cache", "MESH_CACHE")
        mc.cache_format = "PC2"
        mc.filepath = _path_for_blend(paths["pc2"])
        mc.forward_axis, mc.up_axis = "POS_Z", "NEG_Y"  # (x, y, z) → (x, −z, y)
        mc.frame_start = float(start_frame)
        gn = points.modifiers.new("Fluid Form spheres", "NODES")
        gn.node_group = sphere_nodes(f"{name} spheres", float(particle_radius), drops)
        points.hide_render = True  # the sequence is what renders; the points are for the viewport (and your nodes)

        # Sequence: the glTF importer puts every object into the scene's collection; move them into ours.
        objs_before = set(bpy.data.objects[:])
        r = bpy.ops.import_scene.gltf(filepath=paths["glb"], import_shading="SMOOTH")
        if "FINISHED" not in r:
            raise RuntimeError("Blender's glTF importer could not read animation.glb")
        seq = [o for o in bpy.data.objects[:] if o not in objs_before]
        _move_to(seq, sub["Sequence"])
        # Retime the frames to the Blender frames of the run: the importer put time t at frame t·render.fps;
        # the run's frame k (t = k / fps) belongs on start_frame + k.
        for o in seq:
            o[RESULT_TAG] = name
            if o.parent is None and o.type == "EMPTY":
                o.name = f"{name} sequence"
            m = re.fullmatch(r"frame_(\d+)(_mesh)?(\.\d+)?", o.name)
            if m:
                o.name = f"{name} frame {int(m.group(1)):03d}" + (" mesh" if m.group(2) else "")
            if o.type == "MESH":
                o.data.materials.clear()
                o.data.materials.append(water)
            ad = o.animation_data
            if ad is not None and ad.action is not None:
                ad.action.name = f"{name} {o.name}"
                for fc in ad.action.fcurves:
                    for kp in fc.keyframe_points:
                        for pt in (kp.co, kp.handle_left, kp.handle_right):
                            pt[0] = start_frame + pt[0] / scene.render.fps * fps
                    fc.update()
        if not any(o.type == "MESH" for o in seq):
            raise RuntimeError("animation.glb held no meshes")

        # Final: the editable mesh of the last frame with the water material.
        objs_before = set(bpy.data.objects[:])
        view_layer.active_layer_collection = _layer_collection(view_layer.layer_collection, sub["Final"])
        r = bpy.ops.wm.obj_import(filepath=paths["final"])
        if "FINISHED" not in r:
            raise RuntimeError("Blender's OBJ importer could not read mesh/final.obj")
        finals = [o for o in bpy.data.objects[:] if o not in objs_before and o.type == "MESH"]
        if len(finals) != 1:
            raise RuntimeError(f"mesh/final.obj gave {len(finals)} objects (one expected)")
        final = finals[0]
        _move_to([final], sub["Final"])
        final.name = f"{name} final"
        final.data.name = f"{name} final"
        final.data.materials.clear()
        final.data.materials.append(water)
        final[RESULT_TAG] = name
        points[RESULT_TAG] = name
        final.hide_render = True
        final.hide_set(True)

        # Materials the importers made and nothing uses any more.
        for mat in [m for m in bpy.data.materials[:] if m not in before["materials"]]:
            if mat.users == 0:
                bpy.data.materials.remove(mat)

        scene.frame_start = start_frame
        scene.frame_end = start_frame + last_frame
        scene.render.engine = kept["engine"]  # the glTF importer switches Workbench to EEVEE
        # The selection as it was (the targets stay selected for another Form).
        for o in context.selected_objects:
            o.select_set(False)
        for o in kept["selected"]:
            o.select_set(True)
        view_layer.objects.active = kept["active"]
        view_layer.active_layer_collection = kept["active_layer"]
        top["fluidform_frames"] = cache["samples"]
        top["fluidform_output"] = out_dir
        return top
    except BaseException:
        _remove_new(before)
        scene.frame_start, scene.frame_end = kept["frame_range"]
        scene.render.engine = kept["engine"]
        try:
            view_layer.active_layer_collection = kept["active_layer"]
            view_layer.objects.active = kept["active"]
        except (ReferenceError, RuntimeError, TypeError):
            pass
        raise
