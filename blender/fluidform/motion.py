# Blender transforms → fluidform scene terms. Needs only mathutils (Blender's, or the standalone package).
#
# Axes: Blender is Z-up, fluidform's scenes are Y-up (gravity along −y, as glTF and the OBJ/PC2 outputs), so a
# Blender point (x, y, z) is the scene point (x, z, −y): the inverse of what Blender's OBJ and glTF importers do.
#
# A target's keyframe (control/target_motion.h) is a pose about the target's pivot, the centre of the rest
# mesh's bounding box:   x = pivot + translate + s R (x_rest − pivot),   R = R_z R_y R_x (degrees)
# The rest mesh is the object at the start frame, in scene coordinates; the pose at frame f is the object's
# motion since then, A(f) = C M(f) M(start)⁻¹ C⁻¹, which gives s (uniform), R and translate = A(pivot) − pivot.
import math

from mathutils import Matrix, Vector

# Blender world → scene coordinates.
Z_UP_TO_Y_UP = Matrix(((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, -1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
Y_UP_TO_Z_UP = Z_UP_TO_Y_UP.inverted()

# Keyframes closer than these to the straight line between their neighbours are dropped.
TRANSLATE_TOLERANCE = 1e-5  # m
ROTATE_TOLERANCE = 1e-3  # degrees
SCALE_TOLERANCE = 1e-6


def to_scene(point):
    """A Blender world point as scene coordinates."""
    return Vector((point[0], point[2], -point[1]))


def pose_of(motion, pivot, previous_euler=None):
    """The keyframe values (translate, rotate in degrees, scale, non-uniformity) of the scene-space motion matrix
    `motion` about `pivot`; `previous_euler` keeps the angles continuous (no 360° jumps between samples)."""
    linear = motion.to_3x3()
    columns = [linear.col[k].length for k in range(3)]
    det = linear.determinant()
    scale = abs(det) ** (1.0 / 3.0) if det != 0.0 else 0.0
    rotation = linear * (1.0 / scale) if scale > 0.0 else Matrix.Identity(3)
    rotation = rotation.normalized()
    euler = rotation.to_euler("XYZ", previous_euler) if previous_euler is not None else rotation.to_euler("XYZ")
    translate = motion @ Vector(pivot) - Vector(pivot)
    spread = (max(columns) - min(columns)) / scale if scale > 0.0 else 0.0
    return {"translate": tuple(translate), "rotate": tuple(math.degrees(a) for a in euler), "scale": scale,
            "euler": euler, "non_uniform": spread}


def keyframes(times, world_matrices, pivot):
    """Scene keyframes of an object from its world matrices at `times` (s from the start, increasing; the first
    is the rest pose). Returns (keyframes, warnings); no keyframes when the object does not move."""
    if not world_matrices:
        return [], []
    rest_inv = world_matrices[0].inverted_safe()
    poses = []
    euler = None
    worst_spread = 0.0
    for t, m in zip(times, world_matrices):
        motion = Z_UP_TO_Y_UP @ m @ rest_inv @ Y_UP_TO_Z_UP
        p = pose_of(motion, pivot, euler)
        euler = p["euler"]
        worst_spread = max(worst_spread, p["non_uniform"])
        poses.append((t, p))
    warnings = []
    if worst_spread > 0.01:
        warnings.append(f"its animated scale is not uniform (up to {100 * worst_spread:.0f} % apart); "
                        "the target scales uniformly")
    if min(p["scale"] for _, p in poses) <= 1e-6:
        warnings.append("its animated scale reaches zero; kept at the smallest positive scale")
    keys = [{"time": round(t, 9), "translate": [round(c, 7) for c in p["translate"]],
             "rotate": [round(a, 6) for a in p["rotate"]], "scale": round(max(p["scale"], 1e-6), 9)}
            for t, p in poses]
    keys = simplify(keys)
    if all(is_rest(k) for k in keys):
        return [], warnings
    return keys, warnings


def is_rest(key):
    return (max(abs(c) for c in key["translate"]) <= TRANSLATE_TOLERANCE and
            max(abs(a) for a in key["rotate"]) <= ROTATE_TOLERANCE and abs(key["scale"] - 1.0) <= SCALE_TOLERANCE)


def _off_line(a, b, k):
    """Whether keyframe k is further than the tolerances from the linear interpolation of a and b at its time."""
    u = (k["time"] - a["time"]) / (b["time"] - a["time"])
    lerp = lambda x, y: x + u * (y - x)  # noqa: E731
    if any(abs(lerp(x, y) - z) > TRANSLATE_TOLERANCE for x, y, z in zip(a["translate"], b["translate"], k["translate"])):
        return True
    if any(abs(lerp(x, y) - z) > ROTATE_TOLERANCE for x, y, z in zip(a["rotate"], b["rotate"], k["rotate"])):
        return True
    return abs(lerp(a["scale"], b["scale"]) - k["scale"]) > SCALE_TOLERANCE


def simplify(keys):
    """Drops the keyframes that linear interpolation between the kept ones reproduces (fluidform interpolates
    linearly): a straight move sampled every frame becomes its two ends; a standing start or end stays."""
    if len(keys) <= 2:
        return keys
    kept = [keys[0]]
    anchor = 0
    j = anchor + 2
    while j < len(keys):
        if any(_off_line(keys[anchor], keys[j], keys[k]) for k in range(anchor + 1, j)):
            anchor = j - 1
            kept.append(keys[anchor])
        j += 1
    kept.append(keys[-1])
    # A motionless tail (the pose held after the last move) needs only its first key: fluidform holds the last pose.
    while len(kept) >= 2 and _same_pose(kept[-1], kept[-2]):
        kept.pop()
    return kept


def _same_pose(a, b):
    return (all(abs(x - y) <= TRANSLATE_TOLERANCE for x, y in zip(a["translate"], b["translate"])) and
            all(abs(x - y) <= ROTATE_TOLERANCE for x, y in zip(a["rotate"], b["rotate"])) and
            abs(a["scale"] - b["scale"]) <= SCALE_TOLERANCE)
