"""Regression corpus: configurations reported as failing against other collision
libraries (fcl, libccd, coal, parry, Jolt, MuJoCo), re-derived as scenes with our own
expected values.

The scenes are data: tests/regression_scenes.json (name, source thread, what it tests,
shapes, poses, expected signed distance / normal / witness points, and how the expected
value was derived).  A new scene is added there; nothing here needs editing unless it
needs a new closed form.

Sources and what was (and was not) found in the threads:
  * libccd#25, fcl#275, #319 (both configurations), #390, #391, #398, #493/#495, #508,
    coal#351, parry#378 (a 2-D report: mapped to 3-D, see the scene), Jolt#671 (the repro
    sample linked from the thread, BoxVsConvexHullTest), MuJoCo#2206 (the MJCF and sweep
    of the thread), and further real-world failures that fcl's own signed-distance
    regression tests capture (fcl#388, #395, #408, #415, #428; drake#21673: box-box and
    convex-convex): numeric configurations taken from the threads, or from the fix's
    regression test where the stored thread was cut off (said per scene: fcl#398's
    second box pose; fcl#391's full-precision sphere pose).
  * libccd#71 (ccdMPRPenetration returns a wrong direction): the thread has no numeric
    configuration (a video and code excerpts), so two scenes are CONSTRUCTED to match its
    description (MPR's portal near an edge of the Minkowski difference): say so in their
    'tests' field.

Expected values are derived independently of the library:
  * closed forms (``closed_form``): sphere-sphere, sphere-box, sphere-cylinder, equal
    orientation box-box (A - B is an axis-aligned box in the common frame), two
    cylinders at one pose (depth min(r_a + r_b, (h_a + h_b) / 2)), SAT over the
    15 box-box axes (exact penetration depth of two boxes), two hand-derived
    face-contact scenes (capsule over a slab, box over a hull), and an exact
    enumeration over the Minkowski difference of two polytopes
    (``polytope_signed_distance``, also run on every box/convex scene);
  * hand values (``expected.hand_value``), checked against the closed form;
  * for every scene, the slow support-function search of tests/oracles.py
    (signed distance = -min over unit n of h_A(n) + h_B(-n) - n.(c_B - c_A)).

Checks per scene, for methods "auto" and "gjk_epa": never FAILED / NOT_RUN / NaN; the
touching flag when |d| > 1e-6 * scale (scale = sum of the two bounding radii), and the
library's own touching rule (touching iff distance <= TOUCH_TOL * scale) otherwise;
signed distance within 1e-6 * scale; normal within 1e-3 rad (normal_check 'rule': when
|d| > 1e-3 * scale; 'strict': always, the normal is unique; 'sign': kissing contact,
only not flipped; 'none': tied minimising directions, any of them is right, which the
witness-point checks certify); point_b - point_a == distance * normal; witness points
on the surfaces (each the support point of its shape along +-normal, which makes the
normal a minimising direction); expected witness points where they are unique.  The
same with A and B exchanged.  For "mpr": not FAILED, never NaN, the touching flag when
|d| > 1e-6 * scale, its depth an over-estimate (MPR depth >= true depth - 1e-6 *
scale) and, when it reports separated, its distance a lower bound (0 <= d_mpr <= d).

Bugs found in this library itself get a scene too, named ``mkc_*``, with "found here"
and how it was found as source (every bug found gets its saved scene and a test naming
it): mkc_epa_polish_wrong_basin_ellipsoid_cone (Newton's method in EPA keeping a
shallower local minimum, which an oracle search stopping at a local minimum misses too),
mkc_kink_newton_wrong_basin_cylinder_cylinder and
mkc_kink_newton_close_basin_capsule_cylinder (Newton's method along the creases of
cylinders and capsules would keep local minima 0.33 and 0.047 rad from the deepest
direction), mkc_crease_polish_other_crease_cylinder_cylinder (a crease search over one
cylinder's crease only keeps B's crease minimum 0.19 rad from the deepest direction on
A's), mkc_crease_polish_wrong_basin_ellipsoid_capsule (the same search on a capsule's
crease under a 0.5 rad basin cap keeps a minimum 0.19 rad from a deeper one off the
crease), mkc_crease_polish_wrong_basin_ellipsoid_box (the same on a box's edges: a
minimum 0.20 rad from a deeper one in a vertex's region),
mkc_crease_polish_early_wrong_basin_cylinder_cylinder (the search along a cylinder's
crease started at a gain of 1e-2 * scale would keep a minimum 0.34 rad from the deepest
direction; the same between an ellipsoid and a cylinder:
mkc_crease_polish_early_wrong_basin_ellipsoid_cylinder, 0.25 rad),
mkc_face_polish_wrong_basin_ellipsoid_cylinder (the test of a face normal under a 0.5
rad cap: a minimum on a cylinder's axis 0.31 rad from a deeper one),
mkc_hull_face_polish_wrong_basin_ellipsoid_convex (the same test on a convex hull's face
in EPA under a 0.1 rad cap would keep a minimum 0.077 rad from a deeper one; under the
cap the test proves, _face_basin, it is safe but slower, and EPA does not run it),
mkc_coincident_coaxial_cylinders (two cylinders at one pose: a ring of equally deep
directions, EPA's caps hit; a FAILED answer would be dropped by the pipeline),
mkc_coincident_coaxial_capsules (a world-frame capsule pair whose parallel axes'
round-off cross product must not become the normal) and mkc_point_capsule_on_a_segment
(a zero-length capsule on another's segment, whose normal must not lie along that
segment's axis, even in part).

A failing scene names a bug in the library: the test is kept as is and the failure is
reported; tolerances are not loosened to make a scene pass.
"""
import itertools
import json
import math
import os

import numpy as np
import pytest

import oracles as O
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import TOUCH_TOL
from mkcollision_ros.results import Status
from mkcollision_ros.rotations import matrix_to_quat

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES_PATH = os.path.join(HERE, "regression_scenes.json")
quat_matrix = O.quat_matrix


# --- closed forms (independent of the library) -----------------------------------------
def _frame(pose):
    return np.asarray(pose[0], dtype=np.float64), quat_matrix(np.asarray(pose[1], float))


def _half(box):
    return 0.5 * np.asarray(box["size"], dtype=np.float64)


def _coaxial_cylinders(a, pa, b, pb):
    """Two cylinders with one pose: B leaves across the axis after r_a + r_b, along it
    after (h_a + h_b) / 2.  No unique normal (a ring or a tie of directions)."""
    assert a["type"] == b["type"] == "cylinder"
    assert np.allclose(pa[0], pb[0], atol=0) and np.allclose(pa[1], pb[1], atol=0)
    return (-min(a["radius"] + b["radius"], 0.5 * (a["height"] + b["height"])), None,
            None, None)


def _sphere_sphere(a, pa, b, pb):
    ca, _ = _frame(pa)
    cb, _ = _frame(pb)
    v = cb - ca
    L = np.linalg.norm(v)
    n = v / L
    return L - a["radius"] - b["radius"], n, ca + a["radius"] * n, cb - b["radius"] * n


def _point_box(p, h):
    """Signed distance of a body-frame point to a centred box of half sides h, the
    outward normal and the nearest surface point."""
    q = np.clip(p, -h, h)
    if np.any(np.abs(p) > h):
        v = p - q
        L = np.linalg.norm(v)
        return L, v / L, q
    e = np.abs(p) - h
    k = int(np.argmax(e))
    n = np.zeros(3)
    n[k] = 1.0 if p[k] >= 0 else -1.0
    s = p.copy()
    s[k] = n[k] * h[k]
    return e[k], n, s


def _point_cylinder(p, r, hh):
    """Same for a centred z-axis cylinder of radius r and half height hh."""
    rho = math.hypot(p[0], p[1])
    radial = np.array([p[0] / rho, p[1] / rho, 0.0]) if rho > 0 else np.array([1.0, 0, 0])
    dr, da = rho - r, abs(p[2]) - hh
    sz = 1.0 if p[2] >= 0 else -1.0
    if dr <= 0 and da <= 0:                       # inside: nearest of side and cap
        if dr >= da:
            s = np.array([r * radial[0], r * radial[1], p[2]])
            return dr, radial, s
        return da, np.array([0, 0, sz]), np.array([p[0], p[1], sz * hh])
    q = np.array([p[0], p[1], p[2]])
    if dr > 0:
        q[:2] = r * radial[:2]
    if da > 0:
        q[2] = sz * hh
    v = p - q
    L = np.linalg.norm(v)
    return L, v / L, q


def _sphere_vs(solid, a, pa, b, pb):
    """Sphere b against solid a (box or cylinder): (signed distance, normal A->B, pa, pb)."""
    ca, Ra = _frame(pa)
    cb, _ = _frame(pb)
    p = Ra.T @ (cb - ca)
    if solid == "box":
        d, n, s = _point_box(p, _half(a))
    else:
        d, n, s = _point_cylinder(p, a["radius"], 0.5 * a["height"])
    nw = Ra @ n
    return d - b["radius"], nw, ca + Ra @ s, cb - b["radius"] * nw


def _box_axes(R):
    return [R[:, i] for i in range(3)]


def _box_box(a, pa, b, pb):
    ca, Ra = _frame(pa)
    cb, Rb = _frame(pb)
    ha, hb = _half(a), _half(b)
    if np.allclose(Ra.T @ Rb, np.eye(3), atol=1e-12):
        # equal orientation: A - B is the box of half sides ha + hb about ca - cb
        o = Ra.T @ (cb - ca)
        e = np.abs(o) - (ha + hb)
        if np.any(e > 0):
            v = np.sign(o) * np.maximum(e, 0.0)
            L = np.linalg.norm(v)
            return L, Ra @ (v / L), None, None
        k = int(np.argmax(e))
        n = np.zeros(3)
        n[k] = 1.0 if o[k] >= 0 else -1.0
        return e[k], Ra @ n, None, None
    # SAT: the penetration depth of two boxes is the least overlap over the 15 axes
    axes = _box_axes(Ra) + _box_axes(Rb)
    for u in _box_axes(Ra):
        for v in _box_axes(Rb):
            c = np.cross(u, v)
            if np.linalg.norm(c) > 1e-9:
                axes.append(c / np.linalg.norm(c))
    best = (np.inf, None)
    for u in axes:
        ra = float(np.abs(Ra.T @ u) @ ha)
        rb = float(np.abs(Rb.T @ u) @ hb)
        s = float(u @ (cb - ca))
        overlap = ra + rb - abs(s)
        if overlap < 0:
            raise NotImplementedError("separated boxes of different orientation: use "
                                      "the support_search oracle")
        if overlap < best[0]:
            best = (overlap, u if s >= 0 else -u)
    return -best[0], best[1], None, None


def _capsule_box_vertical(a, pa, b, pb):
    """Capsule A (identity rotation, axis z) above box B (identity rotation) whose top
    face lies under the capsule's lowest point."""
    ca, Ra = _frame(pa)
    cb, Rb = _frame(pb)
    assert np.allclose(Ra, np.eye(3)) and np.allclose(Rb, np.eye(3))
    hb = _half(b)
    low = ca - np.array([0, 0, 0.5 * a["length"] + a["radius"]])
    assert np.all(np.abs(low[:2] - cb[:2]) < hb[:2]), "lowest point not over the face"
    top = cb[2] + hb[2]
    return low[2] - top, np.array([0.0, 0.0, -1.0]), low, np.array([low[0], low[1], top])


def _hull_box_vertical(a, pa, b, pb):
    """Convex A (box-like point set) under box B, face-face across A's +y face, in A's
    frame; B's lowest face must be parallel to A's top and its footprint inside it."""
    ca, Ra = _frame(pa)
    cb, Rb = _frame(pb)
    pts = np.asarray(a["points"], dtype=np.float64)
    hb = _half(b)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * hb
    cw = (Ra.T @ ((Rb @ corners.T).T + cb - ca).T).T          # B's corners in A's frame
    ytop = pts[:, 1].max()
    ylow = cw[:, 1].min()
    bottom = cw[np.abs(cw[:, 1] - ylow) < 1e-9]
    assert len(bottom) == 4, "B's lowest feature is not a face parallel to A's top"
    top_face = pts[np.abs(pts[:, 1] - ytop) < 1e-12]
    lo, hi = top_face.min(axis=0), top_face.max(axis=0)
    assert np.all((bottom[:, [0, 2]] > lo[[0, 2]]) & (bottom[:, [0, 2]] < hi[[0, 2]]))
    return ylow - ytop, Ra @ np.array([0.0, 1.0, 0.0]), None, None


def polytope_points(shape, pose):
    """World-frame vertices of a box or a convex point set."""
    c, R = _frame(pose)
    if shape["type"] == "box":
        h = _half(shape)
        P = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    else:
        P = np.asarray(shape["points"], dtype=np.float64)
    return P @ R.T + c


def polytope_signed_distance(a, pose_a, b, pose_b, with_tie=False):
    """Exact signed distance of two polytopes by enumeration over the Minkowski
    difference D = A - B (all differences of vertices; D is their convex hull).
      * Facets: every triple of points whose plane has all points on one side is a
        supporting plane (outward normal n, offset n.p).  The origin is inside D iff
        every offset is positive, and then the penetration depth is the least offset
        (the minimum over unit n of h_D(n) is attained at a facet normal).
      * Outside: the distance from the origin to D is the least distance to any
        vertex, segment or triangle of points of D (D's boundary is a union of such
        triangles, and each of them lies in D).
    Returns (signed distance, unit normal A -> B), and with with_tie=True also whether
    another facet normal (> 1e-3 rad away) is as deep to 1e-9 * size (penetrating only:
    then the normal is not unique).  Slow: O(N^3) triples, N = |A||B|."""
    PA, PB = polytope_points(a, pose_a), polytope_points(b, pose_b)
    return origin_to_hull((PA[:, None, :] - PB[None, :, :]).reshape(-1, 3), with_tie)


def point_to_polytope(p, shape, pose):
    """Exact signed distance of a world point to a box or convex shape."""
    return origin_to_hull(polytope_points(shape, pose) - np.asarray(p, dtype=np.float64))[0]


def origin_to_hull(D, with_tie=False):
    """Signed distance from the origin to the convex hull of the points D (negative
    inside) and the unit direction from the hull to the origin (outward facet normal
    when inside); see polytope_signed_distance."""
    D = np.unique(np.round(D, 15), axis=0)
    size = float(np.ptp(D, axis=0).max())
    n = len(D)
    i, j, k = np.array(list(itertools.combinations(range(n), 3))).T
    N = np.cross(D[j] - D[i], D[k] - D[i])
    L = np.linalg.norm(N, axis=1)
    ok = L > 1e-12 * size * size
    i, j, k, N = i[ok], j[ok], k[ok], N[ok] / L[ok, None]
    off = np.einsum("ij,ij->i", N, D[i])
    eps = 1e-10 * size
    above = np.zeros(len(N), dtype=bool)
    below = np.zeros(len(N), dtype=bool)
    for s0 in range(0, len(N), 8192):                   # blocks of (8192, n) products
        proj = N[s0:s0 + 8192] @ D.T
        above[s0:s0 + 8192] = (proj > off[s0:s0 + 8192, None] + eps).any(axis=1)
        below[s0:s0 + 8192] = (proj < off[s0:s0 + 8192, None] - eps).any(axis=1)
    sup = ~(above & below)                              # all points on one side
    N_s = np.where(above[sup, None], -N[sup], N[sup])   # orient outward
    off_s = np.where(above[sup], -off[sup], off[sup])
    if np.all(off_s > 0.0):
        m = int(np.argmin(off_s))
        if with_tie:
            near = off_s <= off_s[m] + 1e-9 * size
            tie = bool(np.any(N_s[near] @ N_s[m] < math.cos(1e-3)))
            return -float(off_s[m]), N_s[m], tie
        return -float(off_s[m]), N_s[m]
    # outside: nearest point of D to the origin over vertices, segments, triangles
    best_d, best_c = np.inf, None
    dv = np.linalg.norm(D, axis=1)
    m = int(np.argmin(dv))
    best_d, best_c = dv[m], D[m]
    ii, jj = np.triu_indices(n, 1)
    E = D[jj] - D[ii]
    t = np.clip(-np.einsum("ij,ij->i", D[ii], E) / np.einsum("ij,ij->i", E, E), 0, 1)
    C = D[ii] + t[:, None] * E
    dc = np.linalg.norm(C, axis=1)
    m = int(np.argmin(dc))
    if dc[m] < best_d:
        best_d, best_c = dc[m], C[m]
    Q = off[:, None] * N                                 # origin projected on planes
    e0, e1, e2 = D[i] - Q, D[j] - Q, D[k] - Q
    w0 = np.einsum("ij,ij->i", np.cross(e1, e2), N)
    w1 = np.einsum("ij,ij->i", np.cross(e2, e0), N)
    w2 = np.einsum("ij,ij->i", np.cross(e0, e1), N)
    inside = ((w0 >= 0) & (w1 >= 0) & (w2 >= 0)) | ((w0 <= 0) & (w1 <= 0) & (w2 <= 0))
    if inside.any():
        dt = np.abs(off[inside])
        m = int(np.argmin(dt))
        if dt[m] < best_d:
            best_d, best_c = dt[m], Q[inside][m]
    if best_d <= eps:                                    # touching: a facet normal
        m = int(np.argmin(np.abs(off_s)))
        n_out = N_s[m]
    else:
        n_out = -best_c / best_d
    return (float(best_d), n_out, False) if with_tie else (float(best_d), n_out)


def closed_form(oracle, a, pose_a, b, pose_b):
    """(signed distance, unit normal A->B or None, point_a or None, point_b or None)
    from the named closed form / oracle."""
    ta, tb = a["type"], b["type"]
    if oracle == "sphere_sphere":
        return _sphere_sphere(a, pose_a, b, pose_b)
    if oracle in ("sphere_box", "sphere_cylinder"):
        solid = oracle.split("_")[1]
        if ta == "sphere":
            d, n, p_b, p_a = _sphere_vs(solid, b, pose_b, a, pose_a)
            return d, -n, p_a, p_b
        assert tb == "sphere" and ta == solid
        return _sphere_vs(solid, a, pose_a, b, pose_b)
    if oracle == "box_box":
        return _box_box(a, pose_a, b, pose_b)
    if oracle == "coaxial_cylinders":
        return _coaxial_cylinders(a, pose_a, b, pose_b)
    if oracle == "capsule_box_vertical":
        return _capsule_box_vertical(a, pose_a, b, pose_b)
    if oracle == "hull_box_vertical":
        return _hull_box_vertical(a, pose_a, b, pose_b)
    if oracle == "polytope_exact":
        d, n = polytope_signed_distance(a, pose_a, b, pose_b)
        return d, n, None, None
    if oracle == "support_search":
        d, n = O.signed_distance_oracle(a, pose_a, b, pose_b)
        return d, n / np.linalg.norm(n), None, None
    raise ValueError(oracle)


# --- scenes -------------------------------------------------------------------------------
def load_scenes():
    with open(SCENES_PATH, encoding="utf-8") as f:
        return json.load(f)["scenes"]


SCENES = load_scenes()
IDS = [s["name"] for s in SCENES]


def poses(scene):
    pa = (scene["pose_a"]["position"], scene["pose_a"]["quat_xyzw"])
    pb = (scene["pose_b"]["position"], scene["pose_b"]["quat_xyzw"])
    return pa, pb


def scale_of(scene):
    return O.bounding_radius(scene["shape_a"]) + O.bounding_radius(scene["shape_b"])


def angle(u, v):
    c = float(np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v)))
    return math.acos(max(-1.0, min(1.0, c)))


def describe(r):
    return (f"status={r.status.name} touching={r.touching} distance={r.distance!r} "
            f"normal={np.round(r.normal, 9).tolist()} point_a={np.round(r.point_a, 9).tolist()} "
            f"point_b={np.round(r.point_b, 9).tolist()} method={r.method} iters={r.iterations}")


def check_result(scene, r, pose_a, pose_b, expected_d, method):
    """The assertions shared by a scene and each sample of a sweep."""
    a, b = scene["shape_a"], scene["shape_b"]
    exp = scene["expected"]
    scale = scale_of(scene)
    tol = 1e-6 * scale
    msg = f"{scene['name']} [{method}]: expected distance {expected_d!r}; got {describe(r)}"
    assert r.status not in (Status.FAILED, Status.NOT_RUN), msg
    vals = np.r_[r.distance, r.normal, r.point_a, r.point_b]
    assert np.all(np.isfinite(vals)), msg
    assert abs(np.linalg.norm(r.normal) - 1.0) < 1e-9, msg
    # touching flag
    if abs(expected_d) > tol:
        assert r.touching == (expected_d < 0), msg
        assert r.status == (Status.PENETRATING if expected_d < 0 else Status.SEPARATED), msg
    else:
        assert r.touching == (r.distance <= TOUCH_TOL * scale), msg
    # signed distance
    assert abs(r.distance - expected_d) <= tol, msg
    # normal
    n_exp = exp.get("normal")
    mode = scene.get("normal_check", "rule")
    if mode == "strict" and abs(expected_d) <= tol:
        mode = "sign"           # a sweep sample at kissing contact
    if n_exp is not None:
        if mode == "strict" or (mode == "rule" and abs(expected_d) > 1e-3 * scale):
            assert angle(r.normal, n_exp) < 1e-3, msg + f"; expected normal {n_exp}"
        elif mode == "sign":
            assert float(np.dot(r.normal, n_exp)) > 0.99, msg + f"; expected normal {n_exp}"
    # the convention: point_b - point_a == distance * normal
    assert np.allclose(r.point_b - r.point_a, r.distance * r.normal, atol=tol), msg
    # witness points on the surfaces: each the support point of its shape along +-normal
    gap_a = O.surface_gap(a, pose_a, r.point_a, r.normal)
    gap_b = O.surface_gap(b, pose_b, r.point_b, -r.normal)
    assert abs(gap_a) <= tol and abs(gap_b) <= tol, msg + f"; surface gaps {gap_a!r}, {gap_b!r}"
    # ... and on the shapes themselves, not just on their supporting planes (exact for
    # boxes and convex shapes, a sampled certificate for the others)
    outside = []
    for shape, pose, pt in ((a, pose_a, r.point_a), (b, pose_b, r.point_b)):
        if shape["type"] in ("box", "convex"):
            outside.append(point_to_polytope(pt, shape, pose))
        else:
            outside.append(O.inside_value(shape, pose, pt))
    assert max(outside) <= tol, msg + f"; witness points outside their shapes by {outside}"


# --- the data themselves --------------------------------------------------------------------
def test_quat_from_matrix_round_trips():
    rng = np.random.default_rng(3)
    qs = list(O.random_quats(rng, 500))
    # the branch boundaries of Shepperd's method: half turns and quarter turns
    qs += [np.array(v, float) for v in ([1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0],
                                        [0, 0, 0, 1], [0.5, 0.5, 0.5, 0.5],
                                        [math.sqrt(0.5), 0, 0, math.sqrt(0.5)],
                                        [0, math.sqrt(0.5), math.sqrt(0.5), 0])]
    for q in qs:
        q = q / np.linalg.norm(q)
        R = quat_matrix(q)
        q2 = matrix_to_quat(R)
        assert np.allclose(quat_matrix(q2), R, atol=1e-14)
        assert min(np.linalg.norm(q2 - q), np.linalg.norm(q2 + q)) < 1e-12


def test_scene_file_is_well_formed():
    names = [s["name"] for s in SCENES]
    assert len(names) == len(set(names))
    for s in SCENES:
        for key in ("source", "tests", "shape_a", "shape_b", "pose_a", "pose_b",
                    "expected", "oracle", "derivation"):
            assert key in s, (s["name"], key)
        # a thread of another library, or (scenes named mkc_*) a bug found here
        assert (s["source"].startswith("https://github.com/")
                or (s["name"].startswith("mkc_") and s["source"].startswith("found here"))), s["name"]
        for p in (s["pose_a"], s["pose_b"]):
            assert abs(np.linalg.norm(p["quat_xyzw"]) - 1.0) < 1e-12, s["name"]
        # rotation matrices quoted from a thread match the quaternions used
        src = s.get("source_poses", {})
        for key, pose in (("a", s["pose_a"]), ("b", s["pose_b"])):
            M = src.get(key)
            if isinstance(M, list):
                M = np.asarray(M, dtype=np.float64)
                assert np.allclose(quat_matrix(np.asarray(pose["quat_xyzw"])), M[:, :3],
                                   atol=1e-9), s["name"]
                assert np.allclose(pose["position"], M[:, 3], atol=0), s["name"]


@pytest.mark.parametrize("scene", SCENES, ids=IDS)
def test_expected_values_rederived(scene):
    """The stored expected values equal the named closed form, the hand value, and the
    slow support-function search of tests/oracles.py (an independent second oracle)."""
    a, b = scene["shape_a"], scene["shape_b"]
    pa, pb = poses(scene)
    exp = scene["expected"]
    tol = 1e-6 * scale_of(scene)
    d, n, p_a, p_b = closed_form(scene["oracle"], a, pa, b, pb)
    assert abs(d - exp["distance"]) <= 1e-9 * scale_of(scene) or (
        scene["oracle"] == "support_search" and abs(d - exp["distance"]) <= tol)
    if "hand_value" in exp:
        assert abs(exp["distance"] - exp["hand_value"]) <= 1e-12 * max(1.0, scale_of(scene))
    if n is not None and "normal" in exp and abs(d) > 1e-3 * scale_of(scene):
        assert angle(n, exp["normal"]) < 1e-6
    if "point_a" in exp:
        assert np.allclose(p_a, exp["point_a"], atol=1e-12)
        assert np.allclose(p_b, exp["point_b"], atol=1e-12)
        # the expected points lie on the surfaces
        n_exp = np.asarray(exp["normal"])
        eps = 1e-12 * max(1.0, scale_of(scene))
        assert abs(O.surface_gap(a, pa, exp["point_a"], n_exp)) < eps
        assert abs(O.surface_gap(b, pb, exp["point_b"], -n_exp)) < eps
    if {a["type"], b["type"]} <= {"box", "convex"}:
        # every polytope pair: the exact enumeration agrees, and a normal that is
        # checked is unique (ties between facets are marked normal_check 'none')
        d_p, n_p, tie = polytope_signed_distance(a, pa, b, pb, with_tie=True)
        assert abs(d_p - exp["distance"]) <= 1e-9 * scale_of(scene), (d_p, exp["distance"])
        if tie:
            assert scene.get("normal_check") == "none", "tied facets: normal not unique"
    d_search, n_search = O.signed_distance_oracle(a, pa, b, pb)
    assert abs(d_search - exp["distance"]) <= tol, (d_search, exp["distance"])
    if ("normal" in exp and abs(exp["distance"]) > 1e-3 * scale_of(scene)
            and scene.get("normal_check") != "none"):
        assert angle(n_search, exp["normal"]) < 1e-3


# --- the library against the corpus --------------------------------------------------------
@pytest.mark.parametrize("method", ["auto", "gjk_epa"])
@pytest.mark.parametrize("scene", SCENES, ids=IDS)
def test_scene(scene, method):
    a, b = scene["shape_a"], scene["shape_b"]
    pa, pb = poses(scene)
    r = collide(a, pa, b, pb, method=method)
    check_result(scene, r, pa, pb, scene["expected"]["distance"], method)
    exp = scene["expected"]
    if "point_a" in exp:
        tol = 1e-6 * scale_of(scene)
        msg = (f"{scene['name']} [{method}]: expected points {exp['point_a']}, "
               f"{exp['point_b']}; got {describe(r)}")
        assert np.allclose(r.point_a, exp["point_a"], atol=tol), msg
        assert np.allclose(r.point_b, exp["point_b"], atol=tol), msg


@pytest.mark.parametrize("scene", SCENES, ids=IDS)
def test_scene_mpr(scene):
    """MPR: the boolean, and its depth never below the true depth."""
    a, b = scene["shape_a"], scene["shape_b"]
    pa, pb = poses(scene)
    d = scene["expected"]["distance"]
    tol = 1e-6 * scale_of(scene)
    r = collide(a, pa, b, pb, method="mpr")
    msg = f"{scene['name']} [mpr]: expected distance {d!r}; got {describe(r)}"
    assert r.status not in (Status.FAILED, Status.NOT_RUN), msg
    assert np.all(np.isfinite(np.r_[r.distance, r.normal, r.point_a, r.point_b])), msg
    if abs(d) > tol:
        assert r.touching == (d < 0), msg
    if d < -tol:
        assert r.depth >= -d - tol, msg
    if r.status == Status.SEPARATED:
        # separated: a lower bound of the distance (docs/narrowphase-notes.md)
        assert 0.0 <= r.distance <= d + tol, msg


def swapped(scene):
    """The scene with A and B exchanged: same distance, normal and points mirrored."""
    s = dict(scene)
    s["shape_a"], s["shape_b"] = scene["shape_b"], scene["shape_a"]
    s["pose_a"], s["pose_b"] = scene["pose_b"], scene["pose_a"]
    exp = dict(scene["expected"])
    if "normal" in exp:
        exp["normal"] = [-x for x in exp["normal"]]
    if "point_a" in exp:
        exp["point_a"], exp["point_b"] = scene["expected"]["point_b"], scene["expected"]["point_a"]
    s["expected"] = exp
    s["name"] = scene["name"] + " (swapped)"
    return s


@pytest.mark.parametrize("method", ["auto", "gjk_epa"])
@pytest.mark.parametrize("scene", SCENES, ids=IDS)
def test_scene_swapped(scene, method):
    """The same scene with A and B exchanged (the reported bugs were order-sensitive)."""
    test_scene(swapped(scene), method)


@pytest.mark.parametrize("method", ["auto", "gjk_epa"])
@pytest.mark.parametrize("scene", [s for s in SCENES if "sweep" in s],
                         ids=[s["name"] for s in SCENES if "sweep" in s])
def test_sweep(scene, method):
    """A scene with a 'sweep': one body moved along one axis through the listed values,
    with the expected signed distance at each."""
    sw = scene["sweep"]
    a, b = scene["shape_a"], scene["shape_b"]
    pa, pb = poses(scene)
    for v, d in zip(sw["values"], sw["expected_distance"]):
        moving = pb if sw["body"] == "b" else pa
        p = list(moving[0])
        p[sw["axis"]] = v
        if sw["body"] == "b":
            pb_k, pa_k = (p, moving[1]), pa
        else:
            pa_k, pb_k = (p, moving[1]), pb
        r = collide(a, pa_k, b, pb_k, method=method)
        check_result(scene, r, pa_k, pb_k, d, method)
