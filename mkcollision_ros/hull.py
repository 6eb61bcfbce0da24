"""Which points of a convex shape's point list are needed: the convex hull in numpy.

A convex shape is the convex hull of its points, and every kernel that reads it walks
all of them (the support function is a pass over the points, geometry.support_core_xyz;
the contact polygon of manifold.py collects the points near a support plane).  A point
strictly inside the hull never attains a support maximum, so dropping it changes no
support point, and it makes every pass shorter: point clouds and non-convex meshes
given as convex shapes carry many such points.  ``hull_keep`` finds them.

How (quickhull, Barber, Dobkin & Huhdanpaa, ACM TOMS 22(4), 1996, with its conflict
lists): an initial tetrahedron of extreme points, then, face by face, the point
farthest above a face is added, the faces it sees are removed and its horizon is closed
with new faces; the points above a removed face are handed to the new faces they lie
above, or dropped when above none.

Why it is safe whatever the round-off: a point is dropped only if it lies more than
_MARGIN times the points' extent (``margin``) below the plane of every face of the
computed surface Q, and only after Q is
checked to be a closed, consistently oriented surface with the Euler characteristic of
a sphere whose every face plane has the starting tetrahedron's centroid c strictly
below it.  Such a surface is star-shaped about c (radial projection from c covers the
sphere exactly once), so a point below every face plane lies inside Q, and Q, made of
triangles on input points, lies inside their hull: the dropped point, with a ball of
radius ``margin`` about it, is inside the hull, never a support point along any
direction.  Any failed check (flat or needle point sets, whose tetrahedron is too
thin; a horizon broken by round-off) keeps every point.  The kept points stay in their
given order, so the kernels' first-maximum rule picks the same support point as with
all points: every support is bit-identical, and so are GJK/EPA's distances, normals and
witness points (tests/test_hull.py).  What moves is the shape's interior point, the
mean of its points (geometry.centre_core): GJK's first direction, hence at times its
step count, and MPR's portal origin, hence MPR's depth along its portal.

More than GROUP_MIN_POINTS kept points are then reordered into groups
(``support_groups``): the support value stays the maximum, and where points tie the
first found of them is taken, which may be another of them.
"""
import math

import numpy as np

from .kernels.constants import FAN_MAX_POINTS
from .kernels.jit import njit_kernel

# a face's "outside": farther above its plane than this (relative to the points' extent);
# points within it of the hull's surface are kept, so nothing depends on its exact value
_ABOVE = 1e-10
# a point is dropped only when it lies deeper than this below every face plane
_MARGIN = 1e-9
# the starting tetrahedron must be at least this thick (else the set is flat or a needle)
_THICK = 1e-7


def _plane(P, a, b, c):
    """Unit normal (3,) and offset of the plane through P[a], P[b], P[c]; a zero normal
    and a NaN offset when degenerate (every test on it then fails).  Scalar arithmetic:
    numpy's cross product of two 3-vectors costs ~20x more."""
    ax, ay, az = P[a].tolist()
    ux, uy, uz = (P[b] - P[a]).tolist()
    vx, vy, vz = (P[c] - P[a]).tolist()
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    ln = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not ln > 0.0:
        return np.zeros(3), math.nan
    nx, ny, nz = nx / ln, ny / ln, nz / ln
    return np.array([nx, ny, nz]), nx * ax + ny * ay + nz * az


def _tetrahedron(P, size):
    """Four indices of a thick starting tetrahedron, or None when the points are flat or
    collinear to _THICK * size."""
    i0 = int(np.argmin(P[:, 0]))
    i1 = int(np.argmax(np.linalg.norm(P - P[i0], axis=1)))
    e = P[i1] - P[i0]
    le = float(np.linalg.norm(e))
    if not le > _THICK * size:
        return None
    e /= le
    r = P - P[i0]
    off = r - np.outer(r @ e, e)
    i2 = int(np.argmax(np.linalg.norm(off, axis=1)))
    if not float(np.linalg.norm(off[i2])) > _THICK * size:
        return None
    m = np.cross(e, P[i2] - P[i0])
    m /= np.linalg.norm(m)
    h = r @ m
    i3 = int(np.argmax(np.abs(h)))
    if not abs(float(h[i3])) > _THICK * size:
        return None
    return i0, i1, i2, i3


def _closed_star_surface(faces, normals, offsets, c, size):
    """Whether the triangles ``faces`` (list of index triples, outward by winding) form a
    closed oriented surface of Euler characteristic 2 with c strictly below every face
    plane (the conditions of the module docstring); ``normals`` (K, 3) and ``offsets``
    (K,) are the planes the caller keeps (and drops points by)."""
    directed = set()
    for f in faces:
        for k in range(3):
            e = (f[k], f[(k + 1) % 3])
            if e in directed:
                return False
            directed.add(e)
    if any((b, a) not in directed for a, b in directed):
        return False
    nverts = len({v for f in faces for v in f})
    if nverts - len(directed) // 2 + len(faces) != 2:
        return False
    return bool(np.all(normals @ c < offsets - _THICK * size))


def _surface(P):
    """The computed surface Q of the module docstring for the points P (M >= 4, 3):
    (faces (K, 3) int64 wound outward, unit normals (K, 3), offsets (K,), the points'
    extent), or None when a check fails (flat or needle sets, round-off)."""
    n = len(P)
    every = np.arange(n)
    size = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
    tet = _tetrahedron(P, size) if size > 0.0 else None
    if tet is None:
        return None
    above = _ABOVE * size
    c = P[list(tet)].mean(axis=0)
    # faces in growing arrays: corners wound outward, unit normal, offset, alive flag;
    # the points above each live face (not yet on the hull) in ``conflict``
    FA = np.zeros((64, 3), dtype=np.int64)
    FN = np.zeros((64, 3))
    FD = np.full(64, np.inf)
    alive = np.zeros(64, dtype=bool)
    conflict = {}
    edge_face = {}      # directed edge (a, b) of a live face -> that face
    nf = 0

    def add_face(a, b, cc, orient):
        nonlocal FA, FN, FD, alive, nf
        nrm, d = _plane(P, a, b, cc)
        if orient and float(nrm @ c) > d:     # only the starting faces may come inward
            a, b = b, a
            nrm, d = -nrm, -d
        if nf == len(FD):
            FA = np.concatenate([FA, np.zeros_like(FA)])
            FN = np.concatenate([FN, np.zeros_like(FN)])
            FD = np.concatenate([FD, np.full(len(FD), np.inf)])
            alive = np.concatenate([alive, np.zeros(len(alive), dtype=bool)])
        FA[nf] = a, b, cc
        FN[nf] = nrm
        FD[nf] = d
        alive[nf] = True
        conflict[nf] = None
        for e in ((a, b), (b, cc), (cc, a)):
            edge_face[e] = nf
        nf += 1
        return nf - 1

    def assign(ids, pts):
        """Hand each point to the face among ``ids`` it lies farthest above, if any."""
        if len(pts) == 0:
            return
        S = P[pts] @ FN[ids].T - FD[ids]
        best = np.argmax(S, axis=1)
        out = S[np.arange(len(pts)), best] > above
        for k, i in enumerate(ids):
            sel = out & (best == k)
            if sel.any():
                conflict[i] = pts[sel]

    i0, i1, i2, i3 = tet
    start = [add_face(i0, i1, i2, True), add_face(i0, i3, i1, True),
             add_face(i1, i3, i2, True), add_face(i0, i2, i3, True)]
    assign(start, np.setdiff1d(every, np.array(tet)))
    todo = list(start)
    steps = 0
    while todo:
        f = todo.pop()
        if not alive[f] or conflict[f] is None:
            continue
        steps += 1
        if steps > n:                           # each step puts a point on the hull
            return None
        pts = conflict[f]
        p = int(pts[np.argmax(P[pts] @ FN[f] - FD[f])])
        # the faces p sees: a walk over edge neighbours from f (the seen region of a
        # convex surface is connected); the edges to unseen faces form the horizon
        seen = [f]
        alive[f] = False
        horizon = []
        k = 0
        while k < len(seen):
            a, b, cc = FA[seen[k]].tolist()
            k += 1
            for e in ((a, b), (b, cc), (cc, a)):
                g = edge_face.get((e[1], e[0]), -1)
                if g < 0:
                    return None                 # not closed: round-off broke it
                if alive[g] and FN[g] @ P[p] - FD[g] > above:
                    alive[g] = False
                    seen.append(g)
                elif alive[g]:
                    horizon.append(e)
        for g in seen:
            a, b, cc = FA[g].tolist()
            for e in ((a, b), (b, cc), (cc, a)):
                if edge_face.get(e) == g:
                    del edge_face[e]
        lists = [conflict[g] for g in seen if conflict[g] is not None]
        orphans = np.unique(np.concatenate(lists)) if lists else np.zeros(0, np.int64)
        orphans = orphans[orphans != p]
        for g in seen:
            del conflict[g]
        new = [add_face(a, b, p, False) for a, b in horizon]
        if not np.all(FN[new] @ c < FD[new]):   # round-off: the final check would fail
            return None
        assign(new, orphans)
        todo.extend(new)
    live = np.flatnonzero(alive[:nf])
    if not _closed_star_surface(FA[live].tolist(), FN[live], FD[live], c, size):
        return None
    return FA[live], FN[live], FD[live], size


def hull_keep(points):
    """Indices (ascending) of the points a convex shape keeps: all but those certainly
    strictly inside the hull of the others (module docstring).  ``points``: (M, 3)
    finite floats."""
    P = np.asarray(points, dtype=np.float64)
    n = len(P)
    every = np.arange(n)
    if n < 5:
        return every
    surface = _surface(P)
    if surface is None:
        return every
    faces, normals, offsets, size = surface
    # the hull's vertices stay; every other point is tested against all face planes
    # (in blocks: points times faces can be large)
    keep = np.zeros(n, dtype=bool)
    keep[np.unique(faces)] = True
    rest = np.flatnonzero(~keep)
    for k in range(0, len(rest), 1024):
        idx = rest[k:k + 1024]
        depth_below = (offsets - P[idx] @ normals.T).min(axis=1)
        keep[idx] = ~(depth_below > _MARGIN * size)
    return np.flatnonzero(keep)


def hull_triangles(points):
    """The convex hull of ``points`` ((M, 3) finite floats, M >= 4) as triangles: (K, 3)
    int64 indices into ``points``, wound counter-clockwise seen from outside (the
    normal (p1 - p0) x (p2 - p0) points out), from the same quickhull as ``hull_keep``
    (points within its tolerance of a face are no corners).  ValueError when the points
    are flat or round-off broke the surface (module docstring, the checks)."""
    P = np.asarray(points, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) < 4 or not np.all(np.isfinite(P)):
        raise ValueError(f"hull_triangles: need (M >= 4, 3) finite points, got shape "
                         f"{P.shape}")
    surface = _surface(P)
    if surface is None:
        raise ValueError("hull_triangles: the points are flat (or round-off broke the "
                         "hull): no closed convex surface")
    return surface[0].astype(np.int64)


# point sets up to this size are kept whole (see hull_points)
HULL_MIN_POINTS = 64
# hulls of more points than this are stored in groups (see support_groups)
GROUP_MIN_POINTS = 128
GROUP_SIZE = 16
_CACHE = {}
_CACHE_SIZE = 256


def _leaves(P, idx):
    """``idx`` split at the median of the longest extent, again and again, into runs of
    at most GROUP_SIZE points: the runs, each compact in space."""
    if len(idx) <= GROUP_SIZE:
        return [idx]
    Q = P[idx]
    axis = int(np.argmax(Q.max(axis=0) - Q.min(axis=0)))
    order = idx[np.argsort(Q[:, axis], kind="stable")]
    half = len(order) // 2
    return _leaves(P, order[:half]) + _leaves(P, order[half:])


def support_groups(points):
    """(points, rows): a large hull's points reordered into runs of at most GROUP_SIZE
    points close together, and two rows per run for the kernels (geometry's
    ``_grouped_support``): its bounding ball's centre (x, y, z), then (radius, first
    point, point count).  Sets of GROUP_MIN_POINTS points or fewer: the points as given
    and no rows.

    Why: the support along d is at most c . d + r |d| over a run's ball, so a pass over
    the balls finds the run that holds the maximum and skips every run whose bound is
    below it: ~2 bounds per run and a few runs read, where a pass reads every point
    (bench/dev/big_hulls.py).  MuJoCo climbs its hull's vertex graph from its last support
    vertex instead, which needs state per pair that our support has not got."""
    P = np.ascontiguousarray(points, dtype=np.float64)
    if len(P) <= GROUP_MIN_POINTS:
        return P, np.zeros((0, 3))
    runs = _leaves(P, np.arange(len(P)))
    rows = np.zeros((2 * len(runs), 3))
    start = 0
    for g, run in enumerate(runs):
        Q = P[run]
        centre = 0.5 * (Q.max(axis=0) + Q.min(axis=0))
        rows[2 * g] = centre
        rows[2 * g + 1] = np.linalg.norm(Q - centre, axis=1).max(), start, len(run)
        start += len(run)
    return P[np.concatenate(runs)], rows


def hull_points(points):
    """(points, rows): ``points`` (M, 3) without those ``hull_keep`` drops, in their
    given order, then in ``support_groups``' order with its rows when more than
    GROUP_MIN_POINTS are left (else no rows, a (0, 3) array).

    Only sets of more than HULL_MIN_POINTS points are pruned.  The hull costs ~0.15 ms
    per hull vertex here (a Python loop: 1.4 ms for 25 points, 0.6 s for 4,000 on a
    sphere), and a pass over 64 points costs the kernels tens of ns, so a small set would
    need tens of thousands of support calls to repay it, and the tests, which build
    hundreds of thousands of random 20-30 point hulls, would take minutes longer
    (measured: 434 s of hull time in test_gjk_epa.py's 14 convex tests against coal).
    The answer is kept for the last _CACHE_SIZE point sets, keyed by their bytes:
    ``collide`` builds its two shapes again at every call, which a loop over poses
    repeats with the same points."""
    P = np.ascontiguousarray(points, dtype=np.float64)
    if len(P) <= HULL_MIN_POINTS:
        return P, np.zeros((0, 3))
    return _cached(_CACHE, P, _pruned_groups)


def _pruned_groups(P):
    keep = hull_keep(P)
    return support_groups(P if len(keep) == len(P) else P[keep])


def _cached(cache, P, build):
    """build(P), kept in ``cache`` for the last _CACHE_SIZE point sets, keyed by their
    bytes."""
    key = (P.shape, P.tobytes())
    hit = cache.get(key)
    if hit is None:
        hit = build(P)
        if len(cache) >= _CACHE_SIZE:
            cache.pop(next(iter(cache)))
        cache[key] = hit
    return hit


_FAN_TOL = 1e-10        # on a face plane: within this times the points' extent
_FAN_THIN = 1e-6        # a triple spans a plane only if |cross| > this times extent^2
_FAN_CACHE = {}


@njit_kernel
def _fan_build(P, FN, FO, EV, VX):
    """The faces (unit outward normals FN, offsets FO), edges EV (a, b, face, face) and
    vertices VX of the hull of P, by brute force: every triple of points that spans a
    plane with all points on one side gives a face (coplanar points: one face, its
    offset the largest n . p), two faces sharing two or more points (within tolerance)
    share the edge between the extreme two of them.  Returns (faces, edges, vertices),
    or (0, 0, 0) unless the result is the boundary of a 3-D polytope: every edge
    between two distinct planes, every face with 3 or more edges, V - E + F = 2."""
    n = P.shape[0]
    lo0, lo1, lo2 = P[:, 0].min(), P[:, 1].min(), P[:, 2].min()
    hi0, hi1, hi2 = P[:, 0].max(), P[:, 1].max(), P[:, 2].max()
    size = math.sqrt((hi0 - lo0) ** 2 + (hi1 - lo1) ** 2 + (hi2 - lo2) ** 2)
    if not size > 0.0:
        return 0, 0, 0
    tol = _FAN_TOL * size
    # the points' mean: inside the hull, below every face plane (a face through it
    # would make the hull flat), so each triple's plane is oriented away from it and
    # rejected at the first point above it
    c0, c1, c2 = P[:, 0].mean(), P[:, 1].mean(), P[:, 2].mean()
    one = np.uint64(1)
    on = np.zeros(FN.shape[0], np.uint64)     # per face, a bit per point on its plane
    nf = 0
    for i in range(n):
        for j in range(i + 1, n):
            ux, uy, uz = P[j, 0] - P[i, 0], P[j, 1] - P[i, 1], P[j, 2] - P[i, 2]
            for k in range(j + 1, n):
                vx, vy, vz = P[k, 0] - P[i, 0], P[k, 1] - P[i, 1], P[k, 2] - P[i, 2]
                mx, my, mz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
                mm = math.sqrt(mx * mx + my * my + mz * mz)
                if not mm > _FAN_THIN * size * size:
                    continue
                mx, my, mz = mx / mm, my / mm, mz / mm
                o = mx * P[i, 0] + my * P[i, 1] + mz * P[i, 2]
                sc = mx * c0 + my * c1 + mz * c2 - o
                if not abs(sc) > tol:
                    continue
                if sc > 0.0:
                    mx, my, mz, o = -mx, -my, -mz, -o
                above = False
                for u in range(n):
                    if mx * P[u, 0] + my * P[u, 1] + mz * P[u, 2] - o > tol:
                        above = True
                        break
                if above:
                    continue
                # a plane already found holds all three: the same face
                tri = (one << np.uint64(i)) | (one << np.uint64(j)) | (one << np.uint64(k))
                dup = False
                for f in range(nf):
                    if on[f] & tri == tri:
                        dup = True
                        break
                if dup:
                    continue
                if nf == FN.shape[0]:
                    return 0, 0, 0
                best = o
                mask = np.uint64(0)
                for u in range(n):
                    s = mx * P[u, 0] + my * P[u, 1] + mz * P[u, 2]
                    best = max(best, s)
                    if abs(s - o) <= tol:
                        mask |= one << np.uint64(u)
                FN[nf, 0], FN[nf, 1], FN[nf, 2], FO[nf] = mx, my, mz, best
                on[nf] = mask
                nf += 1
    ne = 0
    deg = np.zeros(nf, np.int64)
    isv = np.zeros(n, np.bool_)
    for f in range(nf):
        for g in range(f + 1, nf):
            common = on[f] & on[g]
            if common == 0 or common & (common - one) == 0:
                continue                # fewer than two points on both planes
            cx = FN[f, 1] * FN[g, 2] - FN[f, 2] * FN[g, 1]
            cy = FN[f, 2] * FN[g, 0] - FN[f, 0] * FN[g, 2]
            cz = FN[f, 0] * FN[g, 1] - FN[f, 1] * FN[g, 0]
            a = b = -1
            sa, sb = np.inf, -np.inf
            for u in range(n):
                if common & (one << np.uint64(u)):
                    s = cx * P[u, 0] + cy * P[u, 1] + cz * P[u, 2]
                    if s < sa:
                        sa, a = s, u
                    if s > sb:
                        sb, b = s, u
            if not (a != b and cx * cx + cy * cy + cz * cz > _FAN_THIN * _FAN_THIN):
                return 0, 0, 0
            if ne == EV.shape[0]:
                return 0, 0, 0
            EV[ne, 0], EV[ne, 1], EV[ne, 2], EV[ne, 3] = a, b, f, g
            ne += 1
            deg[f] += 1
            deg[g] += 1
            isv[a] = True
            isv[b] = True
    nv = 0
    for u in range(n):
        if isv[u]:
            VX[nv] = u
            nv += 1
    if nf < 4 or deg.min() < 3 or nv - ne + nf != 2:
        return 0, 0, 0
    return nf, ne, nv


def fan_rows(points):
    """(faces, edges, vertices, rows): the normal fan of the hull of ``points`` (M, 3),
    M <= FAN_MAX_POINTS, for kernels/pairs/ellipsoid_convex.py, as rows to store after the shape's
    points in the table's verts (such a hull has no group rows): ``faces`` rows of unit outward face
    normals, then one flat run of float64 values three to a row: the faces' offsets
    (the largest n . p over the points), the ``vertices``' point indices, and per edge
    four indices (its two end points and its two faces).  (0, 0, 0, no rows) when
    the points are too many, flat or degenerate (the kernels then use GJK/EPA).
    Cached by the points' bytes, as hull_points."""
    P = np.ascontiguousarray(points, dtype=np.float64)
    if not 4 <= len(P) <= FAN_MAX_POINTS:
        return _NO_FAN
    return _cached(_FAN_CACHE, P, _fan)


_NO_FAN = (0, 0, 0, np.zeros((0, 3)))


def _fan(P):
    n = len(P)
    FN, FO = np.zeros((2 * n, 3)), np.zeros(2 * n)
    EV, VX = np.zeros((3 * n, 4), np.int64), np.zeros(n, np.int64)
    nf, ne, nv = _fan_build(P, FN, FO, EV, VX)
    if nf == 0:
        return _NO_FAN
    flat = np.concatenate([FO[:nf], VX[:nv], EV[:ne].ravel()]).astype(np.float64)
    flat = np.concatenate([flat, np.zeros(-len(flat) % 3)])
    return nf, ne, nv, np.concatenate([FN[:nf], flat.reshape(-1, 3)])
