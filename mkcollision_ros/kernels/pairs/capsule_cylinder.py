"""Penetration depth of a capsule and a cylinder whose cores overlap, certified by the
ball of cylinder_common.py, before GJK and EPA (gjk_epa.gjk_epa_ws calls
``collide_capsule_cylinder`` first for such a pair; where nothing is certified it
returns PRE_UNDECIDED and GJK and EPA run as for any pair).  The candidates and the
measurements: _capsule_cylinder_bound's docstring.
"""
import math

from ..constants import CYLINDER, EPA_REL_TOL
from ..geometry import borrow_pose, cylinder_inradius
from ..jit import borrow, njit_inline, njit_separate
from .cylinder_common import (_cap_normal, _certified_out, _frame, _past_cap, _past_side,
                              _side_normal, pre_outcome)


@njit_separate
def _capsule_cylinder_bound(sa, sb, r_ab, t_ab, scale, res):
    """The core depth (> 0) of a capsule and a cylinder (either order), certified by the
    ball of cylinder_common.py, with res (10,) as _cylinder_cylinder_bound's, or minus the
    gap (< 0) when a
    plane proves the cores apart (as _cylinder_cylinder_bound); 0 (res untouched) when neither.
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
def collide_capsule_cylinder(sa, sb, r_ab, t_ab, scale, stop, res):
    """What gjk_epa.gjk_epa_ws learns before GJK for a capsule and a cylinder
    (constants.PRE_*): PRE_EXACT with res[:10] the cores' certified depth, normal and
    points (_capsule_cylinder_bound), PRE_APART when a plane proves the cores farther apart
    than ``stop`` (m; res the bound), else PRE_UNDECIDED."""
    return pre_outcome(_capsule_cylinder_bound(sa, sb, r_ab, t_ab, scale, res), stop)
