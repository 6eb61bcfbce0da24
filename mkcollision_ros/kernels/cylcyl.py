"""Penetration depth of two cylinders whose cores overlap, from a point of one deep
inside the other, certified by a ball and found without GJK or EPA
(gjk_epa.gjk_epa_ws calls it first for a cylinder pair; where no candidate is
certified it returns 0 and GJK and EPA run as for any pair).

The certificate (as gjk_epa._ball_certified).  If a point p of A's core has the ball
of radius delta about it inside B's core, the core difference A - B holds the ball of
radius delta about the origin (that ball minus p's partner), so h(u) >= delta along
every unit u and the core depth, min_u h(u), is at least delta.  It is at most h(n)
for any unit n.  So where h(n) <= delta + EPA_REL_TOL * scale, h(n) is the depth within
EPA's own tolerance and n a normal: no test that n is a local minimum and no polytope
are needed, whatever creases the two support functions have.  The same holds with A
and B swapped.  Inside a cylinder (axis z, radius R, half-height H) the largest such
ball about p has the radius min(R - |p_xy|, H - |p_z|).

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
Two sides (A in B, B in A) give eight candidates.  A cap candidate with h <= 0 proves
the cores apart (the cylinder lies past the other's cap plane): 0 at once.  The rims are
solved in the order of an upper bound on their balls, at most CC_RIMS of them, and only
the deepest rim point found is tried (one support of A - B): every ball is at most the
depth, so only the deepest can be certified.

Measured (pure-Python runs of cylinders_depth on bench/deep_pairs.py's 2,000
cylinder-cylinder cases; the reference is GJK + EPA at 82766e7): 289 of 961 penetrating
pairs certified (270 of the 939 deeper than 1e-3 * scale: 234 a rim against a side, 36
against a cap), depths within 6.0e-9 * scale of EPA's (EPA's tolerance: it reports its
nearest face), normals within 1.3e-4 rad (EPA's error on a curved minimum).  The other
kinds have no ball about a witness inside the other cylinder as deep as the depth: two
sides crossing (their crossing face, gjk_epa._cylinders_crossing, certified in EPA by
the same ball where it holds), two rims, and pairs whose ball the other's cap or side
cuts short.  0.87 rims solved per pair (3.6 Newton steps each), 0.38 supports of A - B.
Compiled, ~175 ns per pair over all 2,000 (a loop calling it alone, less the loop's
own ~27 ns), against ~3.4 us of GJK + EPA saved on each certified pair.

Witness points (A's frame, cores): p and its translate by the depth along n on the
other cylinder's side or cap; pb - pa == -depth * n exactly after meet.
"""
import math

from .constants import EPA_REL_TOL
from .geometry import minkowski_support_xyz
from .jit import njit_inline, njit_kernel

CC_NEWTON_ITERS = 8     # Newton steps on a rim's angle (~4 taken on average)
_CC_HALF_TAN_MAX = 0.25  # longest step: tan of half its angle (~0.49 rad); far from the
                         # minimum F'' may mislead
_CC_HALF_TAN_DONE = 5e-5  # a step this short ends the search (1e-4 rad; the angle's
                          # error is then of its square, and the ball's of its square)
CC_RIMS = 2             # rims solved at most, deepest bound first (measured on the
                        # benchmark's cases: 1 certifies 7% fewer pairs, 3 or 4 no more)


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
        if hh > 0.0 and abs(g) <= 2.0 * _CC_HALF_TAN_MAX * hh:
            # t = -g / (2 hh): cos = (1 - t^2) / (1 + t^2), sin = 2 t / (1 + t^2)
            q, r = 4.0 * hh * hh, 4.0 * g * hh
            inv = 1.0 / (q + g * g)
            cs, sn = (cs * (q - g * g) + sn * r) * inv, (sn * (q - g * g) - cs * r) * inv
            if abs(g) < 2.0 * _CC_HALF_TAN_DONE * hh:
                break
        else:
            t = -math.copysign(_CC_HALF_TAN_MAX, g)
            inv = 1.0 / (1.0 + t * t)
            cs, sn = (cs * (1.0 - t * t) - 2.0 * t * sn) * inv, \
                (sn * (1.0 - t * t) + 2.0 * t * cs) * inv
    return (cx + rho * (ux * cs + vx * sn), cy + rho * (uy * cs + vy * sn),
            cz + rho * (uz * cs + vz * sn))


@njit_inline
def _frame(side, r_ab, t_ab):
    """The centre c and axes u, v, k (twelve floats) of the cylinder on ``side`` in the
    other's frame: A's in B's (side 0) or B's in A's (side 1)."""
    if side == 0:
        return (-(r_ab[0, 0] * t_ab[0] + r_ab[1, 0] * t_ab[1] + r_ab[2, 0] * t_ab[2]),
                -(r_ab[0, 1] * t_ab[0] + r_ab[1, 1] * t_ab[1] + r_ab[2, 1] * t_ab[2]),
                -(r_ab[0, 2] * t_ab[0] + r_ab[1, 2] * t_ab[1] + r_ab[2, 2] * t_ab[2]),
                r_ab[0, 0], r_ab[0, 1], r_ab[0, 2], r_ab[1, 0], r_ab[1, 1], r_ab[1, 2],
                r_ab[2, 0], r_ab[2, 1], r_ab[2, 2])
    return (t_ab[0], t_ab[1], t_ab[2], r_ab[0, 0], r_ab[1, 0], r_ab[2, 0],
            r_ab[0, 1], r_ab[1, 1], r_ab[2, 1], r_ab[0, 2], r_ab[1, 2], r_ab[2, 2])


@njit_kernel
def cylinders_depth(sa, sb, verts, r_ab, t_ab, scale, res):
    """The core depth (> 0) of two cylinders, certified as in the module notes, with
    res (10,) = [depth, n (3), pa (3), pb (3)] on the cores in A's frame (n from A to
    B); 0 (res untouched) when no candidate is certified.  sa, sb: shape tuples of two
    cylinders.

    The caps' four candidates first (none needs a support of A - B, and a certified
    one ends the search: it is the depth within tol); then the rims, in the order of
    an upper bound on their balls (R - |q_xy| + rho and H - |q_z| + rho sin(angle of
    the axes), q the rim's centre), each solved only while its bound exceeds the
    deepest ball found: only the deepest rim point can be certified (every ball is at
    most the depth, and a certified one is within tol of it), and one support of A - B
    along its normal decides."""
    tol = EPA_REL_TOL * scale
    best_h = math.inf
    cap_side = -1
    cap_s = 0.0
    cpx = cpy = cpz = 0.0
    # the rims' upper bounds (index 2 side + (s + 1) / 2), -inf when out of reach
    ub0 = ub1 = ub2 = ub3 = -math.inf
    for side in range(2):
        own = sa[1] if side == 0 else sb[1]
        oth = sb[1] if side == 0 else sa[1]
        rho, eta, big_r, big_h = own[0], own[1], oth[0], oth[1]
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
                return 0.0      # the own core lies past the cap's plane: cores apart
            if h < best_h:
                ball = min(big_r - math.sqrt(px * px + py * py), big_h - abs(pz))
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
        if cap_side == 0:
            nx, ny, nz = -cap_s * r_ab[0, 2], -cap_s * r_ab[1, 2], -cap_s * r_ab[2, 2]
        else:
            nx, ny, nz = 0.0, 0.0, cap_s
        _certified_out(res, best_h, nx, ny, nz, cap_side, r_ab, t_ab, cpx, cpy, cpz)
        return best_h
    # the rims, deepest bound first, while a bound exceeds the deepest ball found
    rim_d = 0.0
    rim_side = -1
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
        own = sa[1] if side == 0 else sb[1]
        oth = sb[1] if side == 0 else sa[1]
        rho, eta, big_r, big_h = own[0], own[1], oth[0], oth[1]
        cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(side, r_ab, t_ab)
        px, py, pz = _rim_nearest_axis(cx + s * eta * kx, cy + s * eta * ky,
                                       cz + s * eta * kz, ux, uy, uz, vx, vy, vz, rho)
        q = math.sqrt(px * px + py * py)
        ball = min(big_r - q, big_h - abs(pz))
        if q > 0.0 and ball > rim_d:
            rim_d = ball
            rim_side = side
            rpx, rpy, rpz = px, py, pz
    if rim_side < 0:
        return 0.0
    # the deepest rim point: h along the other's side normal there (one support)
    q = math.sqrt(rpx * rpx + rpy * rpy)
    mx, my = rpx / q, rpy / q
    if rim_side == 0:
        # A's point inside B: B moves away from it, along -m in B's frame
        nx = -(r_ab[0, 0] * mx + r_ab[0, 1] * my)
        ny = -(r_ab[1, 0] * mx + r_ab[1, 1] * my)
        nz = -(r_ab[2, 0] * mx + r_ab[2, 1] * my)
    else:
        nx, ny, nz = mx, my, 0.0
    ax_, ay_, az_, bx_, by_, bz_ = minkowski_support_xyz(sa, sb, verts, r_ab, t_ab,
                                                         nx, ny, nz, True)
    h = nx * (ax_ - bx_) + ny * (ay_ - by_) + nz * (az_ - bz_)
    if not (h > 0.0 and rim_d >= h - tol):
        return 0.0
    _certified_out(res, h, nx, ny, nz, rim_side, r_ab, t_ab, rpx, rpy, rpz)
    return h


@njit_inline
def _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, px, py, pz):
    """res = [h, n, pa, pb] for a certified candidate: p (the other's frame) is A's
    witness when side is 0 (B's when 1), the other witness its translate by h along
    -n (+n)."""
    if side == 0:
        ax = r_ab[0, 0] * px + r_ab[0, 1] * py + r_ab[0, 2] * pz + t_ab[0]
        ay = r_ab[1, 0] * px + r_ab[1, 1] * py + r_ab[1, 2] * pz + t_ab[1]
        az = r_ab[2, 0] * px + r_ab[2, 1] * py + r_ab[2, 2] * pz + t_ab[2]
        bx, by, bz = ax - h * nx, ay - h * ny, az - h * nz
    else:
        bx, by, bz = px, py, pz
        ax, ay, az = bx + h * nx, by + h * ny, bz + h * nz
    res[0] = h
    res[1], res[2], res[3] = nx, ny, nz
    res[4], res[5], res[6] = ax, ay, az
    res[7], res[8], res[9] = bx, by, bz
