#!/usr/bin/python3
"""Renders a control-particle PLY (fluidform sample) to a PNG: three views, points coloured by a property.

    /usr/bin/python3 scripts/render_controls.py CONTROLS.ply OUT.png [--property phi|weight|density]

Needs numpy and matplotlib (Debian: python3-matplotlib; scripts/setup installs it). Only for looking at results; not used by tests.
"""
import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read_ply(path):
    with open(path, "rb") as f:
        props, n = [], 0
        while True:
            line = f.readline().decode("ascii").strip()
            if line.startswith("element vertex"):
                n = int(line.split()[2])
            elif line.startswith("property"):
                _, t, name = line.split()
                props.append((name, "<f4" if t in ("float", "float32") else "u1"))
            elif line == "end_header":
                break
        return np.frombuffer(f.read(), dtype=np.dtype(props), count=n)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("ply")
    ap.add_argument("png")
    ap.add_argument("--property", default="phi")
    a = ap.parse_args()
    v = read_ply(a.ply)
    x, y, z = v["x"], v["y"], v["z"]
    c = v[a.property]
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.4))
    # Each view draws far points first so the near side is on top.
    for ax, (u, w, depth, title) in zip(axes, [(x, y, z, "front (x, y)"), (z, y, -x, "side (z, y)"), (x, z, y, "top (x, z)")]):
        order = np.argsort(depth)
        sc = ax.scatter(u[order], w[order], c=c[order], s=3, cmap="viridis", linewidths=0)
        ax.set_aspect("equal")
        ax.set_title(title)
    fig.colorbar(sc, ax=axes, shrink=0.8, label=a.property)
    fig.suptitle(f"{a.ply}: {len(v)} samples, colour = {a.property}")
    fig.savefig(a.png, dpi=90)


if __name__ == "__main__":
    sys.exit(main())
