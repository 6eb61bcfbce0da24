"""Penetration depth of a cylinder and a cylinder, a capsule, an ellipsoid or a convex
hull whose cores overlap, from a point of one core deep inside the other cylinder,
certified by a ball and found without GJK or EPA (gjk_epa.gjk_epa_ws calls
cylinders_depth, segment_cylinder_depth, ellipsoid_cylinder_depth or
hull_cylinder_depth first for such a pair; where no candidate is certified they return
0 and GJK and EPA run as for any pair).  Where a plane on the way proves the cores
apart they return minus its gap instead (_apart_out), which gjk_epa_ws takes as GJK's
distance bound in contacts mode.  The notes below are cylinders_depth's; the others
have theirs in their docstrings.

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

Measured (pure-Python runs of cylinders_depth on bench/dev/deep_pairs.py's 2,000
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
cylinder's end that _crossing_global's bound misses (gjk_epa._cylinders_crossing
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

from .constants import CYLINDER, EPA_REL_TOL, P_ROLL
from .geometry import borrow_args, borrow_pose, cylinder_inradius, minkowski_core_xyz
from .jit import borrow, njit_inline, njit_kernel

CC_NEWTON_ITERS = 8     # Newton steps on a rim's angle (~4 taken on average)
_CC_HALF_TAN_MAX = 0.25  # longest step: tan of half its angle (~0.49 rad); far from the
                         # minimum F'' may mislead
_CC_HALF_TAN_DONE = 5e-5  # a step this short ends the search (1e-4 rad; the angle's
                          # error is then of its square, and the ball's of its square)
CC_RIMS = 2             # rims solved at most, deepest bound first (measured on the
                        # benchmark's cases: 1 certifies 7% fewer pairs, 3 or 4 no more)
CC_COVER_STEPS = 12     # greedy steps of _cover at most (each raises the level covered)
CC_CROSS_RINGS = 16      # rings of _crossing_global at most (measured: 8 certify 14
                         # fewer of 965 crossings, 30 two more)
HC_GJK_ITERS = 16       # steps of the 2-D GJK on a hull's shadow (~4 taken)


@njit_inline
def _newton_turn(cs, sn, g, hh):
    """One step of Newton's method towards a minimum of F(t), t an angle held as (cos t,
    sin t) = (cs, sn), with g = F'(t) / 2 and hh = F''(t) / 2: the turn whose half
    angle has the tangent -g / (2 hh) (Newton's step to third order), as a rotation in
    rational form (cos = (1 - x^2) / (1 + x^2), sin = 2 x / (1 + x^2): unit to
    round-off, one division).  Where F'' <= 0 or that step is longer than
    _CC_HALF_TAN_MAX, the longest step downhill instead.  Returns (cs, sn, done), done
    when the step was shorter than _CC_HALF_TAN_DONE (the search may end)."""
    if hh > 0.0 and abs(g) <= 2.0 * _CC_HALF_TAN_MAX * hh:
        q, r = 4.0 * hh * hh, 4.0 * g * hh
        inv = 1.0 / (q + g * g)
        return ((cs * (q - g * g) + sn * r) * inv, (sn * (q - g * g) - cs * r) * inv,
                abs(g) < 2.0 * _CC_HALF_TAN_DONE * hh)
    t = -math.copysign(_CC_HALF_TAN_MAX, g)
    inv = 1.0 / (1.0 + t * t)
    return ((cs * (1.0 - t * t) - 2.0 * t * sn) * inv,
            (sn * (1.0 - t * t) + 2.0 * t * cs) * inv, False)


@njit_inline
def gap_newton_step(al, be, ga, cx, cy, cs, sn):
    """One step of Newton's method towards the maximum over t of g(t) = cx cos t +
    cy sin t - sqrt(q(t)) (+ a constant), q(t) = m^T S m = al + be cos 2t + ga sin 2t
    for m = (cos t, sin t) in a plane (S's 2x2 block there): how far an ellipsoid's core
    lies beyond the line through the origin normal to m.  (cs, sn) = (cos t, sin t).
    Returns (sqrt(q(t)), the next (cos, sin), done as _newton_turn's)."""
    c2t, s2t = cs * cs - sn * sn, 2.0 * cs * sn
    sq = al + be * c2t + ga * s2t
    rs = math.sqrt(sq)
    d1 = 2.0 * (ga * c2t - be * s2t)            # q'
    d2 = -4.0 * (be * c2t + ga * s2t)           # q''
    # g' and g'' times 2 q^(3/2) > 0: their ratio, the Newton step, unchanged
    f = 2.0 * sq * rs
    g1 = f * (cy * cs - cx * sn) - sq * d1
    g2 = -f * (cx * cs + cy * sn) - sq * d2 + 0.5 * d1 * d1
    # a maximum of g: a minimum of -g
    ncs, nsn, done = _newton_turn(cs, sn, -g1, -g2)
    return rs, ncs, nsn, done


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
def _cover(radial, s, px, py, pz, big_r, big_h, d1x, d1y, d1z, d2x, d2y, d2z, d3x, d3y,
           d3z):
    """A lower bound on the core depth where a point p of one core (a cylinder's or a
    hull's; the other cylinder's frame: radius R, half-height H) lies deep under the
    other's side (``radial``) or under its cap s z = H (not ``radial``), but its ball
    is cut short by the other's cap or side: delta, p's gap to that side or cap (R -
    |p_xy|, or H - s p_z), or 0 when the cover below is not found (s: the cap's sign;
    under the side p's nearer cap is taken instead).  The segments p + l d (0 <= l <=
    1) for d = d1, d2 and d3 must lie in p's core (from a cylinder's rim point: its side line, the
    diameter of its cap and the diagonal, d3 = d1 + d2; from a hull's point: to
    vertices).

    Why: the depth is at least delta when every translate A + t with |t| < delta still
    meets B (the ball of radius delta about the origin then lies in B - A).  Under the
    side, say p's nearer cap is at s z = H, eta = H - s p_z < delta and 2 H >= eta +
    delta.  A t with s t_z < eta keeps p + t in B (|p_xy + t_xy| < |p_xy| + delta = R).
    A t with s t_z = u in [eta, delta) has |t_xy| < sqrt(delta^2 - u^2), so a point x of
    p's core with |x_xy| <= R - sqrt(delta^2 - u^2) and -H <= s x_z <= H - u has x
    + t in B: x covers the levels u from sqrt(delta^2 - (R - |x_xy|)^2) to H - s x_z.
    Under the cap, the roles of the axis and the radius swap: eta = R - |p_xy| < delta
    <= H; a t with |t_xy| < eta keeps p + t in B, and x covers the levels u = |t_xy|
    from sqrt(delta^2 - (H - s x_z)^2) to R - |x_xy| (s x_z >= H - delta, p being the
    lowest point along -s z, and H - delta >= delta - H).  Greedily, from the level cur
    = eta that p covers, each step takes on each segment the point that reaches the
    highest level among those that cover cur (under the side the farthest point whose
    |x_xy| is still R - sqrt(delta^2 - cur^2), a quadratic's larger root, the smaller
    being <= 0 as p lies inside that radius; under the cap the point nearest the axis
    whose s x_z is at most H - sqrt(delta^2 - cur^2)), and moves cur to the highest
    level one of them reaches; the levels are covered when cur reaches delta.
    Measured (bench/dev/deep_pairs.py's 2,000 cylinder-cylinder cases, pure Python): it
    certifies 57 of the 939 deep pairs that no ball does (49 under a side, 8 under a
    cap), 615 certified in all.
    With points sampled densely over the whole cylinder instead of the three segments,
    66 of the 91 deep rim-side minima with the ball cut short by a cap would be covered
    (the segments: 52).  Against a hull (hull_cylinder_depth): 240 of the 953 deep
    cylinder-convex pairs certified in all, 57 of them by _cover (each of the hull's
    vertices as a segment of its own would reach 260).  Left uncertified: 111 deep
    rim-side minima whose rim point lies past the other's axis (delta would be R +
    |p_xy|, beyond any point's R - |x_xy|; covering those needs the direction of t_xy,
    not only its length), 109 cap minima (80 of them deeper than H) and 42 rim-side
    ones, 32 crossings and 30 others."""
    q2 = px * px + py * py
    if radial:
        s = 1.0 if pz >= 0.0 else -1.0
        delta = big_r - math.sqrt(q2)
        eta = big_h - s * pz
        if not (0.0 < eta < delta and 2.0 * big_h >= eta + delta):
            return 0.0
    else:
        delta = big_h - s * pz
        eta = big_r - math.sqrt(q2)
        if not (0.0 < eta < delta <= big_h):
            return 0.0
    cur = eta
    for _ in range(CC_COVER_STEPS):
        room = delta * delta - cur * cur
        lim = (big_r if radial else big_h) - math.sqrt(max(0.0, room))
        top = cur
        for j in range(3):
            dx = d1x if j == 0 else (d2x if j == 1 else d3x)
            dy = d1y if j == 0 else (d2y if j == 1 else d3y)
            dz = d1z if j == 0 else (d2z if j == 1 else d3z)
            a = dx * dx + dy * dy
            b = px * dx + py * dy
            if radial:
                # |p_xy + l d_xy| <= lim up to the larger root (lim^2 >= q2)
                if not a > 0.0:
                    continue
                lam = min(1.0, (math.sqrt(max(0.0, b * b - a * (q2 - lim * lim))) - b) / a)
                z = s * (pz + lam * dz)
                if z >= -big_h:
                    top = max(top, big_h - z)
            else:
                # s x_z <= lim up to lam_max, then the point of [0, lam_max] nearest
                # the axis
                sdz = s * dz
                lam_max = 1.0
                if sdz > 0.0:
                    lam_max = min(1.0, (lim - s * pz) / sdz)
                lam = 0.0
                if a > 0.0:
                    lam = min(lam_max, max(0.0, -b / a))
                xx, yy = px + lam * dx, py + lam * dy
                top = max(top, big_r - math.sqrt(xx * xx + yy * yy))
        if top >= delta:
            return delta
        if not top > cur:
            return 0.0
        cur = top
    return 0.0


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
    if not sn > 1e-6:
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
        return _apart_out(res, -h, nx, ny, 0.0, 1, r_ab, t_ab, t_ab[0] - rb * nx + u * bx,
                          t_ab[1] - rb * ny + u * by, t_ab[2] + u * bz, ra * nx, ra * ny,
                          min(la, max(-la, s)))
    ball = -math.inf
    if abs(s) <= la:
        ball = min(rb - abs(rb - h), lb - abs(u))
    if abs(u) <= lb:
        ball = max(ball, min(ra - abs(ra - h), la - abs(s)))
    if not (ball >= h - tol
            or _crossing_global(ra, la, rb, lb, h, s, u, sn, r_ab[2, 2], tol)):
        return 0.0
    _certified_out(res, h, nx, ny, 0.0, 1, r_ab, t_ab, ra * nx - h * nx, ra * ny - h * ny, s)
    return h


@njit_inline
def _roles(sa, sb, side):
    """(rho, eta, R, H): the radius and half-height of the cylinder on ``side`` (A's
    when 0), then the other's."""
    own = sa[1] if side == 0 else sb[1]
    oth = sb[1] if side == 0 else sa[1]
    return own[0], own[1], oth[0], oth[1]


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


@njit_kernel
def cylinders_depth(sa, sb, verts, r_ab, t_ab, scale, res):
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
    cap_side = -1
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
                    ball = _cover(False, s, px, py, pz, big_r, big_h, fx, fy, fz, gx, gy,
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
    rim_side = -1
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
        if not _cover(True, 0.0, rpx, rpy, rpz, big_r, big_h, f * kx, f * ky, f * kz,
                      ex, ey, ez, f * kx + ex, f * ky + ey, f * kz + ez) >= h - tol:
            return 0.0
    _certified_out(res, h, nx, ny, nz, rim_side, r_ab, t_ab, rpx, rpy, rpz)
    return h


@njit_kernel
def segment_cylinder_depth(sa, sb, r_ab, t_ab, scale, res):
    """The core depth (> 0) of a capsule and a cylinder (either order), certified by the
    module's ball, with res (10,) as cylinders_depth's, or minus the gap (< 0) when a
    plane proves the cores apart (as cylinders_depth); 0 (res untouched) when neither.
    A capsule's core is the segment c +- eta k
    (its axis); the depth of the capsules is the core depth grown by the radii.

    The candidates are points of the segment, in the cylinder's frame:
      - p, the segment's point nearest the cylinder's axis (a line's closest approach,
        clipped to the segment; closed form), against the side: n the side normal at p,
        pushing the cylinder away from p.  Along n every point of the segment lies at
        least as far in as p (p is the nearest to the axis, and the segment's points
        beside it run square to n or away), so h(n) is p's gap to the side, R - |p_xy|,
        and p's ball certifies it where the caps leave that ball whole;
      - for each cap, the segment's end lowest under the cap's plane, its support point
        along minus the cap's normal: h along the cap's normal is its gap to the plane;
        where that end's ball falls short (it lies near the rim), p stands in for it
        when the segment runs level with the cap (a capsule lying across a cylinder's
        top), its gap to the plane then the depth.
    p beyond the side's radius proves the cores apart (the segment misses even the
    unbounded cylinder), as an end past a cap's plane does.  No support of A - B, no
    Newton steps: ~20 ns.  Measured on bench/dev/deep_pairs.py's 2,000 capsule-cylinder
    cases (a numpy model of it, GJK + EPA the reference): 314 of the 512 pairs whose
    cores overlap by more than 1e-3 * scale certified (275 by the side, 39 by a cap),
    depths within 4.4e-9 * scale of EPA's, normals within 8.0e-5 rad; the others are
    pushed out over a rim (no ball as deep as the depth fits in the cylinder there)."""
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, r_ab, t_ab = borrow_pose(sa, sb, r_ab, t_ab)
    res = borrow(res)
    side = 0 if sa[0] != CYLINDER else 1
    seg = sa[1] if side == 0 else sb[1]
    cyl = sb[1] if side == 0 else sa[1]
    eta, big_r, big_h = seg[1], cyl[0], cyl[1]
    cx, cy, cz, _, _, _, _, _, _, kx, ky, kz = _frame(side, r_ab, t_ab)
    tol = EPA_REL_TOL * scale
    kk = kx * kx + ky * ky
    t = 0.0
    if kk > 0.0:
        t = min(eta, max(-eta, -(cx * kx + cy * ky) / kk))
    px, py, pz = cx + t * kx, cy + t * ky, cz + t * kz
    qq = px * px + py * py
    if not qq < big_r * big_r:
        # the segment misses even the unbounded cylinder: apart across the side's
        # tangent plane at p's direction
        q = math.sqrt(qq)
        if not q > 0.0:
            return 0.0
        return _past_side(res, q, side, r_ab, t_ab, px / q, py / q, big_r, big_h, px, py,
                          pz)
    ball_p = cylinder_inradius(big_r, big_h, px, py, pz)
    lz = eta * abs(kz)      # the ends' heights are cz -+ lz
    for si in range(2):
        s = 2.0 * si - 1.0
        h = big_h - s * cz + lz
        f = -eta if s * kz >= 0.0 else eta
        ex, ey, ez = cx + f * kx, cy + f * ky, cz + f * kz
        if not h > 0.0:
            # the whole segment lies past the cap's plane
            return _past_cap(res, h, side, r_ab, t_ab, s, big_r, big_h, ex, ey, ez)
        if cylinder_inradius(big_r, big_h, ex, ey, ez) >= h - tol:
            d = h
        elif ball_p >= h - tol:
            ex, ey, ez = px, py, pz
            d = big_h - s * pz
        else:
            continue
        if not d > 0.0:
            continue
        nx, ny, nz = _cap_normal(side, r_ab, s)
        _certified_out(res, d, nx, ny, nz, side, r_ab, t_ab, ex, ey, ez)
        return d
    if not qq > 0.0:
        return 0.0
    q = math.sqrt(qq)
    # h along the side normal at p: R less the least of the ends' radial offsets
    h = big_r - ((px * cx + py * cy) - eta * abs(px * kx + py * ky)) / q
    if not (ball_p > 0.0 and ball_p >= h - tol):
        return 0.0
    nx, ny, nz = _side_normal(side, r_ab, px / q, py / q)
    d = big_r - q
    _certified_out(res, d, nx, ny, nz, side, r_ab, t_ab, px, py, pz)
    return d


@njit_inline
def _k_point(cx, cy, cz, s00, s01, s02, s11, s12, roll, cs, sn, rs):
    """The point of the ellipsoid's core K (centre c, shape matrix S, rolling radius
    r) that is its support point along -m, m = (cs, sn, 0), rs = sqrt(m^T S m):
    c - S m / rs + r m."""
    return (cx - (s00 * cs + s01 * sn) / rs + roll * cs,
            cy - (s01 * cs + s11 * sn) / rs + roll * sn,
            cz - (s02 * cs + s12 * sn) / rs)


@njit_kernel
def ellipsoid_cylinder_depth(sa, sb, r_ab, t_ab, scale, res):
    """The core depth (> 0) of an ellipsoid and a cylinder (either order), certified by
    the module's ball, with res (10,) as cylinders_depth's, or minus the gap (< 0) when a
    plane proves the cores apart (as cylinders_depth); 0 (res untouched) when neither.
    The ellipsoid's core K is the
    ellipsoid E shrunk by its rolling radius r (geometry: h_K(u) = h_E(u) - r |u|); in
    the cylinder's frame E's shape matrix is S = Q diag(a^2, b^2, c^2) Q^T (Q its axes),
    h_E(u) = u . c + sqrt(u^T S u) and E's support point c + S u / sqrt(u^T S u).

    The candidates, points of K:
      - for each cap, K's support point along minus the cap's normal (its lowest point
        under the cap's plane): h along the cap's normal is its gap to the plane,
        exactly; a gap <= 0 proves the cores apart;
      - against the side, p = K's point nearest the cylinder's axis: with m = (cos t,
        sin t, 0), g(t) = min over K of m . x = m . c - sqrt(m^T S m) + r is how far K
        lies beyond the plane through the axis square to m, and its maximum over t is
        K's distance from the axis, reached at p = K's support point along -m, whose
        distance from the axis is then g.  Newton's method on t (from m along c's
        offset from the axis; ~3.3 steps on the benchmark's cases, the rotation in
        rational form, _newton_turn).  h along the side normal there is
        R - g, one closed form, and p's ball certifies it where the caps leave that
        ball whole; g >= R proves the cores apart.
    Nothing depends on Newton's converging: any t gives a lower bound (p's ball) and an
    upper one (R - g), and only their meeting within EPA_REL_TOL * scale certifies.
    Before Newton, bounds on g and on p_z skip the pairs no side ball can certify, and
    each step's g at or past R proves the cores apart: on the cases below, 469 of the
    1,442 pairs the caps leave get past the bounds and Newton's first step (all 160
    side certificates among them).
    Measured on bench/dev/deep_pairs.py's 2,000 ellipsoid-cylinder cases (this function run
    with NUMBA_DISABLE_JIT, GJK + EPA the reference): 190 of the 601 pairs whose
    cores overlap by more than 1e-3 * scale certified (159 by the side, 31 by a cap; and
    one pair that overlaps less), depths within 2.5e-13 *
    scale of EPA's, normals within 1e-6 rad, and 527 of the 2,000 proved apart by a
    cap; every pair the reference has penetrating less deeply, or apart, is left to
    GJK."""
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, r_ab, t_ab = borrow_pose(sa, sb, r_ab, t_ab)
    res = borrow(res)
    side = 0 if sa[0] != CYLINDER else 1
    ell = sa[1] if side == 0 else sb[1]
    cyl = sb[1] if side == 0 else sa[1]
    big_r, big_h, roll = cyl[0], cyl[1], ell[P_ROLL]
    cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(side, r_ab, t_ab)
    a2, b2, c2 = ell[0] * ell[0], ell[1] * ell[1], ell[2] * ell[2]
    s00 = a2 * ux * ux + b2 * vx * vx + c2 * kx * kx
    s01 = a2 * ux * uy + b2 * vx * vy + c2 * kx * ky
    s02 = a2 * ux * uz + b2 * vx * vz + c2 * kx * kz
    s11 = a2 * uy * uy + b2 * vy * vy + c2 * ky * ky
    s12 = a2 * uy * uz + b2 * vy * vz + c2 * ky * kz
    s22 = a2 * uz * uz + b2 * vz * vz + c2 * kz * kz
    tol = EPA_REL_TOL * scale
    w = math.sqrt(s22)
    for si in range(2):
        s = 2.0 * si - 1.0
        # K's support point along -s z: c - s S z / w + s r z
        px, py, pz = cx - s * s02 / w, cy - s * s12 / w, cz - s * (w - roll)
        d = _cap_test(res, side, r_ab, t_ab, s, big_r, big_h, tol, px, py, pz)
        if d != 0.0:
            return d
    # the side.  First a bound: K holds the ball of radius c_min - r about c, so
    # g <= |c_xy| - c_min + r; and |p_z| is at least |c_z| less K's half-extent in z,
    # w - r.  A certificate needs g > 0 (else h = R - g exceeds every ball) and p's
    # ball to reach R - g past the caps: where the bounds rule either out, GJK.
    cn = math.sqrt(cx * cx + cy * cy)
    g_hi = cn - min(ell[0], min(ell[1], ell[2])) + roll
    if not (g_hi > 0.0 and big_h - max(0.0, abs(cz) - (w - roll)) >= big_r - g_hi - tol):
        return 0.0
    # maximise g(t); m^T S m = al + be cos 2t + ga sin 2t.  Every t's g is a lower
    # bound on the maximum: one at or past R proves the cores apart
    al, be, ga = 0.5 * (s00 + s11), 0.5 * (s00 - s11), s01
    cs, sn = 1.0, 0.0
    if cn > 0.0:
        cs, sn = cx / cn, cy / cn
    for _ in range(CC_NEWTON_ITERS):
        rs, ncs, nsn, done = gap_newton_step(al, be, ga, cx, cy, cs, sn)
        g = cx * cs + cy * sn - rs + roll
        if g >= big_r:
            # K lies beyond the side's tangent plane along m: cores apart
            px, py, pz = _k_point(cx, cy, cz, s00, s01, s02, s11, s12, roll, cs, sn, rs)
            return _past_side(res, g, side, r_ab, t_ab, cs, sn, big_r, big_h, px, py, pz)
        cs, sn = ncs, nsn
        if done:
            break
    sq = s00 * cs * cs + 2.0 * s01 * cs * sn + s11 * sn * sn
    rs = math.sqrt(sq)
    g = cx * cs + cy * sn - rs + roll
    px, py, pz = _k_point(cx, cy, cz, s00, s01, s02, s11, s12, roll, cs, sn, rs)
    if not g < big_r:
        # K lies beyond the side's tangent plane: cores apart
        return _past_side(res, g, side, r_ab, t_ab, cs, sn, big_r, big_h, px, py, pz)
    h = big_r - g
    ball = cylinder_inradius(big_r, big_h, px, py, pz)
    if not (ball > 0.0 and ball >= h - tol):
        return 0.0
    nx, ny, nz = _side_normal(side, r_ab, cs, sn)
    _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, px, py, pz)
    return h


@njit_inline
def _side_normal(side, r_ab, mx, my):
    """The normal from A to B (A's frame) that pushes the other core out of the
    cylinder through its side, m = (mx, my, 0) the unit radial direction at the other
    core's point in the cylinder's frame: the cylinder moves along -m when it is B
    (side 0: the point is A's), the point's shape along m when the cylinder is A."""
    if side == 0:
        return (-(r_ab[0, 0] * mx + r_ab[0, 1] * my), -(r_ab[1, 0] * mx + r_ab[1, 1] * my),
                -(r_ab[2, 0] * mx + r_ab[2, 1] * my))
    return mx, my, 0.0


@njit_inline
def _cap_normal(side, r_ab, s):
    """As _side_normal, out through the cylinder's cap at s z (s = +-1)."""
    if side == 0:
        return -s * r_ab[0, 2], -s * r_ab[1, 2], -s * r_ab[2, 2]
    return 0.0, 0.0, s


@njit_inline
def _b_to_a_point(r_ab, t_ab, x, y, z):
    """A point of B's frame in A's frame: r_ab p + t_ab."""
    return (r_ab[0, 0] * x + r_ab[0, 1] * y + r_ab[0, 2] * z + t_ab[0],
            r_ab[1, 0] * x + r_ab[1, 1] * y + r_ab[1, 2] * z + t_ab[1],
            r_ab[2, 0] * x + r_ab[2, 1] * y + r_ab[2, 2] * z + t_ab[2])


@njit_inline
def _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, px, py, pz):
    """res = [h, n, pa, pb] for a certified candidate: p (the other's frame) is A's
    witness when side is 0 (B's when 1), the other witness its translate by h along
    -n (+n)."""
    if side == 0:
        ax, ay, az = _b_to_a_point(r_ab, t_ab, px, py, pz)
        bx, by, bz = ax - h * nx, ay - h * ny, az - h * nz
    else:
        bx, by, bz = px, py, pz
        ax, ay, az = bx + h * nx, by + h * ny, bz + h * nz
    res[0] = h
    res[1], res[2], res[3] = nx, ny, nz
    res[4], res[5], res[6] = ax, ay, az
    res[7], res[8], res[9] = bx, by, bz


@njit_inline
def _apart_out(res, gap, nx, ny, nz, side, r_ab, t_ab, px, py, pz, qx, qy, qz):
    """Cores proved apart by a plane: res = [-gap, n, pa, pb] (gap > 0 along n, from A
    to B) and returns -gap, or 0 (res untouched) when gap is not > 0 (touching: GJK
    decides).  p is the own core's point beyond the plane and q the cylinder's point on
    it, both in the cylinder's frame, p A's when side is 0 (B's when 1); pa and pb are
    then points of the two cores, not the closest ones (as GJK's bound, see
    gjk_epa.gjk_epa_ws)."""
    if not gap > 0.0:
        return 0.0
    if side == 0:
        ax, ay, az = _b_to_a_point(r_ab, t_ab, px, py, pz)
        bx, by, bz = _b_to_a_point(r_ab, t_ab, qx, qy, qz)
    else:
        ax, ay, az, bx, by, bz = qx, qy, qz, px, py, pz
    res[0] = -gap
    res[1], res[2], res[3] = nx, ny, nz
    res[4], res[5], res[6] = ax, ay, az
    res[7], res[8], res[9] = bx, by, bz
    return -gap


@njit_inline
def _past_cap(res, h, side, r_ab, t_ab, s, big_r, big_h, px, py, pz):
    """A core wholly past the cylinder's cap plane z = s H (the cylinder's frame), p its
    point nearest that plane, h = H - s p_z <= 0: _apart_out with the gap -h along the
    cap's normal, q the cap's point nearest p."""
    f = 1.0
    rr = px * px + py * py
    if rr > big_r * big_r:
        f = big_r / math.sqrt(rr)
    nx, ny, nz = _cap_normal(side, r_ab, s)
    return _apart_out(res, -h, nx, ny, nz, side, r_ab, t_ab, px, py, pz, f * px, f * py,
                      s * big_h)


@njit_inline
def _cap_test(res, side, r_ab, t_ab, s, big_r, big_h, tol, px, py, pz):
    """A core's lowest point p under the cylinder's cap plane z = s H (the cylinder's
    frame) against that cap, where h along the cap's normal is H - s p_z exactly: h <= 0
    proves the cores apart (_past_cap, minus the gap returned), p's ball >= h - tol
    certifies h (res written, h returned); else 0."""
    h = big_h - s * pz
    if not h > 0.0:
        return _past_cap(res, h, side, r_ab, t_ab, s, big_r, big_h, px, py, pz)
    if cylinder_inradius(big_r, big_h, px, py, pz) >= h - tol:
        nx, ny, nz = _cap_normal(side, r_ab, s)
        _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, px, py, pz)
        return h
    return 0.0


@njit_inline
def _past_side(res, g, side, r_ab, t_ab, mx, my, big_r, big_h, px, py, pz):
    """A core beyond the plane m . x = g >= R (m = (mx, my, 0) unit, the cylinder's
    frame), p its point on that plane: _apart_out with gap g - R along the side normal
    at m, q the side's point on the line along m at p's height (clamped to the caps)."""
    nx, ny, nz = _side_normal(side, r_ab, mx, my)
    return _apart_out(res, g - big_r, nx, ny, nz, side, r_ab, t_ab, px, py, pz,
                      big_r * mx, big_r * my, min(big_h, max(-big_h, pz)))


@njit_inline
def _shadow_closest(ax, ay, bx, by):
    """The point of the segment [a, b] (2-D) nearest the origin, as (t, x, y) with
    t in [0, 1] its parameter from a."""
    ex, ey = bx - ax, by - ay
    ee = ex * ex + ey * ey
    t = 0.0
    if ee > 0.0:
        t = min(1.0, max(0.0, -(ax * ex + ay * ey) / ee))
    return t, ax + t * ex, ay + t * ey


@njit_kernel
def hull_cylinder_depth(sa, sb, verts, r_ab, t_ab, scale, res):
    """The core depth (> 0) of a convex hull and a cylinder (either order), certified by
    the module's ball, with res (10,) as cylinders_depth's, or minus the gap (< 0) when
    a plane proves the cores apart (as cylinders_depth); 0 (res untouched) when
    neither.  The hull's points are its vertices (verts, body frame) and their convex
    combinations; the candidates are hull points in the cylinder's frame:
      - for each cap, the hull's lowest vertex p under the cap's plane: h along the
        cap's normal is its gap to the plane, exactly, and a gap <= 0 proves the cores
        apart; p's ball certifies h, or where the side cuts it short, _cover's bound
        from the segments p to the vertex nearest the axis, to the highest vertex and
        to their midpoint;
      - against the side, q = the hull's point nearest the cylinder's axis, i.e. the
        point of the hull's shadow on the plane square to the axis nearest the axis's
        foot: GJK in two dimensions over the shadow (its support is the hull's along a
        horizontal direction, one pass over the vertices; the simplex at most a
        segment, whose two vertices are hull points, so q lifts to a hull point).  At
        its end, the support pass along -m (m = q_xy / |q_xy|) gives h along the side
        normal at q, R - min over the hull of m . x, and q's ball certifies it where the
        caps leave the ball whole, else _cover's bound from the segments q to the
        hull's lowest and highest vertices and to the last support point; a pass whose
        minimum lies beyond R proves the cores apart.  The shadow holding the axis's
        foot (a triangle of the simplex around it) leaves no side candidate.
    Nothing depends on the 2-D GJK's converging: any hull point's ball is a lower bound
    and any support pass an upper one; only their meeting within EPA_REL_TOL * scale
    certifies.  The side is what a hull's corner or edge pressed into a cylinder takes;
    a cylinder's rim pressed into a hull's face (its normal the face's) is left to GJK
    and EPA, as no hull faces are kept.
    Measured on bench/dev/deep_pairs.py's 2,000 cylinder-convex cases (this function run
    with NUMBA_DISABLE_JIT, GJK + EPA the reference): 240 of the 953 pairs whose
    cores overlap by more than 1e-3 * scale certified (183 by a ball, 170 of them by the
    side and 13 by a cap, the rest by _cover; and 17 pairs overlapping less), depths
    within 9.3e-9 * scale of EPA's (its nearest face), normals within 2.2e-4 rad; 856
    of the 2,000 proved apart, 457 of them pairs whose bounding spheres overlap (those
    the batch kernel hands to GJK)."""
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    res = borrow(res)
    side = 0 if sa[0] != CYLINDER else 1
    hull = sa if side == 0 else sb
    cyl = sb[1] if side == 0 else sa[1]
    big_r, big_h = cyl[0], cyl[1]
    cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(side, r_ab, t_ab)
    pts = verts[hull[2]:hull[2] + hull[3]]
    nv = pts.shape[0]
    if nv == 0:
        return 0.0
    tol = EPA_REL_TOL * scale
    # one pass: the lowest and highest vertices and the one nearest the axis
    zlo, zhi, rmin = math.inf, -math.inf, math.inf
    ilo = ihi = inear = 0
    for i in range(nv):
        x, y, z = _hull_point(pts, i, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
        if z < zlo:
            zlo, ilo = z, i
        if z > zhi:
            zhi, ihi = z, i
        rr = x * x + y * y
        if rr < rmin:
            rmin, inear = rr, i
    for si in range(2):
        s = 2.0 * si - 1.0
        i = ilo if s > 0.0 else ihi
        px, py, pz = _hull_point(pts, i, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
        d = _cap_test(res, side, r_ab, t_ab, s, big_r, big_h, tol, px, py, pz)
        if d != 0.0:
            return d
        # its ball cut short by the side: the cover (_cover) from p to the vertex
        # nearest the axis, to the highest (along -s z) and to their midpoint
        ax, ay, az = _hull_point(pts, inear, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
        tx, ty, tz = _hull_point(pts, ihi if s > 0.0 else ilo, cx, cy, cz, ux, uy, uz, vx,
                                 vy, vz, kx, ky, kz)
        h = big_h - s * pz
        if _cover(False, s, px, py, pz, big_r, big_h, ax - px, ay - py, az - pz, tx - px,
                  ty - py, tz - pz, 0.5 * (ax + tx) - px, 0.5 * (ay + ty) - py,
                  0.5 * (az + tz) - pz) >= h - tol:
            nx, ny, nz = _cap_normal(side, r_ab, s)
            _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, px, py, pz)
            return h
    # the side: GJK on the shadow, the simplex [a, b] (b used when two), q on it
    ax, ay, az = _hull_point(pts, inear, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
    bx = by = bz = 0.0
    two = False
    qx, qy, qz = ax, ay, az
    for _ in range(HC_GJK_ITERS):
        qq = qx * qx + qy * qy
        if not qq > 0.0:
            return 0.0
        # the hull's support along -q_xy (min over the vertices of q_xy . x)
        dx = qx * ux + qy * uy
        dy = qx * vx + qy * vy
        dz = qx * kx + qy * ky
        low = math.inf
        j = 0
        for i in range(nv):
            val = pts[i, 0] * dx + pts[i, 1] * dy + pts[i, 2] * dz
            if val < low:
                low, j = val, i
        q = math.sqrt(qq)
        g = (qx * cx + qy * cy + low) / q       # min over the hull of m . x
        wx, wy, wz = _hull_point(pts, j, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
        if g > big_r:
            # the hull lies beyond the side's tangent plane along m: cores apart
            return _past_side(res, g, side, r_ab, t_ab, qx / q, qy / q, big_r, big_h,
                              wx, wy, wz)
        if q - g <= tol:
            # q's support plane: q is the shadow's nearest point; h = R - g along m
            h = big_r - g
            ball = cylinder_inradius(big_r, big_h, qx, qy, qz)
            if not (ball > 0.0 and ball >= h - tol):
                # cut short by a cap: the cover (_cover) from q to the hull's lowest
                # and highest vertices and to w
                lx, ly, lz = _hull_point(pts, ilo, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx,
                                         ky, kz)
                tx, ty, tz = _hull_point(pts, ihi, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx,
                                         ky, kz)
                ball = _cover(True, 0.0, qx, qy, qz, big_r, big_h, lx - qx, ly - qy,
                              lz - qz, tx - qx, ty - qy, tz - qz, wx - qx, wy - qy, wz - qz)
            if not (ball > 0.0 and ball >= h - tol):
                return 0.0
            nx, ny, nz = _side_normal(side, r_ab, qx / q, qy / q)
            _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, qx, qy, qz)
            return h
        if not two:
            t, sx, sy = _shadow_closest(ax, ay, wx, wy)
            if t >= 1.0:
                ax, ay, az = wx, wy, wz
            elif t > 0.0:
                bx, by, bz = wx, wy, wz
                two = True
        else:
            # the origin inside the triangle a, b, w: the shadow holds the axis's foot
            c1 = (bx - ax) * (-ay) - (by - ay) * (-ax)
            c2 = (wx - bx) * (-by) - (wy - by) * (-bx)
            c3 = (ax - wx) * (-wy) - (ay - wy) * (-wx)
            if (c1 >= 0.0 and c2 >= 0.0 and c3 >= 0.0) or (c1 <= 0.0 and c2 <= 0.0
                                                            and c3 <= 0.0):
                return 0.0
            t, sx, sy = _shadow_closest(ax, ay, wx, wy)
            t2, sx2, sy2 = _shadow_closest(bx, by, wx, wy)
            if sx2 * sx2 + sy2 * sy2 < sx * sx + sy * sy:
                # the edge b w: a <- b
                t, sx, sy = t2, sx2, sy2
                ax, ay, az = bx, by, bz
            if t >= 1.0:
                ax, ay, az = wx, wy, wz
                two = False
            elif t > 0.0:
                bx, by, bz = wx, wy, wz
            else:
                two = False
        if not sx * sx + sy * sy < qq:
            return 0.0              # no progress (round-off): no side candidate
        if two:
            ex, ey, ez = bx - ax, by - ay, bz - az
            qx, qy, qz = ax + t * ex, ay + t * ey, az + t * ez
        else:
            qx, qy, qz = ax, ay, az
    return 0.0


@njit_inline
def _hull_point(pts, i, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz):
    """Vertex i of pts (the hull's frame) in the cylinder's frame (c, u, v, k: the
    hull's centre and axes there, as _frame gives them)."""
    p0, p1, p2 = pts[i, 0], pts[i, 1], pts[i, 2]
    return (cx + p0 * ux + p1 * vx + p2 * kx, cy + p0 * uy + p1 * vy + p2 * ky,
            cz + p0 * uz + p1 * vz + p2 * kz)
