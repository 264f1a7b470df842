#!/usr/bin/python3
"""Renders OBJ meshes side by side to a PNG (flat Lambert shading, matplotlib), to look at what `fluidform mesh`
made next to the target it should match.

    /usr/bin/python3 scripts/render_mesh.py OUT.png A.obj [B.obj ...] [--titles "a,b"] [--scale S,S,...]
        [--rows N] [--same-size]

--scale multiplies each mesh's coordinates (e.g. 0.1 for the bunny target, which the default scene scales by 0.1).
--rows lays the meshes out row by row (a strip of frames above the posed targets); --same-size draws every panel at
the scale of the largest mesh, each centred on its own box, so a shape that shrinks or stretches shows it.
Y is up (fluidform's and glTF's convention).
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def read_obj(path):
    v, f = [], []
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                v.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = [int(p.split("/")[0]) for p in line.split()[1:]]
                for k in range(1, len(idx) - 1):  # fan polygons into triangles
                    f.append([idx[0] - 1, idx[k] - 1, idx[k + 1] - 1])
    return np.array(v, dtype=float), np.array(f, dtype=int)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--titles", default="")
    ap.add_argument("--scale", default="")
    ap.add_argument("--elev", type=float, default=15.0)
    ap.add_argument("--azim", type=float, default=-60.0)
    ap.add_argument("--rows", type=int, default=1)
    ap.add_argument("--same-size", action="store_true")
    a = ap.parse_args()
    titles = a.titles.split(",") if a.titles else [m.split("/")[-1] for m in a.meshes]
    scales = [float(s) for s in a.scale.split(",")] if a.scale else [1.0] * len(a.meshes)
    rows = max(1, a.rows)
    cols = -(-len(a.meshes) // rows)
    fig = plt.figure(figsize=(5 * cols, 5 * rows), dpi=110)
    light = np.array([0.4, 0.8, 0.45])
    light /= np.linalg.norm(light)
    meshes = [read_obj(path) for path in a.meshes]
    meshes = [(v * scales[k], f) for k, (v, f) in enumerate(meshes)]
    common = max((v.max(axis=0) - v.min(axis=0)).max() / 2 for v, _ in meshes) if a.same_size else None
    for k, (v, f) in enumerate(meshes):
        # Y up: plot (x, z, y) so matplotlib's vertical axis is the mesh's Y.
        p = v[:, [0, 2, 1]]
        tri = p[f]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-20)
        lum = 0.25 + 0.75 * np.clip(n @ light[[0, 2, 1]], 0, 1)
        colors = np.outer(lum, [0.35, 0.6, 0.95])
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(tri, facecolors=colors, edgecolors="none"))
        lo, hi = p.min(axis=0), p.max(axis=0)
        c, r = (lo + hi) / 2, common if common else (hi - lo).max() / 2
        ax.set_xlim(c[0] - r, c[0] + r)
        ax.set_ylim(c[1] - r, c[1] + r)
        ax.set_zlim(c[2] - r, c[2] + r)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=a.elev, azim=a.azim)
        ax.set_axis_off()
        ax.set_title(f"{titles[k]}\n{len(v)} vertices, {len(f)} triangles", fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out)


if __name__ == "__main__":
    main()
