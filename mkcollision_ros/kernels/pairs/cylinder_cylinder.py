"""Penetration depth of two cylinders whose cores overlap, from a point of one core
deep inside the other cylinder, certified by a ball and found without GJK or EPA
(gjk_epa.gjk_epa_ws calls ``collide_cylinder_cylinder`` first for such a pair; where no
candidate is certified it returns PRE_UNDECIDED and GJK and EPA run as for any pair).  The
certificate, the answers and the shared helpers: cylinder_common.py.

The candidates, each a pair (p, n) whose ball radius and h(n) meet when the deepest
direction is theirs:
  1. A rim against the other's side: p the rim's point nearest the other's axis (a
     local minimum of |p_xy| over the rim circle, by Newton's method on its angle) and n
     the other's side normal there.  Its depth along n is R - |p_xy| when p is the
     rim's support point along minus that normal, i.e. when p is the point of the whole
     cylinder nearest the other's axis; h(n) is one support of A - B.
  2. Against the other's cap (axis +-z): p the cylinder's support point along minus the
     cap's normal (its lowest point under the cap's plane).  Along the cap's normal the
     other's support is the whole cap, so h = H -+ p_z exactly, with no support of A - B.
  3. The two sides crossing (sides_crossing): n normal to both axes, where both
     supports are side segments, so h(n) needs no support of A - B either, and p a
     witness on one side at the foot of the origin, h in from the other's side.  Near
     a cylinder's end, where neither witness's ball is whole, _crossing_global bounds
     h over every direction instead (no ball: the concavity of h in the axes' plane).
Two sides (A in B, B in A) give eight candidates of kinds 1 and 2.  A cap candidate
with h <= 0 proves the cores apart (the cylinder lies past the other's cap plane), and
so does the crossing with h <= 0 (the plane between the two side segments), and so
does a side's tangent plane facing the other's centre with the other core wholly
beyond it (_sides_apart): minus that gap at once, with the plane's normal and a point
of each core (_apart_out), which gjk_epa.gjk_epa_ws takes as GJK's distance bound in
contacts mode.  The caps first, then the crossing, then the sides' planes, then the
rims (the only kind that needs a support of A - B).  The
rims are solved in the order of an upper bound on their balls, at most CC_RIMS of
them, and only the deepest rim point found is tried (one support of A - B): every ball
is at most the depth, so only the deepest can be certified.

Measured (pure-Python runs of collide_cylinder_cylinder on bench/dev/deep_pairs.py's 2,000
cylinder-cylinder cases, GJK + EPA the reference): the rims and caps certify 289 of 961
penetrating pairs (270 of the 939 deeper than 1e-3 * scale: 234 a rim against a side, 36
against a cap), depths within 6.0e-9 * scale of EPA's (EPA's tolerance: it reports its
nearest face), normals within 1.3e-4 rad (EPA's error on a curved minimum).  0.87 rims
solved per pair (3.6 Newton steps each), 0.38 supports of A - B.  Compiled, ~175 ns
per pair over all 2,000 (a loop calling it alone, less the loop's own ~27 ns), against
~3.4 us of GJK + EPA saved on each certified pair.  The crossing certifies 96 more of
the 939, its depths within 1e-16 * scale and normals within 4e-8 rad of EPA's.
_crossing_global certifies most crossings near an end as well (889 of 965 crossings
among 2,895 deep pairs of three seeds of the benchmark's cases, against 260 by the
balls alone).  The other kinds have no ball
about a witness inside the other cylinder as deep as the depth: crossings near a
cylinder's end that _crossing_global's bound misses (polish_faces._cylinders_crossing
hands their face to EPA), two rims, and rims whose ball the other's cap or side cuts short.
For the last, and for a cap's candidate whose ball the side cuts short, _cover
bounds the depth from below by the point's gap to the side (or cap) instead, where
the point's cylinder reaches, along three segments from it, far enough round the
other's cap (or side): every translate shorter than the gap still meets the other
cylinder (615 of the 939 deep pairs above are certified in all).

Witness points (A's frame, cores): p and its translate by the depth along n on the
other cylinder's side or cap; pb - pa == -depth * n exactly after meet.
"""
import math

import numpy as np

from ..constants import AXES_SIN_MIN, CC_CROSS_RINGS, CC_NEWTON_ITERS, CC_RIMS, EPA_REL_TOL
from ..geometry import borrow_args, cylinder_inradius, minkowski_core_xyz
from ..jit import borrow, njit_inline, njit_separate
from .cylinder_common import (_apart_out, _cap_normal, _certified_out, _cover, _frame,
                              _newton_turn, _past_cap, _past_side, _side_normal, pre_outcome)


@njit_inline
def _rim_nearest_axis(cx, cy, cz, ux, uy, uz, vx, vy, vz, rho):
    """The point (x, y, z) of the circle c + rho (cos t u + sin t v) (u, v orthonormal)
    at a local minimum of its distance from the z axis: Newton's method on
    F(t) = |E(t)|^2, E the circle's shadow on the xy plane, from the shadow's point
    farthest against c_xy.  Each step turns (cos t, sin t) by the angle whose half has
    the tangent -F' / (2 F'') (Newton's step to third order; a rotation in rational
    form, unit to round-off, with the step's own division: one per step)."""
    ax, ay = rho * ux, rho * uy
    bx, by = rho * vx, rho * vy
    g1 = cx * ax + cy * ay
    g2 = cx * bx + cy * by
    gn = math.sqrt(g1 * g1 + g2 * g2)
    cs, sn = 1.0, 0.0
    if gn > 0.0:
        cs, sn = -g1 / gn, -g2 / gn
    for _ in range(CC_NEWTON_ITERS):
        ex, ey = cx + ax * cs + bx * sn, cy + ay * cs + by * sn     # E
        dx, dy = bx * cs - ax * sn, by * cs - ay * sn              # E'
        g = ex * dx + ey * dy                                      # F' / 2
        hh = dx * dx + dy * dy - (ex - cx) * ex - (ey - cy) * ey    # F'' / 2
        cs, sn, done = _newton_turn(cs, sn, g, hh)
        if done:
            break
    return (cx + rho * (ux * cs + vx * sn), cy + rho * (uy * cs + vy * sn),
            cz + rho * (uz * cs + vz * sn))


@njit_inline
def sides_crossing(sa, sb, r_ab, t_ab):
    """The face of two cylinders' core difference made by their sides crossing, normal
    to both axes (A's frame; a = z, b = B's axis, t = B's centre): returns (nx, ny, h,
    s, u, sn) with n = (nx, ny, 0) the unit normal to both axes with n . t >= 0, h =
    h(n) = r_a + r_b - n . t (along +-n both supports are side segments: no support of
    A - B), s and u the parameters of the origin's foot on the face, i.e. A's witness
    pa = r_a n + s a and B's pb = t - r_b n + u b, with pb - pa = -h n, and sn = |a x
    b|.  Axes parallel within 1e-6: no face, sn = 0 (and the rest 0)."""
    bx, by, bz = r_ab[0, 2], r_ab[1, 2], r_ab[2, 2]
    sn = math.sqrt(bx * bx + by * by)         # |a x b|, a = (0, 0, 1)
    if not sn > AXES_SIN_MIN:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    nx, ny = -by / sn, bx / sn
    nt = nx * t_ab[0] + ny * t_ab[1]
    if nt < 0.0:
        nx, ny, nt = -nx, -ny, -nt
    # s a - u b = g: the foot's parameters on A's and B's segments (their midpoints
    # r_a n and t - r_b n)
    gx, gy, gz = t_ab[0] - nt * nx, t_ab[1] - nt * ny, t_ab[2]
    gb = gx * bx + gy * by + gz * bz
    den = sn * sn
    return nx, ny, sa[1][0] + sb[1][0] - nt, (gz - bz * gb) / den, (bz * gz - gb) / den, sn


@njit_inline
def _end_room(k):
    """The radius of the disc |x| <= rho over which m |x . e| - r (1 - sqrt(1 - (x .
    e)^2)) >= 0 for a unit e, k = m / r >= 0 (_crossing_global's inner disc): the
    function of y = |x . e| is concave and 0 at y = 0, so it holds up to its root,
    y / (1 + sqrt(1 - y^2)) = k, i.e. y = sin(2 atan k) = 2 k / (1 + k^2), and on
    the whole disc when k >= 1."""
    return 1.0 if k >= 1.0 else 2.0 * k / (1.0 + k * k)


@njit_inline
def _crossing_global(ra, la, rb, lb, h, s, u, sn, c, tol):
    """Whether the crossing's h = h(n) (sides_crossing: n normal to both axes, the
    witnesses at s on A's segment and u on B's, sn = |a x b|, c = a . b) is the core
    depth within tol, where a witness's ball falls short because the crossing is near
    a cylinder's end.  h(n) is an upper bound; this proves h(w) >= h - tol for every
    unit w.

    Write w = v n + x, x in the plane of the two axes, and T = n . t = ra + rb - h >= 0.
    Then h(w) - h = F_a(x . a) + F_b(x . b) + T (1 - v), with F_a(y) = ra (sqrt(1 -
    y^2) - 1) + la |y| - s y and F_b(y) likewise with +u y (t's part in the plane is s a
    - u b), and T (1 - v) >= T (1 - sqrt(1 - |x|^2)) >= 0.
      1. Inner disc |x| <= rho0: F_a(y) >= m_a |y| - ra (1 - sqrt(1 - y^2)) with m_a =
         la - |s|, and |y| <= |x|, so h(w) >= h there for rho0 = the smaller
         _end_room of m_a / ra and m_b / rb (both witnesses on their segments).
      2. g(x) = h(w) + T v is, on each of the four sectors where x . a and x . b keep
         their signs, concave in x (sqrt(1 - y^2) of a linear y is; |y| is linear
         there), and g = ra + rb + F_a + F_b >= ra + rb on the inner disc.  On the
         unit circle g is the support function of the in-plane shadow of A - B (two
         rectangles' sum, shifted by -t's part), so its least value P is at one of the
         shadow's eight edge normals +-a, +-b and their in-plane squares, given P > 0
         (the origin inside).  Along a ray, concavity between the disc's edge and the
         circle gives g(x) >= ra + rb - (|x| - rho0) / (1 - rho0) D, D = ra + rb - P.
      3. So on the ring rho_i <= |x| <= rho_(i+1), h(w) - h >= T (1 - sqrt(1 -
         rho_i^2)) - (rho_(i+1) - rho0) / (1 - rho0) D, which is >= -tol up to
         rho_(i+1) = rho0 + (1 - rho0) (T (1 - sqrt(1 - rho_i^2)) + tol) / D.  Rings
         from rho0 outward (at most CC_CROSS_RINGS) that reach |x| = 1 cover every w.
         D <= tol covers every w at once.
    Measured (bench cases, 2,895 deep cylinder pairs, 965 of them at a crossing): the
    witnesses' balls certify 260 of the 965, this 858, both 889 (with the chord from
    the origin instead of from the disc's edge, 708 and 778); never one whose depth
    (GJK + EPA) is below h - tol."""
    ma, mb = la - abs(s), lb - abs(u)
    if not (h > 0.0 and ma >= 0.0 and mb >= 0.0):
        return False
    ac = abs(c)
    p = min(min(la + rb * sn + lb * ac - abs(s - u * c), ra + rb * ac + mb * sn),
            min(lb + ra * sn + la * ac - abs(s * c - u), rb + ra * ac + ma * sn))
    if not p > 0.0:
        return False
    d = ra + rb - p
    if d <= tol:
        return True
    big_t = ra + rb - h
    rho0 = min(_end_room(ma / ra), _end_room(mb / rb))
    rho = rho0
    for _ in range(CC_CROSS_RINGS):
        if rho >= 1.0:
            return True
        nxt = rho0 + (1.0 - rho0) * (big_t * rho * rho / (1.0 + math.sqrt(1.0 - rho * rho))
                                     + tol) / d
        if not nxt > rho:
            return False
        rho = nxt
    return rho >= 1.0


@njit_inline
def _crossing_depth(sa, sb, r_ab, t_ab, tol, res):
    """3. The sides crossing (sides_crossing): h(n) along the face's normal n, certified
    by the ball of a witness.  pa lies h in from B's side (pb - pa = -h n, n normal to
    B's axis) at B's axial coordinate u, so its ball in B has the radius min(r_b - |r_b
    - h|, l_b - |u|), and it is a point of A when |s| <= l_a; pb's in A likewise.
    Either ball >= h - tol certifies h; they fall short where a cap cuts them (the
    crossing near a cylinder's end), and _crossing_global's bound over all directions
    is tried instead.  Returns h (certified, res written), or minus the
    gap -h when h <= 0 (the face's plane separates the cores; _apart_out), or 0."""
    nx, ny, h, s, u, sn = sides_crossing(sa, sb, r_ab, t_ab)
    if not sn > 0.0:
        return 0.0
    ra, la, rb, lb = sa[1][0], sa[1][1], sb[1][0], sb[1][1]
    if not h > 0.0:
        # the plane square to n between the two side segments separates the cores by
        # -h: their points at the foot (clamped to the segments), B's as _apart_out's p
        bx, by, bz = r_ab[0, 2], r_ab[1, 2], r_ab[2, 2]
        u = min(lb, max(-lb, u))
        return _apart_out(res, -h, nx, ny, 0.0, np.int64(1), r_ab, t_ab,
                          t_ab[0] - rb * nx + u * bx, t_ab[1] - rb * ny + u * by,
                          t_ab[2] + u * bz, ra * nx, ra * ny, min(la, max(-la, s)))
    ball = -math.inf
    if abs(s) <= la:
        ball = min(rb - abs(rb - h), lb - abs(u))
    if abs(u) <= lb:
        ball = max(ball, min(ra - abs(ra - h), la - abs(s)))
    if not (ball >= h - tol
            or _crossing_global(ra, la, rb, lb, h, s, u, sn, r_ab[2, 2], tol)):
        return 0.0
    _certified_out(res, h, nx, ny, 0.0, np.int64(1), r_ab, t_ab, ra * nx - h * nx,
                   ra * ny - h * ny, s)
    return h


@njit_inline
def _roles(sa, sb, side):
    """(rho, eta, R, H): the radius and half-height of the cylinder on ``side`` (A's
    when 0), then the other's."""
    own = sa[1] if side == 0 else sb[1]
    oth = sb[1] if side == 0 else sa[1]
    return own[0], own[1], oth[0], oth[1]


@njit_inline
def _sides_apart(sa, sb, r_ab, t_ab, res):
    """4. Each cylinder's side against the other core: m the horizontal unit from its
    axis towards the other's centre (its frame), the other core's lowest point p along
    m (a rim point; with the axes parallel, the side line's lower end); m . p > R
    proves the cores apart by that much beyond the side's tangent plane (_past_side).
    Returns minus the gap (res written as _apart_out's), or 0.  Measured (pure Python,
    bench/dev/deep_pairs.py's 2,000 cylinder-cylinder cases): of the 536 pairs apart
    whose bounding spheres overlap (those the batch kernel hands to gjk_epa_ws), the
    caps' and the crossing's planes decide 283, these 183 more; the other 70 go to
    GJK."""
    for side in range(2):
        rho, eta, big_r, big_h = _roles(sa, sb, side)
        cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(side, r_ab, t_ab)
        cc = math.sqrt(cx * cx + cy * cy)
        if not cc > big_r:
            continue
        mx, my = cx / cc, cy / cc
        mk = mx * kx + my * ky
        zk = eta if mk >= 0.0 else -eta
        px, py, pz = cx - zk * kx, cy - zk * ky, cz - zk * kz
        rx, ry, rz = mx - mk * kx, my - mk * ky, -mk * kz
        rn = math.sqrt(rx * rx + ry * ry + rz * rz)
        if rn > 0.0:
            f = rho / rn
            px, py, pz = px - f * rx, py - f * ry, pz - f * rz
        g = mx * px + my * py
        if g > big_r:
            return _past_side(res, g, side, r_ab, t_ab, mx, my, big_r, big_h, px, py, pz)
    return 0.0


@njit_separate
def _cylinder_cylinder_bound(sa, sb, verts, r_ab, t_ab, scale, res):
    """The core depth (> 0) of two cylinders, certified as in the module notes, with
    res (10,) = [depth, n (3), pa (3), pb (3)] on the cores in A's frame (n from A to
    B); minus the gap (< 0) when a cap's plane or the crossing's proves the cores apart,
    res = [-gap, n, pa, pb] (_apart_out); 0 (res untouched) when neither.  sa, sb:
    shape tuples of two cylinders.

    The caps' four candidates first (none needs a support of A - B, and a certified
    one ends the search: it is the depth within tol); then the rims, in the order of
    an upper bound on their balls (R - |q_xy| + rho and H - |q_z| + rho sin(angle of
    the axes), q the rim's centre), each solved only while its bound exceeds the
    deepest ball found: only the deepest rim point can be certified (every ball is at
    most the depth, and a certified one is within tol of it), and one support of A - B
    along its normal decides."""
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    res = borrow(res)
    tol = EPA_REL_TOL * scale
    best_h = math.inf
    cap_side = np.int64(-1)
    cap_s = 0.0
    cpx = cpy = cpz = 0.0
    # the rims' upper bounds (index 2 side + (s + 1) / 2), -inf when out of reach
    ub0 = ub1 = ub2 = ub3 = -math.inf
    for side in range(2):
        rho, eta, big_r, big_h = _roles(sa, sb, side)
        cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(side, r_ab, t_ab)
        # the rim's point of greatest z: rho (uz u + vz v) / w, w = sin(angle of axes)
        w = math.sqrt(uz * uz + vz * vz)
        if w > 0.0:
            f = rho / w
            ex, ey, ez = f * (uz * ux + vz * vx), f * (uz * uy + vz * vy), rho * w
        else:
            ex, ey, ez = rho * ux, rho * uy, rho * uz
        for si in range(2):
            s = 2.0 * si - 1.0
            # 2. the other's cap s z: the own support point along -s z (the rim's point
            # of least s z on the rim of greatest -s z)
            zk = eta if -s * kz >= 0.0 else -eta
            px, py, pz = cx - s * ex + zk * kx, cy - s * ey + zk * ky, cz - s * ez + zk * kz
            h = big_h - s * pz
            if not h > 0.0:
                # the own core lies past the cap's plane: cores apart
                return _past_cap(res, h, side, r_ab, t_ab, s, big_r, big_h, px, py, pz)
            if h < best_h:
                ball = cylinder_inradius(big_r, big_h, px, py, pz)
                if not ball >= h - tol:
                    # cut short by the side: the cover's bound (_cover) from the rim's
                    # side line, cap diameter and diagonal
                    fx, fy, fz = -2.0 * zk * kx, -2.0 * zk * ky, -2.0 * zk * kz
                    gx, gy, gz = 2.0 * s * ex, 2.0 * s * ey, 2.0 * s * ez
                    ball = _cover(np.bool_(False), s, px, py, pz, big_r, big_h, fx, fy, fz, gx, gy,
                                  gz, fx + gx, fy + gy, fz + gz)
                if ball >= h - tol:
                    best_h = h
                    cap_side, cap_s = side, s
                    cpx, cpy, cpz = px, py, pz
            # 1. the rim at s eta k against the other's side: its bound
            qx, qy, qz = cx + s * eta * kx, cy + s * eta * ky, cz + s * eta * kz
            ub = min(big_r - math.sqrt(qx * qx + qy * qy) + rho, big_h - abs(qz) + rho * w)
            if side == 0 and si == 0:
                ub0 = ub
            elif side == 0:
                ub1 = ub
            elif si == 0:
                ub2 = ub
            else:
                ub3 = ub
    if cap_side >= 0:
        nx, ny, nz = _cap_normal(cap_side, r_ab, cap_s)
        _certified_out(res, best_h, nx, ny, nz, cap_side, r_ab, t_ab, cpx, cpy, cpz)
        return best_h
    h = _crossing_depth(sa, sb, r_ab, t_ab, tol, res)
    if h != 0.0:
        return h        # certified, or the cores apart across the crossing's plane
    h = _sides_apart(sa, sb, r_ab, t_ab, res)
    if h != 0.0:
        return h        # the cores apart beyond a side's tangent plane
    # the rims, deepest bound first, while a bound exceeds the deepest ball found
    rim_d = 0.0
    rim_side = np.int64(-1)
    rim_s = 0.0
    rpx = rpy = rpz = 0.0
    for _ in range(CC_RIMS):
        i = 0
        ub = ub0
        if ub1 > ub:
            i, ub = 1, ub1
        if ub2 > ub:
            i, ub = 2, ub2
        if ub3 > ub:
            i, ub = 3, ub3
        if not ub > rim_d:
            break
        if i == 0:
            ub0 = -math.inf
        elif i == 1:
            ub1 = -math.inf
        elif i == 2:
            ub2 = -math.inf
        else:
            ub3 = -math.inf
        side = i // 2
        s = 2.0 * (i % 2) - 1.0
        rho, eta, big_r, big_h = _roles(sa, sb, side)
        cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(side, r_ab, t_ab)
        px, py, pz = _rim_nearest_axis(cx + s * eta * kx, cy + s * eta * ky,
                                       cz + s * eta * kz, ux, uy, uz, vx, vy, vz, rho)
        ball = cylinder_inradius(big_r, big_h, px, py, pz)
        if ball > rim_d and px * px + py * py > 0.0:
            rim_d = ball
            rim_side, rim_s = side, s
            rpx, rpy, rpz = px, py, pz
    if rim_side < 0:
        return 0.0
    # the deepest rim point: h along the other's side normal there (one support)
    q = math.sqrt(rpx * rpx + rpy * rpy)
    nx, ny, nz = _side_normal(rim_side, r_ab, rpx / q, rpy / q)
    ax_, ay_, az_, bx_, by_, bz_ = minkowski_core_xyz(sa, sb, verts, r_ab, t_ab, nx, ny, nz)
    h = nx * (ax_ - bx_) + ny * (ay_ - by_) + nz * (az_ - bz_)
    if not h > 0.0:
        return 0.0
    if not rim_d >= h - tol:
        # the ball cut short by a cap: the cover's bound (_cover), from the rim's
        # side line, cap diameter and diagonal
        _, eta, big_r, big_h = _roles(sa, sb, rim_side)
        cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(rim_side, r_ab, t_ab)
        f = -2.0 * rim_s * eta
        ex = 2.0 * (cx + rim_s * eta * kx - rpx)
        ey = 2.0 * (cy + rim_s * eta * ky - rpy)
        ez = 2.0 * (cz + rim_s * eta * kz - rpz)
        if not _cover(np.bool_(True), 0.0, rpx, rpy, rpz, big_r, big_h, f * kx, f * ky, f * kz,
                      ex, ey, ez, f * kx + ex, f * ky + ey, f * kz + ez) >= h - tol:
            return 0.0
    _certified_out(res, h, nx, ny, nz, rim_side, r_ab, t_ab, rpx, rpy, rpz)
    return h


@njit_inline
def collide_cylinder_cylinder(sa, sb, verts, r_ab, t_ab, scale, stop, res):
    """What gjk_epa.gjk_epa_ws learns before GJK for two cylinders (constants.PRE_*):
    PRE_EXACT with res[:10] the cores' certified depth, normal and points
    (_cylinder_cylinder_bound), PRE_APART when a plane proves the cores farther apart than
    ``stop`` (m; res the bound), else PRE_UNDECIDED."""
    return pre_outcome(_cylinder_cylinder_bound(sa, sb, verts, r_ab, t_ab, scale, res), stop)
