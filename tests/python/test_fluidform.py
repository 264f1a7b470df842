"""Tests of the Python module `fluidform` (src/python), run by CTest with Debian's python3 and pytest:
    PYTHONPATH=build/release/python python3 -m pytest tests/python
FF_SOURCE_DIR names the repository (for examples/bunny.obj) and FF_BINARY the CLI (for the run comparison)."""
import os
import pathlib
import subprocess
import threading
import time
import gc

import numpy as np
import pytest

import fluidform as ff

SOURCE = pathlib.Path(os.environ.get("FF_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
BUNNY = SOURCE / "examples" / "bunny.obj"
BINARY = os.environ.get("FF_BINARY", str(SOURCE / "build" / "release" / "src" / "app" / "fluidform"))


def small_scene(**extra):
    """The default scene at ~2000 particles (fast), as a dict."""
    scene = {"targets": [{"mesh": str(BUNNY), "scale": 0.1}], "sampling": {"auto_count": 2000}}
    scene.update(extra)
    return scene


def cube(size=1.0):
    """A closed, outward-wound cube [0, size]^3 as (vertices, faces) arrays."""
    v = np.array([[x, y, z] for x in (0, size) for y in (0, size) for z in (0, size)], dtype=np.float64)
    # Vertex index = 4x + 2y + z; two triangles per face, counter-clockwise seen from outside.
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    f = []
    for a, b, c, d in quads:
        f += [(a, b, c), (a, c, d)]
    return v, np.array(f, dtype=np.int64)


def read_ply_frame(path):
    """A fluidform particle frame (binary PLY: x y z vx vy vz float, target uchar) → positions (N, 3)."""
    data = pathlib.Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    n = int(next(line.split()[2] for line in header if line.startswith("element vertex")))
    props = [line.split()[2] for line in header if line.startswith("property")]
    assert props == ["x", "y", "z", "vx", "vy", "vz", "target"], props
    rec = np.dtype([("x", "<f4", 3), ("v", "<f4", 3), ("t", "u1")])
    return np.frombuffer(data, dtype=rec, count=n, offset=end)["x"]


def closed_2_manifold(faces):
    """Every edge in exactly two faces, once in each direction (closed, consistently wound)."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    directed = {tuple(x) for x in e.tolist()}
    return len(directed) == len(e) and all((b, a) in directed for a, b in directed)


# --- sample ---------------------------------------------------------------------------------------------------

def test_sample_file_gives_about_count_samples_inside_the_mesh():
    s = ff.sample(BUNNY, count=3000)
    positions, weights = s
    assert positions.shape == (len(s), 3) and positions.dtype == np.float32
    assert 0.8 * 3000 < len(s) < 1.2 * 3000
    assert weights.shape == (len(s),) and np.all(weights > 0) and np.all(weights <= 1)
    assert s.method == "blue-noise" and s.spacing > 0 and s.support == pytest.approx(3 * s.spacing, rel=1e-5)
    lo, hi = positions.min(0), positions.max(0)
    mesh_lo, mesh_hi = samples_bounds_of_obj(BUNNY)
    assert np.all(lo >= mesh_lo - 1e-3) and np.all(hi <= mesh_hi + 1e-3)


def samples_bounds_of_obj(path):
    v = np.array([[float(x) for x in line.split()[1:4]] for line in open(path) if line.startswith("v ")])
    return v.min(0), v.max(0)


def test_sample_numpy_target_without_a_file():
    v, f = cube(1.0)
    s = ff.sample((v, f), spacing=0.1, method="voxel")
    # A lattice of spacing 0.1 in the unit cube: 10³ cell centres.
    assert len(s) == 1000
    assert np.all(s.positions > 0) and np.all(s.positions < 1)
    b = ff.sample((v, f), spacing=0.1)  # blue noise: about V / d³
    assert 800 < len(b) < 1200 and np.all(b.positions > -0.01) and np.all(b.positions < 1.01)
    assert abs(b.volume - 1.0) < 0.05


def test_sample_is_deterministic_for_a_seed():
    v, f = cube(1.0)
    a = ff.sample((v, f), count=500, seed=3)
    b = ff.sample((v, f), count=500, seed=3)
    c = ff.sample((v, f), count=500, seed=4)
    assert np.array_equal(a.positions, b.positions)
    assert not np.array_equal(a.positions, c.positions)


# --- errors ---------------------------------------------------------------------------------------------------

def test_bad_input_raises_with_the_cli_message(tmp_path):
    with pytest.raises(ff.InputError, match="no such file"):
        ff.sample(tmp_path / "missing.obj")
    v, f = cube()
    with pytest.raises(ff.InputError, match=r"expected an \(N, 3\) array"):
        ff.sample((v[:, :2], f))
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ff.InputError, match="row 3 is not finite"):
        ff.sample((bad, f))
    with pytest.raises(ff.InputError, match="names vertex 8"):
        ff.sample((v, np.where(f == 7, 8, f)))
    with pytest.raises(ff.ParamError, match="sampling.bogus: unknown key"):
        ff.sample((v, f), bogus=1)
    with pytest.raises(ff.ParamError, match="relax_steps"):
        ff.sample((v, f), relax_steps=-5)
    with pytest.raises(ff.ParamError, match="method"):
        ff.sample((v, f), method="poisson")
    with pytest.raises(ff.ParamError, match="not both"):
        ff.sample((v, f), count=10, spacing=0.1)
    # The exception classes are also the built-in ones a caller may catch.
    assert issubclass(ff.InputError, ValueError) and issubclass(ff.ParamError, ValueError)
    assert issubclass(ff.IoError, OSError) and issubclass(ff.InputError, ff.Error)


def test_scene_errors_match_the_cli(tmp_path):
    scene = small_scene(solver={"particle_radius": -1})
    with pytest.raises(ff.ParamError) as py_err:
        ff.Simulation(scene, cache_dir=str(tmp_path / "cache"))
    path = tmp_path / "bad.json"
    path.write_text(__import__("json").dumps(scene))
    cli = subprocess.run([BINARY, "run", str(path), "--out", str(tmp_path / "o")], capture_output=True, text=True)
    assert cli.returncode == 2
    assert str(py_err.value) in cli.stderr
    with pytest.raises(ff.ParamError, match="unknown key"):
        ff.run(small_scene(solvr={}), out=str(tmp_path / "o2"))
    with pytest.raises(ff.InputError):
        ff.run(str(tmp_path / "nope.json"), out=str(tmp_path / "o3"))


# --- reconstruct and measure ----------------------------------------------------------------------------------

def test_reconstruct_a_ball_gives_a_closed_mesh_of_its_size():
    d = 0.05
    g = np.arange(-0.5, 0.5 + 1e-9, d)
    p = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    p = p[np.linalg.norm(p, axis=1) <= 0.4]
    v, f = ff.reconstruct(p)
    assert v.dtype == np.float32 and f.dtype == np.uint32 and len(f) > 100
    assert closed_2_manifold(f)
    radius = np.linalg.norm(v, axis=1)
    assert 0.35 < radius.mean() < 0.47
    with pytest.raises(ff.ParamError, match="surface.nope"):
        ff.reconstruct(p, nope=1)
    with pytest.raises(ff.InputError, match="empty"):
        ff.reconstruct(np.zeros((0, 3)))


def test_measure_tells_a_formed_shape_from_a_wrong_one():
    v, f = cube(1.0)
    inside = ff.sample((v, f), spacing=0.05, method="voxel").positions
    exact = ff.measure(inside, (v, f), particle_radius=0.025, samples=inside)
    assert exact["error_rate"] == 0.0 and exact["inside"] == 1.0
    # Against the mesh's own blue-noise samples (as a run measures): a lattice is within a fraction of a spacing.
    good = ff.measure(inside, (v, f), particle_radius=0.025)
    assert good["inside"] == 1.0 and good["splash"] == 0.0 and good["error_spacings"] < 0.75
    shifted = ff.measure(inside + np.float32([0.5, 0, 0]), (v, f), particle_radius=0.025)
    assert shifted["error_rate"] > 5 * good["error_rate"] and shifted["inside"] < 0.6


# --- run and Simulation ---------------------------------------------------------------------------------------

def test_simulation_steps_the_same_positions_as_run(tmp_path):
    frames = 12
    scene = small_scene()
    summary = ff.run(scene, out=str(tmp_path / "run"), frames=frames, mesh=False)
    assert summary["frames"] == frames + 1 and summary["particles"] > 1000
    ply = read_ply_frame(tmp_path / "run" / "particles" / f"frame_{frames:05d}.ply")

    sim = ff.Simulation(scene, cache_dir=str(tmp_path / "cache"))
    assert len(sim) == summary["particles"]
    info = sim.step(frames)
    assert info["frame"] == frames and sim.frame == frames
    assert sim.time == pytest.approx(frames / sim.fps)
    got = sim.sorted()["positions"]
    # The same scene, set up and stepped by the same code: the same particles, bit for bit.
    assert np.array_equal(got, ply)
    # The zero-copy views agree with the sorted copies once put in id order.
    order = np.argsort(sim.ids)
    assert np.array_equal(sim.positions[order], got)
    # And the CLI writes the same frame as the module's run.
    subprocess.run([BINARY, "run", str(write_scene(tmp_path, scene)), "--out", str(tmp_path / "cli"), "--frames",
                    str(frames), "--no-mesh", "-q"], check=True, capture_output=True)
    assert np.array_equal(read_ply_frame(tmp_path / "cli" / "particles" / f"frame_{frames:05d}.ply"), ply)


def write_scene(tmp_path, scene):
    path = tmp_path / "scene.json"
    path.write_text(__import__("json").dumps(scene))
    return path


def test_views_are_read_only_and_survive_later_steps(tmp_path):
    sim = ff.Simulation(small_scene(), cache_dir=str(tmp_path / "cache"))
    before = sim.positions
    snapshot, ids0 = before.copy(), sim.ids.copy()
    assert before.shape == (len(sim), 3) and not before.flags.writeable
    assert sim.velocities.shape == (len(sim), 3) and sim.target_ids.dtype == np.uint8 and sim.ids.dtype == np.uint32
    with pytest.raises(ValueError):
        before[0, 0] = 1.0
    sim.step(5)
    assert np.array_equal(before, snapshot)  # the old view kept its frame's values
    assert not np.array_equal(sim.sorted()["positions"], snapshot[np.argsort(ids0)])  # the particles moved
    m = sim.metrics()
    assert m["frame"] == 5 and np.isfinite(m["error_rate"])
    sim.restart()
    assert sim.frame == 0 and np.array_equal(before, snapshot)


def test_simulation_controller_pose_and_scene(tmp_path):
    sim = ff.Simulation(small_scene(), controller="none", cache_dir=str(tmp_path / "cache"))
    assert sim.controller == "none"
    sim.controller = "adaptive"
    assert sim.controller == "adaptive"
    with pytest.raises(ff.ParamError, match="not one of"):
        sim.controller = "nope"
    pose = sim.set_pose(0, translate=(0.1, 0, 0))
    assert pose["translate"][0] == pytest.approx(0.1)
    with pytest.raises(ff.ParamError, match="does not exist"):
        sim.set_pose(3)
    assert sim.scene()["targets"][0]["scale"] == pytest.approx([0.1, 0.1, 0.1])
    with pytest.raises(ff.ParamError):
        sim.step(0)


def test_simulation_on_the_gpu_device(tmp_path):
    # Vulkan's first device (lavapipe where there is no GPU): the same Simulation, stepped on the device.
    sim = ff.Simulation(small_scene(), device="gpu", cache_dir=str(tmp_path / "cache"))
    assert sim.device != "cpu"
    start = sim.sorted()["positions"]
    f = sim.step(30)
    assert f["controlled"] > 0
    assert np.isfinite(sim.positions).all()
    assert np.abs(sim.sorted()["positions"] - start).max() > 0.05  # it fell into the bunny
    with pytest.raises(ff.ParamError, match="does not do the controller 'pbfc'"):
        sim.controller = "pbfc"
    assert sim.controller == "adaptive"
    with pytest.raises(ff.ParamError, match="expected cpu, gpu or auto"):
        ff.Simulation(small_scene(), device="tpu", cache_dir=str(tmp_path / "cache"))
    assert ff.Simulation(small_scene(), cache_dir=str(tmp_path / "cache")).device == "cpu"


def test_run_reports_progress_and_can_be_cancelled(tmp_path):
    calls = []

    def progress(what, done, total):
        calls.append((what, done, total))
        return not (what == "simulating" and done >= 3)

    with pytest.raises(ff.Cancelled):
        ff.run(small_scene(), out=str(tmp_path / "o"), frames=50, progress=progress)
    forming = [c for c in calls if c[0] == "simulating"]
    assert forming and forming[-1][1] == 3 and forming[-1][2] == 50
    # A callback that raises stops the run too, and its exception comes out.
    def boom(what, done, total):
        if what == "simulating" and done >= 2:
            raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        ff.run(small_scene(), out=str(tmp_path / "o2"), frames=50, progress=boom)


def test_run_summary_and_outputs(tmp_path):
    s = ff.run(small_scene(), out=str(tmp_path / "o"), frames=30, animation=False)
    assert s["controller"] == "adaptive" and s["mesh_ok"] and s["mesh_triangles"] > 0
    assert (tmp_path / "o" / "mesh" / "final.obj").is_file() and (tmp_path / "o" / "report.json").is_file()
    assert 0 <= s["inside"] <= 1 and np.isfinite(s["error_rate"])
    assert s["device"] == "cpu"


def test_run_takes_a_mesh_file_as_the_smallest_scene_around_it(tmp_path):
    # As the CLI: a mesh path in place of a scene (issue 46 item 6).
    v, f = cube(0.4)
    obj = tmp_path / "box.obj"
    obj.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in v) + "".join(f"f {a+1} {b+1} {c+1}\n" for a, b, c in f))
    s = ff.run(str(obj), out=str(tmp_path / "o"), frames=2, mesh=False)
    assert s["frames"] == 3 and s["particles"] > 5000
    (tmp_path / "notes.txt").write_text("hello\n")
    with pytest.raises(Exception, match="neither a scene file"):
        ff.run(str(tmp_path / "notes.txt"), out=str(tmp_path / "bad"), frames=1, mesh=False)


def test_run_on_the_gpu_device(tmp_path):
    # Vulkan compute on the machine's device (lavapipe where there is no GPU; scripts/setup installs it).
    s = ff.run(small_scene(), out=str(tmp_path / "g"), frames=5, mesh=False, device="gpu")
    assert s["device"] != "cpu" and s["frames"] == 6
    with pytest.raises(ValueError, match="--device"):
        ff.run(small_scene(), out=str(tmp_path / "bad"), frames=1, mesh=False, device="tpu")


def test_step_releases_the_gil(tmp_path):
    sim = ff.Simulation(small_scene(), cache_dir=str(tmp_path / "cache"))
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.monotonic())
            stop.wait(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    time.sleep(0.01)
    start = time.monotonic()
    sim.step(20)
    end = time.monotonic()
    stop.set()
    t.join()
    assert any(start < x < end for x in ticks)  # the other thread ran while C++ stepped


def test_views_outlive_their_simulation(tmp_path):
    sim = ff.Simulation(small_scene(), cache_dir=str(tmp_path / "cache"))
    sim.step(2)
    v, ids = sim.positions, sim.ids
    c = v.copy()
    del sim
    gc.collect()
    junk = [np.full((len(c), 3), 7.0, dtype=np.float32) for _ in range(20)]  # reuse freed memory, if it were freed
    assert np.array_equal(v, c) and len(ids) == len(c) and len(junk) == 20


def test_a_callback_that_returns_anything_or_raises_is_handled(tmp_path):
    v, f = cube(1.0)
    # Any object is taken by its truth value; an object whose truth raises stops the work with that exception.
    s = ff.sample((v, f), count=300, progress=lambda what, done, total: "yes")
    assert len(s) > 0
    with pytest.raises(ff.Cancelled):
        ff.sample((v, f), count=300, progress=lambda what, done, total: [])

    class Bad:
        def __bool__(self):
            raise ZeroDivisionError("no truth")

    with pytest.raises(ZeroDivisionError):
        ff.sample((v, f), count=300, progress=lambda what, done, total: Bad())
