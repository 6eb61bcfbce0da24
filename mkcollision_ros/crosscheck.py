"""Second opinions on a scene's pairs, and repros that can become regression tests.
Plain Python + numba kernels, no ROS.

``cross_check`` runs MPR and GJK/EPA on the same pairs at the same poses and reports
where they disagree: on whether the pair touches, on the depth by more than
``depth_tol`` (m), or on the normal by more than ``angle_tol`` (rad).  ``repro`` (a
scene's pair) and ``repro_call`` (two shape dicts at world poses) write one pair as a
line of Python, every number at 17 significant digits (exact for float64), that calls
``mkcollision_ros.collide`` on the same shapes and poses.
"""
import math
from typing import NamedTuple

import numpy as np

from .kernels.constants import (M_GJK_EPA, M_MPR, METHOD_NAMES, OUT_DIST, OUT_NORMAL,
                                OUT_SIZE, PLANE, ST_PENETRATING, ST_TOUCHING)
from .kernels.narrowphase import collide_batch


class Disagreement(NamedTuple):
    """One pair where MPR and GJK/EPA differ: slots a < b, each method's status and
    depth (m), and the angle between their normals (rad; nan when either is apart)."""
    a: int
    b: int
    status_mpr: int
    status_gjk_epa: int
    depth_mpr: float
    depth_gjk_epa: float
    angle: float


def _g(x):
    return f"{float(x):.17g}"


def _shape_repr(shape):
    def value(v):
        if isinstance(v, str):
            return repr(v)
        arr = np.asarray(v, float)
        if arr.ndim == 0:
            return _g(arr)
        if arr.ndim == 1:
            return "[" + ", ".join(_g(x) for x in arr) + "]"
        return "[" + ", ".join(value(row) for row in arr) + "]"
    return "{" + ", ".join(f"{k!r}: {value(v)}" for k, v in shape.items()) + "}"


def repro_call(shape_a, pose_a, shape_b, pose_b, method="auto"):
    """A line of Python calling ``collide`` on two shape dicts at world poses
    ``(position (3,), quat_xyzw (4,))``, every number at 17 significant digits."""
    parts = []
    for shape, (pos, quat) in ((shape_a, pose_a), (shape_b, pose_b)):
        parts.append(f"{_shape_repr(shape)}, "
                     f"([{', '.join(_g(x) for x in pos)}], "
                     f"[{', '.join(_g(x) for x in quat)}])")
    return f"collide({parts[0]}, {parts[1]}, method={method!r})"


def repro(scene, a, b, method="auto"):
    """A line of Python reproducing pair (a, b) of ``scene`` at its current poses."""
    return repro_call(scene.body(scene.names[a]).shape,
                      (scene.positions[a], scene.orientations[a]),
                      scene.body(scene.names[b]).shape,
                      (scene.positions[b], scene.orientations[b]), method)


def cross_check(scene, pairs, depth_tol, angle_tol):
    """MPR against GJK/EPA on ``pairs`` (int64 (P, 2) slots) at the scene's poses.
    Pairs with a plane are skipped (neither method takes an unbounded shape).  Returns
    (pairs checked, list of Disagreement)."""
    pairs = np.ascontiguousarray(pairs, np.int64).reshape(-1, 2)
    if len(pairs):
        codes = scene.table.codes
        pairs = np.ascontiguousarray(pairs[(codes[pairs[:, 0]] != PLANE)
                                           & (codes[pairs[:, 1]] != PLANE)])
    n = len(pairs)
    if not n:
        return 0, []
    t = scene.table
    rows = {}
    for method in (M_MPR, M_GJK_EPA):
        out = np.empty((n, OUT_SIZE))
        status = np.empty(n, np.int64)
        collide_batch(t.codes, t.params, t.vrange, t.verts, pairs, scene.positions,
                      scene.orientations, method, 0.0, out, status)
        rows[method] = (out, status)
    (om, sm), (og, sg) = rows[M_MPR], rows[M_GJK_EPA]
    touch_m = (sm == ST_TOUCHING) | (sm == ST_PENETRATING)
    touch_g = (sg == ST_TOUCHING) | (sg == ST_PENETRATING)
    depth_m = np.maximum(0.0, -om[:, OUT_DIST])
    depth_g = np.maximum(0.0, -og[:, OUT_DIST])
    cos = np.sum(om[:, OUT_NORMAL:OUT_NORMAL + 3] * og[:, OUT_NORMAL:OUT_NORMAL + 3], axis=1)
    with np.errstate(invalid="ignore"):
        angle = np.where(touch_m & touch_g, np.arccos(np.clip(cos, -1.0, 1.0)), np.nan)
    bad = (touch_m != touch_g) | (touch_m & touch_g & (
        (np.abs(depth_m - depth_g) > depth_tol) | (angle > angle_tol)))
    out = [Disagreement(int(pairs[k, 0]), int(pairs[k, 1]), int(sm[k]), int(sg[k]),
                        float(depth_m[k]), float(depth_g[k]), float(angle[k]))
           for k in np.flatnonzero(bad)]
    return n, out


def describe(d, scene):
    """One log line for a Disagreement, with repros for both methods."""
    na, nb = scene.names[d.a], scene.names[d.b]
    angle = "n/a" if math.isnan(d.angle) else f"{math.degrees(d.angle):.3g} deg"
    return (f"MPR and GJK/EPA disagree on {na}-{nb}: status {d.status_mpr} / "
            f"{d.status_gjk_epa}, depth {d.depth_mpr:.17g} / {d.depth_gjk_epa:.17g} m, "
            f"normals {angle} apart; repro: {repro(scene, d.a, d.b, METHOD_NAMES[M_MPR])} "
            f"vs method='gjk_epa'")
