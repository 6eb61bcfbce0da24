"""Minkowski Portal Refinement (MPR): a boolean intersection test with an approximate
penetration depth, on the whole (inflated) shapes.

Reference: G. Snethen, "XenoCollide: Complex Collision Made Simple", Game Programming
Gems 7, 2008.  MPR works on the Minkowski difference D = A - B (A's frame, support from
geometry.minkowski_full_xyz): the shapes overlap iff the origin lies in D.

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

Trace (for visual debugging, mkcollision_ros/trace.py): a ``buf`` of at least
MPR_WS_ROWS + TR_HEADER_ROWS rows makes ``mpr_ws`` record its iterations in the rows
from MPR_WS_ROWS on, a trace region as kernels/tracebuf.py lays out (its options row
unused here): one record per support point of portal
discovery (TR_MPR_DISCOVERY: v0, v1 after the first, v0-v2 after the second, v0-v3
after each one of the discovery loop) and one per portal refinement step
(TR_MPR_REFINEMENT: v0-v3, the portal at the start of the step; the last one is the
final portal).  The results do not depend on it.
"""
import math

import numpy as np

from .constants import (MPR_MAX_ITERS, MPR_NUDGE, MPR_PARALLEL_SIN, MPR_REL_TOL, M_MPR, OUT_DIST,
                        OUT_ITERS, OUT_METHOD, OUT_NORMAL, OUT_PA, OUT_PB, PLANE, ST_FAILED,
                        ST_NOT_RUN, ST_PENETRATING, ST_SEPARATED, ST_TOUCHING, SUPPORT_TIE,
                        TOUCH_TOL)
from .geometry import borrow_args, centre_core, minkowski_full_xyz, shape_scale
from .jit import borrow, njit_inline, njit_kernel, njit_separate
from .tracebuf import (TR_HEADER_ROWS, TR_MPR_DISCOVERY, TR_MPR_REFINEMENT, trace_reset,
                       trace_rows)

# The working rows are w, wa, wb (5, 3): support points of D = A - B and of A and B,
# row 0 the interior point v0, rows 1-3 the portal, row 4 the new support point.
# Vectors are handled as scalar triples (no array temporaries: a small array per cross
# product and difference would spend most of MPR's time in the allocator).


@njit_inline
def _cross_rows(w, i, j, k):
    """(w[j] - w[i]) x (w[k] - w[i]) as three floats."""
    ux, uy, uz = w[j, 0] - w[i, 0], w[j, 1] - w[i, 1], w[j, 2] - w[i, 2]
    vx, vy, vz = w[k, 0] - w[i, 0], w[k, 1] - w[i, 1], w[k, 2] - w[i, 2]
    return uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx


@njit_inline
def _support(sa, sb, verts, r_ab, t_ab, dx, dy, dz, w, wa, wb, k):
    """Support of D along (dx, dy, dz) into row ``k`` of w, wa, wb; returns w[k] . d."""
    ax, ay, az, bx, by, bz = minkowski_full_xyz(sa, sb, verts, r_ab, t_ab, dx, dy, dz)
    wa[k, 0], wa[k, 1], wa[k, 2] = ax, ay, az
    wb[k, 0], wb[k, 1], wb[k, 2] = bx, by, bz
    w[k, 0], w[k, 1], w[k, 2] = ax - bx, ay - by, az - bz
    return w[k, 0] * dx + w[k, 1] * dy + w[k, 2] * dz


@njit_inline
def _copy_row(w, wa, wb, src, dst):
    for i in range(3):
        w[dst, i] = w[src, i]
        wa[dst, i] = wa[src, i]
        wb[dst, i] = wb[src, i]


@njit_inline
def _write_plane(w, wa, k, dx, dy, dz, floor, out, iters):
    """The contact given by the support plane of row k along the direction d: normal
    d / |d|, signed distance -(w[k] . n) raised to ``floor``, pa = A's support point,
    pb = pa + distance * n.  Returns the distance."""
    dn = math.sqrt(dx * dx + dy * dy + dz * dz)
    nx, ny, nz = dx / dn, dy / dn, dz / dn
    dist = -(w[k, 0] * nx + w[k, 1] * ny + w[k, 2] * nz)
    if dist < floor:
        dist = floor
    out[OUT_DIST] = dist
    out[OUT_NORMAL], out[OUT_NORMAL + 1], out[OUT_NORMAL + 2] = nx, ny, nz
    out[OUT_PA], out[OUT_PA + 1], out[OUT_PA + 2] = wa[k, 0], wa[k, 1], wa[k, 2]
    out[OUT_PB] = wa[k, 0] + dist * nx
    out[OUT_PB + 1] = wa[k, 1] + dist * ny
    out[OUT_PB + 2] = wa[k, 2] + dist * nz
    out[OUT_ITERS] = iters
    out[OUT_METHOD] = M_MPR
    return dist


@njit_inline
def _write_separated(w, wa, k, dx, dy, dz, out, iters):
    """Separation proven by support row k along direction d: write the lower bound
    (>= 0)."""
    _write_plane(w, wa, k, dx, dy, dz, 0.0, out, iters)
    return ST_SEPARATED


@njit_inline
def _write_support_plane(w, wa, out, iters):
    """The ray from v0 meets the boundary at v1, whose support plane has normal -v0:
    write that contact (origin on the segment v0-v1, or a degenerate portal).  Returns
    the signed distance."""
    return _write_plane(w, wa, np.int64(1), -w[0, 0], -w[0, 1], -w[0, 2], -np.inf, out, iters)


@njit_inline
def _portal_normal(w):
    """Unit outward normal (away from the interior point v0) of the portal (rows 1-3)
    and True, or zeros and False for a degenerate portal."""
    nx, ny, nz = _cross_rows(w, np.int64(1), np.int64(2), np.int64(3))
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not nn > 0.0:
        return 0.0, 0.0, 0.0, False
    nx, ny, nz = nx / nn, ny / nn, nz / nn
    if (nx * (w[1, 0] - w[0, 0]) + ny * (w[1, 1] - w[0, 1])
            + nz * (w[1, 2] - w[0, 2])) < 0.0:
        nx, ny, nz = -nx, -ny, -nz
    return nx, ny, nz, True


@njit_inline
def _bary(ax, ay, az, bx, by, bz, nx, ny, nz):
    """(a x b) . n"""
    return (ay * bz - az * by) * nx + (az * bx - ax * bz) * ny + (ax * by - ay * bx) * nz


@njit_inline
def _write_portal(w, wa, wb, out, iters, scale):
    """Result from the portal (rows 1, 2, 3): depth along its normal, barycentric
    witnesses at the origin's projection onto the portal plane.  Returns the signed
    distance, or NaN when the portal is degenerate."""
    nx, ny, nz, ok = _portal_normal(w)
    if not ok:
        return np.nan
    off = nx * w[1, 0] + ny * w[1, 1] + nz * w[1, 2]    # > 0: origin behind the portal
    qx, qy, qz = off * nx, off * ny, off * nz           # origin projected on the plane
    # barycentric coordinates of q in (w1, w2, w3) from sub-triangle areas along n
    p1x, p1y, p1z = w[1, 0] - qx, w[1, 1] - qy, w[1, 2] - qz
    p2x, p2y, p2z = w[2, 0] - qx, w[2, 1] - qy, w[2, 2] - qz
    p3x, p3y, p3z = w[3, 0] - qx, w[3, 1] - qy, w[3, 2] - qz
    l1 = _bary(p2x, p2y, p2z, p3x, p3y, p3z, nx, ny, nz)
    l2 = _bary(p3x, p3y, p3z, p1x, p1y, p1z, nx, ny, nz)
    l3 = _bary(p1x, p1y, p1z, p2x, p2y, p2z, nx, ny, nz)
    s = l1 + l2 + l3
    if not abs(s) > 0.0:
        l1, l2, l3, s = 1.0, 0.0, 0.0, 1.0
    l1 /= s
    l2 /= s
    l3 /= s
    dist = -off
    out[OUT_DIST] = dist
    out[OUT_NORMAL], out[OUT_NORMAL + 1], out[OUT_NORMAL + 2] = nx, ny, nz
    for i in range(3):
        pa = l1 * wa[1, i] + l2 * wa[2, i] + l3 * wa[3, i]
        out[OUT_PA + i] = pa
        out[OUT_PB + i] = pa + dist * out[OUT_NORMAL + i]
    out[OUT_ITERS] = iters
    out[OUT_METHOD] = M_MPR
    return dist


@njit_inline
def _status(dist, scale):
    tol = TOUCH_TOL * scale
    if dist > tol:
        return ST_SEPARATED
    if dist >= -tol:
        return ST_TOUCHING
    return ST_PENETRATING


MPR_WS_ROWS = 17     # rows of the float64 (rows, 3) scratch buffer of ``mpr_ws``


@njit_kernel
def mpr(sa, sb, verts, r_ab, t_ab, out):
    """Minkowski Portal Refinement on the whole shapes (see the module docstring);
    allocates its scratch buffer, batch callers use ``mpr_ws``.

    sa, sb  shape tuples (code int64, prm float64[8], v0 int64, vn int64)
    verts   float64 (M, 3) convex vertices (body frames)
    r_ab    float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    out     float64[OUT_SIZE] result row in A's frame (module docstring for the meaning
            of each entry per status); out[OUT_METHOD] = M_MPR
    Returns ST_SEPARATED, ST_TOUCHING, ST_PENETRATING or ST_FAILED (iteration cap);
    ST_NOT_RUN (``out`` untouched) when either shape is a PLANE (no support mapping).
    """
    return mpr_ws(sa, sb, verts, r_ab, t_ab, out, np.empty((MPR_WS_ROWS, 3)))


@njit_separate
def mpr_ws(sa, sb, verts, r_ab, t_ab, out, buf):
    """``mpr`` with a caller-provided scratch buffer ``buf`` float64 (MPR_WS_ROWS, 3):
    rows 0-4 w, 5-9 wa, 10-14 wb, 15-16 the two centres.  At least
    TR_HEADER_ROWS more rows: those are a trace region (module docstring), reset here
    and filled with the iterations."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    out, buf = borrow(out), borrow(buf)
    trace_on = buf.shape[0] >= MPR_WS_ROWS + TR_HEADER_ROWS
    if trace_on:
        trace_reset(buf, np.int64(MPR_WS_ROWS))
    if sa[0] == PLANE or sb[0] == PLANE:
        return ST_NOT_RUN
    scale = shape_scale(sa, sb)
    tol = MPR_REL_TOL * scale
    w, wa, wb = buf[0:5], buf[5:10], buf[10:15]
    for i in range(3):
        out[i] = 0.0

    # ---- phase 1: interior point and origin ray ---------------------------------------
    ca, cbl = buf[15], buf[16]
    centre_core(sa[0], sa[1], verts, sa[2], sa[3], ca)
    centre_core(sb[0], sb[1], verts, sb[2], sb[3], cbl)
    for i in range(3):
        cb = r_ab[i, 0] * cbl[0] + r_ab[i, 1] * cbl[1] + r_ab[i, 2] * cbl[2] + t_ab[i]
        w[0, i] = ca[i] - cb
        wa[0, i] = ca[i]
        wb[0, i] = cb
    if math.sqrt(w[0, 0] ** 2 + w[0, 1] ** 2 + w[0, 2] ** 2) <= SUPPORT_TIE * scale:
        # centres coincide: the origin is interior; any ray direction will do
        w[0, 0] = MPR_NUDGE * scale
        w[0, 1] = 0.0
        w[0, 2] = 0.0

    # v1 along -v0, then (phase 2, portal discovery) v2 along v1 x v0, from one support
    # site: an inlined function is a copy of its code at every call site (jit.py,
    # "Inlining"), and the support is the largest part of mpr_ws
    dx, dy, dz = -w[0, 0], -w[0, 1], -w[0, 2]
    for k in range(1, 3):
        if k == 2:
            dx = w[1, 1] * w[0, 2] - w[1, 2] * w[0, 1]
            dy = w[1, 2] * w[0, 0] - w[1, 0] * w[0, 2]
            dz = w[1, 0] * w[0, 1] - w[1, 1] * w[0, 0]
            n1 = math.sqrt(w[1, 0] ** 2 + w[1, 1] ** 2 + w[1, 2] ** 2)
            n0 = math.sqrt(w[0, 0] ** 2 + w[0, 1] ** 2 + w[0, 2] ** 2)
            if math.sqrt(dx * dx + dy * dy + dz * dz) <= MPR_PARALLEL_SIN * n1 * n0:
                # origin on the segment v0-v1: the ray meets the boundary at v1, whose
                # support plane has normal -v0 (exact supporting plane)
                return _status(_write_support_plane(w, wa, out, 1.0), scale)
        h = _support(sa, sb, verts, r_ab, t_ab, dx, dy, dz, w, wa, wb, k)
        if trace_on:
            trace_rows(buf, np.int64(MPR_WS_ROWS), np.int64(TR_MPR_DISCOVERY), w, k + 1)
        if h <= 0.0:
            return _write_separated(w, wa, k, dx, dy, dz, out, float(k))
    nx, ny, nz = _cross_rows(w, np.int64(0), np.int64(1), np.int64(2))
    if nx * w[0, 0] + ny * w[0, 1] + nz * w[0, 2] > 0.0:
        _copy_row(w, wa, wb, np.int64(1), np.int64(4))
        _copy_row(w, wa, wb, np.int64(2), np.int64(1))
        _copy_row(w, wa, wb, np.int64(4), np.int64(2))
        nx, ny, nz = -nx, -ny, -nz
    iters = 2
    found = False
    while iters < MPR_MAX_ITERS:
        iters += 1
        if not math.sqrt(nx * nx + ny * ny + nz * nz) > 0.0:
            break
        h = _support(sa, sb, verts, r_ab, t_ab, nx, ny, nz, w, wa, wb, np.int64(3))
        if trace_on:
            trace_rows(buf, np.int64(MPR_WS_ROWS), np.int64(TR_MPR_DISCOVERY), w, np.int64(4))
        if h <= 0.0:
            return _write_separated(w, wa, np.int64(3), nx, ny, nz, out, float(iters))
        # (v1 x v3) . v0 < 0: origin outside (v0, v1, v3), replace v2
        if _bary(w[1, 0], w[1, 1], w[1, 2], w[3, 0], w[3, 1], w[3, 2],
                 w[0, 0], w[0, 1], w[0, 2]) < 0.0:
            _copy_row(w, wa, wb, np.int64(3), np.int64(2))
            nx, ny, nz = _cross_rows(w, np.int64(0), np.int64(1), np.int64(3))
            continue
        # (v3 x v2) . v0 < 0: origin outside (v0, v3, v2), replace v1
        if _bary(w[3, 0], w[3, 1], w[3, 2], w[2, 0], w[2, 1], w[2, 2],
                 w[0, 0], w[0, 1], w[0, 2]) < 0.0:
            _copy_row(w, wa, wb, np.int64(3), np.int64(1))
            nx, ny, nz = _cross_rows(w, np.int64(0), np.int64(3), np.int64(2))
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
        if trace_on:
            trace_rows(buf, np.int64(MPR_WS_ROWS), np.int64(TR_MPR_REFINEMENT), w, np.int64(4))
        nx, ny, nz, ok = _portal_normal(w)
        if not ok:
            break                              # degenerate portal: report as is
        if iters >= MPR_MAX_ITERS:
            dist = _write_portal(w, wa, wb, out, float(iters), scale)
            if dist != dist:
                out[OUT_DIST] = 0.0
            return ST_FAILED
        iters += 1
        h = _support(sa, sb, verts, r_ab, t_ab, nx, ny, nz, w, wa, wb, np.int64(4))
        if h < 0.0:
            return _write_separated(w, wa, np.int64(4), nx, ny, nz, out, float(iters))
        if h - (w[1, 0] * nx + w[1, 1] * ny + w[1, 2] * nz) <= tol:
            break                              # portal within tolerance of the boundary
        # keep the ray from v0 through the origin inside the new portal's cone:
        # x = v4 x v0, then the sign of v_i . x picks the vertex to replace
        xx = w[4, 1] * w[0, 2] - w[4, 2] * w[0, 1]
        xy = w[4, 2] * w[0, 0] - w[4, 0] * w[0, 2]
        xz = w[4, 0] * w[0, 1] - w[4, 1] * w[0, 0]
        if w[1, 0] * xx + w[1, 1] * xy + w[1, 2] * xz > 0.0:
            if w[2, 0] * xx + w[2, 1] * xy + w[2, 2] * xz > 0.0:
                _copy_row(w, wa, wb, np.int64(4), np.int64(1))
            else:
                _copy_row(w, wa, wb, np.int64(4), np.int64(3))
        else:
            if w[3, 0] * xx + w[3, 1] * xy + w[3, 2] * xz > 0.0:
                _copy_row(w, wa, wb, np.int64(4), np.int64(2))
            else:
                _copy_row(w, wa, wb, np.int64(4), np.int64(1))

    dist = _write_portal(w, wa, wb, out, float(iters), scale)
    if dist != dist:
        # degenerate portal (all three points on a line): fall back to v1's support plane
        dist = _write_support_plane(w, wa, out, float(iters))
    return _status(dist, scale)
