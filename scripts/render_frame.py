#!/usr/bin/python3
"""Renders a particle frame of a run next to its target's control samples: front and side views.

    /usr/bin/python3 scripts/render_frame.py OUT/particles/frame_NNNNN.ply OUT.png [--controls OUT/cache/controls_*.ply]

Fluid particles are coloured by target id (free fluid grey), control samples drawn faintly behind them.
Needs numpy and matplotlib (Debian: python3-matplotlib; scripts/setup installs it). Only for looking at results; not used by tests.
"""
import argparse
import glob
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from render_controls import read_ply  # noqa: E402  (the same PLY reader, next to this script)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("frame")
    ap.add_argument("out")
    ap.add_argument("--controls", nargs="*")
    a = ap.parse_args()
    p = read_ply(a.frame)
    controls = a.controls
    if controls is None:
        run = os.path.dirname(os.path.dirname(os.path.abspath(a.frame)))
        controls = sorted(glob.glob(os.path.join(run, "cache", "controls_*.ply")))
    cs = [read_ply(c) for c in controls]
    fig, axes = plt.subplots(1, 2, figsize=(12, 6))
    t = p["target"] if "target" in p.dtype.names else np.zeros(len(p), np.uint8)
    colors = np.where(t[:, None] == 255, [[0.6, 0.6, 0.6]], plt.cm.tab10(t % 10)[:, :3])
    for ax, (u, v, name) in zip(axes, [("x", "y", "front (x, y)"), ("z", "y", "side (z, y)")]):
        for c in cs:
            ax.scatter(c[u], c[v], s=1, c=[[0.85, 0.3, 0.3]], alpha=0.08, linewidths=0)
        ax.scatter(p[u], p[v], s=2, c=colors, alpha=0.6, linewidths=0)
        ax.set_aspect("equal")
        ax.set_title(name)
    fig.suptitle(os.path.basename(a.frame) + ": fluid (blue) over the control samples (red)")
    fig.tight_layout()
    fig.savefig(a.out, dpi=80)


if __name__ == "__main__":
    main()
