# Selected mesh objects → fluidform targets: each object's evaluated mesh (modifiers applied) at the start frame,
# in scene coordinates (Y up, metres), as an OBJ, and its keyframed transform as the target's keyframes.
import json
import os

import numpy as np

from . import motion

RESULT_TAG = "fluidform_result"  # custom property on everything a Form imported (never a target itself)


class TargetError(Exception):
    """A target that cannot be exported (said in one line)."""


def target_objects(context):
    """The mesh objects a Form uses: the selected ones (the active one first), or the active one alone; never
    objects a Form imported."""
    objs = [o for o in context.selected_objects if o.type == "MESH" and RESULT_TAG not in o]
    active = context.active_object
    if active is not None and active.type == "MESH" and RESULT_TAG not in active:
        if active in objs:
            objs.remove(active)
        objs.insert(0, active)
    return objs


def _animated(obj):
    """Whether the object (or one of its parents) has any animation or constraints: its pose is sampled per frame."""
    o = obj
    while o is not None:
        ad = o.animation_data
        if ad is not None and (ad.action is not None or len(ad.drivers) or len(ad.nla_tracks)):
            return True
        if len(o.constraints):
            return True
        o = o.parent
    return False


def _last_key_frame(obj):
    last = None
    o = obj
    while o is not None:
        ad = o.animation_data
        if ad is not None and ad.action is not None:
            end = ad.action.frame_range[1]
            last = end if last is None else max(last, end)
        o = o.parent
    return last


def _write_obj(path, vertices, triangles, name):
    with open(path, "w", encoding="utf-8") as f:
        f.write(f"# fluidform target from Blender object {name!r}; Y up, metres\no {name}\n")
        np.savetxt(f, vertices, fmt="v %.7g %.7g %.7g")
        np.savetxt(f, triangles + 1, fmt="f %d %d %d")


def _mesh_arrays(obj, depsgraph):
    """World-space (scene axes) vertices and triangles of the evaluated object."""
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        mesh.calc_loop_triangles()
        nv, nt = len(mesh.vertices), len(mesh.loop_triangles)
        if nv == 0 or nt == 0:
            raise TargetError(f"{obj.name}: the mesh has no faces (a target needs a surface)")
        co = np.empty(3 * nv, dtype=np.float64)
        mesh.vertices.foreach_get("co", co)
        tris = np.empty(3 * nt, dtype=np.int64)
        mesh.loop_triangles.foreach_get("vertices", tris)
    finally:
        ev.to_mesh_clear()
    co = co.reshape(nv, 3)
    m = np.array(motion.Z_UP_TO_Y_UP @ ev.matrix_world)
    world = co @ m[:3, :3].T + m[:3, 3]
    if not np.all(np.isfinite(world)):
        raise TargetError(f"{obj.name}: the mesh has vertices that are not finite")
    return world, tris.reshape(nt, 3)


def export_targets(context, objects, folder, start_frame, end_frame):
    """Writes one OBJ per object into `folder` and returns (scene "targets" list, warnings, last keyframe time in s
    or None). The scene frame is left where it was."""
    scene = context.scene
    fps = scene.render.fps / scene.render.fps_base
    frame_before = (scene.frame_current, scene.frame_subframe)
    targets, warnings = [], []
    last_key_time = None
    try:
        scene.frame_set(start_frame)
        depsgraph = context.evaluated_depsgraph_get()
        pivots = []
        for k, obj in enumerate(objects):
            vertices, tris = _mesh_arrays(obj, depsgraph)
            name = f"target_{k}.obj"
            _write_obj(os.path.join(folder, name), vertices, tris, obj.name)
            lo, hi = vertices.min(axis=0), vertices.max(axis=0)
            pivots.append(tuple(float(c) for c in 0.5 * (lo + hi)))  # fluidform's pivot: the rest box's centre
            targets.append({"mesh": name})
        # The poses of the moving targets, sampled at every frame from the start to their last keyframe (or the
        # run's end) and thinned to the keyframes linear interpolation needs.
        moving = [k for k, o in enumerate(objects) if _animated(o)]
        if moving:
            last = end_frame
            if last is None:
                ends = [_last_key_frame(objects[k]) for k in moving]
                ends = [e for e in ends if e is not None]
                last = int(max(ends)) if ends else start_frame
            frames = list(range(start_frame, max(last, start_frame) + 1))
            matrices = {k: [] for k in moving}
            for f in frames:
                scene.frame_set(f)
                for k in moving:
                    matrices[k].append(objects[k].matrix_world.copy())
            times = [(f - start_frame) / fps for f in frames]
            for k in moving:
                keys, warn = motion.keyframes(times, matrices[k], pivots[k])
                warnings += [f"{objects[k].name}: {w}" for w in warn]
                if keys:
                    targets[k]["keyframes"] = keys
                    t = keys[-1]["time"]
                    last_key_time = t if last_key_time is None else max(last_key_time, t)
    finally:
        scene.frame_set(frame_before[0], subframe=frame_before[1])
    return targets, warnings, last_key_time


def write_scene(path, targets, particle_count, fps):
    """The scene file: the targets and what the panel sets; fluidform completes the rest (spacing, fluid, domain)."""
    scene = {
        "targets": targets,
        "sampling": {"auto_count": int(particle_count)},
        "output": {"fps": fps},
    }
    with open(path, "w", encoding="utf-8") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")
    return scene
