#!/usr/bin/python3
"""Writes the demo character: a small rigged, animated humanoid as binary glTF 2.0, made procedurally.

The character ships as this recipe, never as a binary (scripts/setup runs it; examples/generated/ is ignored by git).
It is deterministic: the same bytes on every machine (numpy and the standard library only, no randomness).

What it writes (one .glb, ~200 KB):
  - one mesh, one primitive, in bind pose: 1.70 m tall, metres, Y up, facing +Z, feet on y = 0; made of 16 closed,
    outward-wound, watertight parts (pelvis, torso, neck, head, upper/lower arms, hands, upper/lower legs, feet),
    each a genus-0 2-manifold; parts overlap at the joints (read the union by winding number);
  - a skeleton of 17 joints (hips at the root; spine, chest, neck, head; shoulder, upper arm, forearm L+R; thigh,
    shin, foot L+R) as nodes with TRS, a skin with inverseBindMatrices, JOINTS_0 (UNSIGNED_BYTE) and WEIGHTS_0
    (FLOAT, summing to 1, at most 2 of 4 non-zero), blended smoothly over a few cm across every joint;
  - the clips "walk" (a 1.1 s loop in place: hips bob, sway and turn, legs swing, knees bend, feet roll, arms
    counter-swing, 31 LINEAR keys, the first equal to the last) and "wave" (2 s: the right arm rises and waves).

usage: /usr/bin/python3 scripts/make_character.py [--out PATH] [--check]
  --out PATH   where to write (default examples/generated/character.glb); written atomically (temp file + rename)
  --check      then read the file back and check it: every part closed, 2-manifold, genus 0 and outward, no
               degenerate triangle, indices and joints in range, weights finite, non-negative and summing to 1,
               unit normals, inverse bind matrices consistent with the nodes, clips looping with unit quaternions,
               and, posed by linear blend skinning through each clip, no part turned inside out or torn (edge
               stretch and volume within bounds). Exit status 1 and one line per failure when anything fails.
Prints one JSON line: the file, its size, vertices, triangles, parts, joints, clips (and the check's figures).
"""
import argparse
import json
import math
import os
import struct
import sys
import tempfile

import numpy as np

# ---------------------------------------------------------------------------------------------------------------
# Skeleton (bind pose: every joint's rotation is the identity, so a joint's world bind matrix is a translation).
# name, parent, world position (m). The character's left is +X (glTF: facing +Z).
ARM_TILT = math.radians(12.0)  # the arms hang 12° out from vertical (A pose), clear of the torso
UPPER_ARM, FOREARM = 0.28, 0.26
_ARM_DIR = {"L": np.array([math.sin(ARM_TILT), -math.cos(ARM_TILT), 0.0]),
            "R": np.array([-math.sin(ARM_TILT), -math.cos(ARM_TILT), 0.0])}


def _skeleton():
    joints = [("hips", None, (0.0, 0.93, 0.0)), ("spine", "hips", (0.0, 1.05, 0.0)),
              ("chest", "spine", (0.0, 1.25, 0.0)), ("neck", "chest", (0.0, 1.43, 0.0)),
              ("head", "neck", (0.0, 1.53, 0.0))]
    for side, sx in (("L", 1.0), ("R", -1.0)):
        shoulder = np.array([0.19 * sx, 1.39, 0.0])
        elbow = shoulder + UPPER_ARM * _ARM_DIR[side]
        joints += [(f"shoulder_{side}", "chest", (0.06 * sx, 1.39, 0.0)),
                   (f"upper_arm_{side}", f"shoulder_{side}", tuple(shoulder)),
                   (f"forearm_{side}", f"upper_arm_{side}", tuple(elbow))]
    for side, sx in (("L", 1.0), ("R", -1.0)):
        joints += [(f"thigh_{side}", "hips", (0.09 * sx, 0.88, 0.0)),
                   (f"shin_{side}", f"thigh_{side}", (0.09 * sx, 0.48, 0.0)),
                   (f"foot_{side}", f"shin_{side}", (0.09 * sx, 0.08, 0.0))]
    return joints


JOINTS = _skeleton()
JOINT_INDEX = {name: i for i, (name, _, _) in enumerate(JOINTS)}
JOINT_POS = {name: np.array(p, dtype=np.float64) for name, _, p in JOINTS}


# ---------------------------------------------------------------------------------------------------------------
# Closed parts: a lattice of rings between two poles (a sphere's topology), wound outward.
def _lattice(rings, pole_a, pole_b):
    """rings: (n, m, 3) from pole_a's side to pole_b's. Returns vertices (n*m+2, 3), triangles (2nm, 3)."""
    n, m, _ = rings.shape
    verts = np.concatenate([pole_a[None], rings.reshape(-1, 3), pole_b[None]])
    tris = []
    ring = lambda i, j: 1 + i * m + (j % m)
    for j in range(m):
        tris.append((0, ring(0, j + 1), ring(0, j)))
    for i in range(n - 1):
        for j in range(m):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
            tris += [(a, b, c), (a, c, d)]
    last = len(verts) - 1
    for j in range(m):
        tris.append((last, ring(n - 1, j), ring(n - 1, j + 1)))
    tris = np.array(tris, dtype=np.int64)
    if _signed_volume(verts, tris) < 0:  # wind outward whichever way the rings turned
        tris = tris[:, ::-1].copy()
    return verts, tris


def _signed_volume(v, t):
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _frame(axis):
    axis = axis / np.linalg.norm(axis)
    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    return axis, e1, np.cross(axis, e1)


def capsule(a, b, ra, rb, segments=14, cap_rings=4, ring_spacing=0.035):
    """A tapered capsule: hemispheres of radius ra at a and rb at b joined by a cone."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    u, e1, e2 = _frame(b - a)
    length = float(np.linalg.norm(b - a))
    ang = 2 * math.pi * np.arange(segments) / segments
    circle = np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2
    centres, radii = [], []
    for i in range(1, cap_rings + 1):
        th = -math.pi / 2 + i * (math.pi / 2) / cap_rings
        centres.append(a + u * ra * math.sin(th)), radii.append(ra * math.cos(th))
    n_cyl = max(2, int(math.ceil(length / ring_spacing)))
    for j in range(1, n_cyl):
        t = j / n_cyl
        centres.append(a + (b - a) * t), radii.append(ra + (rb - ra) * t)
    for i in range(cap_rings):
        th = i * (math.pi / 2) / cap_rings
        centres.append(b + u * rb * math.sin(th)), radii.append(rb * math.cos(th))
    rings = np.array([c + r * circle for c, r in zip(centres, radii)])
    return _lattice(rings, a - u * ra, b + u * rb)


def superellipsoid(centre, radii, e_lat=1.0, e_lon=1.0, rings=12, segments=20, axes=None, taper=None):
    """x = a·cos^e(η)·cos^e'(ω), y = b·sin^e(η), z = c·cos^e(η)·sin^e'(ω) (signed powers; e < 1 is boxier), poles
    on local ±y; `axes` (3×3, columns = local x, y, z in world) orients it; taper(y_local / b) scales local x, z."""
    sp = lambda v, e: np.sign(v) * np.abs(v) ** e
    eta = -math.pi / 2 + math.pi * np.arange(1, rings) / rings
    om = 2 * math.pi * np.arange(segments) / segments
    E, O = np.meshgrid(eta, om, indexing="ij")
    a, b, c = radii
    x = a * sp(np.cos(E), e_lat) * sp(np.cos(O), e_lon)
    y = b * sp(np.sin(E), e_lat)
    z = c * sp(np.cos(E), e_lat) * sp(np.sin(O), e_lon)
    if taper is not None:
        s = taper(y / b)
        x, z = x * s, z * s
    local = np.stack([x, y, z], axis=-1)
    poles = np.array([[0.0, -b, 0.0], [0.0, b, 0.0]])
    R = np.eye(3) if axes is None else np.asarray(axes, float)
    centre = np.asarray(centre, float)
    to_world = lambda p: p @ R.T + centre
    return _lattice(to_world(local), to_world(poles[0]), to_world(poles[1]))


# ---------------------------------------------------------------------------------------------------------------
# Skin weights: along a chain of joints, a bone's weight falls from 1 to 0 across each joint over ±width (smoothstep),
# so neighbouring bones share the joint 50/50 and weights sum to 1 (a telescoping sum). Parts overlapping at a joint
# use the same chain coordinate there, so they bend together.
def _smoothstep(e0, e1, x):
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def chain_weights(s, bones, cuts, widths):
    """s: (N,) chain coordinate; bones: k names; cuts/widths: k-1 joint coordinates (increasing) and half-widths.
    Returns (N, k) weights."""
    ups = [_smoothstep(c - w, c + w, s) for c, w in zip(cuts, widths)]
    cols = []
    for i in range(len(bones)):
        lo = np.ones_like(s) if i == 0 else ups[i - 1]
        hi = np.zeros_like(s) if i == len(bones) - 1 else ups[i]
        cols.append(lo - hi)
    return np.stack(cols, axis=1)


def _torso_chain(v):  # up the body: y
    return chain_weights(v[:, 1], ["hips", "spine", "chest"], [1.05, 1.25], [0.05, 0.05])


def _neck_chain(v):
    return chain_weights(v[:, 1], ["chest", "neck", "head"], [1.43, 1.53], [0.03, 0.03])


def _leg_chain(side):
    def f(v):  # down the leg: -y
        return chain_weights(-v[:, 1], ["hips", f"thigh_{side}", f"shin_{side}", f"foot_{side}"],
                             [-0.88, -0.48, -0.08], [0.05, 0.05, 0.035])
    return f


def _arm_chain(side):
    def f(v):  # down the arm from the shoulder joint
        s = (v - JOINT_POS[f"upper_arm_{side}"]) @ _ARM_DIR[side]
        return chain_weights(s, [f"shoulder_{side}", f"upper_arm_{side}", f"forearm_{side}"], [0.0, UPPER_ARM],
                             [0.04, 0.04])
    return f


def _foot_weights(v, w, ankle):
    """The foot below the ankle: the shin's share of the ankle blend fades out away from the shin's axis (as the
    shin's own end cap, inside the foot, has it), so the toes and heel move with the foot alone, unsheared."""
    dist = np.hypot(v[:, 0] - ankle[0], v[:, 2] - ankle[2])
    keep = 1.0 - _smoothstep(0.03, 0.06, dist)
    w = w.copy()
    moved = w[:, 2] * (1.0 - keep)
    w[:, 2] -= moved
    w[:, 3] += moved
    return w


def build_parts():
    """Returns [(name, vertices, triangles, weight function returning (bone names, (N, k) weights))]."""
    parts = []
    add = lambda name, vt, chain: parts.append((name, vt[0], vt[1], chain))
    torso_chain = lambda v: (["hips", "spine", "chest"], _torso_chain(v))
    neck_chain = lambda v: (["chest", "neck", "head"], _neck_chain(v))
    add("pelvis", superellipsoid((0.0, 0.93, 0.0), (0.155, 0.10, 0.105), 0.6, 0.7, rings=12, segments=22),
        torso_chain)
    add("torso", superellipsoid((0.0, 1.205, 0.0), (0.17, 0.235, 0.105), 0.55, 0.7, rings=16, segments=24,
                                taper=lambda t: 0.82 + 0.18 * _smoothstep(-1.0, 0.6, t)), torso_chain)
    add("neck", capsule((0.0, 1.40, 0.0), (0.0, 1.54, 0.0), 0.048, 0.044, segments=12, cap_rings=3), neck_chain)
    add("head", superellipsoid((0.0, 1.60, 0.012), (0.085, 0.105, 0.097), 0.9, 0.9, rings=14, segments=20),
        neck_chain)
    for side in ("L", "R"):
        arm = _arm_chain(side)
        arm_bones = [f"shoulder_{side}", f"upper_arm_{side}", f"forearm_{side}"]
        arm_w = lambda v, arm=arm, arm_bones=arm_bones: (arm_bones, arm(v))
        shoulder, d = JOINT_POS[f"upper_arm_{side}"], _ARM_DIR[side]
        elbow, wrist = shoulder + UPPER_ARM * d, shoulder + (UPPER_ARM + FOREARM) * d
        add(f"upper_arm_{side}", capsule(shoulder, elbow, 0.05, 0.04), arm_w)
        add(f"forearm_{side}", capsule(elbow, wrist, 0.04, 0.032), arm_w)
        # the hand: a flattened ellipsoid along the arm (local y), flat across the body's side (local x)
        side_axis = np.cross(d, np.array([0.0, 0.0, 1.0]))
        side_axis /= np.linalg.norm(side_axis)
        axes = np.stack([side_axis, d, np.cross(side_axis, d)], axis=1)
        add(f"hand_{side}", superellipsoid(wrist + 0.075 * d, (0.024, 0.08, 0.045), 0.9, 0.9, rings=8,
                                           segments=12, axes=axes), arm_w)
        leg = _leg_chain(side)
        leg_bones = ["hips", f"thigh_{side}", f"shin_{side}", f"foot_{side}"]
        leg_w = lambda v, leg=leg, leg_bones=leg_bones: (leg_bones, leg(v))
        hip, knee, ankle = (JOINT_POS[f"{j}_{side}"] for j in ("thigh", "shin", "foot"))
        add(f"thigh_{side}", capsule(hip, knee, 0.078, 0.056), leg_w)
        add(f"shin_{side}", capsule(knee, ankle, 0.054, 0.04), leg_w)
        foot_w = lambda v, leg=leg, leg_bones=leg_bones, ankle=ankle: (leg_bones, _foot_weights(v, leg(v), ankle))
        add(f"foot_{side}", superellipsoid(ankle * np.array([1, 0, 1]) + np.array([0.0, 0.042, 0.045]),
                                           (0.048, 0.042, 0.125), 0.6, 0.7, rings=10, segments=18), foot_w)
    return parts


def _vertex_normals(v, t):
    fn = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])  # area-weighted
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, t[:, k], fn)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def build_mesh():
    V, N, T, J, W = [], [], [], [], []
    base = 0
    for name, v, t, chain in build_parts():
        bones, w = chain(v)
        idx = np.array([JOINT_INDEX[b] for b in bones])
        # the (at most 4) largest influences, renormalised
        order = np.argsort(-w, axis=1, kind="stable")[:, :4]
        ww = np.take_along_axis(w, order, axis=1)
        ww[ww < 1e-6] = 0.0
        ww /= ww.sum(axis=1, keepdims=True)
        jj = idx[order]
        if jj.shape[1] < 4:
            jj = np.concatenate([jj, np.zeros((len(v), 4 - jj.shape[1]), np.int64)], axis=1)
            ww = np.concatenate([ww, np.zeros((len(v), 4 - ww.shape[1]))], axis=1)
        jj[ww == 0] = 0  # unused slots: joint 0 with weight 0 (as the glTF validator expects)
        V.append(v), N.append(_vertex_normals(v, t)), T.append(t + base), J.append(jj), W.append(ww)
        base += len(v)
    return (np.concatenate(V), np.concatenate(N), np.concatenate(T), np.concatenate(J), np.concatenate(W))


# ---------------------------------------------------------------------------------------------------------------
# Quaternions (x, y, z, w) and the clips.
def quat(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    h = math.radians(degrees) / 2
    return np.array([*(axis * math.sin(h)), math.cos(h)])


def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz])


X, Y, Z = (1, 0, 0), (0, 1, 0), (0, 0, 1)
WALK_PERIOD, WALK_KEYS = 1.1, 30  # 30 intervals: 31 keys, the last a copy of the first


def walk_pose(t):
    """Local rotations (and the hips' translation) at time t of the walk. The left leg swings forward as sin(p)."""
    p = 2 * math.pi * t / WALK_PERIOD
    rot, legs = {}, {}
    for side, ph in (("L", p), ("R", p + math.pi)):
        thigh = -25.0 * math.sin(ph)  # about X: negative swings the foot forward (+Z)
        knee = 8.0 + 47.0 * ((1 + math.cos(ph + 0.45)) / 2) ** 3  # flexes most early in the swing
        ankle = -0.8 * (thigh + knee)  # keeps the foot near flat; rolls the toes down at push-off
        rot[f"thigh_{side}"] = quat(X, thigh)
        rot[f"shin_{side}"] = quat(X, knee)
        rot[f"foot_{side}"] = quat(X, ankle)
        legs[side] = (thigh, knee)
        arm = 18.0 * math.sin(ph)  # counter-swing: the arm goes back as its leg goes forward
        tilt = 1.0 if side == "L" else -1.0
        rot[f"upper_arm_{side}"] = qmul(quat(Z, 3.0 * tilt), quat(X, arm))
        rot[f"forearm_{side}"] = quat(X, -(14.0 + 14.0 * (1 - math.sin(ph)) / 2))
    # the hips ride on the lower of the two ankles (kept at its bind height): a bob of ~5 cm, lowest at heel strike
    l1 = JOINT_POS["thigh_L"][1] - JOINT_POS["shin_L"][1]
    l2 = JOINT_POS["shin_L"][1] - JOINT_POS["foot_L"][1]
    reach = max(l1 * math.cos(math.radians(a)) + l2 * math.cos(math.radians(a + b)) for a, b in legs.values())
    hips_t = JOINT_POS["hips"] + np.array([-0.025 * math.cos(p), reach - (l1 + l2), 0.0])
    rot["hips"] = qmul(quat(Y, -6.0 * math.sin(p)), quat(Z, -4.0 * math.cos(p)))
    rot["spine"] = qmul(quat(Y, 4.0 * math.sin(p)), quat(Z, 2.5 * math.cos(p)))
    rot["chest"] = qmul(quat(Y, 5.0 * math.sin(p)), quat(X, 3.0))
    rot["neck"] = qmul(quat(Y, -3.0 * math.sin(p)), quat(X, -2.0))
    rot["head"] = quat(Z, 1.5 * math.cos(p))
    return rot, hips_t


WAVE_PERIOD, WAVE_KEYS = 2.0, 48


def wave_pose(t):
    e = _smoothstep(0.0, 0.4, t) * (1 - _smoothstep(1.6, 2.0, t))
    e = float(e)
    w = math.sin(2 * math.pi * max(0.0, t - 0.4) / 0.4)  # three waves between 0.4 s and 1.6 s
    rot = {"shoulder_R": quat(Z, -20.0 * e), "upper_arm_R": qmul(quat(Z, -115.0 * e), quat(X, -12.0 * e)),
           "forearm_R": quat(Z, e * (-25.0 + 28.0 * w)),
           "chest": quat(Z, 3.0 * e), "head": quat(Z, 6.0 * e)}
    return rot, None


def sample_clip(pose, period, keys):
    times = [period * k / keys for k in range(keys + 1)]
    frames = [pose(t) for t in times[:-1]]
    frames.append(frames[0])  # the loop closes exactly: the last key is the first
    names = sorted(frames[0][0], key=lambda n: JOINT_INDEX[n])
    rotations = {}
    for n in names:
        q = np.array([f[0][n] for f in frames])
        q /= np.linalg.norm(q, axis=1, keepdims=True)
        for i in range(1, len(q)):  # the shorter arc between keys
            if np.dot(q[i], q[i - 1]) < 0:
                q[i] = -q[i]
        rotations[n] = q
    translation = None if frames[0][1] is None else np.array([f[1] for f in frames])
    return np.array(times), rotations, translation


# ---------------------------------------------------------------------------------------------------------------
# GLB writer.
class _Glb:
    def __init__(self):
        self.bin = bytearray()
        self.views, self.accessors = [], []

    def view(self, data, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            v["target"] = target
        self.bin += data
        self.views.append(v)
        return len(self.views) - 1

    def accessor(self, array, ctype, atype, target=None, minmax=False, normalized=False):
        dtype = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}[ctype]
        a = np.ascontiguousarray(array, dtype=dtype)
        acc = {"bufferView": self.view(a.tobytes(), target), "componentType": ctype, "count": int(a.shape[0]),
               "type": atype}
        if normalized:
            acc["normalized"] = True
        if minmax:
            flat = a.reshape(a.shape[0], -1)
            acc["min"] = [float(x) for x in flat.min(axis=0)]
            acc["max"] = [float(x) for x in flat.max(axis=0)]
        self.accessors.append(acc)
        return len(self.accessors) - 1


def build_glb():
    V, N, T, J, W = build_mesh()
    g = _Glb()
    pos = g.accessor(V, 5126, "VEC3", 34962, minmax=True)
    nrm = g.accessor(N, 5126, "VEC3", 34962)
    jnt = g.accessor(J, 5121, "VEC4", 34962)
    wgt = g.accessor(W, 5126, "VEC4", 34962)
    idx = g.accessor(T.reshape(-1), 5123 if len(V) < 65536 else 5125, "SCALAR", 34963)
    ibm = np.array([np.eye(4) for _ in JOINTS])
    for i, (name, _, _) in enumerate(JOINTS):
        ibm[i, :3, 3] = -JOINT_POS[name]
    ibm_acc = g.accessor(ibm.transpose(0, 2, 1).reshape(len(JOINTS), 16), 5126, "MAT4")  # column-major

    nodes = []
    for name, parent, p in JOINTS:
        local = JOINT_POS[name] - (JOINT_POS[parent] if parent else 0.0)
        node = {"name": name, "translation": [float(x) for x in local], "rotation": [0.0, 0.0, 0.0, 1.0],
                "scale": [1.0, 1.0, 1.0]}
        kids = [i for i, (_, par, _) in enumerate(JOINTS) if par == name]
        if kids:
            node["children"] = kids
        nodes.append(node)
    body = len(nodes)
    nodes.append({"name": "character", "mesh": 0, "skin": 0})

    animations = []
    for clip, pose, period, keys in (("walk", walk_pose, WALK_PERIOD, WALK_KEYS),
                                     ("wave", wave_pose, WAVE_PERIOD, WAVE_KEYS)):
        times, rotations, translation = sample_clip(pose, period, keys)
        tin = g.accessor(times, 5126, "SCALAR", minmax=True)
        samplers, channels = [], []
        tracks = [(n, "rotation", q, "VEC4") for n, q in rotations.items()]
        if translation is not None:
            tracks.insert(0, ("hips", "translation", translation, "VEC3"))
        for n, path, values, atype in tracks:
            samplers.append({"input": tin, "output": g.accessor(values, 5126, atype), "interpolation": "LINEAR"})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": JOINT_INDEX[n], "path": path}})
        animations.append({"name": clip, "samplers": samplers, "channels": channels})

    doc = {
        "asset": {"version": "2.0", "generator": "fluidform scripts/make_character.py"},
        "scene": 0,
        "scenes": [{"name": "character", "nodes": [JOINT_INDEX["hips"], body]}],
        "nodes": nodes,
        "meshes": [{"name": "character", "primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nrm, "JOINTS_0": jnt, "WEIGHTS_0": wgt},
            "indices": idx, "material": 0, "mode": 4}]}],
        "materials": [{"name": "clay", "pbrMetallicRoughness": {"baseColorFactor": [0.55, 0.72, 0.9, 1.0],
                                                                 "metallicFactor": 0.0, "roughnessFactor": 0.6}}],
        "skins": [{"name": "skeleton", "inverseBindMatrices": ibm_acc, "joints": list(range(len(JOINTS))),
                   "skeleton": JOINT_INDEX["hips"]}],
        "animations": animations,
        "buffers": [{"byteLength": 0}],
        "bufferViews": g.views,
        "accessors": g.accessors,
    }
    while len(g.bin) % 4:
        g.bin.append(0)
    doc["buffers"][0]["byteLength"] = len(g.bin)
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    total = 12 + 8 + len(js) + 8 + len(g.bin)
    out = struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(js), 0x4E4F534A) + js
    out += struct.pack("<II", len(g.bin), 0x004E4942) + bytes(g.bin)
    return out, {"vertices": int(len(V)), "triangles": int(len(T)), "parts": len(build_parts()),
                 "joints": len(JOINTS), "clips": [a["name"] for a in animations]}


def write_atomic(path, data):
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".character-", suffix=".tmp", dir=d)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # as open() would have made it (mkstemp makes 0600)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


# ---------------------------------------------------------------------------------------------------------------
# --check: reads the file back (not the generator's arrays) and checks what a consumer relies on.
def read_glb(data):
    magic, version, length = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67 or version != 2 or length != len(data):
        raise ValueError("not a glTF 2.0 binary of the right length")
    jl, jt = struct.unpack_from("<II", data, 12)
    if jt != 0x4E4F534A:
        raise ValueError("first chunk is not JSON")
    doc = json.loads(data[20:20 + jl])
    bl, bt = struct.unpack_from("<II", data, 20 + jl)
    if bt != 0x004E4942:
        raise ValueError("second chunk is not BIN")
    blob = data[28 + jl:28 + jl + bl]
    ncomp = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
    dtypes = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}

    def acc(i):
        a = doc["accessors"][i]
        v = doc["bufferViews"][a["bufferView"]]
        if "byteStride" in v:
            raise ValueError("strided views are not expected")
        dt = np.dtype(dtypes[a["componentType"]])
        k = ncomp[a["type"]]
        off = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        if off + a["count"] * k * dt.itemsize > v.get("byteOffset", 0) + v["byteLength"]:
            raise ValueError(f"accessor {i} runs past its buffer view")
        arr = np.frombuffer(blob, dtype=dt, count=a["count"] * k, offset=off)
        return arr.reshape(a["count"], k) if k > 1 else arr
    return doc, acc


def _components(nv, tris):
    parent = np.arange(nv)

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for a, b, c in tris:
        ra, rb, rc = find(a), find(b), find(c)
        parent[rb] = ra
        parent[find(rc)] = find(ra)
    roots = np.array([find(i) for i in range(nv)])
    return roots


def _trs(t, r, s):
    x, y, z, w = r
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    M = np.eye(4)
    M[:3, :3] = R * np.asarray(s)[None, :]
    M[:3, 3] = t
    return M


def _interp(times, values, t, path):
    i = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2))
    u = float(np.clip((t - times[i]) / (times[i + 1] - times[i]), 0.0, 1.0))
    a, b = values[i].astype(np.float64), values[i + 1].astype(np.float64)
    if path == "rotation":
        if np.dot(a, b) < 0:
            b = -b
        q = (1 - u) * a + u * b  # nlerp: close to slerp at these key spacings
        return q / np.linalg.norm(q)
    return (1 - u) * a + u * b


def check(data):
    """Returns (failures, figures)."""
    fails, figs = [], {}
    doc, acc = read_glb(data)
    prim = doc["meshes"][0]["primitives"][0]
    at = prim["attributes"]
    V = acc(at["POSITION"]).astype(np.float64)
    Nn = acc(at["NORMAL"]).astype(np.float64)
    J = acc(at["JOINTS_0"]).astype(np.int64)
    W = acc(at["WEIGHTS_0"]).astype(np.float64)
    T = acc(prim["indices"]).astype(np.int64).reshape(-1, 3)
    skin = doc["skins"][0]
    nj = len(skin["joints"])
    if T.min() < 0 or T.max() >= len(V):
        fails.append(f"indices out of range [0, {len(V)})")
    if J.max() >= nj:
        fails.append(f"JOINTS_0 out of range [0, {nj})")
    if fails:  # nothing further can be read safely
        return fails, figs
    if not np.all(np.isfinite(W)) or W.min() < 0:
        fails.append("WEIGHTS_0 not finite and non-negative")
    wsum = W.sum(axis=1)
    if np.abs(wsum - 1).max() > 1e-6:
        fails.append(f"weights do not sum to 1 (worst {np.abs(wsum - 1).max():.2e})")
    for r in np.nonzero([len(set(j[w > 0])) != int((w > 0).sum()) for j, w in zip(J, W)])[0][:1]:
        fails.append(f"vertex {r} names a joint twice")
    if np.abs(np.linalg.norm(Nn, axis=1) - 1).max() > 1e-4:
        fails.append("normals not unit length")
    area2 = np.linalg.norm(np.cross(V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]]), axis=1)
    if area2.min() < 1e-10:
        fails.append(f"degenerate triangle (area {area2.min() / 2:.1e})")
    figs["height"] = round(float(V[:, 1].max() - V[:, 1].min()), 4)
    figs["min_y"] = round(float(V[:, 1].min()), 6)
    if not (1.6 <= figs["height"] <= 1.8) or abs(figs["min_y"]) > 1e-3:
        fails.append(f"not ~1.7 m tall with the feet at y = 0 (height {figs['height']}, min y {figs['min_y']})")

    # parts: connected components, each closed (every directed edge once, with its reverse once), genus 0, outward
    roots = _components(len(V), T)
    part_of_tri = roots[T[:, 0]]
    parts = sorted(set(part_of_tri.tolist()))
    figs["parts"] = len(parts)
    part_tris = {p: T[part_of_tri == p] for p in parts}
    for k, p in enumerate(parts):
        t = part_tris[p]
        directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        keys = directed[:, 0] * len(V) + directed[:, 1]
        rev = directed[:, 1] * len(V) + directed[:, 0]
        uniq, counts = np.unique(keys, return_counts=True)
        if counts.max() > 1 or not np.all(np.isin(rev, uniq)):
            fails.append(f"part {k} is not a closed, consistently wound 2-manifold")
            continue
        nv = len(np.unique(t))
        euler = nv - len(directed) // 2 + len(t)
        if euler != 2:
            fails.append(f"part {k} has Euler characteristic {euler}, not 2")
        if _signed_volume(V, t) <= 0:
            fails.append(f"part {k} is wound inward")

    # skeleton: inverse bind matrices undo the joints' world bind matrices
    nodes = doc["nodes"]
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}

    def world(i, local):
        M = local[i]
        while i in parent:
            i = parent[i]
            M = local[i] @ M
        return M
    rest = {i: _trs(n.get("translation", [0, 0, 0]), n.get("rotation", [0, 0, 0, 1]), n.get("scale", [1, 1, 1]))
            for i, n in enumerate(nodes)}
    ibm = acc(skin["inverseBindMatrices"]).astype(np.float64).reshape(nj, 4, 4).transpose(0, 2, 1)
    bind = np.array([world(j, rest) for j in skin["joints"]])
    if np.abs(bind @ ibm - np.eye(4)).max() > 1e-5:
        fails.append("inverse bind matrices do not match the joints' bind pose")

    # clips: loop closed, unit quaternions; posed by LBS, parts stay closed-shaped (volume, edge stretch)
    edges = np.unique(np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1), axis=0)
    rest_len = np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1)
    rest_vol = {p: _signed_volume(V, part_tris[p]) for p in parts}
    figs["clips"] = {}
    for anim in doc.get("animations", []):
        tracks = []
        duration = 0.0
        for ch in anim["channels"]:
            s = anim["samplers"][ch["sampler"]]
            times = acc(s["input"]).astype(np.float64)
            values = acc(s["output"])
            path = ch["target"]["path"]
            if np.any(np.diff(times) <= 0):
                fails.append(f"{anim['name']}: key times not increasing")
            if not np.array_equal(values[0], values[-1]):
                fails.append(f"{anim['name']}: {nodes[ch['target']['node']]['name']} {path}: first key != last")
            if path == "rotation" and np.abs(np.linalg.norm(values.astype(np.float64), axis=1) - 1).max() > 1e-5:
                fails.append(f"{anim['name']}: non-unit quaternion")
            tracks.append((ch["target"]["node"], path, times, values))
            duration = max(duration, float(times[-1]))
        worst_stretch, worst_squeeze, worst_vol = 1.0, 1.0, 0.0
        for t in np.linspace(0.0, duration, 12, endpoint=False) + duration / 24:
            local = dict(rest)
            trs = {i: [n.get("translation", [0, 0, 0]), n.get("rotation", [0, 0, 0, 1]), n.get("scale", [1, 1, 1])]
                   for i, n in enumerate(nodes)}
            for node, path, times, values in tracks:
                trs[node][{"translation": 0, "rotation": 1, "scale": 2}[path]] = _interp(times, values, t, path)
            local = {i: _trs(*v) for i, v in trs.items()}
            skinning = np.array([world(j, local) for j in skin["joints"]]) @ ibm
            M = np.einsum("vk,vkij->vij", W, skinning[J])
            P = np.einsum("vij,vj->vi", M[:, :3, :3], V) + M[:, :3, 3]
            ratio = np.linalg.norm(P[edges[:, 0]] - P[edges[:, 1]], axis=1) / rest_len
            worst_stretch = max(worst_stretch, float(ratio.max()))
            worst_squeeze = min(worst_squeeze, float(ratio.min()))
            for p in parts:
                worst_vol = max(worst_vol, abs(_signed_volume(P, part_tris[p]) / rest_vol[p] - 1))
        figs["clips"][anim["name"]] = {"duration": round(duration, 4), "channels": len(tracks),
                                       "keys": int(len(tracks[0][2])), "max_edge_stretch": round(worst_stretch, 3),
                                       "min_edge_ratio": round(worst_squeeze, 3),
                                       "max_part_volume_change": round(worst_vol, 3)}
        if worst_stretch > 2.5 or worst_squeeze < 0.1 or worst_vol > 0.15:
            fails.append(f"{anim['name']}: skinning tears or crushes a part (edge stretch {worst_stretch:.2f}, "
                         f"squeeze {worst_squeeze:.2f}, volume change {worst_vol:.0%})")
    names = [a["name"] for a in doc.get("animations", [])]
    if "walk" not in names:
        fails.append("no clip named walk")
    elif not 1.0 <= figs["clips"]["walk"]["duration"] <= 1.2:
        fails.append("walk is not 1.0–1.2 s long")
    return fails, figs


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(here, "..", "examples", "generated", "character.glb"))
    ap.add_argument("--check", action="store_true", help="read the written file back and check it")
    args = ap.parse_args()
    data, info = build_glb()
    write_atomic(args.out, data)
    info = {"file": os.path.normpath(args.out), "bytes": len(data), **info}
    status = 0
    if args.check:
        with open(args.out, "rb") as f:
            try:
                fails, figs = check(f.read())
            except (ValueError, KeyError, IndexError, struct.error) as e:
                fails, figs = [f"the file does not read back: {e}"], {}
        info["check"] = "ok" if not fails else "FAILED"
        info.update(figs)
        for msg in fails:
            print(f"make_character: check failed: {msg}", file=sys.stderr)
        status = 1 if fails else 0
    print(json.dumps(info))
    return status


if __name__ == "__main__":
    sys.exit(main())
