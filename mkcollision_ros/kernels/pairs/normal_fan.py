"""A convex hull's normal fan as hull.fan_rows stores it after the hull's points in
verts (``fan_stored``, ``fan_run``), and what the fan kernels over it share
(ellipsoid_convex.py, cylinder_convex.py): the hull's pose in the other shape's frame
(``hull_pose``), the face planes' least offset (``least_offset``), a face's separating
plane (``face_apart_out``), a vertex's support test (``_vertex_top``), the arc tests
and bounds of an edge (``_in_arc``, ``_planes_on_arc``, ``_sinus_min``), and the feet
of the normals from a point to an ellipse or an ellipsoid (``_plane_feet``,
``plane_foot`` and the root searches ``_newton_from``, ``_root_right``,
``_roots_mid``).  Their scratch rows (HE_V, HE_FACES, HE_X, HE_ROWS) are below; their
outcome codes (PRE_*), caps and tolerances (HE_*) are in constants.py.

A foot is a root t of the secular equation sum_i w_i / (l_i + t)^2 = 1 (w_i = l_i P_i^2,
P the point in the ellipse's or E's axes); the normal there is N_i = P_i / (l_i + t) and
f = -t |N|.  It counts only if n lies in the edge's arc (two signs) or B's support along
-n is attained at the vertex (within 1e-12 * scale).  Of the roots only the one right
of the least pole and the two between the two least poles can be local minima of the
distance on the surface (its Hessian on the tangent plane is I + t D^-1), so no other
is searched.
"""
import math

import numpy as np

from ..constants import (CONVEX, FAN_MAX_POINTS, HE_DMIN_RTOL, HE_FOOT_SLACK, HE_ITERS,
                         HE_POLE_SEP, HE_ROOT_RTOL, HE_ROOT_SLACK, HE_WEIGHT_FLOOR, P_FAN_EDGES,
                         P_FAN_FACES, P_FAN_VERTS)
from ..jit import njit_inline, njit_kernel

HE_MAX_FACES = 2 * FAN_MAX_POINTS - 4  # a polytope's faces, at most (Euler's formula)
HE_V = 0               # scratch rows (collide_ellipsoid_convex's ``rows``): the hull's points
                       # in E's frame (FAN_MAX_POINTS rows)
HE_FACES = HE_V + FAN_MAX_POINTS  # ... per face m (a face's normal, E's frame) times
HE_X = HE_FACES + 3 * HE_MAX_FACES  # L, then m, then (h_E(m), offset, f(-m)); then per
HE_ROWS = HE_X + FAN_MAX_POINTS      # point (its ellipsoid norm rho in E, -, -)


@njit_inline
def fan_stored(code, prm):
    """Whether the shape is a hull with its normal fan stored (hull.fan_rows)."""
    return code == CONVEX and prm[P_FAN_FACES] > 0.0


@njit_inline
def fan_run(prm, v0, vn, verts):
    """A hull's stored fan (hull.fan_rows, after its vn points from row v0): (faces,
    edges, vertices, the face normals' first row, the edges' start in the flat run, the
    flat run: offsets [0, nf), vertex ids [nf, nf + nvx), edges (4 each) after)."""
    nf, ne, nvx = int(prm[P_FAN_FACES]), int(prm[P_FAN_EDGES]), int(prm[P_FAN_VERTS])
    fnr = v0 + vn
    flat = fnr + nf
    return (nf, ne, nvx, fnr, nf + nvx,
            verts[flat:flat + (nf + nvx + 4 * ne + 2) // 3].reshape(-1))


@njit_inline
def hull_pose(side, r_ab, t_ab):
    """The hull's pose in the other shape's frame (the hull is B when side is 0, else
    A), as twelve scalars r00 .. r22, t0 .. t2: stores into scratch rows could alias an
    array, and the compiler would reload it after each."""
    if side == 0:
        return (r_ab[0, 0], r_ab[0, 1], r_ab[0, 2], r_ab[1, 0], r_ab[1, 1], r_ab[1, 2],
                r_ab[2, 0], r_ab[2, 1], r_ab[2, 2], t_ab[0], t_ab[1], t_ab[2])
    r00, r01, r02 = r_ab[0, 0], r_ab[1, 0], r_ab[2, 0]
    r10, r11, r12 = r_ab[0, 1], r_ab[1, 1], r_ab[2, 1]
    r20, r21, r22 = r_ab[0, 2], r_ab[1, 2], r_ab[2, 2]
    return (r00, r01, r02, r10, r11, r12, r20, r21, r22,
            -(r00 * t_ab[0] + r01 * t_ab[1] + r02 * t_ab[2]),
            -(r10 * t_ab[0] + r11 * t_ab[1] + r12 * t_ab[2]),
            -(r20 * t_ab[0] + r21 * t_ab[1] + r22 * t_ab[2]))


@njit_inline
def least_offset(verts, fl, fnr, nf, r00, r01, r02, r10, r11, r12, r20, r21, r22, t0, t1,
                 t2, Q):
    """The other shape's centre c (the origin of its frame; the hull's pose there r, t)
    in the hull's frame and its offset below each face's plane, o - f . c (= o + m . t),
    into Q[:, 1]: (the least offset, its face).  All positive proves the centre inside
    the hull; the face with the least is the plane that most often proves the pair
    apart."""
    c0 = -(r00 * t0 + r10 * t1 + r20 * t2)
    c1 = -(r01 * t0 + r11 * t1 + r21 * t2)
    c2 = -(r02 * t0 + r12 * t1 + r22 * t2)
    fmin, omin = 0, np.inf
    for f in range(nf):
        off = fl[f] - (verts[fnr + f, 0] * c0 + verts[fnr + f, 1] * c1
                       + verts[fnr + f, 2] * c2)
        Q[f, 1] = off
        if off < omin:
            omin, fmin = off, f
    return omin, fmin


@njit_inline
def _phi(l0, l1, l2, w0, w1, w2, t):
    """phi(t) = sum w_i / (l_i + t)^2 - 1 and its first two derivatives."""
    a, b, c = 1.0 / (l0 + t), 1.0 / (l1 + t), 1.0 / (l2 + t)
    a2, b2, c2 = w0 * a * a, w1 * b * b, w2 * c * c
    return (a2 + b2 + c2 - 1.0, -2.0 * (a2 * a + b2 * b + c2 * c),
            6.0 * (a2 * a * a + b2 * b * b + c2 * c * c))


@njit_inline
def _newton_from(l0, l1, l2, w0, w1, w2, t):
    """Newton's method on phi from t with phi(t) >= 0 on a convex, monotone branch of
    phi: the steps move toward the root and never pass it (no bracket needed).
    Returns (root, converged)."""
    for _ in range(HE_ITERS):
        r = _phi(l0, l1, l2, w0, w1, w2, t)
        if not r[0] > 0.0:
            return t, True
        tn = t - r[0] / r[1]
        if abs(tn - t) <= HE_ROOT_RTOL * (abs(t) + l0):
            return tn, True
        t = tn
    return t, False


@njit_inline
def _root_right(l0, l1, l2, w0, w1, w2):
    """The root right of the pole -l0 (l0 the least): phi is convex and decreasing
    there, and >= 0 at -l0 + sqrt(w0) (its first term alone is 1 there)."""
    return _newton_from(l0, l1, l2, w0, w1, w2, -l0 + math.sqrt(w0))


@njit_kernel
def _roots_mid(l0, l1, l2, w0, w1, w2, out, k):
    """The roots of phi between the poles -l1 and -l0 (phi convex, +inf at both): 0 or
    2, written to out[k], out[k + 1]; returns the count, -1 when undecided."""
    gap = l1 - l0
    # with the third term dropped phi is no larger, and that one's least value is
    # (w0^1/3 + w1^1/3)^3 / gap^2 - 1: no root if it is > 0 (first without the cube
    # roots: (.)^3 = w0 + w1 + 3 c0 c1 (c0 + c1) >= w0 + w1 + 6 sqrt(w0 w1))
    if w0 + w1 + 6.0 * math.sqrt(w0 * w1) > gap * gap * (1.0 + HE_ROOT_SLACK):
        return 0
    c0, c1 = np.cbrt(w0), np.cbrt(w1)
    if (c0 + c1) ** 3 > gap * gap * (1.0 + HE_ROOT_SLACK):
        return 0
    # Newton's method on phi' (increasing) from the two-term minimiser, in the bracket,
    # until a point with phi <= 0 (then two roots) or a proof that phi > 0 (none)
    lo = -l1 + HE_ROOT_SLACK * gap
    hi = -l0 - HE_ROOT_SLACK * gap
    t = -l0 - gap * c0 / (c0 + c1)
    found = False
    for _ in range(HE_ITERS):
        r = _phi(l0, l1, l2, w0, w1, w2, t)
        if not r[0] > 0.0:
            found = True
            break
        if r[1] < 0.0:
            lo = t
        else:
            hi = t
        # phi convex: its least value (in [lo, hi]) is >= phi(t) - |phi'(t)| (hi - lo)
        if r[0] - abs(r[1]) * (hi - lo) > 0.0:
            return 0
        tn = t - r[1] / r[2]
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= HE_DMIN_RTOL * abs(t):
            return -1                   # a minimum too close to 0 to tell
        t = tn
    if not found:
        return -1
    # phi(t) <= 0: t lies between the roots.  phi >= 0 at s0 = -l1 + sqrt(w1) and at
    # s1 = -l0 - sqrt(w0) (a term alone is 1 there); if s0 < t < s1, they lie beyond
    # the roots, and phi, convex, is monotone from each to its root
    s0 = -l1 + math.sqrt(w1)
    s1 = -l0 - math.sqrt(w0)
    if not (s0 < t < s1):
        return -1
    r0, ok0 = _newton_from(l0, l1, l2, w0, w1, w2, s0)
    r1, ok1 = _newton_from(l0, l1, l2, w0, w1, w2, s1)
    if not (ok0 and ok1):
        return -1
    out[k], out[k + 1] = r0, r1
    return 2


@njit_inline
def _plane_feet(g11, g12, g22, wp, wq, U, scale, roots):
    """The feet that may give a local minimum below U of h(n) - n . P over the unit n of
    a plane, h the support function of the centred ellipse G = [[g11, g12], [g12, g22]]
    (in the plane's basis) and P = (wp, wq): their roots of the secular equation in
    roots[:k].  Returns (k, u, P0, P1, lam0, lam1): the ellipse's least axis u (2-D),
    P in its axes and the squared semi-axes; k = -1 when undecided (a near-circle, P
    near an axis, a search that does not converge)."""
    tr_ = 0.5 * (g11 + g22)
    dd = math.sqrt(0.25 * (g11 - g22) ** 2 + g12 * g12)
    lam0, lam1 = tr_ - dd, tr_ + dd
    if not lam1 - lam0 > HE_POLE_SEP * lam1:
        return -1, 0.0, 0.0, 0.0, 0.0, lam0, lam1
    # the ellipse's axes e0 = u (lam0), e1 = (-uy, ux)
    if abs(g11 - lam0) > abs(g22 - lam0):
        ux, uy = -g12, g11 - lam0
    else:
        ux, uy = g22 - lam0, -g12
    un = math.sqrt(ux * ux + uy * uy)
    ux, uy = ux / un, uy / un
    P0 = ux * wp + uy * wq
    P1 = -uy * wp + ux * wq
    w0, w1 = lam0 * P0 * P0, lam1 * P1 * P1
    small = HE_WEIGHT_FLOOR * lam1 * scale * scale
    if not (w0 > small and w1 > small):
        return -1, ux, uy, P0, P1, lam0, lam1
    k = 0
    if P0 * P0 / lam0 + P1 * P1 / lam1 < 1.0 + HE_FOOT_SLACK:
        roots[0], ok = _root_right(lam0, lam1, lam1, w0, w1, 0.0)
        if not ok:
            return -1, ux, uy, P0, P1, lam0, lam1
        k = 1
    if lam0 / math.sqrt(lam1) < U and abs(P0) * lam1 < U * (lam1 - lam0):
        km = _roots_mid(lam0, lam1, lam1, w0, w1, 0.0, roots, k)
        if km < 0:
            return -1, ux, uy, P0, P1, lam0, lam1
        k += km
    return k, ux, uy, P0, P1, lam0, lam1


@njit_inline
def plane_foot(tt, P0, P1, lam0, lam1, ux, uy):
    """A foot of _plane_feet (root tt; P, lam, u as it returns them): (h(n) - n . P, n's
    coordinates in the plane's basis).  The value is clamped at 0: a point just outside
    the ellipse (HE_FOOT_SLACK) gives a root tt > 0, while for an overlapping pair the
    value is >= 0 in the cell."""
    N0, N1 = P0 / (lam0 + tt), P1 / (lam1 + tt)
    nn = math.sqrt(N0 * N0 + N1 * N1)
    c0, c1 = N0 / nn, N1 / nn
    return max(-tt * nn, 0.0), ux * c0 - uy * c1, uy * c0 + ux * c1


@njit_inline
def _in_arc(ap, aq, c2, s2):
    """Whether the unit n = ap p + aq q lies on the arc from p to n2 = c2 p + s2 q (p, q
    orthonormal, the arc shorter than pi): both p x n and n x n2 along p x q's side of
    the arc."""
    return aq * s2 >= 0.0 and (ap * s2 - aq * c2) * s2 >= 0.0


@njit_inline
def _vertex_top(X, fl, nf, nv, dx, dy, dz):
    """(the largest d . x, its row) over the hull's vertices: their indices, nv of them,
    at value nf of the flat run ``fl``, their positions the rows of X (the hull's points
    in its own frame, or in E's).  (Indices as uint64 here and in the kernel's hot
    loops: numba checks a signed index for wraparound on every access; ~4% of an apart
    pair's kernel time and of the edge loop's, measured.)"""
    best, top = -np.inf, np.uint64(0)
    for i in range(nv):
        u = np.uint64(int(fl[nf + i]))
        s = dx * X[u, 0] + dy * X[u, 1] + dz * X[u, 2]
        if s > best:
            best, top = s, u
    return best, top


@njit_inline
def _sinus_min(wx, wy, wz, px, py, pz, qx, qy, qz):
    """min over the great-circle arc from unit p to unit q (angle < pi) of w . n."""
    a = wx * px + wy * py + wz * pz
    b = wx * qx + wy * qy + wz * qz
    m = min(a, b)
    # the arc's plane normal c = p x q; -w's projection in the arc?
    cx, cy, cz = py * qz - pz * qy, pz * qx - px * qz, px * qy - py * qx
    cc = cx * cx + cy * cy + cz * cz
    if not cc > 0.0:
        return m
    k = (wx * cx + wy * cy + wz * cz) / cc
    ux, uy, uz = -(wx - k * cx), -(wy - k * cy), -(wz - k * cz)
    uu = math.sqrt(ux * ux + uy * uy + uz * uz)
    if not uu > 0.0:
        return m
    # u in the arc: p x u and u x q along c
    s1 = cx * (py * uz - pz * uy) + cy * (pz * ux - px * uz) + cz * (px * uy - py * ux)
    s2 = cx * (uy * qz - uz * qy) + cy * (uz * qx - ux * qz) + cz * (ux * qy - uy * qx)
    if s1 >= 0.0 and s2 >= 0.0:
        return min(m, -uu)
    return m


@njit_inline
def _planes_on_arc(s1x, s1y, s1z, s2x, s2y, s2z, n1x, n1y, n1z, n2x, n2y, n2z, d1, d2):
    """The least over the arc from unit n1 to n2 of the larger of the planes s_1 . n and
    s_2 . n (tangent to a convex, homogeneous f at n1 and n2: a lower bound of f there),
    each on its side of their crossing; d1 = f(n1) - s_2 . n1, d2 = s_1 . n2 - f(n2).
    -inf where they do not cross on the arc."""
    if not (d1 >= 0.0 and d2 <= 0.0 and d1 - d2 > 0.0):
        return -np.inf
    cx, cy, cz = d1 * n2x - d2 * n1x, d1 * n2y - d2 * n1y, d1 * n2z - d2 * n1z
    cn = math.sqrt(cx * cx + cy * cy + cz * cz)
    cx, cy, cz = cx / cn, cy / cn, cz / cn
    return min(_sinus_min(s1x, s1y, s1z, n1x, n1y, n1z, cx, cy, cz),
               _sinus_min(s2x, s2y, s2z, cx, cy, cz, n2x, n2y, n2z))


@njit_inline
def face_apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my, mz, sx, sy,
                   sz, gap):
    """res = [-gap, n, pa, pb] for cores proved ``gap`` apart by the plane of the hull's
    face of unit normal f (the hull's frame; m in the other shape's, s that shape's
    core's support point along -m there): n from A to B, pa and pb the two cores'
    support points across the plane (not the closest points, as cylinder_common._apart_out's)."""
    u = _vertex_top(pts, fl, nf, nvx, fx, fy, fz)[1]
    px, py, pz = pts[u, 0], pts[u, 1], pts[u, 2]
    res[0] = -gap
    if side == 0:
        # A is the other shape: n = -m; B's point into A's frame
        res[1], res[2], res[3] = -mx, -my, -mz
        res[4], res[5], res[6] = sx, sy, sz
        for c in range(3):
            res[7 + c] = r_ab[c, 0] * px + r_ab[c, 1] * py + r_ab[c, 2] * pz + t_ab[c]
        return
    # A is the hull: n = f; the other's point into A's frame
    res[1], res[2], res[3] = fx, fy, fz
    res[4], res[5], res[6] = px, py, pz
    for c in range(3):
        res[7 + c] = r_ab[c, 0] * sx + r_ab[c, 1] * sy + r_ab[c, 2] * sz + t_ab[c]
