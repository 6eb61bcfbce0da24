"""The crease search: the minimum of h = h_{A-B} along a crease of h, the great circle
of directions normal to a cylinder's axis (its side), a capsule's core or a box's axis
(its edges), where Newton's method gives up (``_kink_polish``, by secant steps on h's
derivative along the circle, ``_crease_min``), with the checks across the crease, the
other crease nearby (two cylinders) and the point kinks (``_kink_points``,
``_box_faces_deeper``).  GJK on cores apart and EPA both try it near a crease
(polish_pairs._kink_side); EPA keeps its minimum under certificates._polish_is_global
or certificates._ball_certified.  The why and the measurements: _kink_polish's
docstring.  ``_support_called`` is the one support of A - B the polish steps call
rather than inline.
"""
import math

import numpy as np

from .certificates import _ball_certified
from .constants import (BOX, CREASE_SLOPE_TOL, CYLINDER, EPA_KINK_ITERS, EPA_KINK_STEP,
                        EPA_POLISH_CAP, EPA_REL_TOL, NO_DIRECTION, POLISH_STEP_DONE, SUPPORT_TIE)
from .geometry import borrow_args, minkowski_core_xyz
from .gjk_epa_workspace import _T_D, _store_min, borrow_gjk_workspace
from .jit import njit_inline, njit_kernel
from .polish_pairs import _axis_of


@njit_kernel
def _support_called(sa, sb, verts, r_ab, t_ab, dx, dy, dz):
    """minkowski_core_xyz called, not inlined: for the crease search, which runs on
    few pairs and evaluates few supports, where every inlined copy of all the shapes'
    support mappings lengthened the first compile."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    return minkowski_core_xyz(sa, sb, verts, r_ab, t_ab, dx, dy, dz)


@njit_kernel
def _crease_min(sa, sb, verts, r_ab, t_ab, scale, kx, ky, kz, dx, dy, dz):
    """Secant search for the minimum of h = h_{A-B} along the great circle of
    directions normal to the unit axis k (a crease of a cylinder's or a capsule core's
    support function), from the direction d projected onto it.

    Along the circle, u(t) = cos t n + sin t e (e = k x n), h is smooth between the
    other shape's creases and its derivative is g(t) = w(u(t)) . u'(t), w a support
    point of A - B (any point of the support segment gives the same g, as u' is
    normal to k).  Converged when the next step is below POLISH_STEP_DONE (rad) with
    |g| <= 1e-6 * scale (a crease of the other shape shows as a jump in g: the secant
    closes in on the jump with g still large) and a positive secant slope.  Returns
    (ok, supports evaluated, lowest h evaluated, then at the last point: h, u (3), the
    support points of A and of B (3 each)); ok is False when it gave up."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    c = dx * kx + dy * ky + dz * kz
    nx, ny, nz = dx - c * kx, dy - c * ky, dz - c * kz
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    ok = False
    hlow = np.inf
    hu = ux = uy = uz = pax = pay = paz = pbx = pby = pbz = 0.0
    if not nn > 0.5:
        return (ok, 0, hlow, hu, ux, uy, uz, pax, pay, paz, pbx, pby, pbz)
    nx, ny, nz = nx / nn, ny / nn, nz / nn
    ex, ey, ez = ky * nz - kz * ny, kz * nx - kx * nz, kx * ny - ky * nx
    t = 0.0
    ta = ga = 0.0
    k_it = 0
    while k_it < EPA_KINK_ITERS:
        ct, st = math.cos(t), math.sin(t)
        ux, uy, uz = ct * nx + st * ex, ct * ny + st * ey, ct * nz + st * ez
        pax, pay, paz, pbx, pby, pbz = _support_called(
            sa, sb, verts, r_ab, t_ab, ux, uy, uz)
        qx, qy, qz = pax - pbx, pay - pby, paz - pbz
        hu = ux * qx + uy * qy + uz * qz
        hlow = min(hlow, hu)
        g = (ct * ex - st * nx) * qx + (ct * ey - st * ny) * qy + (ct * ez - st * nz) * qz
        k_it += 1
        if k_it == 1:
            # first step: Newton's with h'' guessed as half the pair's scale
            step = -g / (0.5 * scale)
        else:
            slope = (g - ga) / (t - ta)
            if not slope > 0.0:
                break
            step = -g / slope
            if abs(step) <= POLISH_STEP_DONE:
                ok = abs(g) <= CREASE_SLOPE_TOL * scale
                break
        step = max(-EPA_KINK_STEP, min(EPA_KINK_STEP, step))
        ta, ga = t, g
        t += step
    return (ok, k_it, hlow, hu, ux, uy, uz, pax, pay, paz, pbx, pby, pbz)


@njit_inline
def _deeper_near(sa, sb, verts, r_ab, t_ab, px, py, pz, ux, uy, uz, cmin, lim):
    """(evaluated, deeper): whether the unit direction p lies within acos(cmin) of u (one
    support is then evaluated there), and whether h(p) < ``lim`` there."""
    if px * ux + py * uy + pz * uz < cmin:
        return 0, False
    pax, pay, paz, pbx, pby, pbz = _support_called(sa, sb, verts, r_ab, t_ab, px, py, pz)
    return 1, px * (pax - pbx) + py * (pay - pby) + pz * (paz - pbz) < lim


@njit_inline
def _kink_points(sa, sb, verts, r_ab, t_ab, ux, uy, uz, lim):
    """Whether h reaches below ``lim`` at a point kink of h within EPA_POLISH_CAP of the
    direction u, for a pair of cylinders: the two cap normals of each and the two
    directions where their creases cross.  Returns (found, supports evaluated)."""
    cmin = math.cos(EPA_POLISH_CAP)
    ox, oy, oz = _axis_of(np.int64(1), np.int64(2), r_ab)
    cx, cy, cz = -oy, ox, 0.0           # z x o (A's axis is z)
    cn = math.sqrt(cx * cx + cy * cy)
    nev = 0
    for m in range(6):
        if m < 2:
            if not cn > NO_DIRECTION:
                continue
            px, py, pz = cx / cn, cy / cn, cz / cn
        elif m < 4:
            px, py, pz = _axis_of(np.int64(0), np.int64(2), r_ab)
        else:
            px, py, pz = ox, oy, oz
        if m % 2 == 1:
            px, py, pz = -px, -py, -pz
        ev, deeper = _deeper_near(sa, sb, verts, r_ab, t_ab, px, py, pz, ux, uy, uz,
                                  cmin, lim)
        nev += ev
        if deeper:
            return True, nev
    return False, nev


@njit_inline
def _box_faces_deeper(sa, sb, verts, r_ab, t_ab, side, axis, ux, uy, uz, lim):
    """Whether h reaches below ``lim`` at one of the four face normals of a box (A's if
    side == 0, else B's) on the circle of directions normal to its axis ``axis``, within
    EPA_POLISH_CAP of the unit direction u.  Returns (found, supports evaluated)."""
    cmin = math.cos(EPA_POLISH_CAP)
    nev = 0
    for m in range(4):
        j = (axis + 1 + m // 2) % 3
        px, py, pz = _axis_of(side, j, r_ab)
        if m % 2 == 1:
            px, py, pz = -px, -py, -pz
        ev, deeper = _deeper_near(sa, sb, verts, r_ab, t_ab, px, py, pz, ux, uy, uz,
                                  cmin, lim)
        nev += ev
        if deeper:
            return True, nev
    return False, nev


_SIN_CAP = math.sin(EPA_POLISH_CAP)


@njit_kernel
def _kink_polish(sa, sb, verts, r_ab, t_ab, scale, ws, side, axis):
    """Minimum of h(u) = h_{A-B}(u) over the great circle of directions normal to the
    axis of a cylinder or a capsule (z), or to a box's axis ``axis`` (A's if side == 0,
    else B's), from EPA's best face normal d (ws t3 row 8), by _crease_min; then checks
    that it is the minimum over all directions near it.

    Why: along those directions the cylinder's support is a whole segment of its side
    (a capsule's: its core segment, grown by the radius), so its support function has
    a crease there.  When the deepest direction lies on the crease (measured: 436 of
    939 deep cylinder-cylinder pairs, 571 of 963 deep ellipsoid-cylinder pairs), A - B
    has a ruled strip there, curved across; EPA then closes its bounds by a factor of
    ~2 per step (~30 steps against ~17 where the minimum is on a flat face) and
    Newton's method in two dimensions gives up on the crease.  A box's support along
    directions normal to one of its axes is an edge along that axis, so the same
    holds for its edges (measured: 357 of 960 deep ellipsoid-box pairs have their
    deepest direction on an edge's crease, 28 GJK + EPA steps on average against 15
    on a face normal).

    Kept only if h there is the lowest the search evaluated, the point h u lies on
    A - B's support segment (the cylinder's support point slid along its side by the
    axial part of w - h u stays within the side, within +-prm[1] along the axis for
    both shapes; a box's edge within +-prm[axis]: then h rises on both sides of the
    crease), for a box, no face normal within EPA_POLISH_CAP of the minimum deeper (the
    crease's circle passes through four of them, where h has kinks the secant does not
    see), and, when the other shape is a cylinder too, nothing nearby is deeper: the
    minimum along its crease (searched from d as well where that crease passes within
    EPA_POLISH_CAP of the first search's minimum, as farther the basin test covers it;
    the deeper of the two converged minima is the candidate, and a search that gave up
    but went deeper rejects it) and the point kinks of _kink_points.  Where two creases
    pass close by, each has a minimum of its own (without this check, 4 of 40,000 deep
    random cylinder-cylinder and capsule-cylinder pairs keep a minimum up to 4.3e-4 *
    scale shallower than the deepest direction, on the other crease 0.13-0.29 rad away;
    regression scene mkc_crease_polish_other_crease_cylinder_cylinder).  EPA then
    applies _polish_is_global as to Newton's method; GJK on cores apart needs no such
    test (h is convex there: a minimum on the sphere below zero is the global one).
    None of those checks is needed when the first search's minimum is the depth by
    _ball_certified (a witness with a ball of radius h inside the other shape's core):
    the search ends there.  Results as _newton_min_support's (ws t3 rows 15-18:
    direction, difference point, witnesses on A and B, the cylinder's one slid to that
    point), stored only when it succeeds (a minimum EPA holds pending its basin test
    stays there otherwise); returns the number of support evaluations, negated when it
    gave up."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    fs = ws[0]
    d = fs[_T_D]
    tol = EPA_REL_TOL * scale
    kx, ky, kz = _axis_of(side, axis, r_ab)
    r = _crease_min(sa, sb, verts, r_ab, t_ab, scale, kx, ky, kz, d[0], d[1], d[2])
    nev = r[1]
    ok = False
    pax = pay = paz = pbx = pby = pbz = 0.0
    if r[0]:
        # the depth itself (_ball_certified): no other crease or kink can be deeper
        ok, pax, pay, paz, pbx, pby, pbz = _crease_slid(sa, sb, t_ab, scale, r, side, axis,
                                                        kx, ky, kz)
        if ok and _ball_certified(sa, sb, r_ab, t_ab, r[3] - tol, r[4], r[5], r[6], pax,
                                  pay, paz, pbx, pby, pbz):
            _store_min(fs, r[4], r[5], r[6], pax - pbx, pay - pby, paz - pbz, pax, pay,
                       paz, pbx, pby, pbz)
            return nev
    both = sa[0] == CYLINDER and sb[0] == CYLINDER
    ox, oy, oz = _axis_of(1 - side, np.int64(2), r_ab)
    # the other cylinder's crease is searched only where it passes within the basin cap
    # (EPA_POLISH_CAP) of the minimum found: farther, _polish_is_global's test covers it
    if both and not (r[0] and abs(r[4] * ox + r[5] * oy + r[6] * oz) > _SIN_CAP):
        r2 = _crease_min(sa, sb, verts, r_ab, t_ab, scale, ox, oy, oz,
                         d[0], d[1], d[2])
        nev += r2[1]
        if r2[0] and (not r[0] or r2[3] < r[3]):
            r, r2 = r2, r
            side = 1 - side
            kx, ky, kz = ox, oy, oz
            # the witnesses of the other crease's minimum (those of the first search's
            # are at hand otherwise)
            ok, pax, pay, paz, pbx, pby, pbz = _crease_slid(sa, sb, t_ab, scale, r, side,
                                                            axis, kx, ky, kz)
        if r[0] and r2[2] < r[3] - tol:
            return -nev                 # the other search went deeper without converging
    if not (r[0] and ok):
        return -nev
    hu, ux, uy, uz = r[3], r[4], r[5], r[6]
    if (sa[0] if side == 0 else sb[0]) == BOX:
        found, nk = _box_faces_deeper(sa, sb, verts, r_ab, t_ab, side, axis,
                                      ux, uy, uz, hu - tol)
        nev += nk
        if found:
            return -nev
    if both:
        found, nk = _kink_points(sa, sb, verts, r_ab, t_ab, ux, uy, uz, hu - tol)
        nev += nk
        if found:
            return -nev
    _store_min(fs, ux, uy, uz, pax - pbx, pay - pby, paz - pbz, pax, pay, paz, pbx, pby,
               pbz)
    return nev


@njit_inline
def _crease_slid(sa, sb, t_ab, scale, r, side, axis, kx, ky, kz):
    """_kink_polish's witnesses for the minimum r of _crease_min along the crease of the
    shape on ``side`` (axis k): (ok, a (3), b (3)).  The cylinder's (capsule's, box's)
    point slides along its axis to cancel w's axial part, so that a - b = h u; ok when
    h there is the lowest the search evaluated and the point stays on the side
    (segment, edge), within +-prm[1] along the axis (a box: +-prm[axis]): then h rises
    on both sides of the crease."""
    hlow, hu = r[2], r[3]
    pax, pay, paz, pbx, pby, pbz = r[7], r[8], r[9], r[10], r[11], r[12]
    if not hu <= hlow + SUPPORT_TIE * scale:
        return False, pax, pay, paz, pbx, pby, pbz
    s = -((pax - pbx) * kx + (pay - pby) * ky + (paz - pbz) * kz)
    if side == 0:
        pax, pay, paz = pax + s * kx, pay + s * ky, paz + s * kz
        ax_ = pax * kx + pay * ky + paz * kz
        hh = sa[1][axis] if sa[0] == BOX else sa[1][1]
    else:
        pbx, pby, pbz = pbx - s * kx, pby - s * ky, pbz - s * kz
        ax_ = (pbx - t_ab[0]) * kx + (pby - t_ab[1]) * ky + (pbz - t_ab[2]) * kz
        hh = sb[1][axis] if sb[0] == BOX else sb[1][1]
    return abs(ax_) <= hh + SUPPORT_TIE * scale, pax, pay, paz, pbx, pby, pbz
