"""An ellipsoid and a box in closed form, before GJK and EPA: the cores' depth at a box
face certified by a ball, or the cores' exact distance over a face, an edge or a vertex,
or a face plane that proves them apart (gjk_epa.gjk_epa_ws calls collide_ellipsoid_box
first for such a pair; where it decides nothing it returns PRE_UNDECIDED and GJK and EPA
run as for any pair).

The problem, in the box's frame (half extents e_i, axes x_i): the ellipsoid's core K is
the ellipsoid E (centre c, shape matrix S = Q diag(a^2, b^2, c^2) Q^T, Q its axes) shrunk
by its rolling radius r (geometry: h_K(u) = u . c + sqrt(u^T S u) - r |u|).  Along the
outward normal s x_k of a box face (s = +-1) the box's support is the whole face and K's
lowest point under the face's plane is its support point along -s x_k,

    p = c - s S x_k / sqrt(S_kk) + s r x_k,   with   h = e_k - s p_k
      = e_k - s c_k + sqrt(S_kk) - r,

h_{K - box} along the normal that pushes K out through that face: the gap K must move to
clear the face's plane.  So the six values h need the diagonal of S only, and the least
of them bounds the core depth from above.

The outcomes, each exact:
  1. The least h is <= 0: K lies wholly beyond that face's plane, the cores are at least
     -h apart.  If p's foot on the plane lies in the face (|p_i| <= e_i for the other two
     axes), -h is their distance exactly: the foot is a point of the box, -h from p, and
     no two points of K and the box are closer than the slab between the plane and its
     parallel through p.  p and the foot are the closest points (the rows GJK's face test
     returns on cores apart, polish_faces._face_polish).  Else -h is a bound and a separating
     plane, which gjk_epa_ws takes in contacts mode (as cylinder_common's) once it clears
     ``stop``; below that, 3.
  2. The least h is > 0 and a ball inside K about a point q lies as deep in the box as
     h: K - box holds that ball less the box, which holds the ball of radius rho + (q's
     depth in the box) about the origin, so the depth is at least that and at most h
     (certificates._ball_certified's argument).  The ball: the largest one inside K that
     touches it at p (certificates._rolling_ball): radius rho = c_min^2 / sqrt(S_kk) - r
     (the normal there is x_k, so |D m| = sqrt(S_kk)), centre q = p + s rho x_k.  q lies
     h - rho under the face, so the ball certifies h where the other faces keep their
     distance from q: e_i - |q_i| >= h - rho for the other two axes, and the opposite
     face's 2 e_k - (h - rho) likewise.  Only the least h can be certified (the depth is
     at most it, the certificate at least h - tol).  If not, and p lies past the face's
     rim, 3.
  3. The cores apart over an edge or a vertex (_beyond_rim): for a unit m whose box
     support is a whole edge (m normal to it, between its faces' normals) or a vertex
     (m in its normal cone), g(m) = min over K of m . y less the box's max of m . x is
     the gap of a separating plane, a lower bound on the distance wherever it is > 0;
     K's point p along -m and the box's point q nearest it bound the distance from
     above by |p - q|.  m is found by Newton's method on the edge's normal angle (the
     2-D problem in the plane normal to the edge, as ellipsoid_cylinder.collide_ellipsoid_cylinder),
     or from the ellipsoid's point nearest the vertex (Newton's method on the Lagrange
     multiplier), and the distance is taken only where the two bounds meet within
     BE_EXACT * scale, whichever feature or root was tried.
  4. Else nothing: GJK and EPA (the cores overlapping at an edge's or a vertex's
     minimum, or at a face whose ball the box's sides cut short).

Measured (pure Python on bench/dev/deep_pairs.py's 2,000 ellipsoid-box cases, against its
reference run of GJK and EPA): of the 960 deep pairs, 142 certified by the ball (of the
390 whose cores overlap at a face minimum) and all 383 whose cores are apart given
their exact distance (121 over a face, 198 an edge, 64 a vertex), within 8.3e-13 *
scale of GJK's; GJK and EPA are left 8.25 supports of A - B per deep pair.  Of the
1,015 apart pairs, every one decided (exact, with an infinite ``stop``).  Figures of
time: BENCHMARKS.md.
"""
import math

import numpy as np

from ..constants import (BE_EXACT, BE_POINT_ITERS, BE_ROOT_STOP, CC_NEWTON_ITERS, ELLIPSOID,
                         EPA_REL_TOL, PRE_EXACT, P_ROLL, ROLL_SHRINK)
from ..geometry import borrow_pose, meet
from ..jit import borrow, njit_inline, njit_kernel, njit_separate
from .cylinder_common import _apart_out, _certified_out, _frame, gap_newton_step, pre_outcome


@njit_inline
def face_room(e, k, x, y, z):
    """The least gap from the point (x, y, z) (the box's frame) to the sides of the box
    faces normal to axis k, e_i - |x_i| over the two other axes i (half extents e):
    the radius of the largest disc about its foot inside the face (polish_faces._face_test)."""
    if k == 0:
        return min(e[1] - abs(y), e[2] - abs(z))
    if k == 1:
        return min(e[0] - abs(x), e[2] - abs(z))
    return min(e[0] - abs(x), e[1] - abs(y))


@njit_inline
def _normal_of(side, r_ab, mx, my, mz):
    """The normal from A to B (A's frame) for the unit m (the box's frame) along which the
    ellipsoid's core lies beyond the box: -m carried into A's frame when the box is B
    (side 0, the ellipsoid A), m itself when the box is A."""
    if side == 0:
        return (-(r_ab[0, 0] * mx + r_ab[0, 1] * my + r_ab[0, 2] * mz),
                -(r_ab[1, 0] * mx + r_ab[1, 1] * my + r_ab[1, 2] * mz),
                -(r_ab[2, 0] * mx + r_ab[2, 1] * my + r_ab[2, 2] * mz))
    return mx, my, mz


@njit_inline
def _exact_apart(res, side, r_ab, t_ab, g, mx, my, mz, px, py, pz, qx, qy, qz):
    """res = [-g, n, pa, pb] for cores exactly g apart along the unit m (the box's frame,
    from the box to the core), p the core's closest point and q the box's (the box's
    frame), moved by halves of the remainder so that pb - pa == g n exactly (meet, as
    GJK's and EPA's witnesses); returns -g.  g must be > 0 (cylinder_common._apart_out's rows)."""
    nx, ny, nz = _normal_of(side, r_ab, mx, my, mz)
    _apart_out(res, g, nx, ny, nz, side, r_ab, t_ab, px, py, pz, qx, qy, qz)
    for c in range(3):
        res[4 + c], res[7 + c] = meet(res[4 + c], res[7 + c], g * res[1 + c])
    return -g


@njit_inline
def _core_point(c, S, roll, mx, my, mz):
    """The core's support point along -m (m unit, the box's frame) and sqrt(m^T S m):
    c - S m / sqrt(m^T S m) + r m."""
    sx = S[0] * mx + S[1] * my + S[2] * mz
    sy = S[1] * mx + S[3] * my + S[4] * mz
    sz = S[2] * mx + S[4] * my + S[5] * mz
    rs = math.sqrt(mx * sx + my * sy + mz * sz)
    return (c[0] - sx / rs + roll * mx, c[1] - sy / rs + roll * my,
            c[2] - sz / rs + roll * mz, rs)


@njit_inline
def _s_at(S, a, b):
    """Entry (a, b) of the symmetric S held as (s00, s01, s02, s11, s12, s22)."""
    if a > b:
        a, b = b, a
    if a == 0:
        return S[b]
    if a == 1:
        return S[2 + b]
    return S[5]


@njit_inline
def _axis_pick(axis, x, y, z):
    """The one of x, y, z for the box axis ``axis`` (0, 1 or 2)."""
    if axis == 0:
        return x
    return y if axis == 1 else z


@njit_inline
def _edge_distance(c, S, roll, box, i, j, k, sj, sk, scale, stop):
    """The cores' distance over the box edge along x_i at (x_j, x_k) = (sj e_j, sk e_k),
    the core beyond it: the unit m (box's frame, in the plane of x_j and x_k, between
    the faces' normals sj x_j and sk x_k) maximising the gap g(m) = min over the core of
    m . y less the edge's m . x (Newton's method on m's angle, as cylinder_common's
    collide_ellipsoid_cylinder maximises its g), the core's point p along -m and q, its
    foot on the edge.  Returns (status, g, m (3), p (3), q (3)): status 1 when g is the
    distance (p within the edge's length and |p - q| within BE_EXACT * scale of g: the
    plane normal to m at the edge separates by g and p, q are g apart), 2 or -1 when p
    lies past the edge's end at +e_i or -e_i, 3 when an iterate's g, a separating
    plane's gap (m between the faces' normals), already exceeds ``stop`` (then q is the
    edge's point nearest p), 0 otherwise."""
    ox = c[j] - sj * box[j]
    oy = c[k] - sk * box[k]
    sjj, skk, sjk = _s_at(S, j, j), _s_at(S, k, k), _s_at(S, j, k)
    al, be, ga = 0.5 * (sjj + skk), 0.5 * (sjj - skk), sjk
    on = math.sqrt(ox * ox + oy * oy)
    cs, sn = sj * math.sqrt(0.5), sk * math.sqrt(0.5)
    if on > 0.0:
        cs, sn = ox / on, oy / on
    far = False
    for _ in range(CC_NEWTON_ITERS):
        rs, ncs, nsn, done = gap_newton_step(al, be, ga, ox, oy, cs, sn)
        if sj * cs >= 0.0 and sk * sn >= 0.0 and ox * cs + oy * sn - rs + roll > stop:
            far = True      # apart by more than the caller asks to know
            break
        cs, sn = ncs, nsn
        if done:
            break
    # m = cs e_j + sn e_k, and q = p with its j and k coordinates on the edge: written
    # as floats (lists would be allocated and freed at every call)
    mx = cs if j == 0 else (sn if k == 0 else 0.0)
    my = cs if j == 1 else (sn if k == 1 else 0.0)
    mz = cs if j == 2 else (sn if k == 2 else 0.0)
    px, py, pz, rs = _core_point(c, S, roll, mx, my, mz)
    g = ox * cs + oy * sn - rs + roll
    p_i = _axis_pick(i, px, py, pz)
    qj, qk = sj * box[j], sk * box[k]
    # far: that plane's gap is the bound, q the edge's point nearest p
    qi = min(box[i], max(-box[i], p_i)) if far else p_i
    qx = qj if j == 0 else (qk if k == 0 else qi)
    qy = qj if j == 1 else (qk if k == 1 else qi)
    qz = qj if j == 2 else (qk if k == 2 else qi)
    if far:
        return 3, g, mx, my, mz, px, py, pz, qx, qy, qz
    if not (sj * cs >= 0.0 and sk * sn >= 0.0 and g > 0.0):
        return 0, g, mx, my, mz, px, py, pz, qx, qy, qz
    if p_i > box[i]:
        return 2, g, mx, my, mz, px, py, pz, qx, qy, qz
    if p_i < -box[i]:
        return -1, g, mx, my, mz, px, py, pz, qx, qy, qz
    dj, dk = _axis_pick(j, px, py, pz) - qj, _axis_pick(k, px, py, pz) - qk
    ok = math.sqrt(dj * dj + dk * dk) - g <= BE_EXACT * scale
    return (1 if ok else 0), g, mx, my, mz, px, py, pz, qx, qy, qz


@njit_inline
def _vertex_distance(c, S, roll, ell, axes, box, sx, sy, sz, scale):
    """The cores' distance over the box vertex v = (sx e_0, sy e_1, sz e_2), outside the
    core: the ellipsoid's point nearest v, x_i = a_i^2 w_i / (a_i^2 + t) (w = v in the
    ellipsoid's frame) at the root t of sum (a_i w_i / (a_i^2 + t))^2 = 1 (Newton's
    method, kept inside its bracket: (0, inf) with v outside the ellipsoid, (-c^2, 0)
    inside it), m the unit along minus the ellipsoid's outward normal there, which
    must lie in v's normal cone (sx m_0, sy m_1, sz m_2 >= 0: v is then the box's
    support along m), the core's point p along -m and the gap g(m) as in
    _edge_distance.  Returns (exact, g, m (3), p (3), v (3)), exact when g > 0 and |p -
    v| is within BE_EXACT * scale of g (whichever root was found: g is a separating
    plane's gap and |p - v| a distance between the two cores)."""
    ux, uy, uz, vx, vy, vz, kx, ky, kz = axes
    qx, qy, qz = sx * box[0], sy * box[1], sz * box[2]
    dx, dy, dz = qx - c[0], qy - c[1], qz - c[2]
    w1 = ux * dx + uy * dy + uz * dz
    w2 = vx * dx + vy * dy + vz * dz
    w3 = kx * dx + ky * dy + kz * dz
    a2, b2, c2 = ell[0] * ell[0], ell[1] * ell[1], ell[2] * ell[2]
    zero = (False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, qx, qy, qz)
    lo, hi = 0.0, np.inf
    if not w1 * w1 / a2 + w2 * w2 / b2 + w3 * w3 / c2 > 1.0:
        lo, hi = -min(a2, min(b2, c2)), 0.0
    t = 0.0
    for _ in range(BE_POINT_ITERS):
        e1, e2, e3 = a2 + t, b2 + t, c2 + t
        q1, q2, q3 = ell[0] * w1 / e1, ell[1] * w2 / e2, ell[2] * w3 / e3
        f = q1 * q1 + q2 * q2 + q3 * q3 - 1.0
        df = 2.0 * (q1 * q1 / e1 + q2 * q2 / e2 + q3 * q3 / e3)
        if f > 0.0:
            lo = t
        else:
            hi = t
        if not df > 0.0:
            return zero
        tn = t + f / df
        if not lo < tn < hi:
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= BE_ROOT_STOP * max(abs(t), min(a2, min(b2, c2))):
            t = tn
            break
        t = tn
    # the outward normal there, x_i / a_i^2 = w_i / (a_i^2 + t), in the box's frame
    n1, n2, n3 = w1 / (a2 + t), w2 / (b2 + t), w3 / (c2 + t)
    mx = n1 * ux + n2 * vx + n3 * kx
    my = n1 * uy + n2 * vy + n3 * ky
    mz = n1 * uz + n2 * vz + n3 * kz
    mn = math.sqrt(mx * mx + my * my + mz * mz)
    if not mn > 0.0:
        return zero
    mx, my, mz = -mx / mn, -my / mn, -mz / mn
    if not (sx * mx >= 0.0 and sy * my >= 0.0 and sz * mz >= 0.0):
        return zero
    px, py, pz, rs = _core_point(c, S, roll, mx, my, mz)
    g = mx * (c[0] - qx) + my * (c[1] - qy) + mz * (c[2] - qz) - rs + roll
    ex, ey, ez = px - qx, py - qy, pz - qz
    exact = g > 0.0 and math.sqrt(ex * ex + ey * ey + ez * ez) - g <= BE_EXACT * scale
    return exact, g, mx, my, mz, px, py, pz, qx, qy, qz


@njit_inline
def _face_normal(side, r_ab, k, s):
    """The normal from A to B (A's frame) that pushes the ellipsoid's core out of the box
    through its face s x_k (the ellipsoid on ``side``): the box moves along -s x_k when
    it is B (side 0), the ellipsoid along s x_k when the box is A."""
    if side == 0:
        return -s * r_ab[0, k], -s * r_ab[1, k], -s * r_ab[2, k]
    return (s if k == 0 else 0.0), (s if k == 1 else 0.0), (s if k == 2 else 0.0)


@njit_inline
def _edge_out(res, side, r_ab, t_ab, st, g, mx, my, mz, ax, ay, az, bx, by, bz):
    """_beyond_rim's answer from an edge (_edge_distance's outputs): (-g, True) for the
    exact distance (status 1, _exact_apart), (-g, False) for its plane's bound (status
    3, _apart_out), else (0, False)."""
    if st == 1:
        return _exact_apart(res, side, r_ab, t_ab, g, mx, my, mz, ax, ay, az, bx, by,
                            bz), True
    if st == 3:
        nx, ny, nz = _normal_of(side, r_ab, mx, my, mz)
        return _apart_out(res, g, nx, ny, nz, side, r_ab, t_ab, ax, ay, az, bx, by,
                          bz), False
    return 0.0, False


@njit_kernel
def _beyond_rim(res, side, r_ab, t_ab, ell, box, roll, cx, cy, cz, ux, uy, uz, vx, vy, vz,
                kx, ky, kz, k, s, px, py, pz, scale, stop):
    """The cores' exact distance when the core's lowest point p under the face s x_k
    (beyond its plane or not) lies past the face's rim, where they may be apart over
    the box's edge or vertex there: over the edge along the
    lateral axis p lies within (p past one lateral side), else over the vertex of p's
    signs; an edge whose nearest point lies past its end hands on to that vertex, and a
    vertex whose normal cone misses (p past both sides) to the edges along either side.
    Returns (-g, True) for the exact distance g (res written, _exact_apart), (-g, False)
    for an edge's separating plane whose gap g exceeds ``stop`` (_apart_out), or (0,
    False) when neither is certain."""
    # owner-less views: no reference counting on them (geometry.borrow_args)
    res, r_ab, t_ab = borrow(res), borrow(r_ab), borrow(t_ab)
    # the radii and the half sides as floats: the arrays, passed on to the helpers
    # inlined below, kept 13 reference-count calls on their struct even borrowed
    ell = (ell[0], ell[1], ell[2])
    box = (box[0], box[1], box[2])
    a2, b2, c2 = ell[0] * ell[0], ell[1] * ell[1], ell[2] * ell[2]
    S = (a2 * ux * ux + b2 * vx * vx + c2 * kx * kx,
         a2 * ux * uy + b2 * vx * vy + c2 * kx * ky,
         a2 * ux * uz + b2 * vx * vz + c2 * kx * kz,
         a2 * uy * uy + b2 * vy * vy + c2 * ky * ky,
         a2 * uy * uz + b2 * vy * vz + c2 * ky * kz,
         a2 * uz * uz + b2 * vz * vz + c2 * kz * kz)
    c = (cx, cy, cz)
    p = (px, py, pz)
    # the two lateral axes, and which of them p lies past
    i1 = 1 if k == 0 else 0
    i2 = 1 if k == 2 else 2
    out1 = abs(p[i1]) > box[i1]
    out2 = abs(p[i2]) > box[i2]
    # the signs of p's octant, the face's s along k: three floats, not a list (a list
    # is allocated and freed at every call)
    sg0 = s if k == 0 else (1.0 if p[0] >= 0.0 else -1.0)
    sg1 = s if k == 1 else (1.0 if p[1] >= 0.0 else -1.0)
    sg2 = s if k == 2 else (1.0 if p[2] >= 0.0 else -1.0)
    if out1 != out2:
        j = i1 if out1 else i2          # the side p lies past
        i = i2 if out1 else i1          # the edge's axis
        st, g, mx, my, mz, ax, ay, az, bx, by, bz = _edge_distance(
            c, S, roll, box, i, j, k, _axis_pick(j, sg0, sg1, sg2), s, scale, stop)
        if st != 2 and st != -1:
            return _edge_out(res, side, r_ab, t_ab, st, g, mx, my, mz, ax, ay, az, bx, by,
                             bz)
        si = 1.0 if st == 2 else -1.0
        sg0 = si if i == 0 else sg0
        sg1 = si if i == 1 else sg1
        sg2 = si if i == 2 else sg2
    ok, g, mx, my, mz, ax, ay, az, bx, by, bz = _vertex_distance(
        c, S, roll, ell, (ux, uy, uz, vx, vy, vz, kx, ky, kz), box, sg0, sg1, sg2,
        scale)
    if ok:
        return _exact_apart(res, side, r_ab, t_ab, g, mx, my, mz, ax, ay, az, bx, by,
                            bz), True
    if out1 and out2:
        # p past both sides, yet the vertex's cone misses: the edge along either side
        for e in range(2):
            i = i1 if e == 0 else i2
            j = i2 if e == 0 else i1
            st, g, mx, my, mz, ax, ay, az, bx, by, bz = _edge_distance(
                c, S, roll, box, i, j, k, _axis_pick(j, sg0, sg1, sg2), s, scale, stop)
            if st == 1 or st == 3:
                return _edge_out(res, side, r_ab, t_ab, st, g, mx, my, mz, ax, ay, az, bx,
                                 by, bz)
    return 0.0, False


@njit_separate
def _ellipsoid_box_bound(sa, sb, r_ab, t_ab, scale, stop, res):
    """The outcomes of the module notes for an ellipsoid and a box (either order; B's
    pose r_ab, t_ab in A's frame; ``stop`` (m, may be inf): a face plane proving the
    cores farther apart than this ends the call with that bound, as GJK's ``stop``).
    Returns (d, exact):

    * (h > 0, True): the core depth h, certified; res[:10] = [h, n (3), pa (3), pb (3)]
      in A's frame, n from A to B, pa and pb on the two cores, pb - pa == -h n.
    * (-g <= 0, True): the cores are exactly g apart, res = [-g, n, pa, pb] with pa, pb
      the closest points (pb - pa == g n).
    * (-g < 0, False): the cores are at least g apart, n normal to a separating plane,
      pa and pb points of the two cores (cylinder_common._apart_out).
    * (0, False): nothing decided, res untouched."""
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, r_ab, t_ab = borrow_pose(sa, sb, r_ab, t_ab)
    res = borrow(res)
    side = 0 if sa[0] == ELLIPSOID else 1
    ell = sa[1] if side == 0 else sb[1]
    box = sb[1] if side == 0 else sa[1]
    roll = ell[P_ROLL]
    cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(side, r_ab, t_ab)
    a2, b2, c2 = ell[0] * ell[0], ell[1] * ell[1], ell[2] * ell[2]
    # the diagonal of S: E's squared half-widths along the box's axes
    w0 = math.sqrt(a2 * ux * ux + b2 * vx * vx + c2 * kx * kx)
    w1 = math.sqrt(a2 * uy * uy + b2 * vy * vy + c2 * ky * ky)
    w2 = math.sqrt(a2 * uz * uz + b2 * vz * vz + c2 * kz * kz)
    # the least h over the six faces: e_k - s c_k + w_k - r, the sign s opposite c_k's
    h0 = box[0] - abs(cx) + w0 - roll
    h1 = box[1] - abs(cy) + w1 - roll
    h2 = box[2] - abs(cz) + w2 - roll
    k = 0
    h, w, ck = h0, w0, cx
    if h1 < h:
        k, h, w, ck = 1, h1, w1, cy
    if h2 < h:
        k, h, w, ck = 2, h2, w2, cz
    if not (w > 0.0 and math.isfinite(h)):
        return 0.0, False
    s = 1.0 if ck >= 0.0 else -1.0
    # p = c - s S x_k / w + s r x_k; S x_k = a^2 u_k u + b^2 v_k v + c^2 k_k k
    uk = ux if k == 0 else (uy if k == 1 else uz)
    vk = vx if k == 0 else (vy if k == 1 else vz)
    kk = kx if k == 0 else (ky if k == 1 else kz)
    f = s / w
    px = cx - f * (a2 * uk * ux + b2 * vk * vx + c2 * kk * kx)
    py = cy - f * (a2 * uk * uy + b2 * vk * vy + c2 * kk * ky)
    pz = cz - f * (a2 * uk * uz + b2 * vk * vz + c2 * kk * kz)
    if k == 0:
        px += s * roll
    elif k == 1:
        py += s * roll
    else:
        pz += s * roll
    nx, ny, nz = _face_normal(side, r_ab, k, s)
    if not h > 0.0:
        # K beyond the face's plane x_k = s e_k; q, p's foot on it clamped to the face
        qx = s * box[0] if k == 0 else min(box[0], max(-box[0], px))
        qy = s * box[1] if k == 1 else min(box[1], max(-box[1], py))
        qz = s * box[2] if k == 2 else min(box[2], max(-box[2], pz))
        if not h < 0.0:
            return 0.0, False           # the core touches the face's plane: GJK decides
        if face_room(box, k, px, py, pz) >= 0.0:
            # the closest points: p on the ellipsoid's core, its foot q on the box
            return _exact_apart(res, side, r_ab, t_ab, -h, s if k == 0 else 0.0,
                                s if k == 1 else 0.0, s if k == 2 else 0.0, px, py, pz, qx,
                                qy, qz), True
        if -h <= stop:
            # the foot past the face's rim: the nearest feature may be an edge or a vertex
            d, exact = _beyond_rim(res, side, r_ab, t_ab, ell, box, roll, cx, cy, cz, ux,
                                   uy, uz, vx, vy, vz, kx, ky, kz, k, s, px, py, pz, scale,
                                   stop)
            if d < 0.0:
                return d, exact
        return _apart_out(res, -h, nx, ny, nz, side, r_ab, t_ab, px, py, pz, qx, qy, qz), False
    # the rolling ball at p: radius c_min^2 / w - r, centre p + s rho x_k; no larger
    # than h, so that its centre stays under the face (a smaller ball touching at p lies
    # inside the larger one)
    cmin = min(ell[0], min(ell[1], ell[2]))
    rho = min(h, max(0.0, (1.0 - ROLL_SHRINK) * cmin * cmin / w - roll))
    # the centre's distances to the other five faces: the opposite one and the sides
    fr = face_room(box, k, px, py, pz)
    room = min(2.0 * box[k] - (h - rho), fr)
    # the centre inside the box (room >= 0), its depth there min(h - rho, room)
    if not (room >= 0.0 and rho + min(room, h - rho) >= h - EPA_REL_TOL * scale):
        # the lowest point under the face's plane but past its rim: the cores may still
        # be apart over an edge or a vertex
        if fr < 0.0:
            d, exact = _beyond_rim(res, side, r_ab, t_ab, ell, box, roll, cx, cy, cz, ux,
                                   uy, uz, vx, vy, vz, kx, ky, kz, k, s, px, py, pz, scale,
                                   stop)
            if d < 0.0:
                return d, exact
        return 0.0, False
    _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, px, py, pz)
    return h, True


@njit_inline
def collide_ellipsoid_box(sa, sb, r_ab, t_ab, scale, stop, res):
    """What gjk_epa.gjk_epa_ws learns before GJK for an ellipsoid and a box (constants.PRE_*):
    PRE_EXACT with res[:10] the cores' certified depth or exact distance, normal and points
    (_ellipsoid_box_bound's first two outcomes), PRE_APART when a face plane proves the
    cores farther apart than ``stop`` (m; res the bound), else PRE_UNDECIDED."""
    d, exact = _ellipsoid_box_bound(sa, sb, r_ab, t_ab, scale, stop, res)
    # an inexact d is never > 0 (a bound or nothing): pre_outcome's apart test decides it
    return PRE_EXACT if exact else pre_outcome(d, stop)
