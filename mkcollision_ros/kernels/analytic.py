"""Exact closed-form pair tests: sphere-sphere, sphere-box, sphere-capsule,
sphere-cylinder, sphere-cone, sphere-ellipsoid (ellipsoid without margin), capsule-capsule,
box-capsule, and a half-space (plane) against any shape; plus
``box_box_sat``, the separating-axis depth of two boxes whose cores overlap (used by the
dispatcher's auto method before GJK; not part of ``collide_analytic``, since separated
boxes need GJK for their exact distance; their SAT gap is only a lower bound, which the
dispatcher keeps for pairs beyond its distance cutoff).

All kernels here work on scalars (numba keeps them in registers): no array is allocated
on the per-pair path.

Every pair is reduced to the closest points of two *cores* (a point, a segment, a box;
kernels/geometry.py) followed by subtracting the two inflation radii, which is exact
because a shape with margin is its core grown by a ball (Minkowski sum):

    signed distance = core distance - (r_a + r_b),   normal = core direction A -> B.

When the cores overlap (sphere centre inside the core box; capsule axes that cross) the
core distance is signed (negative) and the normal is the minimum-translation direction
of the cores, so the result stays exact (sphere-box: nearest face; crossing segments:
the common perpendicular, since their Minkowski difference is a flat parallelogram).

Frames and signs (as everywhere, see mkcollision_ros/results.py): inputs ``r_ab``
(3, 3) and ``t_ab`` (3,) are B's pose in A's frame (float64, metres); every output is in
A's frame; ``out`` float64[OUT_SIZE] receives the signed distance (> 0 apart), the unit
normal from A to B, witness points ``pa`` on A's surface and ``pb`` on B's surface with
``pb - pa == dist * normal``, iterations (1) and ``M_ANALYTIC``.

Pairs are accepted in either order (A, B) or (B, A); unsupported pairs and plane-plane
return ST_NOT_RUN and leave ``out`` untouched.

Half-space: B = {x : n.x <= d} in B's frame (prm[0:3] = unit n, prm[3] = d).  The signed
distance of A is min over x in A of (n.x - d), reached at A's support point along -n; B
lies on the -n side, so the normal from A to B is -n (rotated into A's frame), and moving
B by the depth along it moves the boundary plane onto A's deepest point.

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

Segment-segment closest points follow the classic clamped parametric solution (e.g.
Ericson, *Real-Time Collision Detection*, 2005, sec. 5.1.9), with the parallel case
handled by clamping an endpoint projection.
"""
import math

import numpy as np

from .constants import (BOX, CAPSULE, CONE, CYLINDER, ELLIPSOID, ELL_MAX_ITERS, M_ANALYTIC,
                        P_MARGIN, OUT_DIST, OUT_ITERS, OUT_METHOD,
                        OUT_NORMAL, OUT_PA, OUT_PB, PLANE, SPHERE, ST_NOT_RUN,
                        ST_PENETRATING, ST_SEPARATED, ST_TOUCHING, TOUCH_TOL)
from .geometry import (borrow_args, borrow_pose, inflation, meet, quat_entries,
                       quat_rotate_xyz, shape_scale, support_full_xyz)
from .jit import borrow, njit_inline, njit_kernel


@njit_kernel
def _mv(r, v):
    """r @ v for a (3, 3) matrix and a (3,) vector (no BLAS)."""
    o = np.empty(3)
    for i in range(3):
        o[i] = r[i, 0] * v[0] + r[i, 1] * v[1] + r[i, 2] * v[2]
    return o


@njit_kernel
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit_inline
def classify(dist, scale):
    """Status code of a signed distance (m) under the touching rule (constants.py)."""
    tol = TOUCH_TOL * scale
    if dist > tol:
        return ST_SEPARATED
    if dist >= -tol:
        return ST_TOUCHING
    return ST_PENETRATING


@njit_inline
def _finish_s(cax, cay, caz, core_dist, nx, ny, nz, ra, rb, out):
    """``_finish`` on scalars (allocation-free): core witness on A (cax, cay, caz),
    signed core distance along the unit normal (nx, ny, nz) (A -> B), radii."""
    dist = core_dist - ra - rb
    out[OUT_DIST] = dist
    pax, pay, paz = cax + ra * nx, cay + ra * ny, caz + ra * nz
    out[OUT_NORMAL] = nx
    out[OUT_NORMAL + 1] = ny
    out[OUT_NORMAL + 2] = nz
    out[OUT_PA] = pax
    out[OUT_PA + 1] = pay
    out[OUT_PA + 2] = paz
    out[OUT_PB] = pax + dist * nx
    out[OUT_PB + 1] = pay + dist * ny
    out[OUT_PB + 2] = paz + dist * nz
    out[OUT_ITERS] = 1.0
    out[OUT_METHOD] = M_ANALYTIC
    return dist


@njit_inline
def _point_point_s(ax, ay, az, bx, by, bz, ra, rb, out):
    """Two inflated points (A frame): distance along b - a, +z when they coincide."""
    dx, dy, dz = bx - ax, by - ay, bz - az
    dn = math.sqrt(dx * dx + dy * dy + dz * dz)
    if dn > 0.0:
        return _finish_s(ax, ay, az, dn, dx / dn, dy / dn, dz / dn, ra, rb, out)
    return _finish_s(ax, ay, az, dn, 0.0, 0.0, 1.0, ra, rb, out)


@njit_kernel
def _closest_on_segment_s(px, py, pz, ax, ay, az, bx, by, bz):
    """Closest point (x, y, z) to p on segment [a, b] (scalars)."""
    ex, ey, ez = bx - ax, by - ay, bz - az
    den = ex * ex + ey * ey + ez * ez
    if den <= 0.0:
        return ax, ay, az
    s = ((px - ax) * ex + (py - ay) * ey + (pz - az) * ez) / den
    s = min(1.0, max(0.0, s))
    return ax + s * ex, ay + s * ey, az + s * ez


@njit_inline
def _origin_in_b(r_ab, t_ab):
    """A's origin (the sphere centre of the sphere-* kernels) in B's frame:
    -r_ab^T t_ab, as three floats."""
    return (-(r_ab[0, 0] * t_ab[0] + r_ab[1, 0] * t_ab[1] + r_ab[2, 0] * t_ab[2]),
            -(r_ab[0, 1] * t_ab[0] + r_ab[1, 1] * t_ab[1] + r_ab[2, 1] * t_ab[2]),
            -(r_ab[0, 2] * t_ab[0] + r_ab[1, 2] * t_ab[1] + r_ab[2, 2] * t_ab[2]))


@njit_inline
def _b_to_a(r_ab, x, y, z):
    """A direction given in B's frame, in A's frame: r_ab (x, y, z), as three floats."""
    return (r_ab[0, 0] * x + r_ab[0, 1] * y + r_ab[0, 2] * z,
            r_ab[1, 0] * x + r_ab[1, 1] * y + r_ab[1, 2] * z,
            r_ab[2, 0] * x + r_ab[2, 1] * y + r_ab[2, 2] * z)


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
                for _ in range(1100):
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
            if abs(un - u) <= 4e-16 * u or not lo < hi:
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
def _sphere_closed_form(sa, sb, r_ab, t_ab, out):
    """A = sphere (centre at A's origin), B = a shape of has_point_form: its closed
    form in B's frame, the normal brought back to A's frame."""
    ra = inflation(sa[0], sa[1])
    c0, c1, c2 = _origin_in_b(r_ab, t_ab)
    core, n0, n1, n2, rb = _point_to_shape(sb[0], sb[1], c0, c1, c2)
    nx, ny, nz = _b_to_a(r_ab, n0, n1, n2)
    return _finish_s(0.0, 0.0, 0.0, core, nx, ny, nz, ra, rb, out)


@njit_inline
def _plane_any(sa, sb, verts, r_ab, t_ab, out):
    """A = any non-plane shape, B = half-space n.x <= d (B's frame), grown by its
    margin m to n.x <= d + m."""
    nb = sb[1]
    d = sb[1][3] + sb[1][P_MARGIN]
    # plane normal in A's frame
    nax, nay, naz = _b_to_a(r_ab, nb[0], nb[1], nb[2])
    x0, x1, x2 = support_full_xyz(sa[0], sa[1], verts, sa[2], sa[3], -nax, -nay, -naz)
    # signed distance: n.(x in B's frame) - d
    y0, y1, y2 = x0 - t_ab[0], x1 - t_ab[1], x2 - t_ab[2]
    dist = -d
    for i in range(3):
        dist += nb[i] * (r_ab[0, i] * y0 + r_ab[1, i] * y1 + r_ab[2, i] * y2)
    out[OUT_DIST] = dist
    out[OUT_NORMAL] = -nax
    out[OUT_NORMAL + 1] = -nay
    out[OUT_NORMAL + 2] = -naz
    out[OUT_PA] = x0
    out[OUT_PA + 1] = x1
    out[OUT_PA + 2] = x2
    out[OUT_PB] = x0 - dist * nax
    out[OUT_PB + 1] = x1 - dist * nay
    out[OUT_PB + 2] = x2 - dist * naz
    out[OUT_ITERS] = 1.0
    out[OUT_METHOD] = M_ANALYTIC
    return dist


@njit_inline
def _ordered(sa, sb, verts, r_ab, t_ab, out):
    """Closed form for code_a <= code_b; returns (ran, dist)."""
    ca, cb = sa[0], sb[0]
    if cb == PLANE:
        if ca == PLANE:
            return False, 0.0
        return True, _plane_any(sa, sb, verts, r_ab, t_ab, out)
    ra = inflation(ca, sa[1])
    rb = inflation(cb, sb[1])
    if ca == SPHERE and cb == SPHERE:
        return True, _point_point_s(0.0, 0.0, 0.0, t_ab[0], t_ab[1], t_ab[2], ra, rb, out)
    if ca == SPHERE and has_point_form(cb, sb[1]):
        return True, _sphere_closed_form(sa, sb, r_ab, t_ab, out)
    if ca == CAPSULE and cb == CAPSULE:
        return True, _capsule_capsule(sa, sb, r_ab, t_ab, ra, rb, out)
    if ca == BOX and cb == CAPSULE:
        return True, _box_capsule(sa, sb, r_ab, t_ab, ra, rb, out)
    return False, 0.0


@njit_kernel
def _segments(p1x, p1y, p1z, d1x, d1y, d1z, p2x, p2y, p2z, q2x, q2y, q2z, tx, ty, tz,
              fx, fy, fz, gx, gy, gz, ra, rb, tiny, out):
    """Two capsules as the segments [p1, p1 + d1] and [p2, q2] grown by ra and rb, in
    any frame: closest points of the segments (Ericson 5.1.9), scalars; ``out`` in that
    frame.  Axes that meet (closest points within ``tiny``) separate along the common
    perpendicular when they cross, oriented along t (A's centre to B's) when that is
    defined; parallel ones along f, A's y axis (unit, normal to A's axis); a point on
    a segment along f or A's x axis g made normal to the segment."""
    rx, ry, rz = p1x - p2x, p1y - p2y, p1z - p2z
    d2x, d2y, d2z = q2x - p2x, q2y - p2y, q2z - p2z
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    if a <= 0.0 and e <= 0.0:
        s, t = 0.0, 0.0
        den = 0.0
    elif a <= 0.0:
        s = 0.0
        t = min(1.0, max(0.0, f / e))
        den = 0.0
    elif e <= 0.0:
        t = 0.0
        s = min(1.0, max(0.0, -(d1x * rx + d1y * ry + d1z * rz) / a))
        den = 0.0
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        b = d1x * d2x + d1y * d2y + d1z * d2z
        den = a * e - b * b
        # den = |d1|^2 |d2|^2 sin^2: treat as parallel below a relative threshold
        if den > 1e-14 * a * e:
            s = min(1.0, max(0.0, (b * f - c * e) / den))
        else:
            s = 0.0
        t = (b * s + f) / e
        if t < 0.0:
            t = 0.0
            s = min(1.0, max(0.0, -c / a))
        elif t > 1.0:
            t = 1.0
            s = min(1.0, max(0.0, (b - c) / a))
    c1x, c1y, c1z = p1x + s * d1x, p1y + s * d1y, p1z + s * d1z
    c2x, c2y, c2z = p2x + t * d2x, p2y + t * d2y, p2z + t * d2z
    if a > 0.0 and e > 0.0 and den <= 1e-14 * a * e:
        # parallel: the pair above is valid but pick the middle of the overlap so the
        # witness does not jump between ends; re-project the overlap midpoint
        ua = ((p2x - p1x) * d1x + (p2y - p1y) * d1y + (p2z - p1z) * d1z) / a
        ub = ((q2x - p1x) * d1x + (q2y - p1y) * d1y + (q2z - p1z) * d1z) / a
        lo = max(0.0, min(ua, ub))
        hi = min(1.0, max(ua, ub))
        if lo <= hi:
            s = 0.5 * (lo + hi)
            c1x, c1y, c1z = p1x + s * d1x, p1y + s * d1y, p1z + s * d1z
            c2x, c2y, c2z = _closest_on_segment_s(c1x, c1y, c1z, p2x, p2y, p2z,
                                                  q2x, q2y, q2z)
    dx, dy, dz = c2x - c1x, c2y - c1y, c2z - c1z
    dn = math.sqrt(dx * dx + dy * dy + dz * dz)
    skew = den > 1e-14 * a * e and 0.0 < s < 1.0 and 0.0 < t < 1.0
    if skew:
        # closest points inside both segments of skew axes: along the common
        # perpendicular d1 x d2, at the lines' offset along it.  c2 - c1 carries the
        # round-off of s and t (~ eps |d| / sin^2 of the axes' angle), which can exceed
        # ``tiny`` where the axes cross: its direction is then noise
        nx = d1y * d2z - d1z * d2y
        ny = d1z * d2x - d1x * d2z
        nz = d1x * d2y - d1y * d2x
        nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / nn, ny / nn, nz / nn
        off = -(nx * rx + ny * ry + nz * rz)
        if off < 0.0:
            nx, ny, nz, off = -nx, -ny, -nz, -off
        if off > tiny:
            return _finish_s(c1x, c1y, c1z, off, nx, ny, nz, ra, rb, out)
    elif dn > tiny:
        return _point_point_s(c1x, c1y, c1z, c2x, c2y, c2z, ra, rb, out)
    if den > 1e-14 * a * e:
        # crossing axes: separate along the common perpendicular d1 x d2 (|d1 x d2|^2
        # = den, well away from zero here)
        nx = d1y * d2z - d1z * d2y
        ny = d1z * d2x - d1x * d2z
        nz = d1x * d2y - d1y * d2x
        nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / nn, ny / nn, nz / nn
        if nx * tx + ny * ty + nz * tz < 0.0:
            nx, ny, nz = -nx, -ny, -nz
    elif a > 0.0 or not e > 0.0:
        # parallel axes through one point (or two points): every direction normal to
        # A's axis is as deep; f is one.  (Not the cross product: for parallel axes it
        # is round-off, and its direction anything.)
        nx, ny, nz = fx, fy, fz
    else:
        # A's segment a point on B's: a direction normal to B's axis, f or g (unit,
        # normal to f) made normal to it, whichever keeps more of its length (>= 0.7)
        k = (fx * d2x + fy * d2y + fz * d2z) / e
        nx, ny, nz = fx - k * d2x, fy - k * d2y, fz - k * d2z
        nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        if nn < 0.7:
            k = (gx * d2x + gy * d2y + gz * d2z) / e
            nx, ny, nz = gx - k * d2x, gy - k * d2y, gz - k * d2z
            nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / nn, ny / nn, nz / nn
    return _finish_s(c1x, c1y, c1z, 0.0, nx, ny, nz, ra, rb, out)


@njit_kernel
def _capsule_capsule(sa, sb, r_ab, t_ab, ra, rb, out):
    """Two capsules in A's frame (A's segment on its z axis): _segments."""
    ha = sa[1][1]
    hb = sb[1][1]
    p2x, p2y, p2z = t_ab[0] + hb * r_ab[0, 2], t_ab[1] + hb * r_ab[1, 2], t_ab[2] + hb * r_ab[2, 2]
    q2x, q2y, q2z = t_ab[0] - hb * r_ab[0, 2], t_ab[1] - hb * r_ab[1, 2], t_ab[2] - hb * r_ab[2, 2]
    return _segments(0.0, 0.0, ha, 0.0, 0.0, -2.0 * ha, p2x, p2y, p2z, q2x, q2y, q2z,
                     t_ab[0], t_ab[1], t_ab[2], 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, ra, rb,
                     1e-15 * shape_scale(sa, sb), out)


@njit_inline
def capsule_capsule_world(prm_a, prm_b, pos_a, quat_a, pos_b, quat_b, scale, out):
    """Two capsules straight from their world poses (the same _segments as the
    body-frame path, on the axes taken from the quaternions, coordinates relative to
    A's centre): no rotation matrices, relative pose or way back from A's frame.  The
    normals of axes that meet are chosen from A's y and x axes, as in A's frame.
    Writes ``out`` (world) and returns the signed distance (m)."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_entries(quat_a)
    s00, s01, s02, s10, s11, s12, s20, s21, s22 = quat_entries(quat_b)
    ha, hb = prm_a[1], prm_b[1]
    tx, ty, tz = pos_b[0] - pos_a[0], pos_b[1] - pos_a[1], pos_b[2] - pos_a[2]
    p2x, p2y, p2z = tx + hb * s02, ty + hb * s12, tz + hb * s22
    q2x, q2y, q2z = tx - hb * s02, ty - hb * s12, tz - hb * s22
    dist = _segments(ha * r02, ha * r12, ha * r22, -2.0 * ha * r02, -2.0 * ha * r12,
                     -2.0 * ha * r22, p2x, p2y, p2z, q2x, q2y, q2z,
                     tx, ty, tz, r01, r11, r21, r00, r10, r20, prm_a[0] + prm_a[P_MARGIN],
                     prm_b[0] + prm_b[P_MARGIN], 1e-15 * scale, out)
    for c in range(3):
        out[OUT_PA + c] += pos_a[c]
        out[OUT_PB + c] += pos_a[c]
    return dist


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
                                     pos_s[2] - pos_o[2], True)
        core, n0, n1, n2, ro = _point_to_shape(code_o, prm_o, c0, c1, c2)
        nx, ny, nz = quat_rotate_xyz(quat_o, n0, n1, n2, False)
    if sphere_is_a:
        return _finish_s(pos_s[0], pos_s[1], pos_s[2], core, nx, ny, nz, rs, ro, out)
    # the other shape is A: its core witness is the sphere's centre moved by the core
    # distance along n, and the normal from A to B is -n
    return _finish_s(pos_s[0] + core * nx, pos_s[1] + core * ny, pos_s[2] + core * nz,
                     core, -nx, -ny, -nz, ro, rs, out)


@njit_inline
def _seg_box_slope(a0, a1, a2, c0, c1, c2, u0, u1, u2, s):
    """Half the derivative in s of the squared distance from c + s u to the box
    [-a, a] (convex in s, piecewise quadratic, continuously differentiable)."""
    g = 0.0
    x = c0 + s * u0
    if x > a0:
        g += (x - a0) * u0
    elif x < -a0:
        g += (x + a0) * u0
    x = c1 + s * u1
    if x > a1:
        g += (x - a1) * u1
    elif x < -a1:
        g += (x + a1) * u1
    x = c2 + s * u2
    if x > a2:
        g += (x - a2) * u2
    elif x < -a2:
        g += (x + a2) * u2
    return g


@njit_inline
def _seg_box_offset(a0, a1, a2, c0, c1, c2, u0, u1, u2, s):
    """The box point q nearest to x = c + s u, and x - q, as six floats."""
    x0, x1, x2 = c0 + s * u0, c1 + s * u1, c2 + s * u2
    q0 = min(a0, max(-a0, x0))
    q1 = min(a1, max(-a1, x1))
    q2 = min(a2, max(-a2, x2))
    return q0, q1, q2, x0 - q0, x1 - q1, x2 - q2


@njit_inline
def _seg_box_kink(k, a0, a1, a2, c0, c1, c2, u0, u1, u2, lo, glo, hi, ghi):
    """Narrow the bracket [lo, hi] of the minimum (slopes glo < 0 < ghi) by the kink
    at s = k, where the segment crosses a face plane: the slope is monotone, so a kink
    with a negative slope lies left of the minimum and one with a positive slope right
    of it; a zero slope is the minimum (returned as lo = hi = k)."""
    if lo < k < hi:
        g = _seg_box_slope(a0, a1, a2, c0, c1, c2, u0, u1, u2, k)
        if g < 0.0:
            return k, g, hi, ghi
        if g > 0.0:
            return lo, glo, k, g
        return k, 0.0, k, 0.0
    return lo, glo, hi, ghi


@njit_inline
def _seg_slab_middle(a0, a1, a2, c0, c1, c2, u0, u1, u2, h, use0, use1, use2):
    """Middle of the part of the segment c + s u (|s| <= h) inside the slabs
    |x_i| <= a_i of the coordinates flagged ``use_i`` (s = 0 when it is empty)."""
    lo, hi = -h, h
    for i in range(3):
        use = use0 if i == 0 else (use1 if i == 1 else use2)
        ui = u0 if i == 0 else (u1 if i == 1 else u2)
        if use and ui != 0.0:
            ai = a0 if i == 0 else (a1 if i == 1 else a2)
            ci = c0 if i == 0 else (c1 if i == 1 else c2)
            k1, k2 = (-ai - ci) / ui, (ai - ci) / ui
            lo = max(lo, min(k1, k2))
            hi = min(hi, max(k1, k2))
    return 0.5 * (lo + hi) if lo <= hi else 0.0


@njit_kernel
def _box_capsule(sa, sb, r_ab, t_ab, ra, rb, out):
    """A = box (half extents a), B = capsule (segment c + s u, |s| <= h, in A's frame).

    Apart: the squared distance from the segment to the box is a convex, continuously
    differentiable, piecewise quadratic function of s whose kinks are where the
    segment crosses a face plane (x_i = +-a_i).  Its slope is monotone, so the six
    kinks, tested by the sign of the slope there, bracket the minimum in one smooth
    piece, where the slope is linear: one interpolation gives the exact minimiser.

    Overlapping cores: the Minkowski difference of a box and a segment is a polytope
    whose face normals are the box's face normals e_k and the cross products u x e_k,
    so the smallest overlap over those six axes is the exact core depth (the
    separating-axis theorem, as box_box_sat).  Witnesses: on a face axis, the deepest
    end of the segment (the middle of its part over the face when it lies flat); on an
    edge axis, the common perpendicular of the segment and the box edge along e_k."""
    a0, a1, a2 = sa[1][0], sa[1][1], sa[1][2]
    h = sb[1][1]
    c0, c1, c2 = t_ab[0], t_ab[1], t_ab[2]
    u0, u1, u2 = r_ab[0, 2], r_ab[1, 2], r_ab[2, 2]
    scale = shape_scale(sa, sb)
    lo, hi = -h, h
    glo = _seg_box_slope(a0, a1, a2, c0, c1, c2, u0, u1, u2, lo)
    ghi = _seg_box_slope(a0, a1, a2, c0, c1, c2, u0, u1, u2, hi)
    if glo >= 0.0:
        s = lo
    elif ghi <= 0.0:
        s = hi
    else:
        for i in range(3):
            ai = a0 if i == 0 else (a1 if i == 1 else a2)
            ci = c0 if i == 0 else (c1 if i == 1 else c2)
            ui = u0 if i == 0 else (u1 if i == 1 else u2)
            if ui != 0.0:
                lo, glo, hi, ghi = _seg_box_kink((-ai - ci) / ui, a0, a1, a2, c0, c1, c2,
                                                 u0, u1, u2, lo, glo, hi, ghi)
                lo, glo, hi, ghi = _seg_box_kink((ai - ci) / ui, a0, a1, a2, c0, c1, c2,
                                                 u0, u1, u2, lo, glo, hi, ghi)
        if glo == ghi:
            s = lo
        else:
            s = min(hi, max(lo, lo - glo * (hi - lo) / (ghi - glo)))
    q0, q1, q2, d0, d1, d2 = _seg_box_offset(a0, a1, a2, c0, c1, c2, u0, u1, u2, s)
    core = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if core > 1e-12 * scale:
        # lying flat (parallel to every face plane it is beyond): the distance is the
        # same along the part of the segment over the box; take its middle, so the
        # witness does not jump between the ends
        flat = 2.0 * h * max(abs(u0) if d0 != 0.0 else 0.0, abs(u1) if d1 != 0.0 else 0.0,
                             abs(u2) if d2 != 0.0 else 0.0) <= 1e-12 * scale
        if flat and h > 0.0:
            s = _seg_slab_middle(a0, a1, a2, c0, c1, c2, u0, u1, u2, h,
                                 d0 == 0.0, d1 == 0.0, d2 == 0.0)
            q0, q1, q2, d0, d1, d2 = _seg_box_offset(a0, a1, a2, c0, c1, c2, u0, u1, u2, s)
            core = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        return _finish_s(q0, q1, q2, core, d0 / core, d1 / core, d2 / core, ra, rb, out)
    # cores overlap: separating axes, faces first (ties keep the face)
    best = a0 + h * abs(u0) - abs(c0)
    axis = 0
    o = a1 + h * abs(u1) - abs(c1)
    if o < best:
        best, axis = o, 1
    o = a2 + h * abs(u2) - abs(c2)
    if o < best:
        best, axis = o, 2
    n0, n1, n2 = 0.0, 0.0, 0.0
    for k in range(3):
        # u x e_k, normalised by |u x e_k| = sqrt(1 - u_k^2)
        if k == 0:
            m0, m1, m2 = 0.0, u2, -u1
        elif k == 1:
            m0, m1, m2 = -u2, 0.0, u0
        else:
            m0, m1, m2 = u1, -u0, 0.0
        ln = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
        if ln < 1e-9:
            continue
        o = (a0 * abs(m0) + a1 * abs(m1) + a2 * abs(m2) - abs(m0 * c0 + m1 * c1 + m2 * c2)) / ln
        if o < best:
            best, axis = o, 3 + k
            n0, n1, n2 = m0 / ln, m1 / ln, m2 / ln
    if axis < 3:
        ck = c0 if axis == 0 else (c1 if axis == 1 else c2)
        uk = u0 if axis == 0 else (u1 if axis == 1 else u2)
        sg = 1.0 if ck >= 0.0 else -1.0
        if axis == 0:
            n0 = sg
        elif axis == 1:
            n1 = sg
        else:
            n2 = sg
        # B's deepest point along -n: an end, or the middle of the part over the face
        if 2.0 * h * abs(uk) > 1e-12 * scale:
            s = -h if sg * uk > 0.0 else h
        else:
            s = _seg_slab_middle(a0, a1, a2, c0, c1, c2, u0, u1, u2, h,
                                 axis != 0, axis != 1, axis != 2)
        p0 = min(a0, max(-a0, c0 + s * u0 + best * n0))
        p1 = min(a1, max(-a1, c1 + s * u1 + best * n1))
        p2 = min(a2, max(-a2, c2 + s * u2 + best * n2))
        return _finish_s(p0, p1, p2, -best, n0, n1, n2, ra, rb, out)
    if n0 * c0 + n1 * c1 + n2 * c2 < 0.0:
        n0, n1, n2 = -n0, -n1, -n2
    # the box edge along e_k that is A's support along n, and the segment's closest
    # point to its line: w = c - E, s = (b w_k - u.w) / (1 - b^2), t = w_k + s b
    k = axis - 3
    e0 = 0.0 if k == 0 else (a0 if n0 >= 0.0 else -a0)
    e1 = 0.0 if k == 1 else (a1 if n1 >= 0.0 else -a1)
    e2 = 0.0 if k == 2 else (a2 if n2 >= 0.0 else -a2)
    w0, w1, w2 = c0 - e0, c1 - e1, c2 - e2
    b = u0 if k == 0 else (u1 if k == 1 else u2)
    wk = w0 if k == 0 else (w1 if k == 1 else w2)
    s = (b * wk - (u0 * w0 + u1 * w1 + u2 * w2)) / (1.0 - b * b)
    t = wk + s * b
    ak = a0 if k == 0 else (a1 if k == 1 else a2)
    t = min(ak, max(-ak, t))
    if k == 0:
        e0 = t
    elif k == 1:
        e1 = t
    else:
        e2 = t
    return _finish_s(e0, e1, e2, -best, n0, n1, n2, ra, rb, out)


@njit_inline
def _sat_apart(a, gap, nx, ny, nz, ra, rb, out):
    """box_box_sat's answer for cores separated by ``gap`` (m) along the unit axis n
    (A -> B): the lower bound gap - ra - rb from A's support vertex along n."""
    _finish_s(a[0] if nx >= 0.0 else -a[0], a[1] if ny >= 0.0 else -a[1],
              a[2] if nz >= 0.0 else -a[2], gap, nx, ny, nz, ra, rb, out)
    return ST_NOT_RUN


@njit_kernel
def box_box_sat(sa, sb, r_ab, t_ab, out):
    """Penetration of two boxes whose cores overlap, by the separating-axis theorem.

    The minimum translation of two convex polytopes is along a face normal of their
    Minkowski difference: a face normal of A, of B, or a cross product of an edge of
    each (15 axes for boxes; Gottschalk, Lin, Manocha, "OBBTree", SIGGRAPH 1996, for the
    projected radii).  The smallest overlap over the 15 axes is the exact core depth;
    margins add exactly (the shapes are the cores grown by balls).  Face axes are
    preferred over edge axes within 1e-9 * scale.  Witness points: the deepest feature
    of the other box, taken to its nearest point within the face (face axes), or the
    closest points of the two edges (edge axes), with pb - pa == dist * normal.

    sa, sb  box shape tuples; r_ab (3, 3), t_ab (3,) pose of B in A's frame (m)
    out     float64[OUT_SIZE] written (A's frame).
    Returns the status when the cores overlap (exact).  When an axis separates the
    cores the exact distance needs GJK: it returns ST_NOT_RUN and writes a LOWER BOUND
    instead (the cores' gap along the first separating unit axis minus the radii, that
    axis as normal, A's support point along it as pa and pb = pa + bound * normal), which
    the dispatcher may keep for a pair farther than its distance cutoff.
    """
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, r_ab, t_ab = borrow_pose(sa, sb, r_ab, t_ab)
    out = borrow(out)
    a = sa[1]
    b = sb[1]
    ra = inflation(sa[0], a)
    rb = inflation(sb[0], b)
    scale = shape_scale(sa, sb)
    best = np.inf
    kind = -1
    ki = 0
    kj = 0
    # faces of A: axis e_i
    for i in range(3):
        rbl = b[0] * abs(r_ab[i, 0]) + b[1] * abs(r_ab[i, 1]) + b[2] * abs(r_ab[i, 2])
        ov = a[i] + rbl - abs(t_ab[i])
        if ov < 0.0:
            s = 1.0 if t_ab[i] >= 0.0 else -1.0
            return _sat_apart(a, -ov, s if i == 0 else 0.0, s if i == 1 else 0.0,
                              s if i == 2 else 0.0, ra, rb, out)
        if ov < best:
            best = ov
            kind = 0
            ki = i
    # faces of B: axis r_ab[:, j]
    for j in range(3):
        ral = a[0] * abs(r_ab[0, j]) + a[1] * abs(r_ab[1, j]) + a[2] * abs(r_ab[2, j])
        tl = t_ab[0] * r_ab[0, j] + t_ab[1] * r_ab[1, j] + t_ab[2] * r_ab[2, j]
        ov = ral + b[j] - abs(tl)
        if ov < 0.0:
            s = 1.0 if tl >= 0.0 else -1.0
            return _sat_apart(a, -ov, s * r_ab[0, j], s * r_ab[1, j], s * r_ab[2, j], ra,
                              rb, out)
        if ov < best:
            best = ov
            kind = 1
            kj = j
    face_best = best
    # edge pairs: axis e_i x r_ab[:, j]
    for i in range(3):
        for j in range(3):
            c0, c1, c2 = r_ab[0, j], r_ab[1, j], r_ab[2, j]
            if i == 0:
                l0, l1, l2 = 0.0, -c2, c1
            elif i == 1:
                l0, l1, l2 = c2, 0.0, -c0
            else:
                l0, l1, l2 = -c1, c0, 0.0
            ll = l0 * l0 + l1 * l1 + l2 * l2
            if not ll > 1e-12:
                continue     # parallel edges: covered by the face axes
            ln = math.sqrt(ll)
            ral = a[0] * abs(l0) + a[1] * abs(l1) + a[2] * abs(l2)
            rbl = 0.0
            for m in range(3):
                rbl += b[m] * abs(l0 * r_ab[0, m] + l1 * r_ab[1, m] + l2 * r_ab[2, m])
            tl = l0 * t_ab[0] + l1 * t_ab[1] + l2 * t_ab[2]
            ov = (ral + rbl - abs(tl)) / ln
            if ov < 0.0:
                s = 1.0 / ln if tl >= 0.0 else -1.0 / ln
                return _sat_apart(a, -ov, s * l0, s * l1, s * l2, ra, rb, out)
            if ov < best and ov < face_best - 1e-9 * scale:
                best = ov
                kind = 2
                ki = i
                kj = j
    depth = best
    if kind == 0:
        s = 1.0 if t_ab[ki] >= 0.0 else -1.0
        nx, ny, nz = 0.0, 0.0, 0.0
        if ki == 0:
            nx = s
        elif ki == 1:
            ny = s
        else:
            nz = s
        # B's deepest feature along -n; flat directions: nearest to A's face centre
        fx, fy, fz = s * a[0] * nx * s, s * a[1] * ny * s, s * a[2] * nz * s
        px, py, pz = _box_feature_point(b, r_ab, t_ab, -nx, -ny, -nz, fx, fy, fz)
        # A's witness: on A's face, nearest to B's point; then B's = A's - depth n
        qx, qy, qz = px + depth * nx, py + depth * ny, pz + depth * nz
        qx = min(a[0], max(-a[0], qx))
        qy = min(a[1], max(-a[1], qy))
        qz = min(a[2], max(-a[2], qz))
    elif kind == 1:
        tl = t_ab[0] * r_ab[0, kj] + t_ab[1] * r_ab[1, kj] + t_ab[2] * r_ab[2, kj]
        s = 1.0 if tl >= 0.0 else -1.0
        nx, ny, nz = s * r_ab[0, kj], s * r_ab[1, kj], s * r_ab[2, kj]
        # B's face centre (A's frame), A's deepest feature along +n nearest to it
        fx = t_ab[0] - s * b[kj] * r_ab[0, kj]
        fy = t_ab[1] - s * b[kj] * r_ab[1, kj]
        fz = t_ab[2] - s * b[kj] * r_ab[2, kj]
        ax_, ay_, az_ = _box_feature_point_a(a, nx, ny, nz, fx, fy, fz)
        # B's witness on B's face nearest to A's point (B's frame clamp), back to A
        px, py, pz = ax_ - depth * nx, ay_ - depth * ny, az_ - depth * nz
        dx, dy, dz = px - t_ab[0], py - t_ab[1], pz - t_ab[2]
        u0 = r_ab[0, 0] * dx + r_ab[1, 0] * dy + r_ab[2, 0] * dz
        u1 = r_ab[0, 1] * dx + r_ab[1, 1] * dy + r_ab[2, 1] * dz
        u2 = r_ab[0, 2] * dx + r_ab[1, 2] * dy + r_ab[2, 2] * dz
        u0 = min(b[0], max(-b[0], u0))
        u1 = min(b[1], max(-b[1], u1))
        u2 = min(b[2], max(-b[2], u2))
        px = r_ab[0, 0] * u0 + r_ab[0, 1] * u1 + r_ab[0, 2] * u2 + t_ab[0]
        py = r_ab[1, 0] * u0 + r_ab[1, 1] * u1 + r_ab[1, 2] * u2 + t_ab[1]
        pz = r_ab[2, 0] * u0 + r_ab[2, 1] * u1 + r_ab[2, 2] * u2 + t_ab[2]
        qx, qy, qz = px + depth * nx, py + depth * ny, pz + depth * nz
    else:
        c0, c1, c2 = r_ab[0, kj], r_ab[1, kj], r_ab[2, kj]
        if ki == 0:
            nx, ny, nz = 0.0, -c2, c1
        elif ki == 1:
            nx, ny, nz = c2, 0.0, -c0
        else:
            nx, ny, nz = -c1, c0, 0.0
        ln = math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / ln, ny / ln, nz / ln
        if nx * t_ab[0] + ny * t_ab[1] + nz * t_ab[2] < 0.0:
            nx, ny, nz = -nx, -ny, -nz
        # A's edge along e_ki through its support point along +n
        e0 = a[0] if nx >= 0.0 else -a[0]
        e1 = a[1] if ny >= 0.0 else -a[1]
        e2 = a[2] if nz >= 0.0 else -a[2]
        if ki == 0:
            e0 = 0.0
        elif ki == 1:
            e1 = 0.0
        else:
            e2 = 0.0
        # B's edge along r_ab[:, kj] through its support point along -n
        g0, g1, g2 = 0.0, 0.0, 0.0
        for m in range(3):
            if m != kj:
                mm = -(r_ab[0, m] * nx + r_ab[1, m] * ny + r_ab[2, m] * nz)
                bm = b[m] if mm >= 0.0 else -b[m]
                g0 += r_ab[0, m] * bm
                g1 += r_ab[1, m] * bm
                g2 += r_ab[2, m] * bm
        g0 += t_ab[0]
        g1 += t_ab[1]
        g2 += t_ab[2]
        # closest points of the lines e + s e_ki and g + u c (unit directions)
        w0, w1, w2 = e0 - g0, e1 - g1, e2 - g2
        bb = r_ab[ki, kj]
        dd = w0 if ki == 0 else (w1 if ki == 1 else w2)
        ee = c0 * w0 + c1 * w1 + c2 * w2
        den = 1.0 - bb * bb
        sp = (bb * ee - dd) / den
        up = (ee - bb * dd) / den
        sp = min(a[ki], max(-a[ki], sp))
        up = min(b[kj], max(-b[kj], up))
        qx, qy, qz = e0, e1, e2
        if ki == 0:
            qx += sp
        elif ki == 1:
            qy += sp
        else:
            qz += sp
        px, py, pz = g0 + up * c0, g1 + up * c1, g2 + up * c2
        # split any mismatch so that pb - pa == -depth n exactly (A's point kept)
        qx = meet(qx, px, -(depth * nx))[0]
        qy = meet(qy, py, -(depth * ny))[0]
        qz = meet(qz, pz, -(depth * nz))[0]
    dist = _finish_s(qx, qy, qz, -depth, nx, ny, nz, ra, rb, out)
    return classify(dist, scale)


@njit_kernel
def _box_feature_point(b, r_ab, t_ab, dx, dy, dz, fx, fy, fz):
    """Point (A's frame) of B's deepest feature along the A-frame direction d: the
    support vertex, with each coordinate whose direction component vanishes (a flat
    feature) taken nearest to the A-frame point f."""
    out0, out1, out2 = t_ab[0], t_ab[1], t_ab[2]
    for m in range(3):
        mm = r_ab[0, m] * dx + r_ab[1, m] * dy + r_ab[2, m] * dz
        if abs(mm) > 1e-12:
            bm = b[m] if mm > 0.0 else -b[m]
        else:
            fm = (r_ab[0, m] * (fx - t_ab[0]) + r_ab[1, m] * (fy - t_ab[1])
                  + r_ab[2, m] * (fz - t_ab[2]))
            bm = min(b[m], max(-b[m], fm))
        out0 += r_ab[0, m] * bm
        out1 += r_ab[1, m] * bm
        out2 += r_ab[2, m] * bm
    return out0, out1, out2


@njit_kernel
def _box_feature_point_a(a, dx, dy, dz, fx, fy, fz):
    """``_box_feature_point`` for A's own box (A's frame, no transform)."""
    if abs(dx) > 1e-12:
        x = a[0] if dx > 0.0 else -a[0]
    else:
        x = min(a[0], max(-a[0], fx))
    if abs(dy) > 1e-12:
        y = a[1] if dy > 0.0 else -a[1]
    else:
        y = min(a[1], max(-a[1], fy))
    if abs(dz) > 1e-12:
        z = a[2] if dz > 0.0 else -a[2]
    else:
        z = min(a[2], max(-a[2], fz))
    return x, y, z


@njit_inline
def closed_form_ordered(sa, sb, verts, r_ab, t_ab, out):
    """Signed distance (m) of a pair in canonical order that has a closed form (the
    dispatcher checks which); writes ``out`` as ``collide_analytic`` does."""
    ran, dist = _ordered(sa, sb, verts, r_ab, t_ab, out)
    return dist


@njit_kernel
def collide_analytic(sa, sb, verts, r_ab, t_ab, out):
    """Exact closed-form collision of a supported pair; ST_NOT_RUN otherwise.

    sa, sb  shape tuples (code int64, prm float64[8], v0 int64, vn int64)
    verts   float64 (M, 3) convex vertices (body frames), used by plane-vs-convex
    r_ab    float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    out     float64[OUT_SIZE]: signed distance (m), unit normal A -> B, pa, pb (A's
            frame, pb - pa = dist * normal), iterations = 1, method = M_ANALYTIC
    Returns the status code under the touching rule (scale = sum of bounding radii).
    Either order of a supported pair is accepted.
    """
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    out = borrow(out)
    if sa[0] <= sb[0]:
        ran, dist = _ordered(sa, sb, verts, r_ab, t_ab, out)
        if not ran:
            return ST_NOT_RUN
        return classify(dist, shape_scale(sa, sb))
    # swapped: solve (B, A) in B's frame, then map back and flip the normal
    r_ba = np.ascontiguousarray(r_ab.T)
    t_ba = -_mv(r_ba, t_ab)
    tmp = np.empty(out.shape[0])
    ran, dist = _ordered(sb, sa, verts, r_ba, t_ba, tmp)
    if not ran:
        return ST_NOT_RUN
    n = -_mv(r_ab, tmp[OUT_NORMAL:OUT_NORMAL + 3])
    pa = _mv(r_ab, tmp[OUT_PB:OUT_PB + 3]) + t_ab
    pb = _mv(r_ab, tmp[OUT_PA:OUT_PA + 3]) + t_ab
    out[OUT_DIST] = dist
    for i in range(3):
        out[OUT_NORMAL + i] = n[i]
        out[OUT_PA + i] = pa[i]
        out[OUT_PB + i] = pb[i]
    out[OUT_ITERS] = tmp[OUT_ITERS]
    out[OUT_METHOD] = M_ANALYTIC
    return classify(dist, shape_scale(sa, sb))
