"""What every closed form ends with: the closest points of two *cores* made the
result row (``_finish_s``, ``_point_point_s``), the touching rule's status
(``classify``), and the small frame helpers the closed forms share (``_origin_in_b``,
``_b_to_a``, ``_closest_on_segment_s``).

Every pair is reduced to the closest points of two *cores* (a point, a segment, a box;
kernels/geometry.py) followed by subtracting the two inflation radii, which is exact
because a shape with margin is its core grown by a ball (Minkowski sum):

    signed distance = core distance - (r_a + r_b),   normal = core direction A -> B.

When the cores overlap (sphere centre inside the core box; capsule axes that cross) the
core distance is signed (negative) and the normal is the minimum-translation direction
of the cores, so the result stays exact (sphere-box: nearest face; crossing segments:
the common perpendicular, since their Minkowski difference is a flat parallelogram).
"""
import math

from ..constants import (M_ANALYTIC, OUT_DIST, OUT_ITERS, OUT_METHOD, OUT_NORMAL, OUT_PA, OUT_PB,
                         ST_PENETRATING, ST_SEPARATED, ST_TOUCHING, TOUCH_TOL)
from ..jit import njit_inline, njit_kernel


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
