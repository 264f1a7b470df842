# The Blender add-on (blender/fluidform), headless in Debian's Blender 3.4, as an artist would use it: installed
# from its zip, Form on the bunny and on a two-object scene (one object keyframed), a cancelled Form, and Forms that
# fail (in the CLI, and in the import). Run by tests/blender/run_addon_test.py:
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P tests/blender/addon_test.py -- \
#       --zip ADDON.zip --cli FLUIDFORM --bunny examples/bunny.obj --work TMPDIR
# Prints one JSON line "FLUIDFORM_ADDON_TEST {...}" (what it measured) and exits 0 when every check held, 1 when
# one failed (each failure is printed as "FAIL: ..."), 77 when Blender's Python lacks numpy (skipped).
import json
import math
import os
import struct
import sys
import time
import traceback

import bpy

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
opt = {args[i].lstrip("-"): args[i + 1] for i in range(0, len(args) - 1, 2)}
try:
    import numpy as np
    import bmesh
except ImportError as e:
    print(f"SKIP: Blender's Python cannot import numpy ({e}): install python3-numpy", flush=True)
    sys.exit(77)

failures = []
report = {}


def check(cond, what):
    if not cond:
        failures.append(what)
        print(f"FAIL: {what}", flush=True)
    return cond


def clear_scene():
    """An empty scene (read_factory_settings would also reset the preferences, and so unload the add-on)."""
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    for coll in (bpy.data.collections, bpy.data.meshes, bpy.data.materials, bpy.data.actions, bpy.data.node_groups):
        for idb in list(coll):
            coll.remove(idb)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 250
    scene.frame_set(1)


def data_ids():
    return {k: set(i.name for i in getattr(bpy.data, k)) for k in
            ("objects", "meshes", "materials", "actions", "collections", "node_groups")}


def glb_json(path):
    with open(path, "rb") as f:
        b = f.read()
    n = struct.unpack("<I", b[12:16])[0]
    return json.loads(b[20:20 + n])


def pc2(path):
    with open(path, "rb") as f:
        head = f.read(32)
        _v, n, _start, _rate, samples = struct.unpack("<iiffi", head[12:32])
        data = np.frombuffer(f.read(), dtype="<f4", count=samples * n * 3)
    return data.reshape(samples, n, 3)


def closed(obj):
    """Every edge of the mesh has exactly two faces."""
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    ok = len(bm.edges) > 0 and all(len(e.link_faces) == 2 for e in bm.edges)
    bm.free()
    return ok


def principled(mat):
    node = next((n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None) if mat and mat.use_nodes else None
    if node is None:
        return None
    return {k: node.inputs[k].default_value for k in ("Transmission", "IOR", "Roughness")}


def evaluated_points(obj, frame):
    bpy.context.scene.frame_set(frame)
    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    me = ev.to_mesh()
    co = np.empty(3 * len(me.vertices), dtype=np.float32)
    me.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    return co.reshape(-1, 3)


def visible_sequence_meshes(seq_objs, frame):
    bpy.context.scene.frame_set(frame)
    return [o.name for o in seq_objs if o.type == "MESH" and o.matrix_world.to_scale().length > 1e-6]


def groups_gone(pgid):
    for pid in os.listdir("/proc"):
        if pid.isdigit():
            try:
                with open(f"/proc/{pid}/stat") as f:
                    s = f.read()
            except OSError:
                continue
            fields = s[s.rindex(")") + 2:].split()
            if int(fields[2]) == pgid:
                return False
    return True


def check_result(tag, coll, start, frames, n_targets):
    """The imported collection: points + cache, sequence, final mesh, material, frame range."""
    scene = bpy.context.scene
    out = coll["fluidform_output"]
    res = {"output": out}
    kids = {c.name.rsplit(" ", 1)[-1]: c for c in coll.children}
    check(set(kids) == {"points", "sequence", "final"}, f"{tag}: collections {sorted(kids)}")
    if set(kids) != {"points", "sequence", "final"}:
        return res
    # Frame range and the point cache.
    cache = pc2(os.path.join(out, "particles.pc2"))
    res["frames"] = cache.shape[0]
    check(cache.shape[0] == frames + 1, f"{tag}: {cache.shape[0]} cache samples, {frames + 1} expected")
    check((scene.frame_start, scene.frame_end) == (start, start + frames),
          f"{tag}: frame range {scene.frame_start}–{scene.frame_end}, expected {start}–{start + frames}")
    points = [o for o in kids["points"].objects if o.type == "MESH"]
    check(len(points) == 1, f"{tag}: {len(points)} point objects")
    pts = points[0]
    mods = [m.type for m in pts.modifiers]
    check(mods[:1] == ["MESH_CACHE"], f"{tag}: point modifiers {mods}")
    check(os.path.isfile(bpy.path.abspath(pts.modifiers[0].filepath)), f"{tag}: the cache file is missing")
    # The played points are the cache's samples in Blender's axes, (x, y, z) → (x, −z, y), on the right frames.
    mc = pts.modifiers[0]
    gn = pts.modifiers[1] if len(pts.modifiers) > 1 else None
    if gn is not None:
        gn.show_viewport = False  # read the played points, not the spheres on them
    worst = 0.0
    for k in (0, frames // 2, frames):
        got = evaluated_points(pts, start + k)
        want = np.stack([cache[k][:, 0], -cache[k][:, 2], cache[k][:, 1]], axis=1)
        worst = max(worst, float(np.abs(got - want).max()) if got.shape == want.shape else math.inf)
    if gn is not None:
        gn.show_viewport = True
    res["points"] = int(cache.shape[1])
    res["max_point_difference"] = worst
    check(worst < 1e-5, f"{tag}: played points differ from the cache by {worst} (Mesh Cache {mc.frame_start})")
    # The sequence: one mesh per meshed frame of animation.glb, exactly one shown at a time, the first on the start
    # frame and the last on the last frame.
    seq = list(kids["sequence"].objects)
    meshes = [o for o in seq if o.type == "MESH"]
    glb = glb_json(os.path.join(out, "animation.glb"))
    res["sequence_meshes"] = len(meshes)
    check(len(meshes) == len(glb["meshes"]) and len(meshes) >= 2,
          f"{tag}: {len(meshes)} sequence meshes, animation.glb has {len(glb['meshes'])}")
    names = sorted(o.name for o in meshes)
    for frame, want in ((start, names[0]), (start + frames, names[-1])):
        vis = visible_sequence_meshes(seq, frame)
        check(vis == [want], f"{tag}: frame {frame} shows {vis}, expected [{want}]")
    vis = visible_sequence_meshes(seq, start + frames // 2)
    check(len(vis) == 1, f"{tag}: frame {start + frames // 2} shows {vis}")
    # The final mesh: closed, with the water material.
    finals = [o for o in kids["final"].objects if o.type == "MESH"]
    check(len(finals) == 1, f"{tag}: {len(finals)} final meshes")
    final = finals[0]
    res["final_faces"] = len(final.data.polygons)
    res["final_closed"] = closed(final)
    check(res["final_closed"], f"{tag}: the final mesh is not closed (an edge without exactly two faces)")
    # The sequence's last mesh and the final mesh are the same frame: the same place (the glTF and OBJ importers'
    # axes agree).
    last_mesh = next(o for o in meshes if o.name == names[-1])
    bpy.context.scene.frame_set(start + frames)
    boxes = []
    for o in (last_mesh, final):
        w = np.array([o.matrix_world @ v.co for v in o.data.vertices])
        boxes.append(np.concatenate([w.min(axis=0), w.max(axis=0)]))
    res["sequence_final_box_difference"] = float(np.abs(boxes[0] - boxes[1]).max())
    check(res["sequence_final_box_difference"] < 0.05, f"{tag}: the last sequence mesh and the final mesh are "
          f"{res['sequence_final_box_difference']:.3f} m apart")
    mat = principled(final.active_material)
    res["material"] = mat
    check(mat is not None and mat["Transmission"] > 0.99 and abs(mat["IOR"] - 1.33) < 1e-3 and mat["Roughness"] < 0.2,
          f"{tag}: final material {mat}")
    check(all(principled(o.active_material) == mat for o in meshes), f"{tag}: sequence meshes lack the water material")
    with open(os.path.join(out, "input", "scene.json"), encoding="utf-8") as f:
        res["scene"] = json.load(f)
    check(len(res["scene"]["targets"]) == n_targets, f"{tag}: {len(res['scene']['targets'])} targets in the scene")
    for d in ("particles", "checkpoint"):
        check(not os.path.exists(os.path.join(out, d)), f"{tag}: {d}/ was left in the output")
    return res


def form(tag):
    """Form through the operator (background: the blocking path); returns (result, seconds)."""
    objs_before = set(bpy.data.objects)
    t0 = time.monotonic()
    r = bpy.ops.fluidform.form()
    secs = time.monotonic() - t0
    import fluidform.task as ft
    t = ft.last()
    check(r == {"FINISHED"}, f"{tag}: Form returned {r} ({t.message if t else ''})")
    check(t is not None and groups_gone(t.run.pgid), f"{tag}: a process of the run is left")
    new_colls = [c for c in bpy.data.collections if c.name.startswith("Fluid Form:")]
    return (new_colls[-1] if new_colls else None), secs, [o for o in bpy.data.objects if o not in objs_before]


def setup_addon():
    bpy.ops.preferences.addon_install(filepath=opt["zip"], overwrite=True)
    r = bpy.ops.preferences.addon_enable(module="fluidform")
    check(r == {"FINISHED"}, f"addon_enable returned {r}")
    prefs = bpy.context.preferences.addons["fluidform"].preferences
    prefs.cli_path = opt["cli"]
    prefs.output_dir = os.path.join(opt["work"], "runs")
    import fluidform
    report["addon_file"] = fluidform.__file__
    check(fluidform.__file__.startswith(os.environ.get("BLENDER_USER_SCRIPTS", "")),
          f"the add-on was loaded from {fluidform.__file__}, not the installed zip")
    check(hasattr(bpy.types, "FLUIDFORM_PT_panel"), "no Fluid Form panel")


def bunny_case():
    clear_scene()
    bpy.ops.wm.obj_import(filepath=opt["bunny"])
    bunny = bpy.context.selected_objects[0]
    bunny.scale = (0.1, 0.1, 0.1)  # about 1 m tall, as examples/default_scene.json
    bpy.context.view_layer.objects.active = bunny
    s = bpy.context.scene.fluidform
    s.particle_count, s.duration, s.start_frame = 3000, 0.75, 10
    s.device = "auto"  # the panel's device choice reaches the run: a real GPU when there is one, else the CPU
    coll, secs, new = form("bunny")
    if not check(coll is not None, "bunny: nothing imported"):
        return None
    import fluidform.task as ft
    argv = ft.last().argv
    check(argv[argv.index("--device") + 1] == "auto", f"bunny: the run was started with {argv}")
    with open(os.path.join(coll["fluidform_output"], "report.json")) as f:
        report["bunny_device"] = json.load(f).get("device")
    check(bool(report["bunny_device"]), "bunny: report.json names no device")
    frames = round(0.75 * bpy.context.scene.render.fps)
    res = check_result("bunny", coll, 10, frames, 1)
    res["seconds"] = secs
    # Up is up: frame 0 is the fluid column standing on the bunny (scene +y is Blender +z), centred over it.
    pts = pc2(os.path.join(res["output"], "particles.pc2"))[0]
    col = np.stack([pts[:, 0], -pts[:, 2], pts[:, 1]], axis=1)
    box = np.array([bunny.matrix_world @ v.co for v in bunny.data.vertices])
    lo, hi = box.min(axis=0), box.max(axis=0)
    centre = 0.5 * (lo + hi)
    res["column_offset_xy"] = float(np.linalg.norm(col[:, :2].mean(axis=0) - centre[:2]))
    check(res["column_offset_xy"] < 0.1 * float(np.linalg.norm(hi - lo)), f"bunny: the fluid column is not over the bunny "
          f"({res['column_offset_xy']:.3f} m off)")
    check(col[:, 2].mean() > centre[2], "bunny: the fluid starts below the bunny (up axis?)")
    # The final mesh lies in the bunny's box (its bottom part at least: after 0.75 s the fluid has not all arrived).
    final = next(o for o in coll.children[-1].objects)
    fb = np.array([final.matrix_world @ v.co for v in final.data.vertices])
    inside = np.all((fb >= lo - 0.1) & (fb <= hi + 0.1), axis=1).mean()
    res["final_in_box"] = float(inside)
    check(inside > 0.5, f"bunny: only {100 * inside:.0f} % of the final mesh lies in the bunny's box")
    return res


def two_object_case():
    clear_scene()
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_cube_add(size=0.4, location=(-0.45, 0.0, 0.4))
    cube = bpy.context.object
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.25, location=(0.45, 0.0, 0.4))
    sphere = bpy.context.object
    sphere.keyframe_insert("location", frame=1)
    sphere.keyframe_insert("rotation_euler", frame=1)
    sphere.location = (0.45, 0.3, 0.4)
    sphere.rotation_euler = (0.0, 0.0, math.radians(90.0))
    sphere.keyframe_insert("location", frame=13)
    sphere.keyframe_insert("rotation_euler", frame=13)
    scene.frame_set(1)
    cube.select_set(True)
    sphere.select_set(True)
    bpy.context.view_layer.objects.active = cube
    s = scene.fluidform
    s.particle_count, s.duration, s.start_frame = 3000, 0.75, 1
    coll, secs, new = form("two objects")
    if not check(coll is not None, "two objects: nothing imported"):
        return None
    frames = round(0.75 * scene.render.fps)
    res = check_result("two objects", coll, 1, frames, 2)
    res["seconds"] = secs
    tg = res["scene"]["targets"]
    check("keyframes" not in tg[0], "two objects: the cube (standing still) got keyframes")
    keys = tg[1].get("keyframes", [])
    res["sphere_keyframes"] = len(keys)
    if check(len(keys) >= 2, f"two objects: the sphere has {len(keys)} keyframes"):
        last = keys[-1]
        check(abs(last["time"] - 12 / scene.render.fps) < 1e-6, f"two objects: last keyframe at {last['time']} s")
        # Blender +y is the scene's −z; a turn about Blender's z is one about the scene's y.
        check(np.allclose(last["translate"], [0.0, 0.0, -0.3], atol=1e-5), f"two objects: last translate {last['translate']}")
        check(np.allclose(last["rotate"], [0.0, 90.0, 0.0], atol=1e-3), f"two objects: last rotate {last['rotate']}")
        # fluidform's pose (pose/target_motion.h) on the exported rest mesh reproduces Blender's sphere at every
        # keyframe: x = pivot + translate + s R (x_rest − pivot), R = R_z R_y R_x.
        rest = np.loadtxt([l for l in open(os.path.join(res["output"], "input", "target_1.obj")) if l.startswith("v ")],
                          usecols=(1, 2, 3))
        pivot = 0.5 * (rest.min(axis=0) + rest.max(axis=0))
        worst = 0.0
        for key in keys:
            rx, ry, rz = (math.radians(a) for a in key["rotate"])
            Rx = np.array([[1, 0, 0], [0, math.cos(rx), -math.sin(rx)], [0, math.sin(rx), math.cos(rx)]])
            Ry = np.array([[math.cos(ry), 0, math.sin(ry)], [0, 1, 0], [-math.sin(ry), 0, math.cos(ry)]])
            Rz = np.array([[math.cos(rz), -math.sin(rz), 0], [math.sin(rz), math.cos(rz), 0], [0, 0, 1]])
            moved = pivot + np.array(key["translate"]) + key["scale"] * (rest - pivot) @ (Rz @ Ry @ Rx).T
            scene.frame_set(1 + round(key["time"] * scene.render.fps))
            world = np.array([sphere.matrix_world @ v.co for v in sphere.data.vertices])
            blender = np.stack([world[:, 0], world[:, 2], -world[:, 1]], axis=1)
            worst = max(worst, float(np.abs(moved - blender).max()))
        res["keyframe_pose_error"] = worst
        check(worst < 1e-4, f"two objects: the keyframed pose is {worst} m off Blender's")
    check(coll.name == "Fluid Form: Cube +1", f"two objects: collection {coll.name}")
    return res


def cancel_case():
    import fluidform.task as ft
    clear_scene()
    bpy.ops.wm.obj_import(filepath=opt["bunny"])
    bunny = bpy.context.selected_objects[0]
    bunny.scale = (0.1, 0.1, 0.1)
    bpy.context.view_layer.objects.active = bunny
    s = bpy.context.scene.fluidform
    s.particle_count, s.duration, s.start_frame = 3000, 20.0, 1
    before = data_ids()
    frame_range = (bpy.context.scene.frame_start, bpy.context.scene.frame_end)
    t = ft.start(bpy.context)
    t0 = time.monotonic()
    # Until the simulation itself runs (after the sampling), then two seconds more.
    while not t.step(bpy.context) and t.run.progress.stage not in ("simulating", "forming") and time.monotonic() - t0 < 60:
        time.sleep(0.05)
    t1 = time.monotonic()
    while not t.step(bpy.context) and time.monotonic() - t1 < 2.0:
        time.sleep(0.05)
    res = {"stage_when_cancelled": t.run.progress.text(), "state_before": t.state}
    check(t.state == "RUNNING", f"cancel: the run was {t.state} before the cancel ({t.message})")
    check(ft.current() is t, "cancel: the running Form is not current")
    check(bpy.ops.fluidform.form.poll() is False, "cancel: Form can start while one runs")
    tc = time.monotonic()
    r = bpy.ops.fluidform.cancel()
    res["cancel_seconds"] = time.monotonic() - tc
    check(r == {"FINISHED"}, f"cancel: the Cancel operator returned {r}")
    check(t.state == "CANCELLED", f"cancel: state {t.state}")
    check(groups_gone(t.run.pgid), "cancel: a process of the run's group is left")
    check(not os.path.exists(t.out_dir), f"cancel: {t.out_dir} was left")
    check(data_ids() == before, "cancel: objects or data were added")
    check((bpy.context.scene.frame_start, bpy.context.scene.frame_end) == frame_range, "cancel: the frame range changed")
    check(ft.current() is None and bpy.ops.fluidform.form.poll(), "cancel: Form cannot start again")
    return res


def form_reporting_error():
    """Form that is expected to fail: in background Blender an operator's error report raises RuntimeError."""
    try:
        return bpy.ops.fluidform.form()
    except RuntimeError as e:
        print(f"(expected) {e}", flush=True)
        return {"CANCELLED"}


def failure_cases(bunny_out):
    """A run that fails in the CLI, one whose output cannot be imported, and a target without faces: each leaves
    nothing behind."""
    import fluidform.task as ft
    res = {}
    clear_scene()
    bpy.ops.mesh.primitive_ico_sphere_add(radius=0.3, location=(0, 0, 0.5))
    bpy.context.scene.fluidform.duration = 0.25
    prefs = bpy.context.preferences.addons["fluidform"].preferences
    cli = prefs.cli_path
    work = opt["work"]
    fake_fail = os.path.join(work, "fail.sh")
    with open(fake_fail, "w") as f:
        f.write("#!/bin/sh\necho '[00:00:00] info: simulating: 1/10 (10%)  ETA 1s' >&2\n"
                "echo 'fluidform: error: targets[0]: something is wrong' >&2\nexit 2\n")
    fake_broken = os.path.join(work, "broken.sh")
    with open(fake_broken, "w") as f:
        # "Succeeds" with the bunny's output but a truncated animation.glb: the import fails after the points.
        f.write(f"#!/bin/sh\nout=\"$4\"\ncp -r '{bunny_out}'/mesh '{bunny_out}'/particles.pc2 "
                f"'{bunny_out}'/particles_frame0.ply '{bunny_out}'/report.json \"$out\"/\n"
                "head -c 1000 " + f"'{bunny_out}'/animation.glb > \"$out\"/animation.glb\nexit 0\n")
    for p in (fake_fail, fake_broken):
        os.chmod(p, 0o755)
    for tag, path, want in (("cli error", fake_fail, "something is wrong"), ("import error", fake_broken, "import failed")):
        prefs.cli_path = path
        before = data_ids()
        frame_range = (bpy.context.scene.frame_start, bpy.context.scene.frame_end)
        r = form_reporting_error()
        t = ft.last()
        res[tag] = t.message
        check(r == {"CANCELLED"}, f"{tag}: Form returned {r}")
        check(t.state == "FAILED" and want in t.message, f"{tag}: {t.state}: {t.message}")
        check(data_ids() == before, f"{tag}: objects or data were left: "
              f"{ {k: sorted(set(v) - before[k]) for k, v in data_ids().items() if set(v) - before[k]} }")
        check((bpy.context.scene.frame_start, bpy.context.scene.frame_end) == frame_range, f"{tag}: frame range changed")
        check(not os.path.exists(t.out_dir), f"{tag}: {t.out_dir} was left")
    prefs.cli_path = cli
    # A mesh without faces is refused before anything runs.
    me = bpy.data.meshes.new("dots")
    me.from_pydata([(0, 0, 0), (1, 0, 0)], [], [])
    dots = bpy.data.objects.new("dots", me)
    bpy.context.scene.collection.objects.link(dots)
    for o in bpy.context.selected_objects:
        o.select_set(False)
    dots.select_set(True)
    bpy.context.view_layer.objects.active = dots
    runs = set(os.listdir(os.path.join(work, "runs")))
    before = data_ids()
    r = form_reporting_error()
    check(r == {"CANCELLED"}, f"no faces: Form returned {r}")
    check(data_ids() == before and set(os.listdir(os.path.join(work, "runs"))) == runs, "no faces: something was left")
    return res


try:
    t0 = time.monotonic()
    setup_addon()
    report["bunny"] = bunny_case()
    report["two_objects"] = two_object_case()
    report["cancel"] = cancel_case()
    if report["bunny"]:
        report["failures"] = failure_cases(report["bunny"]["output"])
    report["seconds"] = time.monotonic() - t0
except Exception:
    traceback.print_exc()
    failures.append("exception: " + traceback.format_exc().strip().splitlines()[-1])
report["failed"] = failures
print("FLUIDFORM_ADDON_TEST " + json.dumps(report, default=str), flush=True)
sys.exit(1 if failures else 0)
