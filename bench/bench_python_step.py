#!/usr/bin/env python3
"""Overhead of fluidform.Simulation.step() over the C++ frame it runs, and against the CLI's frames (issue: ≤ 2 % of
a 10k frame). On the default scene (10k particles), in one process run after run:
  python   wall time of each sim.step() call against the solver's own time for that frame (LiveFrame.step_seconds):
           overhead = wall / solver − 1, median over frames; on alternate frames without the shape metrics (what the
           binding adds: GIL, arguments, the result dict) and with them (which the CLI computes every frame too);
  cli      `fluidform run --frames F --no-mesh`: metrics.csv's per-frame solver time, and the run's wall time per
           frame (everything: sampling, PLY frames, metrics, checkpoints) for scale.
usage: PYTHONPATH=build/release/python python3 bench/bench_python_step.py [--frames 60] [--rounds 3]
"""
import argparse
import csv
import json
import os
import pathlib
import statistics
import subprocess
import tempfile
import time

import fluidform as ff

root = pathlib.Path(__file__).resolve().parents[1]
ap = argparse.ArgumentParser()
ap.add_argument("--frames", type=int, default=60)
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--cli", default=str(root / "build" / "release" / "src" / "app" / "fluidform"))
a = ap.parse_args()
scene = root / "examples" / "default_scene.json"

rows = []
with tempfile.TemporaryDirectory() as tmp:
    for r in range(a.rounds):
        sim = ff.Simulation(str(scene), cache_dir=os.path.join(tmp, "cache"))
        walls, solver, walls_m, solver_m = [], [], [], []
        for k in range(a.frames):
            # Odd frames without the shape metrics: what the binding itself adds to the solver's frame.
            with_metrics = k % 2 == 0
            t0 = time.perf_counter()
            info = sim.step(metrics=with_metrics)
            (walls_m if with_metrics else walls).append(time.perf_counter() - t0)
            (solver_m if with_metrics else solver).append(info["step_seconds"])
        over = statistics.median(w / s - 1.0 for w, s in zip(walls, solver))
        over_m = statistics.median(w / s - 1.0 for w, s in zip(walls_m, solver_m))
        out = os.path.join(tmp, f"cli{r}")
        t0 = time.perf_counter()
        subprocess.run([a.cli, "run", str(scene), "--out", out, "--frames", str(a.frames), "--no-mesh", "-q"],
                       check=True, capture_output=True)
        cli_wall = time.perf_counter() - t0
        with open(os.path.join(out, "metrics.csv")) as f:
            cli_step = [float(x["step_time_s"]) for x in csv.DictReader(f)][1:]
        rows.append({"round": r, "py_step_ms": 1e3 * statistics.median(walls),
                     "py_solver_ms": 1e3 * statistics.median(solver), "py_overhead_pct": 100 * over, "py_overhead_metrics_pct": 100 * over_m,
                     "cli_solver_ms": 1e3 * statistics.median(cli_step), "cli_wall_per_frame_ms": 1e3 * cli_wall / a.frames})

print("| round | step() wall ms | its solver ms | binding overhead % | with metrics % | CLI solver ms | CLI wall/frame ms |")
print("|---|---|---|---|---|---|---|")
for x in rows:
    print(f"| {x['round']} | {x['py_step_ms']:.2f} | {x['py_solver_ms']:.2f} | {x['py_overhead_pct']:.2f} | "
          f"{x['py_overhead_metrics_pct']:.2f} | {x['cli_solver_ms']:.2f} | {x['cli_wall_per_frame_ms']:.2f} |")
med = {k: statistics.median(x[k] for x in rows) for k in rows[0] if k != "round"}
print("medians: " + json.dumps({k: round(v, 3) for k, v in med.items()}))
print(f"step() wall / CLI solver time per frame: {med['py_step_ms'] / med['cli_solver_ms']:.3f}")
