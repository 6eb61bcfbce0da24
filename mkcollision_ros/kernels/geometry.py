"""Poses and support mappings of every shape.

Frames: a shape's parameters are in its own body frame (``_a``/``_b``); ``x_ab`` is the
pose of B expressed in A's frame, given as a rotation matrix ``r_ab`` (3, 3) and a
translation ``t_ab`` (3,), both float64, metres.  Quaternions are ``quat_xyzw``.

Each shape is split into a *core* and an *inflation radius*: a sphere is a point grown by
its radius, a capsule a segment grown by its radius, an ellipsoid the convex body K whose
support function is h_E(u) - r |u|, grown by r (plus its margin), and every other shape
is its own core grown by its margin only.  GJK runs on the cores and subtracts the
radii, which is exact and converges in a few iterations for spheres and capsules.

The ellipsoid's r (params[P_ROLL]) is its smallest radius of curvature, c_min^2 / a_max:
a ball of radius r rolls freely inside the ellipsoid, and then (and only then) h_E - r|u|
is again a support function, of the inner parallel body K, and E = K + ball(r) exactly.
K is less round than E (a sphere's K is a point), so GJK and EPA need fewer support
steps to resolve it; any r between 0 and that bound gives the same answers.

Shape parameter row (float64[8], see constants.N_PARAMS):
  sphere    [r]                     ellipsoid [a, b, c, roll] (semi-axes, r above)
  box       [hx, hy, hz] (half)     capsule   [r, half_length]       (segment along z)
  cylinder  [r, half_height]        cone      [r, half_height]       (tip at +z, centred)
  convex    [groups] (vertices in ``verts[v0:v0+vn]``, body frame; a hull of more than
            hull.GROUP_MIN_POINTS points has two rows per group of them right after,
            see _grouped_support)
  plane     [nx, ny, nz, d] (unit n; half-space n.x <= d)
  [6] margin, [7] bounding radius about the origin with margin (plane: 0, unbounded).
"""
import math

import numpy as np

from .constants import (BOX, CAPSULE, CONE, CONVEX, CYLINDER, ELLIPSOID, PLANE, P_GROUPS, P_MARGIN,
                        P_RADIUS, P_ROLL, SPHERE, SUPPORT_TIE)
from .jit import borrow, njit_inline, njit_kernel


@njit_inline
def quat_entries(q):
    """The nine entries r00, r01, ..., r22 (row by row) of the rotation matrix of a unit
    quaternion ``q`` = (x, y, z, w), as scalars: the one place of this formula."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    return (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w),
            2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w),
            2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y))


@njit_inline
def quat_to_matrix_into(q, r):
    """Write the rotation matrix of a unit quaternion ``q`` = (x, y, z, w) into ``r``
    (3, 3) float64 (allocation-free variant of ``quat_to_matrix``)."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_entries(q)
    r[0, 0], r[0, 1], r[0, 2] = r00, r01, r02
    r[1, 0], r[1, 1], r[1, 2] = r10, r11, r12
    r[2, 0], r[2, 1], r[2, 2] = r20, r21, r22


@njit_inline
def quat_rotate_xyz(q, x, y, z, inverse):
    """The vector (x, y, z) rotated by the unit quaternion ``q`` (by its inverse if
    ``inverse``), with no matrix stored."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_entries(q)
    if inverse:
        r01, r10, r02, r20, r12, r21 = r10, r01, r20, r02, r21, r12
    return (r00 * x + r01 * y + r02 * z, r10 * x + r11 * y + r12 * z,
            r20 * x + r21 * y + r22 * z)


@njit_kernel
def quat_to_matrix(q):
    """Rotation matrix (3, 3) of a unit quaternion ``q`` = (x, y, z, w), float64."""
    r = np.empty((3, 3))
    quat_to_matrix_into(q, r)
    return r


@njit_inline
def meet(a, b, sn):
    """One coordinate of a pair of witness points a (on A), b (on B) moved by halves of
    the remainder so that b - a == sn exactly, sn being that coordinate of the signed
    distance times the normal (-depth * n when penetrating).  Returns (a, b).  Shared
    by GJK/EPA's results and the closed forms."""
    corr = 0.5 * ((b - a) - sn)
    return a + corr, b - corr


@njit_kernel
def relative_pose(pos_a_w, r_a_w, pos_b_w, r_b_w):
    """Pose of B in A's frame from two world poses: returns (r_ab (3, 3), t_ab (3,)).
    Written as loops: numba's ``@`` needs scipy's BLAS, which is not a dependency."""
    r_ab = np.empty((3, 3))
    t_ab = np.empty(3)
    for i in range(3):
        t_ab[i] = (r_a_w[0, i] * (pos_b_w[0] - pos_a_w[0]) + r_a_w[1, i] * (pos_b_w[1] - pos_a_w[1])
                   + r_a_w[2, i] * (pos_b_w[2] - pos_a_w[2]))
        for j in range(3):
            r_ab[i, j] = r_a_w[0, i] * r_b_w[0, j] + r_a_w[1, i] * r_b_w[1, j] + r_a_w[2, i] * r_b_w[2, j]
    return r_ab, t_ab


@njit_inline
def cylinder_inradius(r, h, x, y, z):
    """The radius of the largest ball about the point (x, y, z) inside the cylinder of
    radius r and half-height h about the z axis: the point's gap to the side or to the
    nearer cap, the smaller; negative where the point lies outside."""
    return min(r - math.sqrt(x * x + y * y), h - abs(z))


@njit_inline
def inflation(code, prm):
    """Radius (m) by which the core of the shape is grown: its margin, plus the radius
    for spheres and capsules and the rolling radius for ellipsoids."""
    if code == SPHERE or code == CAPSULE:
        return prm[0] + prm[P_MARGIN]
    if code == ELLIPSOID:
        return prm[P_ROLL] + prm[P_MARGIN]
    return prm[P_MARGIN]


@njit_inline
def support_core_xyz(code, prm, verts, v0, vn, dx, dy, dz):
    """Point (x, y, z) of the shape's core farthest along the direction (dx, dy, dz),
    both in the body frame; the direction need not be unit.  Allocation-free (scalars
    stay in registers); ``support_core`` writes the same point into an array."""
    if code == SPHERE:
        return 0.0, 0.0, 0.0
    elif code == ELLIPSOID:
        a, b, c, r = prm[0], prm[1], prm[2], prm[P_ROLL]
        ex, ey, ez = a * a * dx, b * b * dy, c * c * dz
        n = math.sqrt(ex * dx + ey * dy + ez * dz)
        if n > 0.0:
            # the ellipsoid's support point less r along the unit direction
            s = r / math.sqrt(dx * dx + dy * dy + dz * dz)
            return ex / n - s * dx, ey / n - s * dy, ez / n - s * dz
        return a - r, 0.0, 0.0
    elif code == BOX:
        return (prm[0] if dx >= 0.0 else -prm[0], prm[1] if dy >= 0.0 else -prm[1],
                prm[2] if dz >= 0.0 else -prm[2])
    elif code == CAPSULE:
        return 0.0, 0.0, (prm[1] if dz >= 0.0 else -prm[1])
    elif code == CYLINDER:
        r, h = prm[0], prm[1]
        s = math.sqrt(dx * dx + dy * dy)
        z = h if dz >= 0.0 else -h
        if s > 0.0:
            return r * dx / s, r * dy / s, z
        return r, 0.0, z
    elif code == CONE:
        r, h = prm[0], prm[1]
        s = math.sqrt(dx * dx + dy * dy)
        if s > 0.0:
            bx, by = r * dx / s, r * dy / s
        else:
            bx, by = r, 0.0
        # tip (0, 0, h) against the best rim point (bx, by, -h)
        if dz * h >= dx * bx + dy * by - dz * h:
            return 0.0, 0.0, h
        return bx, by, -h
    elif code == CONVEX:
        if prm[P_GROUPS] > 0.0:
            return _grouped_support(prm, verts, v0, vn, dx, dy, dz)
        # over a view from 0, not range(v0, v0 + vn): LLVM then knows the index is not
        # negative and drops numba's wraparound of signed indices in this hot loop
        pts = verts[v0:v0 + vn]
        best = -np.inf
        k = 0
        for i in range(vn):
            v = pts[i, 0] * dx + pts[i, 1] * dy + pts[i, 2] * dz
            if v > best:
                best = v
                k = i
        return pts[k, 0], pts[k, 1], pts[k, 2]
    # PLANE has no support point; callers route planes to the half-space path
    return 0.0, 0.0, 0.0


@njit_inline
def _group_bound(grp, g, dx, dy, dz, dn):
    """The bound c . d + r |d| (dn = |d|) of run g's bounding ball (_grouped_support):
    no point of the run lies farther along d."""
    return (grp[2 * g, 0] * dx + grp[2 * g, 1] * dy + grp[2 * g, 2] * dz
            + grp[2 * g + 1, 0] * dn)


@njit_kernel
def _grouped_support(prm, verts, v0, vn, dx, dy, dz):
    """support_core_xyz of a convex hull stored in groups (hull.support_groups: runs of
    nearby points, and after the points two rows per run, its bounding ball's centre c
    and (radius r, first point, count)).  No point of a run lies farther along d than
    c . d + r |d|: the run of the highest bound is read first, then every other run
    whose bound reaches the best value so far (less a slack of 1e-12 of the shape's
    radius for the bound's round-off), so the value found is the maximum over all
    points; where points tie, the first found of them.  A called kernel, not inlined:
    the support is inlined at every site of GJK, EPA and MPR, and this is for large
    hulls only."""
    pts = verts[v0:v0 + vn]
    grp = verts[v0 + vn:]
    ng = int(prm[P_GROUPS])
    dn = math.sqrt(dx * dx + dy * dy + dz * dz)
    top = 0
    top_bound = -np.inf
    for g in range(ng):
        b = _group_bound(grp, g, dx, dy, dz, dn)
        if b > top_bound:
            top_bound = b
            top = g
    best = -np.inf
    k = 0
    slack = SUPPORT_TIE * prm[P_RADIUS] * dn
    for q in range(-1, ng):
        g = top if q < 0 else q
        if q >= 0:
            if g == top:
                continue
            b = _group_bound(grp, g, dx, dy, dz, dn)
            if b + slack < best:
                continue
        lo = int(grp[2 * g + 1, 1])
        for i in range(lo, lo + int(grp[2 * g + 1, 2])):
            v = pts[i, 0] * dx + pts[i, 1] * dy + pts[i, 2] * dz
            if v > best:
                best = v
                k = i
    return pts[k, 0], pts[k, 1], pts[k, 2]


@njit_inline
def support_full_xyz(code, prm, verts, v0, vn, dx, dy, dz):
    """Support point (x, y, z) (body frame) of the whole shape along (dx, dy, dz): core
    plus inflation.  Allocation-free variant of ``support_full``.

    An ellipsoid's core is the ellipsoid less its rolling radius along the direction,
    which the inflation adds back, so its full support is the ellipsoid's own support
    point plus the margin: computed so (two divisions and a square root fewer, and no
    rolling radius taken off and put back in floating point)."""
    if code == ELLIPSOID:
        a, b, c, m = prm[0], prm[1], prm[2], prm[P_MARGIN]
        ex, ey, ez = a * a * dx, b * b * dy, c * c * dz
        n = math.sqrt(ex * dx + ey * dy + ez * dz)
        if not n > 0.0:
            return a + m, 0.0, 0.0
        x, y, z = ex / n, ey / n, ez / n
        if m > 0.0:
            s = m / math.sqrt(dx * dx + dy * dy + dz * dz)
            x += s * dx
            y += s * dy
            z += s * dz
        return x, y, z
    x, y, z = support_core_xyz(code, prm, verts, v0, vn, dx, dy, dz)
    rad = inflation(code, prm)
    if rad > 0.0:
        n = math.sqrt(dx * dx + dy * dy + dz * dz)
        if n > 0.0:
            x += rad * dx / n
            y += rad * dy / n
            z += rad * dz / n
    return x, y, z


@njit_kernel
def support_core(code, prm, verts, v0, vn, d, out):
    """Write into ``out`` (3,) the point of the shape's core farthest along the
    direction ``d`` (3,), both in the body frame.  ``d`` need not be unit."""
    x, y, z = support_core_xyz(code, prm, verts, v0, vn, d[0], d[1], d[2])
    out[0] = x
    out[1] = y
    out[2] = z


@njit_kernel
def support_full(code, prm, verts, v0, vn, d, out):
    """Support point (body frame) of the whole shape: core plus inflation along ``d``."""
    x, y, z = support_full_xyz(code, prm, verts, v0, vn, d[0], d[1], d[2])
    out[0] = x
    out[1] = y
    out[2] = z


@njit_kernel
def centre_core(code, prm, verts, v0, vn, out):
    """A point strictly inside the core (body frame): the origin, or the vertex mean."""
    out[0] = 0.0
    out[1] = 0.0
    out[2] = 0.0
    if code == CONVEX and vn > 0:
        for i in range(v0, v0 + vn):
            out[0] += verts[i, 0]
            out[1] += verts[i, 1]
            out[2] += verts[i, 2]
        out[0] /= vn
        out[1] /= vn
        out[2] /= vn


@njit_inline
def borrow_args(sa, sb, verts, r_ab, t_ab):
    """The pair arguments of a kernel as owner-less views (jit.borrow): a kernel that
    is called (not inlined) re-borrows its array arguments first, so that the reference
    counts numba updates for every view it takes are on null meminfos, which numba's
    reference-count pruning removes at compile time; on the arguments as passed the
    calls stay (unknown meminfo), one or two per view taken."""
    sa, sb, r_ab, t_ab = borrow_pose(sa, sb, r_ab, t_ab)
    return sa, sb, borrow(verts), r_ab, t_ab


@njit_inline
def borrow_pose(sa, sb, r_ab, t_ab):
    """borrow_args for a kernel that takes no hull vertices."""
    return ((sa[0], borrow(sa[1]), sa[2], sa[3]), (sb[0], borrow(sb[1]), sb[2], sb[3]),
            borrow(r_ab), borrow(t_ab))


@njit_inline
def shape_scale(sa, sb):
    """Length scale (m) of a pair: the sum of the bounding radii (planes count 0)."""
    s = sa[1][7] + sb[1][7]
    return s if s > 0.0 else 1.0


@njit_kernel
def minkowski_support(sa, sb, verts, r_ab, t_ab, d, core, wa, wb, w):
    """Support point of the Minkowski difference A - B along ``d`` (3,), in A's frame.

    ``sa``/``sb`` are shape tuples ``(code int64, prm float64[8], v0 int64, vn int64)``;
    ``core`` selects the cores (True) or the whole inflated shapes (False).
    Writes the support point of A into ``wa``, that of B (in A's frame) into ``wb`` and
    their difference into ``w``, each float64 (3,).
    """
    # direction -d seen from B's frame: r_ab^T (-d)
    dx = -(r_ab[0, 0] * d[0] + r_ab[1, 0] * d[1] + r_ab[2, 0] * d[2])
    dy = -(r_ab[0, 1] * d[0] + r_ab[1, 1] * d[1] + r_ab[2, 1] * d[2])
    dz = -(r_ab[0, 2] * d[0] + r_ab[1, 2] * d[1] + r_ab[2, 2] * d[2])
    if core:
        ax, ay, az = support_core_xyz(sa[0], sa[1], verts, sa[2], sa[3], d[0], d[1], d[2])
        bx, by, bz = support_core_xyz(sb[0], sb[1], verts, sb[2], sb[3], dx, dy, dz)
    else:
        ax, ay, az = support_full_xyz(sa[0], sa[1], verts, sa[2], sa[3], d[0], d[1], d[2])
        bx, by, bz = support_full_xyz(sb[0], sb[1], verts, sb[2], sb[3], dx, dy, dz)
    wa[0] = ax
    wa[1] = ay
    wa[2] = az
    for i in range(3):
        wb[i] = r_ab[i, 0] * bx + r_ab[i, 1] * by + r_ab[i, 2] * bz + t_ab[i]
        w[i] = wa[i] - wb[i]


@njit_inline
def minkowski_core_xyz(sa, sb, verts, r_ab, t_ab, dx, dy, dz):
    """Allocation-free ``minkowski_support`` on the cores (GJK and EPA): for the
    direction (dx, dy, dz) in A's frame returns the support points of A's core and of
    B's core (both in A's frame) as six floats (ax, ay, az, bx, by, bz); the Minkowski
    difference point is a - b.

    Two functions, not one with a ``core`` flag: each is inlined at every site of GJK,
    EPA and MPR (jit.py, "Inlining"), and one with both would hand LLVM six shape
    switches to optimise at each site, where GJK and EPA use two, before it could drop
    the unused ones."""
    ex = -(r_ab[0, 0] * dx + r_ab[1, 0] * dy + r_ab[2, 0] * dz)
    ey = -(r_ab[0, 1] * dx + r_ab[1, 1] * dy + r_ab[2, 1] * dz)
    ez = -(r_ab[0, 2] * dx + r_ab[1, 2] * dy + r_ab[2, 2] * dz)
    ax, ay, az = support_core_xyz(sa[0], sa[1], verts, sa[2], sa[3], dx, dy, dz)
    px, py, pz = support_core_xyz(sb[0], sb[1], verts, sb[2], sb[3], ex, ey, ez)
    bx = r_ab[0, 0] * px + r_ab[0, 1] * py + r_ab[0, 2] * pz + t_ab[0]
    by = r_ab[1, 0] * px + r_ab[1, 1] * py + r_ab[1, 2] * pz + t_ab[1]
    bz = r_ab[2, 0] * px + r_ab[2, 1] * py + r_ab[2, 2] * pz + t_ab[2]
    return ax, ay, az, bx, by, bz


@njit_inline
def minkowski_full_xyz(sa, sb, verts, r_ab, t_ab, dx, dy, dz):
    """``minkowski_core_xyz`` on the whole (inflated) shapes, for MPR."""
    ex = -(r_ab[0, 0] * dx + r_ab[1, 0] * dy + r_ab[2, 0] * dz)
    ey = -(r_ab[0, 1] * dx + r_ab[1, 1] * dy + r_ab[2, 1] * dz)
    ez = -(r_ab[0, 2] * dx + r_ab[1, 2] * dy + r_ab[2, 2] * dz)
    ax, ay, az = support_full_xyz(sa[0], sa[1], verts, sa[2], sa[3], dx, dy, dz)
    px, py, pz = support_full_xyz(sb[0], sb[1], verts, sb[2], sb[3], ex, ey, ez)
    bx = r_ab[0, 0] * px + r_ab[0, 1] * py + r_ab[0, 2] * pz + t_ab[0]
    by = r_ab[1, 0] * px + r_ab[1, 1] * py + r_ab[1, 2] * pz + t_ab[1]
    bz = r_ab[2, 0] * px + r_ab[2, 1] * py + r_ab[2, 2] * pz + t_ab[2]
    return ax, ay, az, bx, by, bz
