"""Closed forms of two capsules: in A's frame (``collide_capsule_capsule``) and from the
world poses (``capsule_capsule_world``), both by ``_segments``, the closest points of
the two core segments grown by the radii.  The result row: core_distance.py.

Segment-segment closest points follow the classic clamped parametric solution (e.g.
Ericson, *Real-Time Collision Detection*, 2005, sec. 5.1.9), with the parallel case
handled by clamping an endpoint projection.
"""
import math

from ..constants import OUT_PA, OUT_PB, P_MARGIN, SEGMENT_MEET, SEGMENT_SIN2
from ..geometry import quat_entries, shape_scale
from ..jit import njit_inline, njit_kernel
from .core_distance import _closest_on_segment_s, _finish_s, _point_point_s


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
        if den > SEGMENT_SIN2 * a * e:
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
    if a > 0.0 and e > 0.0 and den <= SEGMENT_SIN2 * a * e:
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
    skew = den > SEGMENT_SIN2 * a * e and 0.0 < s < 1.0 and 0.0 < t < 1.0
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
    if den > SEGMENT_SIN2 * a * e:
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
def collide_capsule_capsule(sa, sb, r_ab, t_ab, ra, rb, out):
    """Two capsules in A's frame (A's segment on its z axis): _segments."""
    ha = sa[1][1]
    hb = sb[1][1]
    p2x, p2y, p2z = t_ab[0] + hb * r_ab[0, 2], t_ab[1] + hb * r_ab[1, 2], t_ab[2] + hb * r_ab[2, 2]
    q2x, q2y, q2z = t_ab[0] - hb * r_ab[0, 2], t_ab[1] - hb * r_ab[1, 2], t_ab[2] - hb * r_ab[2, 2]
    return _segments(0.0, 0.0, ha, 0.0, 0.0, -2.0 * ha, p2x, p2y, p2z, q2x, q2y, q2z,
                     t_ab[0], t_ab[1], t_ab[2], 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, ra, rb,
                     SEGMENT_MEET * shape_scale(sa, sb), out)


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
                     prm_b[0] + prm_b[P_MARGIN], SEGMENT_MEET * scale, out)
    for c in range(3):
        out[OUT_PA + c] += pos_a[c]
        out[OUT_PB + c] += pos_a[c]
    return dist
