"""What the certified pair kernels before GJK share (cylinder_cylinder.py,
capsule_cylinder.py, ellipsoid_cylinder.py, cylinder_convex.py, ellipsoid_box.py): the
ball certificate below, the answers they write (``_certified_out``: a certified core
depth; ``_apart_out``: a plane proving the cores apart, whose gap gjk_epa.gjk_epa_ws
takes as GJK's distance bound in contacts mode), a cylinder's frame and its side and
cap normals (``_frame``, ``_side_normal``, ``_cap_normal``), the tests against a cap
and past a side (``_cap_test``, ``_past_cap``, ``_past_side``), the cover bound
(``_cover``), Newton's step on an angle (``_newton_turn``, ``gap_newton_step``) and the
outcome code of a bound (``pre_outcome``).

Each pair's bound kernel (``_<a>_<b>_bound``) returns the core depth (> 0) with res (10,)
= [depth, n (3), pa (3), pb (3)] on the cores in A's frame (n from A to B), minus the gap
(< 0) with res = [-gap, n, pa, pb] when a plane proves the cores apart, or 0 (res
untouched) when neither; its entry point ``collide_<a>_<b>`` turns that into the outcome
code of every pair kernel run before GJK (constants.PRE_*, ``pre_outcome``), and on
PRE_UNDECIDED GJK and EPA run as for any pair.

The certificate (as certificates._ball_certified).  If a point p of A's core has the ball
of radius delta about it inside B's core, the core difference A - B holds the ball of
radius delta about the origin (that ball minus p's partner), so h(u) >= delta along
every unit u and the core depth, min_u h(u), is at least delta.  It is at most h(n)
for any unit n.  So where h(n) <= delta + EPA_REL_TOL * scale, h(n) is the depth within
EPA's own tolerance and n a normal: no test that n is a local minimum and no polytope
are needed, whatever creases the two support functions have.  The same holds with A
and B swapped.  Inside a cylinder (axis z, radius R, half-height H) the largest such
ball about p has the radius min(R - |p_xy|, H - |p_z|).
"""
import math

from ..constants import (CC_COVER_STEPS, CC_HALF_TAN_DONE, CC_HALF_TAN_MAX, PRE_APART, PRE_EXACT,
                         PRE_UNDECIDED)
from ..geometry import cylinder_inradius
from ..jit import njit_inline


@njit_inline
def pre_outcome(d, stop):
    """The outcome code (constants.PRE_*) of a cylinder pair's bound d (its res[0]): a
    certified core depth d > 0 is PRE_EXACT, a proved gap -d beyond ``stop`` (m)
    PRE_APART, anything else (0: nothing proved; a gap within ``stop``, which GJK
    refines) PRE_UNDECIDED."""
    if d > 0.0:
        return PRE_EXACT
    if d < 0.0 and -d > stop:
        return PRE_APART
    return PRE_UNDECIDED


@njit_inline
def _newton_turn(cs, sn, g, hh):
    """One step of Newton's method towards a minimum of F(t), t an angle held as (cos t,
    sin t) = (cs, sn), with g = F'(t) / 2 and hh = F''(t) / 2: the turn whose half
    angle has the tangent -g / (2 hh) (Newton's step to third order), as a rotation in
    rational form (cos = (1 - x^2) / (1 + x^2), sin = 2 x / (1 + x^2): unit to
    round-off, one division).  Where F'' <= 0 or that step is longer than
    CC_HALF_TAN_MAX, the longest step downhill instead.  Returns (cs, sn, done), done
    when the step was shorter than CC_HALF_TAN_DONE (the search may end)."""
    if hh > 0.0 and abs(g) <= 2.0 * CC_HALF_TAN_MAX * hh:
        q, r = 4.0 * hh * hh, 4.0 * g * hh
        inv = 1.0 / (q + g * g)
        return ((cs * (q - g * g) + sn * r) * inv, (sn * (q - g * g) - cs * r) * inv,
                abs(g) < 2.0 * CC_HALF_TAN_DONE * hh)
    t = -math.copysign(CC_HALF_TAN_MAX, g)
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
    (the segments: 52).  Against a hull (collide_cylinder_convex_ball): 240 of the 953 deep
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
