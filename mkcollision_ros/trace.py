"""The iterations of the narrow phase for one pair of shapes, for visual debugging.

    from mkcollision_ros.trace import trace_pair, minkowski_difference
    t = trace_pair(shape_a, pose_a, shape_b, pose_b, method="auto")
    vertices, triangles = minkowski_difference(shape_a, pose_a, shape_b, pose_b)

Shapes and poses as ``mkcollision_ros.collide`` takes them (shape dicts, poses
``(position, quat_xyzw)`` in the world frame, metres).  Everything returned is in one
frame: the Minkowski difference A - B = {a - b} of the world-frame points of A and B,
so the pair penetrates iff the origin is inside it, and its point nearest the origin
is ``distance * (-normal)`` when apart.

How: the real kernels record their iterations when given a larger scratch buffer
(kernels/tracebuf.py lays out the trace region; kernels/mpr.py and kernels/gjk_epa.py,
"Trace", say what each records); nothing here re-implements them.  The kernels run in
the canonical order of the dispatcher (the lower shape code first) in the first
shape's frame; their points are mapped back to the world frame and to A - B (negated
when the pair was swapped, whose kernel saw B - A).

Which method is traced: MPR when MPR gave the answer (``collide``'s result names the
method), else GJK/EPA.  A closed-form answer (method "analytic", or a closed form
inside gjk_epa: cylinder pairs, an ellipsoid and a box, an ellipsoid or a cylinder and
a small hull) and a pair the bounding-sphere test settled are traced with GJK/EPA run
on the same pair with those closed forms skipped, so the iterations shown are GJK/EPA's
on the pair, not the computation that gave ``result``.  GJK and EPA work on the cores
(spheres as points, capsules as segments, ellipsoids shrunk by their rolling radius,
margins removed): their simplices and polytopes lie in the cores' difference, which
grown by a ball of radius ``core_radius`` is A - B; MPR's portals lie on A - B itself.
Planes have no support mapping: ValueError.
"""
import math
from dataclasses import dataclass

import numpy as np

from .hull import hull_triangles
from .kernels.constants import OUT_SIZE, PLANE
from .kernels.geometry import inflation, minkowski_full_xyz, quat_to_matrix
from .kernels.gjk_epa import gjk_epa_ws
from .kernels.gjk_epa_workspace import make_gjk_workspace_traced
from .kernels.mpr import MPR_WS_ROWS, mpr_ws
from .kernels.tracebuf import (TR_EPA, TR_GJK, TR_HEADER_ROWS, TR_MPR_DISCOVERY,
                               TR_MPR_REFINEMENT)
from .narrowphase import _pack, collide
from .results import CollisionResult
from .shapes import validate_pose

# rows of the trace region trace_pair hands the kernels: enough for EPA at its caps
# (EPA_MAX_ITERS steps of polytopes up to EPA_MAX_FACES faces take ~2e5 rows)
TRACE_ROWS = 1 << 18
_STAGES = {TR_MPR_DISCOVERY: "discovery", TR_MPR_REFINEMENT: "refinement"}


@dataclass(frozen=True)
class PairTrace:
    """One traced pair (module docstring for the frame and the choice of method).

    result         the CollisionResult of ``collide(..., method)``, equal to it
    answered_by    the method that produced ``result`` (its ``method`` field)
    traced         "mpr" or "gjk_epa": the method whose iterations are recorded
    mpr_portals    list of (stage "discovery" | "refinement", float64 (k, 3)): v0
                   (MPR's interior point) and the portal vertices found so far, k <= 4;
                   the last one holds MPR's final portal
    gjk_simplices  list of float64 (n, 3), n <= 4: GJK's simplex after each step that
                   changed it, the last one its final simplex (cores' difference)
    epa_polytopes  list of (vertices float64 (m, 3), faces int32 (f, 3)): EPA's polytope
                   at the start of each step, faces wound counter-clockwise seen from
                   outside; the last one is the final polytope (cores' difference)
    core_radius    m: the cores' difference grown by a ball of this radius is A - B
    dropped        records that did not fit in the trace region (0 unless ``rows`` was
                   small); the lists hold the ones that did, in order
    """
    result: CollisionResult
    answered_by: str
    traced: str
    mpr_portals: list
    gjk_simplices: list
    epa_polytopes: list
    core_radius: float
    dropped: int


def _no_plane(code, what):
    if code == PLANE:
        raise ValueError(f"{what} is a plane: a half-space has no support mapping, so "
                         f"MPR and GJK/EPA cannot be traced on it")


class _Pair:
    """Two shapes at world poses as the kernels take them, in the dispatcher's
    canonical order: k0 / k1 the kernel's A / B, ``to_world`` (3, 3) maps a point of
    the kernel's difference (its A's frame) to the world-frame A - B."""

    def __init__(self, shape_a, pose_a, shape_b, pose_b):
        ca, pa, va, verts_a = _pack(shape_a, 0)
        cb, pb, vb, verts_b = _pack(shape_b, len(verts_a))
        _no_plane(ca, "shape_a")
        _no_plane(cb, "shape_b")
        pos_a, q_a = validate_pose(pose_a, "pose_a")
        pos_b, q_b = validate_pose(pose_b, "pose_b")
        self.verts = np.ascontiguousarray(
            np.concatenate([verts_a, verts_b]).reshape(-1, 3), dtype=np.float64)
        sa = (ca, pa, va[0], va[1])
        sb = (cb, pb, vb[0], vb[1])
        ra, rb = quat_to_matrix(q_a), quat_to_matrix(q_b)
        self.swapped = ca > cb
        if self.swapped:
            sa, sb, ra, rb, pos_a, pos_b = sb, sa, rb, ra, pos_b, pos_a
        self.sa, self.sb = sa, sb
        self.r_ab = np.ascontiguousarray(ra.T @ rb)
        self.t_ab = np.ascontiguousarray(ra.T @ (pos_b - pos_a))
        self.to_world = -ra if self.swapped else ra
        self.core_radius = float(inflation(sa[0], sa[1]) + inflation(sb[0], sb[1]))

    def world(self, points):
        return np.asarray(points) @ self.to_world.T

    def faces(self, faces):
        """Faces of a kernel polytope, wound outward in the world-frame A - B (a
        point reflection turns the winding)."""
        f = np.asarray(faces, dtype=np.int32)
        return f[:, [0, 2, 1]] if self.swapped else f


def _records(buf, base):
    """(kind, first block (n1, 3), second block (n2, 3)) per record of the trace
    region at row ``base`` (kernels/tracebuf.py), and the dropped count."""
    n_rec, dropped, used = (int(x) for x in buf[base])
    out = []
    r = base + TR_HEADER_ROWS
    for _ in range(n_rec):
        kind, n1, n2 = (int(x) for x in buf[r])
        out.append((kind, buf[r + 1:r + 1 + n1].copy(),
                    buf[r + 1 + n1:r + 1 + n1 + n2].copy()))
        r += 1 + n1 + n2
    assert r == base + TR_HEADER_ROWS + used
    return out, dropped


def _run_mpr(pair, rows):
    """MPR on the pair with a trace region of ``rows`` rows: (status, result row in
    the kernel's frame, records, dropped)."""
    buf = np.empty((MPR_WS_ROWS + rows, 3))
    buf[MPR_WS_ROWS:MPR_WS_ROWS + TR_HEADER_ROWS] = 0.0
    out = np.zeros(OUT_SIZE)
    st = mpr_ws(pair.sa, pair.sb, pair.verts, pair.r_ab, pair.t_ab, out, buf)
    return (st, out) + _records(buf, MPR_WS_ROWS)


def _run_gjk_epa(pair, rows, iterate):
    """GJK/EPA on the pair with a trace region of ``rows`` rows, its closed forms
    skipped when ``iterate``: (status, result row in the kernel's frame, records,
    dropped)."""
    ws = make_gjk_workspace_traced(rows)
    base = ws[0].shape[0] - rows
    ws[0][base + 1, 0] = 1.0 if iterate else 0.0
    out = np.zeros(OUT_SIZE)
    st = gjk_epa_ws(pair.sa, pair.sb, pair.verts, pair.r_ab, pair.t_ab, out, ws, math.inf)
    return (st, out) + _records(ws[0], base)


def trace_pair(shape_a, pose_a, shape_b, pose_b, method="auto", rows=TRACE_ROWS):
    """Trace the narrow phase on one pair (module docstring).

    shape_a, shape_b  shape dicts (mkcollision_ros.shapes), no planes (ValueError)
    pose_a, pose_b    (position (3,), quat_xyzw (4,)), world frame, metres
    method            a ``collide`` method name
    rows              rows of the trace region (>= 2); records beyond it are dropped
                      and counted in ``dropped``
    Returns a PairTrace, every point in the world frame of A - B.
    """
    pair = _Pair(shape_a, pose_a, shape_b, pose_b)
    rows = int(rows)
    if rows < TR_HEADER_ROWS:
        raise ValueError(f"rows must be >= {TR_HEADER_ROWS}, got {rows}")
    result = collide(shape_a, pose_a, shape_b, pose_b, method)
    traced = "mpr" if result.method == "mpr" else "gjk_epa"
    portals, simplices, polytopes = [], [], []
    if traced == "mpr":
        _, _, records, dropped = _run_mpr(pair, rows)
        portals = [(_STAGES[k], pair.world(p)) for k, p, _ in records]
    else:
        _, _, records, dropped = _run_gjk_epa(pair, rows, True)
        simplices = [pair.world(p) for k, p, _ in records if k == TR_GJK]
        polytopes = [(pair.world(p), pair.faces(f)) for k, p, f in records if k == TR_EPA]
    return PairTrace(result=result, answered_by=result.method, traced=traced,
                     mpr_portals=portals, gjk_simplices=simplices,
                     epa_polytopes=polytopes, core_radius=pair.core_radius,
                     dropped=dropped)


def fibonacci_directions(n):
    """n unit vectors (n, 3) spread evenly over the sphere (a Fibonacci lattice)."""
    if int(n) < 4:
        raise ValueError(f"need at least 4 directions, got {n}")
    k = np.arange(int(n)) + 0.5
    z = 1.0 - 2.0 * k / int(n)
    r = np.sqrt(1.0 - z * z)
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def minkowski_difference(shape_a, pose_a, shape_b, pose_b, directions=400):
    """The Minkowski difference A - B (world frame, the frame of trace_pair) as a
    triangle mesh: the convex hull (mkcollision_ros.hull) of the support points
    s_A(u) - s_B(-u) of the whole shapes over ``directions`` (a count of Fibonacci
    directions, or unit vectors (k, 3), world frame).  An inner approximation: every
    vertex is a boundary point of A - B.

    Returns (vertices float64 (m, 3), triangles int32 (t, 3)) with every vertex a
    corner and the triangles wound counter-clockwise seen from outside.  ValueError
    for a plane or when the difference is flat.
    """
    pair = _Pair(shape_a, pose_a, shape_b, pose_b)
    if np.ndim(directions) == 0:
        u = fibonacci_directions(directions)
    else:
        u = np.asarray(directions, dtype=np.float64)
        if u.ndim != 2 or u.shape[1] != 3 or not np.all(np.isfinite(u)):
            raise ValueError(f"directions: need a count or (k, 3) finite vectors, got "
                             f"shape {u.shape}")
    # world direction u -> the kernel's frame (the kernel's difference is -(A - B)
    # when swapped: its support along -u)
    d = u @ pair.to_world
    pts = np.empty((len(d), 3))
    for i, (dx, dy, dz) in enumerate(d.tolist()):
        ax, ay, az, bx, by, bz = minkowski_full_xyz(pair.sa, pair.sb, pair.verts,
                                                    pair.r_ab, pair.t_ab, dx, dy, dz)
        pts[i] = ax - bx, ay - by, az - bz
    return _convex_mesh(pair.world(pts))


def _spread(P, tol):
    """Indices of the points of P kept when each point within ``tol`` of an earlier
    kept one is dropped."""
    keep = []
    for i in range(len(P)):
        if not keep or np.min(np.linalg.norm(P[keep] - P[i], axis=1)) > tol:
            keep.append(i)
    return np.array(keep)


def _convex_mesh(P):
    """(vertices, triangles int32) of the hull of the points P, every vertex a corner.
    Points closer together than a tolerance are merged first (the hull's tolerances
    leave a dent where two corners nearly coincide); the tolerance grows until the
    hull is convex to round-off (no corner above a face plane by 1e-9 of the extent)."""
    size = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
    for tol in (1e-6, 1e-4, 1e-2):
        Q = P[_spread(P, tol * size)]
        if len(Q) < 4:
            break
        tri = hull_triangles(Q)
        nrm = np.cross(Q[tri[:, 1]] - Q[tri[:, 0]], Q[tri[:, 2]] - Q[tri[:, 0]])
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        off = np.einsum("ij,ij->i", nrm, Q[tri[:, 0]])
        if np.all(Q @ nrm.T <= off + 1e-9 * size):
            used, tri = np.unique(tri, return_inverse=True)
            return Q[used], tri.reshape(-1, 3).astype(np.int32)
    raise ValueError("minkowski_difference: no convex hull of the support points (the "
                     "difference is flat or degenerate)")
