#!/usr/bin/env python3
"""What a skinned target's posing adds to a formed frame (issue 19: ≤ 10 % of a formed 10k frame). The demo character
(examples/generated/character.glb, ~9k control samples, as examples/character.json) three times in one process:
  animated  playing its `walk` clip (samples skinned every sub-step, metrics against the posed target)
  held      the same clip played a million times slower: every bit of posing runs (the samples skinned and their u_c
            every sub-step, the posed target measured), but the pose stands, so the fluid is formed and still
  still     standing in its bind pose (the same mesh, samples and fluid, no clip: nothing posed)
All are stepped to `--formed` frames, then frame by frame in turn:
  solver   the solver's own time for the frame (LiveFrame.step_seconds: posing the samples every sub-step included)
  frame    the wall time of sim.step(metrics=True): the solver and the shape metrics (posed target included)
and the ratios to still of their medians, per round and over rounds. held / still is what posing adds to a formed
frame; animated / still adds what carrying the walking fluid costs (the walk throws it about at 2-3 m/s, and the CFL
rule takes more sub-steps).
usage: PYTHONPATH=build/release/python python3 bench/bench_posing.py [--formed 180] [--frames 60] [--rounds 3]
"""
import argparse
import json
import os
import pathlib
import statistics
import tempfile
import time

import fluidform as ff

root = pathlib.Path(__file__).resolve().parents[1]
ap = argparse.ArgumentParser()
ap.add_argument("--formed", type=int, default=180, help="frames stepped before timing (the walk forms by ~2.5 s)")
ap.add_argument("--frames", type=int, default=60, help="timed frames per round and scene")
ap.add_argument("--rounds", type=int, default=3)
a = ap.parse_args()
glb = root / "examples" / "generated" / "character.glb"
if not glb.exists():
    raise SystemExit(f"bench_posing: {glb} is missing (scripts/setup writes it)")

rows = []
with tempfile.TemporaryDirectory() as tmp:
    scenes = {}
    for name, target in (("animated", {"mesh": str(glb), "animation": {"clip": "walk"}}),
                         ("held", {"mesh": str(glb), "animation": {"clip": "walk", "speed": 1e-6}}),
                         ("still", {"mesh": str(glb)})):
        path = os.path.join(tmp, f"{name}.json")
        with open(path, "w") as f:
            json.dump({"targets": [target]}, f)
        scenes[name] = path
    for r in range(a.rounds):
        sims = {k: ff.Simulation(p, cache_dir=os.path.join(tmp, "cache")) for k, p in scenes.items()}
        for s in sims.values():
            s.step(a.formed, metrics=False)
        solver = {k: [] for k in sims}
        frame = {k: [] for k in sims}
        substeps = {k: [] for k in sims}
        last = {}
        for _ in range(a.frames):
            for k, s in sims.items():
                t0 = time.perf_counter()
                info = s.step(metrics=True)
                frame[k].append(time.perf_counter() - t0)
                solver[k].append(info["step_seconds"])
                substeps[k].append(info["substeps"])
                last[k] = info
        med = {f"{k}_{what}_ms": 1e3 * statistics.median(v[k]) for k in sims for what, v in (("solver", solver), ("frame", frame))}
        for k in sims:  # what the frame takes beyond the solver: the shape metrics (posing the target included)
            med[f"{k}_metrics_ms"] = 1e3 * statistics.median(f - s for f, s in zip(frame[k], solver[k]))
        med["particles"] = len(sims["animated"].positions)
        for k in sims:
            med[f"{k}_substeps"] = statistics.mean(substeps[k])
            med[f"{k}_per_substep_ms"] = 1e3 * sum(solver[k]) / sum(substeps[k])
        for k in sims:
            med[f"E_{k}"] = last[k].get("error_rate", float("nan"))
        rows.append(med)

names = list(scenes)
print("| round | particles | " + " | ".join(f"{k} solver ms | {k} frame ms" for k in names) + " | held/still frame | "
      + " | ".join(f"E {k} %" for k in names) + " |")
print("|---|---|" + "---|---|" * len(names) + "---|" + "---|" * len(names))
for i, x in enumerate(rows):
    print(f"| {i} | {x['particles']} | " + " | ".join(f"{x[k + '_solver_ms']:.1f} | {x[k + '_frame_ms']:.1f}" for k in names)
          + f" | {x['held_frame_ms'] / x['still_frame_ms']:.3f} | " + " | ".join(f"{x['E_' + k]:.3f}" for k in names) + " |")
m = {k: statistics.median(x[k] for x in rows) for k in rows[0]}
print("medians: " + json.dumps({k: round(v, 3) for k, v in m.items()}))
for k in ("held", "animated"):
    print(f"{k} / still: solver {m[k + '_solver_ms'] / m['still_solver_ms']:.3f}; frame with metrics "
          f"{m[k + '_frame_ms'] / m['still_frame_ms']:.3f}; sub-steps per frame {m[k + '_substeps']:.2f} vs "
          f"{m['still_substeps']:.2f}; per sub-step {m[k + '_per_substep_ms'] / m['still_per_substep_ms']:.3f}")
# The held frame takes fewer sub-steps than the still one (its pose is not the bind pose, so its fluid settles
# differently), which flatters the frame ratio. Posing's own share, at the still frame's sub-steps: the extra per
# sub-step times their count, plus the posed metrics' extra, over the still frame.
extra_solver = (m["held_per_substep_ms"] - m["still_per_substep_ms"]) * m["still_substeps"]
extra_metrics = m["held_metrics_ms"] - m["still_metrics_ms"]
print(f"posing's share of a formed still frame ({m['still_frame_ms']:.1f} ms): solver {extra_solver:+.2f} ms + metrics "
      f"{extra_metrics:+.2f} ms ({m['held_metrics_ms']:.2f} against {m['still_metrics_ms']:.2f}) = "
      f"{100 * (extra_solver + extra_metrics) / m['still_frame_ms']:+.1f} %")
