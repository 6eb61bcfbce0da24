"""The closed form of a box A and a capsule B in A's frame (``collide_box_capsule``):
the exact distance of the segment to the box when the cores are apart, the
separating-axis depth over the box's face normals and the cross products of the
segment with its axes when they overlap (the method: collide_box_capsule's
docstring).  The result row: core_distance.py.
"""
import math

from ..constants import PARALLEL_SIN, SUPPORT_TIE
from ..geometry import shape_scale
from ..jit import njit_inline, njit_kernel
from .core_distance import _finish_s


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
def collide_box_capsule(sa, sb, r_ab, t_ab, ra, rb, out):
    """A = box (half extents a), B = capsule (segment c + s u, |s| <= h, in A's frame).

    Apart: the squared distance from the segment to the box is a convex, continuously
    differentiable, piecewise quadratic function of s whose kinks are where the
    segment crosses a face plane (x_i = +-a_i).  Its slope is monotone, so the six
    kinks, tested by the sign of the slope there, bracket the minimum in one smooth
    piece, where the slope is linear: one interpolation gives the exact minimiser.

    Overlapping cores: the Minkowski difference of a box and a segment is a polytope
    whose face normals are the box's face normals e_k and the cross products u x e_k,
    so the smallest overlap over those six axes is the exact core depth (the
    separating-axis theorem, as collide_box_box).  Witnesses: on a face axis, the deepest
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
    if core > SUPPORT_TIE * scale:
        # lying flat (parallel to every face plane it is beyond): the distance is the
        # same along the part of the segment over the box; take its middle, so the
        # witness does not jump between the ends
        flat = 2.0 * h * max(abs(u0) if d0 != 0.0 else 0.0, abs(u1) if d1 != 0.0 else 0.0,
                             abs(u2) if d2 != 0.0 else 0.0) <= SUPPORT_TIE * scale
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
        if ln < PARALLEL_SIN:
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
        if 2.0 * h * abs(uk) > SUPPORT_TIE * scale:
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
