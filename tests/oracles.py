"""Slow, obvious oracles and shared helpers for the narrow-phase tests.

* random shape dicts and poses (seeded, vectorised), in three size regimes;
* a coal adapter (peer oracle): ``coal_signed_distance(shape_a, pose_a, shape_b, pose_b)``
  -> (distance, normal A->B, point_a, point_b), world frame;
* implicit functions / support functions in numpy, to check that witness points lie on
  the surfaces, and an ellipsoid's exact inner distance (``inner_distance``);
* runners the test files share: one pair through GJK/EPA (``gjk``, ``pose``, ``ID``),
  the batch kernel on many (``run_batch``, ``paired_table``, ``table_pair``), and the
  pair kernels run before GJK, called directly (``pre_kernel``,
  ``check_certified_shortcut``).

coal conventions verified here (coal 3.0.3): Box takes full side lengths; Capsule(r, L)
with L the full segment length; Cylinder(r, h) and Cone(r, h) with h the full height,
centred, the cone's tip at +h/2 (a sphere on the tip at z = h/2 + r_s touches).
coal.distance returns a signed distance (negative when penetrating) and its ``normal``
points from shape 1 to shape 2.
"""
import math

import numpy as np

from mkcollision_ros import collide, rotations
from mkcollision_ros.kernels.constants import OUT_DIST, OUT_NORMAL, OUT_PA, OUT_PB, ST_PENETRATING

TYPES = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex")


# --- random inputs -------------------------------------------------------------------------
def random_quats(rng, n):
    """(n, 4) unit quaternions xyzw, uniform on SO(3)."""
    return rotations.random_quat(rng, n)


def random_rotation(rng):
    """One rotation matrix (3, 3), uniform on SO(3) (four normal draws)."""
    q = rng.normal(size=4)
    return rotations.quat_to_matrix(q / np.linalg.norm(q))


def quat_matrix(q):
    """Rotation matrix of one xyzw quaternion (normalised here)."""
    q = np.asarray(q, np.float64)
    return rotations.quat_to_matrix(q / np.linalg.norm(q))


def quat_axis(axis, angle):
    """The xyzw quaternion of a turn by ``angle`` (rad) about ``axis``."""
    return rotations.quat_axis_angle(axis, angle)


def quat_mul(a, b):
    """The product a * b of two xyzw quaternions (b applied first)."""
    return rotations.quat_mul(a, b)


def random_shape(rng, kind, size=1.0, ratio=4.0):
    """A random shape dict of the given type; dimensions in [size/ratio, size]."""
    def dim(k=None):
        return size * (1.0 / ratio + (1.0 - 1.0 / ratio) * rng.random(k))
    if kind == "sphere":
        return {"type": "sphere", "radius": float(dim())}
    if kind == "ellipsoid":
        return {"type": "ellipsoid", "radii": dim(3).tolist()}
    if kind == "box":
        return {"type": "box", "size": (2 * dim(3)).tolist()}
    if kind in ("capsule", "cylinder", "cone"):
        key = "length" if kind == "capsule" else "height"
        return {"type": kind, "radius": float(dim()), key: float(2 * dim())}
    if kind == "convex":
        n = int(rng.integers(6, 20))
        p = rng.normal(size=(n, 3))
        p /= np.linalg.norm(p, axis=1, keepdims=True)
        return {"type": "convex", "points": (p * dim(3)).tolist()}
    raise ValueError(kind)


def bounding_radius(shape):
    from mkcollision_ros.shapes import shape_row
    return float(shape_row(shape)[1][7])


# --- coal adapter ---------------------------------------------------------------------------
def coal_shape(shape):
    import coal
    kind = shape["type"]
    if kind == "sphere":
        g = coal.Sphere(shape["radius"])
    elif kind == "ellipsoid":
        g = coal.Ellipsoid(*shape["radii"])
    elif kind == "box":
        g = coal.Box(*shape["size"])
    elif kind == "capsule":
        g = coal.Capsule(shape["radius"], shape["length"])
    elif kind == "cylinder":
        g = coal.Cylinder(shape["radius"], shape["height"])
    elif kind == "cone":
        g = coal.Cone(shape["radius"], shape["height"])
    elif kind == "convex":
        m = coal.BVHModelOBBRSS()
        pts = np.asarray(shape["points"], dtype=np.float64)
        m.beginModel(0, len(pts))
        m.addVertices(pts)
        m.endModel()
        m.buildConvexHull(False, "Qt")
        _HULL_MODELS.append(m)      # the hull belongs to its model: keep the model alive
        del _HULL_MODELS[:-8]
        g = m.convex
    elif kind == "plane":
        g = coal.Halfspace(np.asarray(shape["normal"], float), float(shape["offset"]))
    else:
        raise ValueError(kind)
    if shape.get("margin", 0.0):
        g.setSweptSphereRadius(float(shape["margin"]))
    return g


_HULL_MODELS = []


def coal_dist(shape_a, shape_b, r, t):
    """coal.distance of A at the origin and B at rotation ``r`` (3, 3), translation
    ``t`` (3,) in A's frame, GJK tolerance 1e-12: the signed distance (m)."""
    import coal
    tf = coal.Transform3s()
    tf.setRotation(r)
    tf.setTranslation(t)
    req = coal.DistanceRequest()
    req.gjk_tolerance = 1e-12
    res = coal.DistanceResult()
    return coal.distance(coal_shape(shape_a), coal.Transform3s(), coal_shape(shape_b), tf,
                         req, res)


def coal_transform(pose):
    import coal
    p, q = pose
    return coal.Transform3s(quat_matrix(np.asarray(q, dtype=np.float64)),
                            np.asarray(p, dtype=np.float64))


def coal_request():
    import coal
    req = coal.DistanceRequest()
    req.enable_signed_distance = True
    req.gjk_tolerance = 1e-12
    req.gjk_max_iterations = 1000
    req.epa_tolerance = 1e-10      # tighter (1e-12) makes coal's EPA fail (-DBL_MAX)
    req.epa_max_iterations = 255
    return req


def coal_signed_distance(ga, pose_a, gb, pose_b, req=None):
    """(distance, normal A->B, point_a, point_b) from coal, world frame.  coal's EPA
    sometimes gives up (returns -DBL_MAX) at tight tolerances; then it is retried with
    looser ones (1e-8, 1e-6).  Returns NaNs if every try failed."""
    import coal
    ta, tb = coal_transform(pose_a), coal_transform(pose_b)
    for tol in (None, 1e-8, 1e-6):
        r = req or coal_request()
        if tol is not None:
            r.epa_tolerance = tol
        res = coal.DistanceResult()
        d = coal.distance(ga, ta, gb, tb, r, res)
        if abs(d) < 1e100:
            return d, np.array(res.normal), np.array(res.getNearestPoint1()), \
                np.array(res.getNearestPoint2())
    nan = np.full(3, np.nan)
    return np.nan, nan, nan, nan


# --- implicit functions / supports (body frame) --------------------------------------------
def support_np(shape, d):
    """Support point of the whole shape (body frame) along d (3,), numpy oracle."""
    d = np.asarray(d, dtype=np.float64)
    u = d / np.linalg.norm(d)
    kind = shape["type"]
    m = shape.get("margin", 0.0)
    if kind == "sphere":
        return (shape["radius"] + m) * u
    if kind == "ellipsoid":
        r = np.asarray(shape["radii"])
        e = r * r * d
        return e / math.sqrt(float(e @ d)) + m * u
    if kind == "box":
        h = 0.5 * np.asarray(shape["size"])
        return np.where(d >= 0, h, -h) + m * u
    if kind == "capsule":
        return np.array([0, 0, math.copysign(shape["length"] / 2, d[2])]) \
            + (shape["radius"] + m) * u
    if kind in ("cylinder", "cone"):
        r, h = shape["radius"], shape["height"] / 2
        s = math.hypot(d[0], d[1])
        b = np.array([r * d[0] / s, r * d[1] / s]) if s > 0 else np.array([r, 0.0])
        if kind == "cylinder":
            return np.array([b[0], b[1], math.copysign(h, d[2])]) + m * u
        tip = np.array([0.0, 0.0, h])
        rim = np.array([b[0], b[1], -h])
        return (tip if tip @ d >= rim @ d else rim) + m * u
    if kind == "convex":
        p = np.asarray(shape["points"])
        return p[np.argmax(p @ d)] + m * u
    raise ValueError(kind)


def support_value(shape, d):
    """Support function h(d) = max_x x.d for unit d (body frame)."""
    d = np.asarray(d, dtype=np.float64)
    return float(support_np(shape, d) @ (d / np.linalg.norm(d)))


def surface_gap(shape, pose, p_w, n_w):
    """How far the world point p_w is from being the shape's support point along n_w
    (world): h(n) - n.p; zero for a point on the surface with outward normal n."""
    R = quat_matrix(np.asarray(pose[1], dtype=np.float64))
    p = R.T @ (np.asarray(p_w) - np.asarray(pose[0]))
    n = R.T @ np.asarray(n_w)
    n = n / np.linalg.norm(n)
    return support_value(shape, n) - float(n @ p)


def inside_value(shape, pose, p_w, n_dirs=200, rng=None):
    """Max over sampled unit directions of (u.p - h(u)): <= 0 inside the shape, and ~0
    on its surface (slow oracle of the signed distance from outside)."""
    rng = rng or np.random.default_rng(0)
    R = quat_matrix(np.asarray(pose[1], dtype=np.float64))
    p = R.T @ (np.asarray(p_w) - np.asarray(pose[0]))
    u = rng.normal(size=(n_dirs, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return max(float(ui @ p) - support_value(shape, ui) for ui in u)


# --- batch runner -------------------------------------------------------------------------
def run_batch(shapes_a, pos_a, quat_a, shapes_b, pos_b, quat_b, method="gjk_epa"):
    """Collide pair k = (shapes_a[k], shapes_b[k]) at the given world poses through the
    batch kernel.  Returns (out (P, OUT_SIZE) world frame, status (P,))."""
    from mkcollision_ros.kernels.constants import METHOD_NAMES, OUT_SIZE
    from mkcollision_ros.kernels.narrowphase import collide_batch
    from mkcollision_ros.shapes import build_table
    n = len(shapes_a)
    table = build_table(list(shapes_a) + list(shapes_b))
    pairs = np.stack([np.arange(n), np.arange(n) + n], axis=1).astype(np.int64)
    pos = np.ascontiguousarray(np.concatenate([pos_a, pos_b]), dtype=np.float64)
    quat = np.concatenate([quat_a, quat_b])
    quat = np.ascontiguousarray(quat / np.linalg.norm(quat, axis=1, keepdims=True))
    out = np.zeros((n, OUT_SIZE))
    status = np.zeros(n, dtype=np.int64)
    collide_batch(table.codes, table.params, table.vrange,
                  np.ascontiguousarray(table.verts), pairs, pos, quat,
                  np.int64(METHOD_NAMES.index(method)), np.inf, out, status)
    return out, status


def random_pairs(rng, kind_a, kind_b, n, size=1.0, ratio=4.0, offset=(0.0, 1.2),
                 centre=0.0):
    """n random pairs of the two types: B's centre at a random direction from A's at a
    distance uniform in offset * (bounding radius sum).  Returns
    (shapes_a, pos_a, quat_a, shapes_b, pos_b, quat_b)."""
    sa = [random_shape(rng, kind_a, size, ratio) for _ in range(n)]
    sb = [random_shape(rng, kind_b, size, ratio) for _ in range(n)]
    ra = np.array([bounding_radius(s) for s in sa])
    rb = np.array([bounding_radius(s) for s in sb])
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    f = offset[0] + (offset[1] - offset[0]) * rng.random(n)
    pos_a = centre + size * rng.normal(size=(n, 3))
    pos_b = pos_a + u * (f * (ra + rb))[:, None]
    return sa, pos_a, random_quats(rng, n), sb, pos_b, random_quats(rng, n)


# --- slow oracle: signed distance = -min over unit u of h_{A-B}(u) -------------------------
def support_values(shape, d):
    """Support function h(u) of the whole shape for K unit directions d (K, 3), body
    frame, vectorised."""
    kind = shape["type"]
    m = shape.get("margin", 0.0)
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    if kind == "sphere":
        h = np.full(len(d), shape["radius"])
    elif kind == "ellipsoid":
        a, b, c = shape["radii"]
        h = np.sqrt((a * x) ** 2 + (b * y) ** 2 + (c * z) ** 2)
    elif kind == "box":
        hx, hy, hz = 0.5 * np.asarray(shape["size"])
        h = hx * np.abs(x) + hy * np.abs(y) + hz * np.abs(z)
    elif kind == "capsule":
        h = shape["radius"] + 0.5 * shape["length"] * np.abs(z)
    elif kind == "cylinder":
        h = shape["radius"] * np.hypot(x, y) + 0.5 * shape["height"] * np.abs(z)
    elif kind == "cone":
        hh = 0.5 * shape["height"]
        h = np.maximum(hh * z, shape["radius"] * np.hypot(x, y) - hh * z)
    elif kind == "convex":
        h = (d @ np.asarray(shape["points"]).T).max(axis=1)
    else:
        raise ValueError(kind)
    return h + m


def cso_support(shape_a, pose_a, shape_b, pose_b, u):
    """h_{A-B}(u) for K world directions u (K, 3): h_A(u) + h_B(-u)."""
    ra = quat_matrix(np.asarray(pose_a[1], dtype=np.float64))
    rb = quat_matrix(np.asarray(pose_b[1], dtype=np.float64))
    ha = support_values(shape_a, u @ ra) + u @ np.asarray(pose_a[0], dtype=np.float64)
    hb = support_values(shape_b, -u @ rb) - u @ np.asarray(pose_b[0], dtype=np.float64)
    return ha + hb


def _sphere_dirs(n, rng):
    u = rng.normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def signed_distance_oracle(shape_a, pose_a, shape_b, pose_b, n_start=4000, n_keep=8,
                           n_iter=400, rng=None):
    """Signed distance by brute force: -min over unit u of h_{A-B}(u) (the minimum is
    the penetration depth when the origin is inside A - B, and minus the distance when
    it is outside).  Sampled start directions, then a shrinking random-pattern search
    around the best few.  Returns (signed distance, unit normal A -> B (world))."""
    rng = rng or np.random.default_rng(12345)
    # random starts plus both bodies' axes (face normals of boxes, caps of cylinders
    # and cones: kinks of h where a random pattern search converges slowly)
    axes = np.concatenate([quat_matrix(np.asarray(pose_a[1], dtype=np.float64)).T,
                           quat_matrix(np.asarray(pose_b[1], dtype=np.float64)).T])
    u = np.concatenate([_sphere_dirs(n_start, rng), axes, -axes])
    h = cso_support(shape_a, pose_a, shape_b, pose_b, u)
    # starts: the n_keep lowest samples, plus the lowest sample of each of the n_keep
    # lowest cells of a 6 x 4 x 4 cube-map grid of directions, so that a narrow basin
    # of h is searched even when wider ones hold all the lowest samples (found: an
    # ellipsoid-cone pair whose deepest direction the first n_keep starts all missed)
    order = np.argsort(h)
    rows = np.arange(len(u))
    face = np.argmax(np.abs(u), axis=1)
    major = u[rows, face]
    uv = np.stack([u[rows, (face + 1) % 3], u[rows, (face + 2) % 3]], 1) / np.abs(major)[:, None]
    sgn = major > 0
    cell_ij = np.clip(((uv + 1.0) * 2.0).astype(np.int64), 0, 3)
    cell = ((face * 2 + sgn) * 4 + cell_ij[:, 0]) * 4 + cell_ij[:, 1]
    seen, per_cell = set(), []
    for k in order:
        if cell[k] not in seen:
            seen.add(cell[k])
            per_cell.append(k)
            if len(per_cell) == n_keep:
                break
    starts = list(dict.fromkeys(list(order[:n_keep]) + per_cell))
    best_u, best_h = None, np.inf
    for k in starts:
        uk, hk, step = u[k], h[k], 0.05
        for _ in range(n_iter):
            cand = uk + step * _sphere_dirs(64, rng)
            cand /= np.linalg.norm(cand, axis=1, keepdims=True)
            hc = cso_support(shape_a, pose_a, shape_b, pose_b, cand)
            j = int(np.argmin(hc))
            if hc[j] < hk:
                uk, hk = cand[j], hc[j]
            else:
                step *= 0.5
            if step < 1e-10:
                break
        if hk < best_h:
            best_u, best_h = uk, hk
    # u is the outward normal of A - B: the normal from A to B in both regimes.
    # -best_h is a lower bound of the true signed distance (h(u) >= min h).
    return -best_h, best_u


# --- runners shared by the narrow-phase test files ---------------------------------------
ID = ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])


def gjk(sa, pa, sb, pb):
    return collide(sa, pa, sb, pb, method="gjk_epa")


def pose(p, q=(0.0, 0.0, 0.0, 1.0)):
    return (list(p), list(q))


def pressed_in(shape, ell, pe, shape_is_a, scale):
    """GJK/EPA on ``shape`` (at the origin) and the ellipsoid ``ell`` at pose ``pe``,
    either as A: the pair must penetrate, and its depth must not exceed the slow
    oracle's direction search (both are upper bounds of the true depth).  Returns the
    result, its normal turned out of ``shape`` and h_{shape - ell} along it."""
    res = gjk(shape, ID, ell, pe) if shape_is_a else gjk(ell, pe, shape, ID)
    assert res.status == ST_PENETRATING
    want, _ = (signed_distance_oracle(shape, ID, ell, pe) if shape_is_a
               else signed_distance_oracle(ell, pe, shape, ID))
    assert res.distance >= want - 1e-9 * scale
    n = np.asarray(res.normal) * (1.0 if shape_is_a else -1.0)
    return res, n, cso_support(shape, ID, ell, pe, n[None])[0]


def inner_distance(centre, sigma, p):
    """Distance from a point p inside the ellipsoid (or ellipse) {x : (x - centre)^T
    sigma^-1 (x - centre) <= 1} to its boundary, by bisection on the Lagrange
    multiplier t of the nearest boundary point x_i = a_i^2 y_i / (a_i^2 + t) (principal
    frame, y = p - centre there): sum (a_i y_i / (a_i^2 + t))^2 = 1 has one root in
    (-min a_i^2, 0] for a point inside, which falls strictly there.  Returns the
    distance and the boundary's outward unit normal at that nearest point."""
    w, q = np.linalg.eigh(np.asarray(sigma, dtype=float))
    y = q.T @ (np.asarray(p, dtype=float) - np.asarray(centre, dtype=float))
    lo, hi = -w.min(), 0.0
    assert np.sum(y * y / w) < 1.0
    for _ in range(200):
        t = 0.5 * (lo + hi)
        if np.sum(w * (y / (w + t)) ** 2) > 1.0:
            lo = t
        else:
            hi = t
    x = w * y / (w + hi)
    n = q @ (x / w)
    return float(np.linalg.norm(x - y)), n / np.linalg.norm(n)


def hull_cylinder_first(sa, sb, verts, r_ab, t_ab, scale, res):
    """What gjk_epa_ws tries first for a cylinder and a hull (contacts mode), as an
    outcome code (constants.PRE_*): collide_cylinder_convex's exact depth or separating
    plane when the hull has its fan stored (stop: the inflation radii and the touching
    band), collide_cylinder_convex_ball (stop 0) where that decides nothing
    (PRE_UNDECIDED) or there is no fan."""
    from mkcollision_ros.kernels.constants import PRE_UNDECIDED, TOUCH_TOL
    from mkcollision_ros.kernels.geometry import inflation
    from mkcollision_ros.kernels.pairs.cylinder_convex import (collide_cylinder_convex,
                                                               collide_cylinder_convex_ball,
                                                               cylinder_hull_pair)
    from mkcollision_ros.kernels.pairs.normal_fan import HE_ROWS
    got = PRE_UNDECIDED
    if cylinder_hull_pair(sa, sb):
        stop = inflation(sa[0], sa[1]) + inflation(sb[0], sb[1]) + TOUCH_TOL * scale
        got = collide_cylinder_convex(sa, sb, verts, r_ab, t_ab, scale, False, stop,
                                      np.zeros((HE_ROWS, 3)), np.zeros(8), res)
    if got == PRE_UNDECIDED:
        got = collide_cylinder_convex_ball(sa, sb, verts, r_ab, t_ab, scale, 0.0, res)
    return got


def pre_kernel(kinds):
    """The pair kernel before GJK for a cylinder and the other kind of ``kinds``
    (collide_box_cylinder for a box; collide_ellipsoid_box for an ellipsoid and a box;
    for a hull, collide_cylinder_convex first, hull_cylinder_first), as f(shape_a,
    shape_b, verts, r_ab, t_ab, scale, res) giving res[0] on PRE_EXACT or PRE_APART (a
    certified core depth > 0, an exact distance or a proved gap, minus it) and 0 on any
    other outcome.  Those called with a ``stop`` get 0, so that every gap they prove
    counts."""
    from mkcollision_ros.kernels.constants import BC_MAX_LEVEL, PRE_APART, PRE_EXACT
    from mkcollision_ros.kernels.pairs.box_cylinder import collide_box_cylinder
    from mkcollision_ros.kernels.pairs.capsule_cylinder import collide_capsule_cylinder
    from mkcollision_ros.kernels.pairs.cylinder_cylinder import collide_cylinder_cylinder
    from mkcollision_ros.kernels.pairs.ellipsoid_box import collide_ellipsoid_box
    from mkcollision_ros.kernels.pairs.ellipsoid_cylinder import collide_ellipsoid_cylinder
    other = kinds[0] if kinds[1] == "cylinder" else kinds[1]
    if sorted(kinds) == ["box", "ellipsoid"]:
        def run(sa, sb, verts, r_ab, t_ab, scale, res):
            return collide_ellipsoid_box(sa, sb, r_ab, t_ab, scale, 0.0, res)
    elif other == "cylinder":
        def run(sa, sb, verts, r_ab, t_ab, scale, res):
            return collide_cylinder_cylinder(sa, sb, verts, r_ab, t_ab, scale, 0.0, res)
    elif other == "box":
        def run(sa, sb, verts, r_ab, t_ab, scale, res):
            return collide_box_cylinder(sa, sb, r_ab, t_ab, scale,
                                        np.zeros((BC_MAX_LEVEL + 8, 3)), 0.0, res)
    elif other == "convex":
        run = hull_cylinder_first
    else:
        f = collide_capsule_cylinder if other == "capsule" else collide_ellipsoid_cylinder

        def run(sa, sb, verts, r_ab, t_ab, scale, res):
            return f(sa, sb, r_ab, t_ab, scale, 0.0, res)

    def shortcut(sa, sb, verts, r_ab, t_ab, scale, res):
        got = run(sa, sb, verts, r_ab, t_ab, scale, res)
        return res[0] if got == PRE_EXACT or got == PRE_APART else 0.0
    return shortcut


def check_certified_shortcut(seed, kinds, n_oracle, h_slack):
    """800 random pairs of the two kinds through the batch kernel; on each penetrating
    pair that pre_kernel(kinds) (called directly)
    certifies: the batch kernel reports its core depth grown by the inflation radii,
    h_{A-B}(normal) by the numpy oracle is that depth to within h_slack * scale and
    never below it, the witnesses lie on the two surfaces, and (on the first n_oracle)
    the depth is never deeper than the slow oracle's minimum of h over directions (a
    wrong certificate, a ball that is not inside, would report a depth above the true
    one).  Returns (pairs certified, pairs penetrating, the certified pairs' (core
    normal in A's frame, r_ab))."""
    from mkcollision_ros.kernels.geometry import inflation, quat_to_matrix, relative_pose
    from mkcollision_ros.shapes import build_table
    shortcut = pre_kernel(kinds)
    rng = np.random.default_rng(seed)
    sa, pa, qa, sb, pb, qb = random_pairs(rng, *kinds, 800, offset=(0.0, 0.8))
    out, st = run_batch(sa, pa, qa, sb, pb, qb)
    pen = np.flatnonzero(st == ST_PENETRATING)
    certified = 0
    found = []
    for k in pen:
        table = build_table([sa[k], sb[k]])
        qa_k, qb_k = (q / np.linalg.norm(q) for q in (qa[k], qb[k]))
        r_ab, t_ab = relative_pose(pa[k], quat_to_matrix(qa_k), pb[k], quat_to_matrix(qb_k))
        shapes = [(table.codes[i], table.params[i], table.vrange[i, 0], table.vrange[i, 1])
                  for i in range(2)]
        scale = table.params[0, 7] + table.params[1, 7]
        res = np.zeros(10)
        h_core = shortcut(shapes[0], shapes[1], table.verts, r_ab, t_ab, scale, res)
        if not h_core > 0.0:
            continue
        certified += 1
        found.append((res[1:4].copy(), r_ab))
        grown = sum(inflation(table.codes[i], table.params[i]) for i in range(2))
        depth = -out[k, OUT_DIST]
        assert abs(depth - (h_core + grown)) <= 1e-12 * scale
        a, pose_a, b, pose_b = sa[k], (pa[k], qa_k), sb[k], (pb[k], qb_k)
        nrm = out[k, OUT_NORMAL:OUT_NORMAL + 3]
        h = cso_support(a, pose_a, b, pose_b, nrm[None])[0]
        assert -1e-12 * scale <= h - depth <= (h_slack + 1e-12) * scale
        assert abs(surface_gap(a, pose_a, out[k, OUT_PA:OUT_PA + 3], nrm)) <= 1e-9 * scale
        assert abs(surface_gap(b, pose_b, out[k, OUT_PB:OUT_PB + 3], -nrm)) <= 1e-9 * scale
        if certified <= n_oracle:
            sd, _ = signed_distance_oracle(a, pose_a, b, pose_b, n_start=2000, n_keep=6,
                                             n_iter=200)
            assert depth <= -sd + 1e-8 * scale
    return certified, len(pen), found


def paired_table(sa, pa, qa, sb, pb, qb):
    """One table of the shapes sa then sb, with pairs (k, k + n), positions and unit
    quaternions in that order, as the batch kernel takes them: (table, pairs, pos, quat,
    n)."""
    from mkcollision_ros.shapes import build_table
    n = len(sa)
    table = build_table(list(sa) + list(sb))
    pairs = np.stack([np.arange(n), np.arange(n) + n], axis=1).astype(np.int64)
    quat = np.concatenate([qa, qb])
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    pos = np.ascontiguousarray(np.concatenate([pa, pb]))
    return table, pairs, pos, quat, n


def table_pair(table, pos, quat, k, n):
    """Pair k of a table whose shapes k and k + n are paired: the two shape tuples, the
    pair's scale and B's pose in A's frame (r_ab, t_ab)."""
    from mkcollision_ros.kernels.geometry import quat_to_matrix, relative_pose
    shapes = [(table.codes[i], table.params[i], table.vrange[i, 0], table.vrange[i, 1])
              for i in (k, k + n)]
    scale = table.params[k, 7] + table.params[k + n, 7]
    r_ab, t_ab = relative_pose(pos[k], quat_to_matrix(quat[k]), pos[k + n],
                               quat_to_matrix(quat[k + n]))
    return shapes, scale, r_ab, t_ab
