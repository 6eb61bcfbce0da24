"""Seeded random pair cases shared by the tests, the benchmarks and the tools: shape dicts
of every bounded type (plus the plane) with random dimensions, and pairs of them at
random orientations placed about their contact offset, so that about half collide.

Conventions as in the library: metres, quaternions ``quat_xyzw``, shape dicts of
``mkcollision_ros.shapes``.  Every generator takes a seed or a ``numpy.random.Generator``,
so a run is reproducible.
"""
import numpy as np

from .kernels.constants import M_AUTO, OUT_SIZE, ST_PENETRATING, ST_TOUCHING
from .kernels.geometry import relative_pose
from .kernels.narrowphase import collide_batch
from .rotations import quat_to_matrix, random_quat
from .shapes import build_table

KINDS = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex", "plane")
BOUNDED = KINDS[:-1]
IDENTITY_XYZW = np.array([0.0, 0.0, 0.0, 1.0])


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


def overlapping(table, pairs, pos, quat):
    """Whether each pair (rows of ``pairs`` into ``table``) touches or penetrates at the
    world poses ``pos``, ``quat``, by the batch kernel's auto method: bool (P,)."""
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
        hit = overlapping(table, pairs, pos, quat)
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
