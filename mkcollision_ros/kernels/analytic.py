"""Exact closed-form pair tests: sphere-sphere, sphere-box, sphere-capsule,
capsule-capsule, and a half-space (plane) against any shape.

Every pair is reduced to the closest points of two *cores* (a point, a segment, a box;
kernels/geometry.py) followed by subtracting the two inflation radii, which is exact
because a shape with margin is its core grown by a ball (Minkowski sum):

    signed distance = core distance - (r_a + r_b),   normal = core direction A -> B.

When the cores overlap (sphere centre inside the core box; capsule axes that cross) the
core distance is signed (negative) and the normal is the minimum-translation direction
of the cores, so the result stays exact (sphere-box: nearest face; crossing segments:
the common perpendicular, since their Minkowski difference is a flat parallelogram).

Frames and signs (as everywhere, see mkcollision_ros/results.py): inputs ``r_ab``
(3, 3) and ``t_ab`` (3,) are B's pose in A's frame (float64, metres); every output is in
A's frame; ``out`` float64[OUT_SIZE] receives the signed distance (> 0 apart), the unit
normal from A to B, witness points ``pa`` on A's surface and ``pb`` on B's surface with
``pb - pa == dist * normal``, iterations (1) and ``M_ANALYTIC``.

Pairs are accepted in either order (A, B) or (B, A); unsupported pairs and plane-plane
return ST_NOT_RUN and leave ``out`` untouched.

Half-space: B = {x : n.x <= d} in B's frame (prm[0:3] = unit n, prm[3] = d).  The signed
distance of A is min over x in A of (n.x - d), reached at A's support point along -n; B
lies on the -n side, so the normal from A to B is -n (rotated into A's frame), and moving
B by the depth along it moves the boundary plane onto A's deepest point.

Segment-segment closest points follow the classic clamped parametric solution (e.g.
Ericson, *Real-Time Collision Detection*, 2005, sec. 5.1.9), with the parallel case
handled by clamping an endpoint projection.
"""
import math

import numpy as np

from .constants import (BOX, CAPSULE, M_ANALYTIC, OUT_DIST, OUT_ITERS, OUT_METHOD,
                        OUT_NORMAL, OUT_PA, OUT_PB, PLANE, SPHERE, ST_NOT_RUN,
                        ST_PENETRATING, ST_SEPARATED, ST_TOUCHING, TOUCH_TOL)
from .geometry import inflation, shape_scale, support_full
from .jit import njit_kernel


@njit_kernel
def _mv(r, v):
    """r @ v for a (3, 3) matrix and a (3,) vector (no BLAS)."""
    o = np.empty(3)
    for i in range(3):
        o[i] = r[i, 0] * v[0] + r[i, 1] * v[1] + r[i, 2] * v[2]
    return o


@njit_kernel
def _mtv(r, v):
    """r.T @ v for a (3, 3) matrix and a (3,) vector."""
    o = np.empty(3)
    for i in range(3):
        o[i] = r[0, i] * v[0] + r[1, i] * v[1] + r[2, i] * v[2]
    return o


@njit_kernel
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit_kernel
def _cross(a, b):
    o = np.empty(3)
    o[0] = a[1] * b[2] - a[2] * b[1]
    o[1] = a[2] * b[0] - a[0] * b[2]
    o[2] = a[0] * b[1] - a[1] * b[0]
    return o


@njit_kernel
def classify(dist, scale):
    """Status code of a signed distance (m) under the touching rule (constants.py)."""
    tol = TOUCH_TOL * scale
    if dist > tol:
        return ST_SEPARATED
    if dist >= -tol:
        return ST_TOUCHING
    return ST_PENETRATING


@njit_kernel
def _any_perp(v, out):
    """A unit vector perpendicular to ``v`` (3,) (or +z when v is zero)."""
    ax, ay, az = abs(v[0]), abs(v[1]), abs(v[2])
    if ax == 0.0 and ay == 0.0 and az == 0.0:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = 1.0
        return
    # cross with the least aligned axis
    if ax <= ay and ax <= az:
        e = np.array([1.0, 0.0, 0.0])
    elif ay <= az:
        e = np.array([0.0, 1.0, 0.0])
    else:
        e = np.array([0.0, 0.0, 1.0])
    c = _cross(v, e)
    out[:] = c / math.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])


@njit_kernel
def _finish(ca, cb, core_dist, n, ra, rb, out):
    """Write a result from core witness points ``ca``, ``cb`` (A frame), the signed core
    distance along the unit normal ``n`` (A -> B) and the inflation radii."""
    dist = core_dist - ra - rb
    out[OUT_DIST] = dist
    for i in range(3):
        out[OUT_NORMAL + i] = n[i]
        out[OUT_PA + i] = ca[i] + ra * n[i]
        out[OUT_PB + i] = out[OUT_PA + i] + dist * n[i]
    out[OUT_ITERS] = 1.0
    out[OUT_METHOD] = M_ANALYTIC
    return dist


@njit_kernel
def _point_point(pa, pb, ra, rb, out):
    d = pb - pa
    dn = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    n = np.empty(3)
    if dn > 0.0:
        n[:] = d / dn
    else:
        n[0] = 0.0
        n[1] = 0.0
        n[2] = 1.0
    return _finish(pa, pb, dn, n, ra, rb, out)


@njit_kernel
def _closest_on_segment(p, a, b):
    """Closest point to ``p`` on segment [a, b] (all (3,))."""
    ab = b - a
    den = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]
    if den <= 0.0:
        return a.copy()
    s = ((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1] + (p[2] - a[2]) * ab[2]) / den
    s = min(1.0, max(0.0, s))
    return a + s * ab


@njit_kernel
def _segment_segment(p1, q1, p2, q2):
    """Closest points (c1 on [p1, q1], c2 on [p2, q2]); robust for parallel and
    degenerate (point) segments."""
    d1 = q1 - p1
    d2 = q2 - p2
    r = p1 - p2
    a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]
    e = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]
    f = d2[0] * r[0] + d2[1] * r[1] + d2[2] * r[2]
    if a <= 0.0 and e <= 0.0:
        return p1.copy(), p2.copy()
    if a <= 0.0:
        return p1.copy(), _closest_on_segment(p1, p2, q2)
    if e <= 0.0:
        return _closest_on_segment(p2, p1, q1), p2.copy()
    c = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2]
    b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]
    den = a * e - b * b
    # den = |d1|^2 |d2|^2 sin^2: treat as parallel below a relative threshold
    if den > 1e-14 * a * e:
        s = min(1.0, max(0.0, (b * f - c * e) / den))
    else:
        s = 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = min(1.0, max(0.0, -c / a))
    elif t > 1.0:
        t = 1.0
        s = min(1.0, max(0.0, (b - c) / a))
    c1 = p1 + s * d1
    c2 = p2 + t * d2
    if den <= 1e-14 * a * e:
        # parallel: the pair above is valid but pick the middle of the overlap so the
        # witness does not jump between ends; re-project the overlap midpoint
        ua = _dot(p2 - p1, d1) / a
        ub = _dot(q2 - p1, d1) / a
        lo = max(0.0, min(ua, ub))
        hi = min(1.0, max(ua, ub))
        if lo <= hi:
            s = 0.5 * (lo + hi)
            c1 = p1 + s * d1
            c2 = _closest_on_segment(c1, p2, q2)
    return c1, c2


@njit_kernel
def _sphere_box(sa, sb, r_ab, t_ab, out):
    """A = sphere (centre at A's origin), B = box (rounded by its margin)."""
    ra = inflation(sa[0], sa[1])
    rb = inflation(sb[0], sb[1])
    h = sb[1][0:3]
    # sphere centre in B's frame: r_ab^T (0 - t_ab)
    c = -_mtv(r_ab, t_ab)
    q = np.empty(3)
    inside = True
    for i in range(3):
        q[i] = min(h[i], max(-h[i], c[i]))
        if abs(c[i]) > h[i]:
            inside = False
    n_b = np.zeros(3)
    if not inside:
        d = q - c
        core = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        n_b[:] = d / core
    else:
        # nearest face: B must move along -sign(c_k) e_k to push that face past the centre
        k = 0
        best = np.inf
        for i in range(3):
            g = h[i] - abs(c[i])
            if g < best:
                best = g
                k = i
        core = -best
        s = 1.0 if c[k] >= 0.0 else -1.0
        n_b[k] = -s
        q[k] = s * h[k]
    n = _mv(r_ab, n_b)
    ca = np.zeros(3)
    return _finish(ca, _mv(r_ab, q) + t_ab, core, n, ra, rb, out)


@njit_kernel
def _plane_any(sa, sb, verts, r_ab, t_ab, out):
    """A = any non-plane shape, B = half-space n.x <= d (B's frame)."""
    nb = sb[1][0:3]
    d = sb[1][3]
    n_a = _mv(r_ab, nb)                     # plane normal in A's frame
    dirn = -n_a
    x = np.empty(3)
    support_full(sa[0], sa[1], verts, sa[2], sa[3], dirn, x)
    # signed distance: n.(x in B's frame) - d
    xb = _mtv(r_ab, x - t_ab)
    dist = nb[0] * xb[0] + nb[1] * xb[1] + nb[2] * xb[2] - d
    out[OUT_DIST] = dist
    for i in range(3):
        out[OUT_NORMAL + i] = -n_a[i]
        out[OUT_PA + i] = x[i]
        out[OUT_PB + i] = x[i] - dist * n_a[i]
    out[OUT_ITERS] = 1.0
    out[OUT_METHOD] = M_ANALYTIC
    return dist


@njit_kernel
def _ordered(sa, sb, verts, r_ab, t_ab, out):
    """Closed form for code_a <= code_b; returns (ran, dist)."""
    ca, cb = sa[0], sb[0]
    if cb == PLANE:
        if ca == PLANE:
            return False, 0.0
        return True, _plane_any(sa, sb, verts, r_ab, t_ab, out)
    ra = inflation(ca, sa[1])
    rb = inflation(cb, sb[1])
    if ca == SPHERE and cb == SPHERE:
        return True, _point_point(np.zeros(3), t_ab.copy(), ra, rb, out)
    if ca == SPHERE and cb == BOX:
        return True, _sphere_box(sa, sb, r_ab, t_ab, out)
    if ca == SPHERE and cb == CAPSULE:
        hb = sb[1][1]
        p = t_ab + hb * r_ab[:, 2]
        q = t_ab - hb * r_ab[:, 2]
        c2 = _closest_on_segment(np.zeros(3), p, q)
        if c2[0] * c2[0] + c2[1] * c2[1] + c2[2] * c2[2] > 0.0:
            return True, _point_point(np.zeros(3), c2, ra, rb, out)
        n = np.empty(3)
        _any_perp(r_ab[:, 2].copy(), n)
        return True, _finish(np.zeros(3), c2, 0.0, n, ra, rb, out)
    if ca == CAPSULE and cb == CAPSULE:
        ha = sa[1][1]
        hb = sb[1][1]
        p1 = np.array([0.0, 0.0, ha])
        q1 = np.array([0.0, 0.0, -ha])
        p2 = t_ab + hb * r_ab[:, 2]
        q2 = t_ab - hb * r_ab[:, 2]
        c1, c2 = _segment_segment(p1, q1, p2, q2)
        d = c2 - c1
        dn = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        if dn > 1e-15 * shape_scale(sa, sb):
            return True, _point_point(c1, c2, ra, rb, out)
        # crossing axes: separate along the common perpendicular
        n = _cross(q1 - p1, q2 - p2)
        nn = math.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        if nn > 0.0:
            n /= nn
            # orient from A's centre towards B's centre when that is defined
            if n[0] * t_ab[0] + n[1] * t_ab[1] + n[2] * t_ab[2] < 0.0:
                n = -n
        else:
            _any_perp(np.array([0.0, 0.0, 1.0]), n)
        return True, _finish(c1, c1, 0.0, n, ra, rb, out)
    return False, 0.0


@njit_kernel
def collide_analytic(sa, sb, verts, r_ab, t_ab, out):
    """Exact closed-form collision of a supported pair; ST_NOT_RUN otherwise.

    sa, sb  shape tuples (code int64, prm float64[8], v0 int64, vn int64)
    verts   float64 (M, 3) convex vertices (body frames), used by plane-vs-convex
    r_ab    float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    out     float64[OUT_SIZE]: signed distance (m), unit normal A -> B, pa, pb (A's
            frame, pb - pa = dist * normal), iterations = 1, method = M_ANALYTIC
    Returns the status code under the touching rule (scale = sum of bounding radii).
    Either order of a supported pair is accepted.
    """
    if sa[0] <= sb[0]:
        ran, dist = _ordered(sa, sb, verts, r_ab, t_ab, out)
        if not ran:
            return ST_NOT_RUN
        return classify(dist, shape_scale(sa, sb))
    # swapped: solve (B, A) in B's frame, then map back and flip the normal
    r_ba = r_ab.T.copy()
    t_ba = -_mv(r_ba, t_ab)
    tmp = np.empty(out.shape[0])
    ran, dist = _ordered(sb, sa, verts, r_ba, t_ba, tmp)
    if not ran:
        return ST_NOT_RUN
    n = -_mv(r_ab, tmp[OUT_NORMAL:OUT_NORMAL + 3])
    pa = _mv(r_ab, tmp[OUT_PB:OUT_PB + 3]) + t_ab
    pb = _mv(r_ab, tmp[OUT_PA:OUT_PA + 3]) + t_ab
    out[OUT_DIST] = dist
    for i in range(3):
        out[OUT_NORMAL + i] = n[i]
        out[OUT_PA + i] = pa[i]
        out[OUT_PB + i] = pb[i]
    out[OUT_ITERS] = tmp[OUT_ITERS]
    out[OUT_METHOD] = M_ANALYTIC
    return classify(dist, shape_scale(sa, sb))
