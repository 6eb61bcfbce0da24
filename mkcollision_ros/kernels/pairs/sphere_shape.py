"""Closed forms of a sphere against a sphere, box, capsule, cylinder, cone or an
ellipsoid without margin (``has_point_form``): the sphere's centre against the other
shape's core (``_point_to_shape``: ``_point_box``, ``_point_capsule``,
``_point_cylinder``, ``_point_cone``, ``_point_ellipsoid``), in B's frame
(``collide_sphere_shape``, A the sphere) or from the world poses (``sphere_world``).
The result row: core_distance.py; frames and signs: analytic.py.

Sphere-ellipsoid: the sphere's centre p against the ellipsoid x_i^2 / e_i^2 = 1 (B's
frame).  The nearest surface point is x_i = e_i^2 p_i / (e_i^2 + t) for the root t of
F(t) = sum (e_i p_i / (e_i^2 + t))^2 - 1, which is decreasing and convex for
t > -e_min^2: t > 0 when p is outside, -e_min^2 < t <= 0 when inside (the nearest
boundary point of an interior point).  Written in u = t + e_min^2 (no cancellation at
the pole), the root is found by Newton steps kept inside a bracket (bisection when a
step leaves it); an interior p on the plane of the shortest axis whose F stays negative
down to u = 0 has its nearest point at u = 0 with the shortest-axis coordinate from the
surface equation (D. Eberly, "Distance from a Point to an Ellipse, an Ellipsoid, or a
Hyperellipsoid", Geometric Tools, 2013, gives the same case analysis).  The normal
from A to B is minus B's outward surface normal at x.
"""
import math

import numpy as np

from ..constants import (BOX, CAPSULE, CONE, CYLINDER, ELLIPSOID, ELL_MAX_ITERS, P_MARGIN,
                         SE_HALVINGS, SE_ROOT_STOP, SPHERE)
from ..geometry import inflation, quat_rotate_xyz
from ..jit import njit_inline, njit_kernel
from .core_distance import _b_to_a, _finish_s, _origin_in_b


@njit_kernel
def _point_box(h0, h1, h2, c0, c1, c2):
    """A point c against the box core [-h, h] (the box's frame): the signed core
    distance and the unit normal (n0, n1, n2) from the point towards the box (the
    direction of A -> B when the point is A's sphere centre).  Inside, the nearest
    face: the box must move along -sign(c_k) e_k to push that face past the point."""
    q0 = min(h0, max(-h0, c0))
    q1 = min(h1, max(-h1, c1))
    q2 = min(h2, max(-h2, c2))
    inside = abs(c0) <= h0 and abs(c1) <= h1 and abs(c2) <= h2
    if not inside:
        d0, d1, d2 = q0 - c0, q1 - c1, q2 - c2
        core = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        return core, d0 / core, d1 / core, d2 / core
    g0, g1, g2 = h0 - abs(c0), h1 - abs(c1), h2 - abs(c2)
    if g0 <= g1 and g0 <= g2:
        return -g0, -1.0 if c0 >= 0.0 else 1.0, 0.0, 0.0
    if g1 <= g2:
        return -g1, 0.0, -1.0 if c1 >= 0.0 else 1.0, 0.0
    return -g2, 0.0, 0.0, -1.0 if c2 >= 0.0 else 1.0


@njit_kernel
def _point_cylinder(rr, h, c0, c1, c2):
    """A point c against the cylinder core (radius rr, half height h, axis z, its
    frame): signed core distance and unit normal from the point towards the cylinder.
    The closest point of a solid of revolution to a point lies in the point's meridian
    plane, so this is a point against the rectangle [0, rr] x [-h, h] in (rho, z):
    beyond the side only (the gap rho - rr along the radial line), beyond a cap only
    (|z| - h along z), beyond both (the rim: the one case that needs a second square
    root); inside, the nearest of the side and the two caps."""
    rho = math.sqrt(c0 * c0 + c1 * c1)
    dz = abs(c2) - h
    sz = -1.0 if c2 >= 0.0 else 1.0
    if rho <= rr:
        if dz > 0.0:
            return dz, 0.0, 0.0, sz
        g_side = rr - rho
        if g_side < -dz:
            if rho > 0.0:
                return -g_side, -c0 / rho, -c1 / rho, 0.0
            return -g_side, -1.0, 0.0, 0.0
        return dz, 0.0, 0.0, sz
    ux, uy = c0 / rho, c1 / rho
    dr = rho - rr
    if dz <= 0.0:
        return dr, -ux, -uy, 0.0
    core = math.sqrt(dr * dr + dz * dz)
    return core, -ux * (dr / core), -uy * (dr / core), sz * (dz / core)


@njit_inline
def _point_capsule(h, c0, c1, c2):
    """A point c against the capsule core, the segment z in [-h, h] (its frame): the
    core distance and the unit normal from the point towards the segment; a point on
    the segment gets distance 0 and the capsule's x axis (any direction normal to the
    segment is as deep)."""
    d2 = min(h, max(-h, c2)) - c2
    core = math.sqrt(c0 * c0 + c1 * c1 + d2 * d2)
    if core > 0.0:
        return core, -c0 / core, -c1 / core, d2 / core
    return 0.0, 1.0, 0.0, 0.0


@njit_kernel
def _seg2_closest(px, pz, ax, az, bx, bz):
    """Closest point (x, z) to (px, pz) on the 2-D segment [(ax, az), (bx, bz)]."""
    ex, ez = bx - ax, bz - az
    ee = ex * ex + ez * ez
    t = 0.0
    if ee > 0.0:
        t = min(1.0, max(0.0, ((px - ax) * ex + (pz - az) * ez) / ee))
    return ax + t * ex, az + t * ez


@njit_kernel
def _point_cone(rr, h, c0, c1, c2):
    """A point c against the cone core (base radius rr at z = -h, tip at z = +h, its
    frame): signed core distance and unit normal from the point towards the cone.  In
    the point's meridian plane (rho, z) the cone is the triangle tip (0, h), rim
    (rr, -h), base centre (0, -h), whose surface edges are the slant tip-rim and the
    base rim-centre (its right angle is at the base centre, so an inside point's feet
    on both edge lines fall within the edges)."""
    rho = math.sqrt(c0 * c0 + c1 * c1)
    if rho > 0.0:
        ux, uy = c0 / rho, c1 / rho
    else:
        ux, uy = 1.0, 0.0
    # outward unit normal of the slant in (rho, z): (2h, rr) / L
    ln = math.sqrt(4.0 * h * h + rr * rr)
    sr, sz = 2.0 * h / ln, rr / ln
    g_slant = rho * sr + (c2 - h) * sz      # signed distance to the slant line
    g_base = -(c2 + h)                     # signed distance to the base plane
    if g_slant <= 0.0 and g_base <= 0.0:
        # inside the core: the cone moves against the outward normal of the nearer face
        if g_slant >= g_base:
            return g_slant, -sr * ux, -sr * uy, -sz
        return g_base, 0.0, 0.0, 1.0
    qr, qz = _seg2_closest(rho, c2, 0.0, h, rr, -h)
    br, bz = _seg2_closest(rho, c2, rr, -h, 0.0, -h)
    if (br - rho) ** 2 + (bz - c2) ** 2 < (qr - rho) ** 2 + (qz - c2) ** 2:
        qr, qz = br, bz
    d0, d1, d2 = qr * ux - c0, qr * uy - c1, qz - c2
    core = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    return core, d0 / core, d1 / core, d2 / core


@njit_kernel
def _ellipsoid_newton_f(y0, y1, y2, e0, e1, e2, g0, g1, g2, u):
    """F(u) = sum (e_i y_i / (g_i + u))^2 - 1 and its derivative dF/du."""
    q0, q1, q2 = e0 * y0 / (g0 + u), e1 * y1 / (g1 + u), e2 * y2 / (g2 + u)
    f = q0 * q0 + q1 * q1 + q2 * q2 - 1.0
    df = -2.0 * (q0 * q0 / (g0 + u) + q1 * q1 / (g1 + u) + q2 * q2 / (g2 + u))
    return f, df


@njit_kernel
def _point_ellipsoid(e0, e1, e2, p0, p1, p2):
    """A point p against the ellipsoid x_i^2 / e_i^2 = 1 (its frame, no margin; module
    docstring): the signed distance to its surface and the unit normal from the point
    towards the ellipsoid (minus the outward surface normal at the nearest point)."""
    # the point folded into the positive octant
    y0, y1, y2 = abs(p0), abs(p1), abs(p2)
    em = min(e0, min(e1, e2))
    m = 0 if e0 == em else (1 if e1 == em else 2)
    g0, g1, g2 = e0 * e0 - em * em, e1 * e1 - em * em, e2 * e2 - em * em
    if m == 0:
        g0 = 0.0
    elif m == 1:
        g1 = 0.0
    else:
        g2 = 0.0
    # largest coordinate along the shortest axes (ties: g_i == 0)
    ym = max(y0 if g0 == 0.0 else 0.0, max(y1 if g1 == 0.0 else 0.0, y2 if g2 == 0.0 else 0.0))
    level = (y0 / e0) ** 2 + (y1 / e1) ** 2 + (y2 / e2) ** 2
    outside = level > 1.0
    u = -1.0                               # the root; -1 marks the flat interior case
    if outside:
        lo = em * em
        hi = em * em + max(e0, max(e1, e2)) * math.sqrt(y0 * y0 + y1 * y1 + y2 * y2)
    else:
        hi = em * em
        lo = em * ym
        if not lo > 0.0:
            # p on the plane of the shortest axes: F(0+) is the other axes' terms; the
            # flat case when it is <= 0
            f0 = -1.0
            if g0 > 0.0:
                f0 += (e0 * y0 / g0) ** 2
            if g1 > 0.0:
                f0 += (e1 * y1 / g1) ** 2
            if g2 > 0.0:
                f0 += (e2 * y2 / g2) ** 2
            if f0 <= 0.0:
                u = 0.0
            else:
                lo = hi
                for _ in range(SE_HALVINGS):
                    lo *= 0.5
                    f, df = _ellipsoid_newton_f(y0, y1, y2, e0, e1, e2, g0, g1, g2, lo)
                    if f >= 0.0 or not lo > 0.0:
                        break
    if u != 0.0:
        u = lo
        for _ in range(ELL_MAX_ITERS):
            f, df = _ellipsoid_newton_f(y0, y1, y2, e0, e1, e2, g0, g1, g2, u)
            if f == 0.0:
                break
            if f > 0.0:
                lo = u
            else:
                hi = u
            un = u - f / df if df < 0.0 else 0.5 * (lo + hi)
            if not (lo < un < hi):
                un = 0.5 * (lo + hi)
            if abs(un - u) <= SE_ROOT_STOP * u or not lo < hi:
                u = un
                break
            u = un
    if u == 0.0:
        # flat interior case: x_i = e_i^2 y_i / g_i off the shortest axis, which takes
        # the rest of the surface equation
        x0 = e0 * e0 * y0 / g0 if g0 > 0.0 else 0.0
        x1 = e1 * e1 * y1 / g1 if g1 > 0.0 else 0.0
        x2 = e2 * e2 * y2 / g2 if g2 > 0.0 else 0.0
        rest = 1.0 - (x0 / e0) ** 2 - (x1 / e1) ** 2 - (x2 / e2) ** 2
        xm = em * math.sqrt(max(rest, 0.0))
        if m == 0:
            x0 = xm
        elif m == 1:
            x1 = xm
        else:
            x2 = xm
    else:
        x0, x1, x2 = e0 * e0 * y0 / (g0 + u), e1 * e1 * y1 / (g1 + u), e2 * e2 * y2 / (g2 + u)
    # unfold the octant (a zero coordinate keeps the + side)
    if p0 < 0.0:
        x0 = -x0
    if p1 < 0.0:
        x1 = -x1
    if p2 < 0.0:
        x2 = -x2
    dx, dy, dz = x0 - p0, x1 - p1, x2 - p2
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    # outward surface normal at x (B's frame); the normal A -> B is its opposite
    nx, ny, nz = x0 / (e0 * e0), x1 / (e1 * e1), x2 / (e2 * e2)
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    return d if outside else -d, -nx / nn, -ny / nn, -nz / nn


@njit_inline
def has_point_form(code, prm):
    """Whether _point_to_shape solves a point against a shape of this code and these
    parameters: a box, capsule, cylinder, cone or an ellipsoid without margin (an
    ellipsoid grown by a margin is no ellipsoid).  With a sphere on the other side,
    these are the sphere-* closed forms of _ordered and of sphere_world."""
    return (code == BOX or code == CAPSULE or code == CYLINDER or code == CONE
            or (code == ELLIPSOID and prm[P_MARGIN] == 0.0))


@njit_inline
def _point_to_shape(code, prm, c0, c1, c2):
    """A sphere's centre c, given in the frame of a shape of has_point_form, against
    that shape: returns
    (d, n0, n1, n2, r), the signed distance from the sphere's centre to the shape being
    d - r - (the sphere's radius), and n the unit normal from the sphere towards the
    shape in the shape's frame.  r is the shape's inflation (0 for the ellipsoid, whose
    d is measured to its surface, not to a core)."""
    if code == BOX:
        d, n0, n1, n2 = _point_box(prm[0], prm[1], prm[2], c0, c1, c2)
    elif code == CYLINDER:
        d, n0, n1, n2 = _point_cylinder(prm[0], prm[1], c0, c1, c2)
    elif code == CONE:
        d, n0, n1, n2 = _point_cone(prm[0], prm[1], c0, c1, c2)
    elif code == CAPSULE:
        d, n0, n1, n2 = _point_capsule(prm[1], c0, c1, c2)
    else:
        d, n0, n1, n2 = _point_ellipsoid(prm[0], prm[1], prm[2], c0, c1, c2)
        return d, n0, n1, n2, 0.0
    return d, n0, n1, n2, inflation(code, prm)


@njit_kernel
def collide_sphere_shape(sa, sb, r_ab, t_ab, out):
    """A = sphere (centre at A's origin), B = a shape of has_point_form: its closed
    form in B's frame, the normal brought back to A's frame."""
    ra = inflation(sa[0], sa[1])
    c0, c1, c2 = _origin_in_b(r_ab, t_ab)
    core, n0, n1, n2, rb = _point_to_shape(sb[0], sb[1], c0, c1, c2)
    nx, ny, nz = _b_to_a(r_ab, n0, n1, n2)
    return _finish_s(0.0, 0.0, 0.0, core, nx, ny, nz, ra, rb, out)


@njit_inline
def sphere_world(prm_s, code_o, prm_o, pos_s, pos_o, quat_o, sphere_is_a, out):
    """A sphere against a sphere or a shape of has_point_form, in the world frame: the
    sphere's centre goes into the other body's frame (one rotation), the closed form
    runs there, its normal comes back (one rotation); the sphere's own orientation is
    never needed.  The same closed forms as _ordered, without the two rotation
    matrices, the relative pose and the way back from A's frame, and for either order
    of the pair (``sphere_is_a``: the sphere is A).  Two spheres: the centre line in
    the world frame (+z when the centres coincide).  Writes ``out`` (world; normal from
    A to B) and returns the signed distance (m)."""
    rs = prm_s[0] + prm_s[P_MARGIN]
    if code_o == SPHERE:
        dx, dy, dz = pos_o[0] - pos_s[0], pos_o[1] - pos_s[1], pos_o[2] - pos_s[2]
        core = math.sqrt(dx * dx + dy * dy + dz * dz)
        if core > 0.0:
            nx, ny, nz = dx / core, dy / core, dz / core
        else:
            nx, ny, nz = 0.0, 0.0, 1.0
        ro = prm_o[0] + prm_o[P_MARGIN]
    else:
        c0, c1, c2 = quat_rotate_xyz(quat_o, pos_s[0] - pos_o[0], pos_s[1] - pos_o[1],
                                     pos_s[2] - pos_o[2], np.bool_(True))
        core, n0, n1, n2, ro = _point_to_shape(code_o, prm_o, c0, c1, c2)
        nx, ny, nz = quat_rotate_xyz(quat_o, n0, n1, n2, np.bool_(False))
    if sphere_is_a:
        return _finish_s(pos_s[0], pos_s[1], pos_s[2], core, nx, ny, nz, rs, ro, out)
    # the other shape is A: its core witness is the sphere's centre moved by the core
    # distance along n, and the normal from A to B is -n
    return _finish_s(pos_s[0] + core * nx, pos_s[1] + core * ny, pos_s[2] + core * nz,
                     core, -nx, -ny, -nz, ro, rs, out)
