"""Penetration depth of an ellipsoid and a cylinder whose cores overlap, certified by
the ball of cylinder_common.py, before GJK and EPA (gjk_epa.gjk_epa_ws calls
``collide_ellipsoid_cylinder`` first for such a pair; where nothing is certified it
returns PRE_UNDECIDED and GJK and EPA run as for any pair).  The candidates and the
measurements: _ellipsoid_cylinder_bound's docstring.
"""
import math

from ..constants import CC_NEWTON_ITERS, CYLINDER, EPA_REL_TOL, P_ROLL
from ..geometry import borrow_pose, cylinder_inradius
from ..jit import borrow, njit_inline, njit_separate
from .cylinder_common import (_cap_test, _certified_out, _frame, _past_side, _side_normal,
                              gap_newton_step, pre_outcome)


@njit_inline
def _k_point(cx, cy, cz, s00, s01, s02, s11, s12, roll, cs, sn, rs):
    """The point of the ellipsoid's core K (centre c, shape matrix S, rolling radius
    r) that is its support point along -m, m = (cs, sn, 0), rs = sqrt(m^T S m):
    c - S m / rs + r m."""
    return (cx - (s00 * cs + s01 * sn) / rs + roll * cs,
            cy - (s01 * cs + s11 * sn) / rs + roll * sn,
            cz - (s02 * cs + s12 * sn) / rs)


@njit_separate
def _ellipsoid_cylinder_bound(sa, sb, r_ab, t_ab, scale, res):
    """The core depth (> 0) of an ellipsoid and a cylinder (either order), certified by
    the ball of cylinder_common.py, with res (10,) as _cylinder_cylinder_bound's, or minus
    the gap (< 0) when a
    plane proves the cores apart (as _cylinder_cylinder_bound); 0 (res untouched) when neither.
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
def collide_ellipsoid_cylinder(sa, sb, r_ab, t_ab, scale, stop, res):
    """What gjk_epa.gjk_epa_ws learns before GJK for an ellipsoid and a cylinder
    (constants.PRE_*): PRE_EXACT with res[:10] the cores' certified depth, normal and
    points (_ellipsoid_cylinder_bound), PRE_APART when a plane proves the cores farther
    apart than ``stop`` (m; res the bound), else PRE_UNDECIDED."""
    return pre_outcome(_ellipsoid_cylinder_bound(sa, sb, r_ab, t_ab, scale, res), stop)
