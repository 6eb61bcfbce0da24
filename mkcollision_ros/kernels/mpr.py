"""Minkowski Portal Refinement (MPR): a boolean intersection test with an approximate
penetration depth, on the whole (inflated) shapes.

Reference: G. Snethen, "XenoCollide: Complex Collision Made Simple", Game Programming
Gems 7, 2008.  MPR works on the Minkowski difference D = A - B (A's frame, support from
geometry.minkowski_support with core=False): the shapes overlap iff the origin lies in D.

Phases
  1. Origin ray.  v0 = centre(A) - centre(B) is inside D (centres from
     geometry.centre_core); the ray from v0 through the origin leaves D through exactly
     one boundary point.  Coincident centres are nudged (any ray direction is valid
     then, the origin being the interior point itself).
  2. Portal discovery.  Find a triangle (v1, v2, v3) of support points whose cone from
     v0 contains the ray: v1 = support(-v0), v2 = support(v1 x v0), then swap support
     points into the triangle until the ray passes through it.
  3. Portal refinement.  Replace one portal vertex with the support point v4 along the
     portal's outward normal, keeping the ray inside the cone, until the support gain
     n.(v4 - v1) falls below MPR_REL_TOL * scale.  The origin lies inside D iff it is
     behind some portal.  Any support point with v.n < 0 proves separation.

Outputs (``out`` float64[OUT_SIZE], A's frame, metres, normal from A to B):
  * penetrating / touching: normal = the final portal's unit outward normal n, signed
    distance = -(n.v1) (minus the distance from the origin to the portal plane); the
    witness points are the barycentric combination of the portal vertices' support
    points on A and on B at the origin's projection onto the portal plane, so
    pb - pa == dist * normal holds exactly.  This is the depth *along the portal
    normal found by the ray from v0*, not the minimum translation: it is >= the true
    depth (up to the tolerance), and the normal can differ from the true one (measured
    in docs/narrowphase-notes.md).  The contact point is the midpoint (pa + pb) / 2.
  * separated: MPR only proves separation.  The distance written is a cheap *lower
    bound* of the true distance, -max(support . d) for the unit direction d whose
    support plane excludes the origin (>= 0; can be 0 when the origin lies on that
    plane); normal = d (it separates A from B); pa = A's support point along d and
    pb = pa + dist * normal (pb is not on B in general).
  * the iteration cap (MPR_MAX_ITERS support evaluations) returns ST_FAILED with the
    current finite estimate (never reached in the tests: penetrating pairs use 28
    support calls on average, 57 at most, separated ones 2.3 on average).
  * a PLANE on either side returns ST_NOT_RUN (use kernels/analytic.py).
Never writes NaN for finite input.
"""
import math

import numpy as np

from .constants import (M_MPR, MPR_MAX_ITERS, MPR_REL_TOL, OUT_DIST, OUT_ITERS,
                        OUT_METHOD, OUT_NORMAL, OUT_PA, OUT_PB, PLANE, ST_FAILED,
                        ST_NOT_RUN, ST_PENETRATING, ST_SEPARATED, ST_TOUCHING,
                        TOUCH_TOL)
from .geometry import centre_core, minkowski_support_xyz, shape_scale
from .jit import njit_kernel


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
def _norm(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@njit_kernel
def _support(sa, sb, verts, r_ab, t_ab, d, w, wa, wb, k):
    """Support of D along ``d`` into row ``k`` of w, wa, wb (each (5, 3))."""
    ax, ay, az, bx, by, bz = minkowski_support_xyz(sa, sb, verts, r_ab, t_ab, d[0], d[1],
                                                   d[2], False)
    wa[k, 0], wa[k, 1], wa[k, 2] = ax, ay, az
    wb[k, 0], wb[k, 1], wb[k, 2] = bx, by, bz
    w[k, 0], w[k, 1], w[k, 2] = ax - bx, ay - by, az - bz


@njit_kernel
def _copy_row(w, wa, wb, src, dst):
    for i in range(3):
        w[dst, i] = w[src, i]
        wa[dst, i] = wa[src, i]
        wb[dst, i] = wb[src, i]


@njit_kernel
def _write_separated(w, wa, k, d, out, iters):
    """Separation proven by support row k along direction d: write the lower bound."""
    dn = _norm(d)
    n = d / dn
    dist = -_dot(w[k], n)
    if dist < 0.0:
        dist = 0.0
    out[OUT_DIST] = dist
    for i in range(3):
        out[OUT_NORMAL + i] = n[i]
        out[OUT_PA + i] = wa[k, i]
        out[OUT_PB + i] = wa[k, i] + dist * n[i]
    out[OUT_ITERS] = iters
    out[OUT_METHOD] = M_MPR
    return ST_SEPARATED


@njit_kernel
def _write_portal(w, wa, wb, out, iters, scale):
    """Result from the portal (rows 1, 2, 3): depth along its normal, barycentric
    witnesses at the origin's projection onto the portal plane.  Returns the signed
    distance, or NaN when the portal is degenerate."""
    n = _cross(w[2] - w[1], w[3] - w[1])
    nn = _norm(n)
    if not nn > 0.0:
        return np.nan
    n /= nn
    if _dot(n, w[1] - w[0]) < 0.0:   # outward: away from the interior point v0
        n = -n
    off = _dot(n, w[1])               # > 0: origin behind the portal (inside)
    q = off * n                       # projection of the origin on the portal plane
    # barycentric coordinates of q in (w1, w2, w3) from sub-triangle areas along n
    l1 = _dot(_cross(w[2] - q, w[3] - q), n)
    l2 = _dot(_cross(w[3] - q, w[1] - q), n)
    l3 = _dot(_cross(w[1] - q, w[2] - q), n)
    s = l1 + l2 + l3
    if not abs(s) > 0.0:
        l1, l2, l3, s = 1.0, 0.0, 0.0, 1.0
    l1 /= s
    l2 /= s
    l3 /= s
    dist = -off
    out[OUT_DIST] = dist
    for i in range(3):
        pa = l1 * wa[1, i] + l2 * wa[2, i] + l3 * wa[3, i]
        out[OUT_NORMAL + i] = n[i]
        out[OUT_PA + i] = pa
        out[OUT_PB + i] = pa + dist * n[i]
    out[OUT_ITERS] = iters
    out[OUT_METHOD] = M_MPR
    return dist


@njit_kernel
def _status(dist, scale):
    tol = TOUCH_TOL * scale
    if dist > tol:
        return ST_SEPARATED
    if dist >= -tol:
        return ST_TOUCHING
    return ST_PENETRATING


@njit_kernel
def mpr(sa, sb, verts, r_ab, t_ab, out):
    """Minkowski Portal Refinement on the whole shapes (see the module docstring).

    sa, sb  shape tuples (code int64, prm float64[8], v0 int64, vn int64)
    verts   float64 (M, 3) convex vertices (body frames)
    r_ab    float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    out     float64[OUT_SIZE] result row in A's frame (module docstring for the meaning
            of each entry per status); out[OUT_METHOD] = M_MPR
    Returns ST_SEPARATED, ST_TOUCHING, ST_PENETRATING or ST_FAILED (iteration cap);
    ST_NOT_RUN (``out`` untouched) when either shape is a PLANE (no support mapping).
    """
    if sa[0] == PLANE or sb[0] == PLANE:
        return ST_NOT_RUN
    scale = shape_scale(sa, sb)
    tol = MPR_REL_TOL * scale
    w = np.zeros((5, 3))
    wa = np.zeros((5, 3))
    wb = np.zeros((5, 3))
    for i in range(3):
        out[i] = 0.0

    # ---- phase 1: interior point and origin ray ---------------------------------------
    ca = np.empty(3)
    cbl = np.empty(3)
    centre_core(sa[0], sa[1], verts, sa[2], sa[3], ca)
    centre_core(sb[0], sb[1], verts, sb[2], sb[3], cbl)
    for i in range(3):
        cb = r_ab[i, 0] * cbl[0] + r_ab[i, 1] * cbl[1] + r_ab[i, 2] * cbl[2] + t_ab[i]
        w[0, i] = ca[i] - cb
        wa[0, i] = ca[i]
        wb[0, i] = cb
    if _norm(w[0]) <= 1e-12 * scale:
        # centres coincide: the origin is interior; any ray direction will do
        w[0, 0] = 1e-9 * scale
        w[0, 1] = 0.0
        w[0, 2] = 0.0

    d = -w[0]
    _support(sa, sb, verts, r_ab, t_ab, d, w, wa, wb, 1)
    if _dot(w[1], d) <= 0.0:
        return _write_separated(w, wa, 1, d, out, 1.0)

    d = _cross(w[1], w[0])
    if _norm(d) <= 1e-14 * _norm(w[1]) * _norm(w[0]):
        # origin on the segment v0-v1: the ray meets the boundary at v1, whose support
        # plane has normal -v0 (exact supporting plane)
        n = -w[0] / _norm(w[0])
        dist = -_dot(w[1], n)
        out[OUT_DIST] = dist
        for i in range(3):
            out[OUT_NORMAL + i] = n[i]
            out[OUT_PA + i] = wa[1, i]
            out[OUT_PB + i] = wa[1, i] + dist * n[i]
        out[OUT_ITERS] = 1.0
        out[OUT_METHOD] = M_MPR
        return _status(dist, scale)

    # ---- phase 2: portal discovery -----------------------------------------------------
    _support(sa, sb, verts, r_ab, t_ab, d, w, wa, wb, 2)
    if _dot(w[2], d) <= 0.0:
        return _write_separated(w, wa, 2, d, out, 2.0)
    n = _cross(w[1] - w[0], w[2] - w[0])
    if _dot(n, w[0]) > 0.0:
        _copy_row(w, wa, wb, 1, 4)
        _copy_row(w, wa, wb, 2, 1)
        _copy_row(w, wa, wb, 4, 2)
        n = -n
    iters = 2
    found = False
    while iters < MPR_MAX_ITERS:
        iters += 1
        if not _norm(n) > 0.0:
            break
        _support(sa, sb, verts, r_ab, t_ab, n, w, wa, wb, 3)
        if _dot(w[3], n) <= 0.0:
            return _write_separated(w, wa, 3, n, out, float(iters))
        if _dot(_cross(w[1], w[3]), w[0]) < 0.0:
            _copy_row(w, wa, wb, 3, 2)          # origin outside (v0, v1, v3): replace v2
            n = _cross(w[1] - w[0], w[3] - w[0])
            continue
        if _dot(_cross(w[3], w[2]), w[0]) < 0.0:
            _copy_row(w, wa, wb, 3, 1)          # origin outside (v0, v3, v2): replace v1
            n = _cross(w[3] - w[0], w[2] - w[0])
            continue
        found = True
        break
    if not found:
        out[OUT_DIST] = 0.0
        out[OUT_NORMAL] = 0.0
        out[OUT_NORMAL + 1] = 0.0
        out[OUT_NORMAL + 2] = 1.0
        for i in range(3):
            out[OUT_PA + i] = wa[0, i]
            out[OUT_PB + i] = wa[0, i]
        out[OUT_ITERS] = float(iters)
        out[OUT_METHOD] = M_MPR
        return ST_FAILED

    # ---- phase 3: portal refinement ----------------------------------------------------
    while True:
        n = _cross(w[2] - w[1], w[3] - w[1])
        nn = _norm(n)
        if not nn > 0.0:
            break                              # degenerate portal: report as is
        n /= nn
        if _dot(n, w[1] - w[0]) < 0.0:
            n = -n
        if iters >= MPR_MAX_ITERS:
            dist = _write_portal(w, wa, wb, out, float(iters), scale)
            if dist != dist:
                out[OUT_DIST] = 0.0
            return ST_FAILED
        iters += 1
        _support(sa, sb, verts, r_ab, t_ab, n, w, wa, wb, 4)
        h = _dot(w[4], n)
        if h < 0.0:
            return _write_separated(w, wa, 4, n, out, float(iters))
        if h - _dot(w[1], n) <= tol:
            break                              # portal within tolerance of the boundary
        # keep the ray from v0 through the origin inside the new portal's cone
        x = _cross(w[4], w[0])
        if _dot(w[1], x) > 0.0:
            if _dot(w[2], x) > 0.0:
                _copy_row(w, wa, wb, 4, 1)
            else:
                _copy_row(w, wa, wb, 4, 3)
        else:
            if _dot(w[3], x) > 0.0:
                _copy_row(w, wa, wb, 4, 2)
            else:
                _copy_row(w, wa, wb, 4, 1)

    dist = _write_portal(w, wa, wb, out, float(iters), scale)
    if dist != dist:
        # degenerate portal (all three points on a line): fall back to v1's support plane
        n = -w[0] / _norm(w[0])
        dist = -_dot(w[1], n)
        out[OUT_DIST] = dist
        for i in range(3):
            out[OUT_NORMAL + i] = n[i]
            out[OUT_PA + i] = wa[1, i]
            out[OUT_PB + i] = wa[1, i] + dist * n[i]
        out[OUT_ITERS] = float(iters)
        out[OUT_METHOD] = M_MPR
    return _status(dist, scale)
