"""The separating-axis depth of two boxes whose cores overlap (``collide_box_box``, A's
frame): exact when the cores overlap, else a lower bound on their gap, which the
narrow phase's auto method keeps for pairs beyond its distance cutoff and otherwise
replaces by GJK's exact distance (kernels/narrowphase.py, ``_box_box``).  The method:
collide_box_box's docstring.
"""
import math

import numpy as np

from ..constants import NO_DIRECTION, SAT_EDGE_BIAS, ST_NOT_RUN
from ..geometry import borrow_pose, inflation, meet, shape_scale
from ..jit import borrow, njit_inline, njit_kernel
from .core_distance import _finish_s, classify


@njit_inline
def _sat_apart(a, gap, nx, ny, nz, ra, rb, out):
    """collide_box_box's answer for cores separated by ``gap`` (m) along the unit axis n
    (A -> B): the lower bound gap - ra - rb from A's support vertex along n."""
    _finish_s(a[0] if nx >= 0.0 else -a[0], a[1] if ny >= 0.0 else -a[1],
              a[2] if nz >= 0.0 else -a[2], gap, nx, ny, nz, ra, rb, out)
    return ST_NOT_RUN


@njit_kernel
def collide_box_box(sa, sb, r_ab, t_ab, out):
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
            if not ll > NO_DIRECTION:
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
            if ov < best and ov < face_best - SAT_EDGE_BIAS * scale:
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
        if abs(mm) > NO_DIRECTION:
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
    if abs(dx) > NO_DIRECTION:
        x = a[0] if dx > 0.0 else -a[0]
    else:
        x = min(a[0], max(-a[0], fx))
    if abs(dy) > NO_DIRECTION:
        y = a[1] if dy > 0.0 else -a[1]
    else:
        y = min(a[1], max(-a[1], fy))
    if abs(dz) > NO_DIRECTION:
        z = a[2] if dz > 0.0 else -a[2]
    else:
        z = min(a[2], max(-a[2], fz))
    return x, y, z
