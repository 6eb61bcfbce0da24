"""Shape descriptions: the dicts of the YAML config and the Python API, validated and
packed into the flat tables the kernels read.

A shape is a dict with a ``type`` and its dimensions, in metres, in the body frame:

=========  ==============================================  ===========================
type       keys                                            notes
=========  ==============================================  ===========================
sphere     ``radius``
ellipsoid  ``radii: [a, b, c]``                            semi-axes along x, y, z
box        ``size: [x, y, z]``                             full side lengths
capsule    ``radius``, ``length``                          segment length along z,
                                                           caps excluded
cylinder   ``radius``, ``height``                          along z, centred
cone       ``radius``, ``height``                          along z, centred, tip at +z
convex     ``points: [[x, y, z], ...]`` or ``mesh: f.obj``  the hull of the points
plane      ``normal: [nx, ny, nz]``, ``offset: d``         the half-space n.x <= d
=========  ==============================================  ===========================

A convex shape keeps only the points its hull needs: a point strictly inside the hull of
the others is dropped when the shape is built (mkcollision_ros.hull; no support point
changes, every pass over the points gets shorter), and a hull of many points is stored in
groups of nearby points whose bounding balls let the support skip most of them, one of
at most 64 points with its faces, edges and vertices (the exact ellipsoid-hull kernel,
kernels/pairs/ellipsoid_convex.py).
Any shape may add ``margin: m`` (>= 0): the shape grown by a sphere of radius m.
Invalid input raises ``ValueError`` with a message naming the shape and the key.
"""
import math
import os
from typing import NamedTuple

import numpy as np

from .hull import fan_rows, hull_points
from .kernels.constants import (BOX, CAPSULE, CONE, CONVEX, CYLINDER, ELLIPSOID,
                                N_PARAMS, P_FAN_EDGES, P_FAN_FACES, P_FAN_VERTS,
                                P_GROUPS, P_MARGIN, P_RADIUS, P_ROLL, PLANE,
                                SHAPE_NAMES, SPHERE)

SHAPE_CODES = {name: code for code, name in enumerate(SHAPE_NAMES)}
_KEYS = {
    "sphere": {"radius"}, "ellipsoid": {"radii"}, "box": {"size"},
    "capsule": {"radius", "length"}, "cylinder": {"radius", "height"},
    "cone": {"radius", "height"}, "convex": {"points", "mesh"},
    "plane": {"normal", "offset"},
}


class ShapeTable(NamedTuple):
    """Every shape of a scene as flat arrays (the kernels' view).

    codes  int64 (N,)      shape-type code (constants.SPHERE ...)
    params float64 (N, 8)  parameter rows, layout in kernels/geometry.py
    vrange int64 (N, 2)    (first vertex, vertex count) in ``verts`` for convex shapes
    verts  float64 (M, 3)  convex hull vertices, body frame, metres; a hull stored in
                           groups (params[i, P_GROUPS] > 0) has two rows per group right
                           after its vertices (mkcollision_ros.hull.support_groups), a
                           small hull with its normal fan (params[i, P_FAN_FACES] > 0)
                           the fan's rows there instead (mkcollision_ros.hull.fan_rows)
    """
    codes: np.ndarray
    params: np.ndarray
    vrange: np.ndarray
    verts: np.ndarray


def _number(shape, key, positive=True):
    value = shape.get(key)
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{shape.get('type')} shape: '{key}' must be a number, got {value!r}")
    if not math.isfinite(x):
        raise ValueError(f"{shape.get('type')} shape: '{key}' must be finite, got {x}")
    if positive and not x > 0.0:
        raise ValueError(f"{shape.get('type')} shape: '{key}' must be > 0, got {x}")
    return x


def _vector(shape, key, n, positive=True):
    value = shape.get(key)
    try:
        v = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{shape.get('type')} shape: '{key}' must be {n} numbers, got {value!r}")
    if v.shape != (n,):
        raise ValueError(f"{shape.get('type')} shape: '{key}' must be {n} numbers, got {value!r}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{shape.get('type')} shape: '{key}' must be finite, got {value!r}")
    if positive and not np.all(v > 0.0):
        raise ValueError(f"{shape.get('type')} shape: '{key}' must be > 0, got {value!r}")
    return v


def load_obj_vertices(path):
    """Vertices (M, 3) of a Wavefront OBJ file (``v x y z`` lines; faces are ignored,
    since the shape is the convex hull of the vertices)."""
    pts = []
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("v "):
                parts = line.split()
                pts.append([float(parts[1]), float(parts[2]), float(parts[3])])
    if not pts:
        raise ValueError(f"convex shape: mesh {path!r} has no 'v' vertex lines")
    return np.asarray(pts, dtype=np.float64)


def shape_row(shape, base_dir=None, prune=True):
    """Validate one shape dict; return (code, params float64[8], vertices (M, 3)).
    ``prune``: a convex shape drops the points strictly inside its hull
    (mkcollision_ros.hull; False keeps every point, for comparisons)."""
    if not isinstance(shape, dict):
        raise ValueError(f"a shape must be a dict with a 'type', got {shape!r}")
    kind = shape.get("type")
    if kind not in SHAPE_CODES:
        raise ValueError(f"unknown shape type {kind!r}; expected one of {', '.join(SHAPE_NAMES)}")
    unknown = set(shape) - _KEYS[kind] - {"type", "margin"}
    if unknown:
        raise ValueError(f"{kind} shape: unknown key(s) {sorted(unknown)}; "
                         f"expected {sorted(_KEYS[kind] | {'margin'})}")
    margin = _number(shape, "margin", positive=False) if "margin" in shape else 0.0
    if margin < 0.0:
        raise ValueError(f"{kind} shape: 'margin' must be >= 0, got {margin}")
    prm = np.zeros(N_PARAMS)
    verts = np.zeros((0, 3))
    code = SHAPE_CODES[kind]
    if code == SPHERE:
        prm[0] = _number(shape, "radius")
        radius = prm[0]
    elif code == ELLIPSOID:
        prm[:3] = _vector(shape, "radii", 3)
        radius = prm[:3].max()
        # the smallest radius of curvature of the surface, c_min^2 / a_max: a ball of
        # this radius rolls freely inside, so the ellipsoid is a core grown by it
        # (kernels/geometry.py), which GJK/EPA resolve in fewer steps
        prm[P_ROLL] = prm[:3].min() ** 2 / radius
    elif code == BOX:
        prm[:3] = 0.5 * _vector(shape, "size", 3)
        radius = float(np.linalg.norm(prm[:3]))
    elif code == CAPSULE:
        prm[0] = _number(shape, "radius")
        prm[1] = 0.5 * _number(shape, "length", positive=False)
        if prm[1] < 0.0:
            raise ValueError(f"capsule shape: 'length' must be >= 0, got {2 * prm[1]}")
        radius = prm[0] + prm[1]
    elif code in (CYLINDER, CONE):
        prm[0] = _number(shape, "radius")
        prm[1] = 0.5 * _number(shape, "height")
        radius = math.hypot(prm[0], prm[1])
    elif code == CONVEX:
        if ("points" in shape) == ("mesh" in shape):
            raise ValueError("convex shape: give exactly one of 'points' or 'mesh'")
        if "mesh" in shape:
            path = str(shape["mesh"])
            if base_dir is not None and not os.path.isabs(path):
                path = os.path.join(base_dir, path)
            verts = load_obj_vertices(path)
        else:
            try:
                verts = np.asarray(shape["points"], dtype=np.float64)
            except (TypeError, ValueError):
                raise ValueError("convex shape: 'points' must be a list of [x, y, z]")
        if verts.ndim != 2 or verts.shape[1] != 3 or len(verts) < 1:
            raise ValueError(f"convex shape: 'points' must be a non-empty list of [x, y, z], "
                             f"got shape {verts.shape}")
        if not np.all(np.isfinite(verts)):
            raise ValueError("convex shape: points must be finite")
        fan = np.zeros((0, 3))
        if prune:
            verts, groups = hull_points(verts)
            prm[P_GROUPS] = len(groups) // 2
            if len(groups) == 0:
                # the hull's faces, edges and vertices for the exact ellipsoid-hull
                # kernel (kernels/pairs/ellipsoid_convex.py; small hulls only, none when degenerate)
                nf, ne, nv, fan = fan_rows(verts)
                prm[P_FAN_FACES], prm[P_FAN_EDGES], prm[P_FAN_VERTS] = nf, ne, nv
        radius = float(np.linalg.norm(verts, axis=1).max())
    else:  # PLANE
        n = _vector(shape, "normal", 3, positive=False)
        norm = float(np.linalg.norm(n))
        if not norm > 0.0:
            raise ValueError("plane shape: 'normal' must be non-zero")
        prm[:3] = n / norm
        prm[3] = _number(shape, "offset", positive=False) / norm
        radius = 0.0
    prm[P_MARGIN] = margin
    prm[P_RADIUS] = radius + margin if code != PLANE else 0.0
    if code == CONVEX and prm[P_GROUPS] > 0:
        verts = np.concatenate([verts, groups])
    elif code == CONVEX and prm[P_FAN_FACES] > 0:
        verts = np.concatenate([verts, fan])
    return code, prm, verts


def point_count(code, prm, verts):
    """How many of ``shape_row``'s rows ``verts`` are the shape's points (the rest, a
    large hull's group rows, mkcollision_ros.hull.support_groups, or a small hull's
    normal fan, mkcollision_ros.hull.fan_rows)."""
    if code != CONVEX:
        return len(verts)
    nf, ne, nv = int(prm[P_FAN_FACES]), int(prm[P_FAN_EDGES]), int(prm[P_FAN_VERTS])
    fan = nf + (nf + nv + 4 * ne + 2) // 3 if nf > 0 else 0
    return len(verts) - 2 * int(prm[P_GROUPS]) - fan


def build_table(shapes, base_dir=None, prune=True):
    """Pack a list of shape dicts into a ``ShapeTable`` (``prune``: as ``shape_row``)."""
    codes, params, vrange, chunks = [], [], [], []
    start = 0
    for shape in shapes:
        code, prm, verts = shape_row(shape, base_dir, prune)
        codes.append(code)
        params.append(prm)
        vrange.append((start, point_count(code, prm, verts)))
        chunks.append(verts)
        start += len(verts)
    return ShapeTable(
        codes=np.asarray(codes, dtype=np.int64).reshape(-1),
        params=np.asarray(params, dtype=np.float64).reshape(-1, N_PARAMS),
        vrange=np.asarray(vrange, dtype=np.int64).reshape(-1, 2),
        verts=np.concatenate(chunks).reshape(-1, 3) if chunks else np.zeros((0, 3)),
    )


def validate_pose(pose, what="pose"):
    """Check a ``(position [x, y, z], quat_xyzw [x, y, z, w])`` pose; return float64
    arrays (3,), (4,) with the quaternion normalised.  Raises ValueError on wrong
    lengths, NaN/Inf or a zero quaternion."""
    try:
        position, quat = pose
        p = np.asarray(position, dtype=np.float64)
        q = np.asarray(quat, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected (position [x, y, z], quaternion [x, y, z, w]), "
                         f"got {pose!r}")
    if p.shape != (3,) or q.shape != (4,):
        raise ValueError(f"{what}: position needs 3 numbers and quaternion 4, got "
                         f"{p.shape} and {q.shape}")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(q))):
        raise ValueError(f"{what}: position and quaternion must be finite")
    n = float(np.linalg.norm(q))
    if not n > 1e-12:
        raise ValueError(f"{what}: zero quaternion")
    return p, q / n
