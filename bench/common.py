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

from mkcollision_ros.cases import (BOUNDED, IDENTITY_XYZW, KINDS, overlapping,  # noqa: F401
                                   pair_cases, random_hull_points, random_shape,
                                   relative_poses)
from mkcollision_ros.rotations import quat_mul, quat_to_matrix, random_quat  # noqa: F401
from mkcollision_ros.shapes import build_table

# shapes of the pipeline scenes (a plane would touch every body resting on it)
SCENE_KINDS = BOUNDED


# --- shapes and poses -------------------------------------------------------------------
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
    hit = overlapping(table, cand, pos, quat)
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


def print_table(head, rows):
    """Print a markdown table: the header cells ``head``, then one row of str cells per
    item of ``rows``."""
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        print("| " + " | ".join(r) + " |")


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
