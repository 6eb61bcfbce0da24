"""Shared pieces of the benchmarks: seeded shapes, pair poses and scenes, and adapters
that hand the same shapes and poses to the peers (MuJoCo, coal, python-fcl, pybullet).

Conventions as in the library: metres, quaternions ``quat_xyzw``, shape dicts of
``mkcollision_ros.shapes``.  Every generator takes a ``numpy.random.Generator`` so a
run is reproducible from its seed.  Peers that lack a shape get an approximation,
named where it is made (``approx_mesh``): MuJoCo has no cone, pybullet has no cone and
no ellipsoid.
"""
import math
import time

import numpy as np

from mkcollision_ros.kernels.constants import (M_AUTO, OUT_SIZE, ST_PENETRATING,
                                               ST_TOUCHING)
from mkcollision_ros.kernels.geometry import relative_pose
from mkcollision_ros.kernels.narrowphase import collide_batch
from mkcollision_ros.shapes import build_table

KINDS = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex", "plane")
BOUNDED = KINDS[:-1]
# shapes of the pipeline scenes (a plane would touch every body resting on it)
SCENE_KINDS = BOUNDED
IDENTITY_XYZW = np.array([0.0, 0.0, 0.0, 1.0])


# --- shapes and poses -------------------------------------------------------------------
def random_quat(rng, n):
    """n uniformly random unit quaternions, xyzw, float64 (n, 4)."""
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def random_hull_points(rng, size=0.5, n=None):
    """20-30 points on a random ellipsoid-ish blob about the origin (origin inside)."""
    n = int(rng.integers(20, 31)) if n is None else n
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return d * size * rng.uniform(0.6, 1.0, size=3) * rng.uniform(0.85, 1.0, size=(n, 1))


def random_shape(rng, kind, size=0.5):
    """A shape dict of ``kind`` whose bounding radius is about ``size`` (m)."""
    u = lambda lo=0.5, hi=1.0: float(size * rng.uniform(lo, hi))  # noqa: E731
    if kind == "sphere":
        return {"type": "sphere", "radius": u()}
    if kind == "ellipsoid":
        return {"type": "ellipsoid", "radii": [u(0.3), u(0.3), u(0.3)]}
    if kind == "box":
        return {"type": "box", "size": [u(0.6, 1.2), u(0.6, 1.2), u(0.6, 1.2)]}
    if kind == "capsule":
        return {"type": "capsule", "radius": u(0.2, 0.5), "length": u(0.5, 1.0)}
    if kind in ("cylinder", "cone"):
        return {"type": kind, "radius": u(0.3, 0.7), "height": u(0.8, 1.4)}
    if kind == "convex":
        return {"type": "convex", "points": random_hull_points(rng, size).tolist()}
    if kind == "plane":
        n = rng.normal(size=3)
        return {"type": "plane", "normal": (n / np.linalg.norm(n)).tolist(), "offset": 0.0}
    raise ValueError(kind)


def _overlap(table, pairs, pos, quat):
    out = np.zeros((len(pairs), OUT_SIZE))
    st = np.zeros(len(pairs), np.int64)
    collide_batch(table.codes, table.params, table.vrange, table.verts, pairs, pos, quat,
                  M_AUTO, np.inf, out, st)
    return (st == ST_TOUCHING) | (st == ST_PENETRATING)


def pair_cases(kind_a, kind_b, n, seed=0):
    """n random cases of the pair (kind_a, kind_b), roughly half of them colliding.

    Each case gets its own random dimensions, orientations and a direction u.  B is
    placed at s * u from A (for a plane B, A at s * n above B's plane); the contact
    offset s* along u is found by bisection with our ``M_AUTO`` kernel (closed forms,
    else GJK/EPA), then s = s* * (1 + g) with g drawn from a mixture: 40% deep to
    shallow penetration (-0.9 .. -0.02), 20% near touching (-0.01 .. 0.01), 40%
    separated (0.02 .. 0.5).  For plane pairs g scales A's bounding radius instead.
    Returns (shapes list of 2n dicts, table, pairs (n, 2), pos (2n, 3), quat (2n, 4)).
    """
    rng = np.random.default_rng(seed)
    shapes = []
    for _ in range(n):
        shapes += [random_shape(rng, kind_a), random_shape(rng, kind_b)]
    table = build_table(shapes)
    pairs = np.arange(2 * n, dtype=np.int64).reshape(n, 2)
    quat = random_quat(rng, 2 * n)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    plane = kind_b == "plane"
    radius = table.params[:, 7]
    if plane:
        quat[1::2] = IDENTITY_XYZW
        u = table.params[1::2, :3].copy()      # the plane's outward normal
        lo, hi = -radius[0::2].copy(), radius[0::2].copy()
    else:
        lo, hi = np.zeros(n), radius[0::2] + radius[1::2]
    pos = np.zeros((2 * n, 3))
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        if plane:
            pos[0::2] = mid[:, None] * u
        else:
            pos[1::2] = mid[:, None] * u
        hit = _overlap(table, pairs, pos, quat)
        lo = np.where(hit, mid, lo)
        hi = np.where(hit, hi, mid)
    s_star = 0.5 * (lo + hi)
    pick = rng.uniform(size=n)
    g = np.where(pick < 0.4, rng.uniform(-0.9, -0.02, n),
                 np.where(pick < 0.6, rng.uniform(-0.01, 0.01, n), rng.uniform(0.02, 0.5, n)))
    if plane:
        pos[0::2] = (s_star + g * radius[0::2])[:, None] * u
    else:
        pos[1::2] = (s_star * (1.0 + g))[:, None] * u
    return shapes, table, pairs, pos, quat


def scene(n_bodies, density, seed=0, size=0.5, side=None):
    """Bodies of mixed bounded shapes spread uniformly in a cube of edge ``side``.

    If ``side`` is None it is set from ``density`` (expected touching pairs per body) by
    ``calibrate_side``.  Returns (bodies list of dicts for Pipeline, pos (N, 3),
    quat (N, 4), side).  Convex bodies reuse 8 seeded hulls (MuJoCo needs one mesh
    asset per distinct hull)."""
    rng = np.random.default_rng(seed)
    hulls = [random_hull_points(rng, size).tolist() for _ in range(8)]
    bodies = []
    for i in range(n_bodies):
        kind = SCENE_KINDS[i % len(SCENE_KINDS)]
        shape = ({"type": "convex", "points": hulls[i % 8]} if kind == "convex"
                 else random_shape(rng, kind, size))
        bodies.append({"name": f"b{i}", "shape": shape})
    unit = rng.uniform(size=(n_bodies, 3))
    quat = random_quat(rng, n_bodies)
    if side is None:
        side = calibrate_side(bodies, unit, quat, density)
    return bodies, unit * side, quat, side


def touching_pairs(table, pos, quat):
    """Exact touching pairs (i < j) by brute-force bounding-sphere culling plus our
    M_AUTO kernel; used only to calibrate scene density."""
    r = table.params[:, 7]
    cand = []
    order = np.argsort(pos[:, 0])
    xs = pos[order, 0]
    rmax = r.max()
    for a in range(len(order)):
        i = order[a]
        b_end = np.searchsorted(xs, xs[a] + r[i] + rmax, side="right")
        js = order[a + 1:b_end]
        if len(js):
            d = np.linalg.norm(pos[js] - pos[i], axis=1)
            js = js[d <= r[js] + r[i]]
            cand += [(min(i, j), max(i, j)) for j in js]
    if not cand:
        return np.zeros((0, 2), np.int64)
    cand = np.array(cand, np.int64)
    hit = _overlap(table, cand, pos, quat)
    return cand[hit]


def calibrate_side(bodies, unit, quat, density):
    """Edge of the cube giving ``density`` touching pairs per body (3 secant steps on
    the observation that pairs per body scale as side**-3)."""
    table = build_table([b["shape"] for b in bodies])
    n = len(bodies)
    mean_r = table.params[:, 7].mean()
    side = (n * 4.0 / 3.0 * math.pi * (2 * 0.6 * mean_r) ** 3 / (2.0 * density)) ** (1 / 3)
    for _ in range(3):
        got = len(touching_pairs(table, unit * side, quat)) / n
        if got == 0:
            side *= 0.5
            continue
        side *= (got / density) ** (1.0 / 3.0)
    return side


def move(rng, pos, quat, step=0.01):
    """Small random motion: positions by up to ``step`` m, orientations by ~step rad."""
    pos = pos + rng.uniform(-step, step, size=pos.shape)
    dq = np.concatenate([rng.uniform(-step / 2, step / 2, size=(len(quat), 3)),
                         np.ones((len(quat), 1))], axis=1)
    q = quat_mul(quat, dq)
    return pos, q / np.linalg.norm(q, axis=1, keepdims=True)


def quat_mul(a, b):
    """Hamilton product of xyzw quaternion arrays (n, 4)."""
    ax, ay, az, aw = a.T
    bx, by, bz, bw = b.T
    return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz], axis=1)


def quat_to_matrix(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def relative_poses(pos, quat):
    """Pose of B in A's frame for each case (pairs (2k, 2k + 1) of ``pos``, ``quat``), as
    the API computes it (geometry.relative_pose): rotations (n, 3, 3), translations
    (n, 3)."""
    n = len(pos) // 2
    rot, tr = np.zeros((n, 3, 3)), np.zeros((n, 3))
    for k in range(n):
        rot[k], tr[k] = relative_pose(pos[2 * k], quat_to_matrix(quat[2 * k]),
                                      pos[2 * k + 1], quat_to_matrix(quat[2 * k + 1]))
    return rot, tr


def z_to(n):
    """xyzw quaternion rotating +z onto the unit vector n."""
    z = np.array([0.0, 0.0, 1.0])
    c = float(np.dot(z, n))
    if c < -1 + 1e-12:
        return np.array([1.0, 0.0, 0.0, 0.0])
    v = np.cross(z, n)
    q = np.array([v[0], v[1], v[2], 1.0 + c])
    return q / np.linalg.norm(q)


def approx_mesh(shape, n_around=32):
    """Vertices (M, 3) approximating a cone or an ellipsoid as a hull (for peers that
    lack the shape); the hull lies inside the true shape (inscribed)."""
    if shape["type"] == "cone":
        r, h = shape["radius"], 0.5 * shape["height"]
        t = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
        ring = np.stack([r * np.cos(t), r * np.sin(t), -h * np.ones_like(t)], axis=1)
        return np.vstack([ring, [[0.0, 0.0, h]]])
    if shape["type"] == "ellipsoid":
        k = np.arange(n_around * 8) + 0.5            # Fibonacci sphere
        phi = np.arccos(1 - 2 * k / len(k))
        th = np.pi * (1 + 5 ** 0.5) * k
        d = np.stack([np.cos(th) * np.sin(phi), np.sin(th) * np.sin(phi), np.cos(phi)], 1)
        return d * np.asarray(shape["radii"])
    raise ValueError(shape["type"])


def timed(fn, repeat, inner=1):
    """Median seconds per call of fn() over ``repeat`` runs of ``inner`` calls."""
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        ts.append((time.perf_counter() - t0) / inner)
    return float(np.median(ts))


# --- MuJoCo -------------------------------------------------------------------------------
def _fmt(v):
    return " ".join(f"{float(x):.17g}" for x in np.ravel(v))


def mujoco_geom(shape, name, assets, attrs="", approx_cone=True):
    """MJCF <geom> of a shape dict (body frame = geom frame except for planes), adding
    a mesh asset to ``assets`` (dict name -> vertices) for convex hulls and for the
    cone approximation.  Returns the XML string, or None for a shape MuJoCo lacks."""
    t = shape["type"]
    if t == "sphere":
        g = f'type="sphere" size="{_fmt([shape["radius"]])}"'
    elif t == "ellipsoid":
        g = f'type="ellipsoid" size="{_fmt(shape["radii"])}"'
    elif t == "box":
        g = f'type="box" size="{_fmt(0.5 * np.asarray(shape["size"]))}"'
    elif t == "capsule":
        g = f'type="capsule" size="{_fmt([shape["radius"], 0.5 * shape["length"]])}"'
    elif t == "cylinder":
        g = f'type="cylinder" size="{_fmt([shape["radius"], 0.5 * shape["height"]])}"'
    elif t == "cone" and not approx_cone:
        return None
    elif t in ("convex", "cone"):
        pts = np.asarray(shape["points"]) if t == "convex" else approx_mesh(shape)
        key = _fmt(pts)
        mname = assets.setdefault(key, f"mesh{len(assets)}")
        g = f'type="mesh" mesh="{mname}"'
    elif t == "plane":
        n = np.asarray(shape["normal"], float)
        n /= np.linalg.norm(n)
        p = n * shape["offset"]
        q = z_to(n)
        g = (f'type="plane" size="0 0 1" pos="{_fmt(p)}" '
             f'quat="{_fmt([q[3], q[0], q[1], q[2]])}"')
    else:
        return None
    return f'<geom name="{name}" {g} {attrs}/>'


def mujoco_assets_xml(assets):
    return "".join(f'<mesh name="{m}" vertex="{k}"/>' for k, m in assets.items())


def wxyz(q):
    q = np.asarray(q)
    return np.concatenate([q[..., 3:4], q[..., 0:3]], axis=-1)


# --- coal / python-fcl --------------------------------------------------------------------
def _hull(points):
    """(vertices (M, 3), triangles (T, 3)) of the hull of points (coal's qhull)."""
    import coal
    v = coal.StdVec_Vec3s()
    for p in np.asarray(points, float):
        v.append(p)
    c = coal.Convex.convexHull(v, True, "")
    verts = np.array([c.points(i) for i in range(c.num_points)])
    tris = np.array([[c.polygons(i)[k] for k in range(3)] for i in range(c.num_polygons)],
                    np.int64)
    return c, verts, tris


def coal_geometry(shape):
    import coal
    t = shape["type"]
    if t == "sphere":
        return coal.Sphere(shape["radius"])
    if t == "ellipsoid":
        return coal.Ellipsoid(*shape["radii"])
    if t == "box":
        return coal.Box(*shape["size"])
    if t == "capsule":
        return coal.Capsule(shape["radius"], shape["length"])
    if t == "cylinder":
        return coal.Cylinder(shape["radius"], shape["height"])
    if t == "cone":
        return coal.Cone(shape["radius"], shape["height"])
    if t == "convex":
        return _hull(shape["points"])[0]
    if t == "plane":
        return coal.Halfspace(np.asarray(shape["normal"], float), shape["offset"])
    raise ValueError(t)


def coal_transform(p, q_xyzw):
    import coal
    return coal.Transform3s(quat_to_matrix(q_xyzw), np.asarray(p, float))


def fcl_geometry(shape):
    import fcl
    t = shape["type"]
    if t == "sphere":
        return fcl.Sphere(shape["radius"])
    if t == "ellipsoid":
        return fcl.Ellipsoid(*shape["radii"])
    if t == "box":
        return fcl.Box(*shape["size"])
    if t == "capsule":
        return fcl.Capsule(shape["radius"], shape["length"])
    if t == "cylinder":
        return fcl.Cylinder(shape["radius"], shape["height"])
    if t == "cone":
        return fcl.Cone(shape["radius"], shape["height"])
    if t == "convex":
        _, verts, tris = _hull(shape["points"])
        faces = np.hstack([np.full((len(tris), 1), 3), tris]).ravel()
        return fcl.Convex(verts, len(tris), faces)
    if t == "plane":
        return fcl.Halfspace(np.asarray(shape["normal"], float), shape["offset"])
    raise ValueError(t)


def fcl_transform(p, q_xyzw):
    import fcl
    return fcl.Transform(quat_to_matrix(q_xyzw), np.asarray(p, float))


# --- pybullet -----------------------------------------------------------------------------
def pybullet_shape(pb, client, shape):
    """A pybullet collision shape id (ellipsoid and cone as inscribed hulls)."""
    t = shape["type"]
    kw = {"physicsClientId": client}
    if t == "sphere":
        return pb.createCollisionShape(pb.GEOM_SPHERE, radius=shape["radius"], **kw)
    if t == "box":
        return pb.createCollisionShape(pb.GEOM_BOX,
                                       halfExtents=(0.5 * np.asarray(shape["size"])).tolist(),
                                       **kw)
    if t == "capsule":
        return pb.createCollisionShape(pb.GEOM_CAPSULE, radius=shape["radius"],
                                       height=shape["length"], **kw)
    if t == "cylinder":
        return pb.createCollisionShape(pb.GEOM_CYLINDER, radius=shape["radius"],
                                       height=shape["height"], **kw)
    if t in ("convex", "ellipsoid", "cone"):
        pts = np.asarray(shape["points"]) if t == "convex" else approx_mesh(shape)
        return pb.createCollisionShape(pb.GEOM_MESH, vertices=pts.tolist(), **kw)
    if t == "plane":
        return pb.createCollisionShape(pb.GEOM_PLANE, planeNormal=shape["normal"], **kw)
    raise ValueError(t)
