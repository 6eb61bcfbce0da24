"""The closest point to the origin of a simplex of up to four points (GJK's
sub-problem), for gjk_epa's GJK and EPA and for ellipsoid_convex's GJK in an ellipsoid's unit-ball
frame."""
import math

import numpy as np

from .constants import BARY_SLACK, GJK_FLAT_TOL, SLIVER_TOL
from .jit import njit_inline, njit_kernel


@njit_kernel
def _tri_closest(a0, a1, a2, b0, b1, b2, c0, c1, c2):
    """Barycentric coordinates (l0, l1, l2) of the point of the triangle a, b, c (given
    by coordinates, so that no array views are made) closest to the origin
    (Voronoi-region tests), and its squared norm: returns (l0, l1, l2, dd)."""
    abx, aby, abz = b0 - a0, b1 - a1, b2 - a2
    acx, acy, acz = c0 - a0, c1 - a1, c2 - a2
    d1 = -(abx * a0 + aby * a1 + abz * a2)
    d2 = -(acx * a0 + acy * a1 + acz * a2)
    l0, l1, l2 = 1.0, 0.0, 0.0
    done = False
    if d1 <= 0.0 and d2 <= 0.0:
        done = True
    if not done:
        d3 = -(abx * b0 + aby * b1 + abz * b2)
        d4 = -(acx * b0 + acy * b1 + acz * b2)
        d5 = -(abx * c0 + aby * c1 + abz * c2)
        d6 = -(acx * c0 + acy * c1 + acz * c2)
        vc = d1 * d4 - d3 * d2
        vb = d5 * d2 - d1 * d6
        va = d3 * d6 - d5 * d4
        if d3 >= 0.0 and d4 <= d3:
            l0, l1, l2 = 0.0, 1.0, 0.0
        elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
            t = d1 / (d1 - d3)
            l0, l1, l2 = 1.0 - t, t, 0.0
        elif d6 >= 0.0 and d5 <= d6:
            l0, l1, l2 = 0.0, 0.0, 1.0
        elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
            t = d2 / (d2 - d6)
            l0, l1, l2 = 1.0 - t, 0.0, t
        elif va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
            t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
            l0, l1, l2 = 0.0, 1.0 - t, t
        else:
            # inside the face: barycentric weights from the projection p of the origin
            # and cross products (conditioned like 1/sin of the thinnest angle, unlike
            # the ratio va : vb : vc of squared areas)
            nx = aby * acz - abz * acy
            ny = abz * acx - abx * acz
            nz = abx * acy - aby * acx
            nn = nx * nx + ny * ny + nz * nz
            den = nn
            if nn > 0.0:
                s = (nx * a0 + ny * a1 + nz * a2) / nn
                px, py, pz = s * nx, s * ny, s * nz
                bx, by, bz = b0 - px, b1 - py, b2 - pz
                cx, cy, cz = c0 - px, c1 - py, c2 - pz
                ax_, ay_, az_ = a0 - px, a1 - py, a2 - pz
                l0 = (nx * (by * cz - bz * cy) + ny * (bz * cx - bx * cz)
                      + nz * (bx * cy - by * cx)) / nn
                l1 = (nx * (cy * az_ - cz * ay_) + ny * (cz * ax_ - cx * az_)
                      + nz * (cx * ay_ - cy * ax_)) / nn
                l2 = 1.0 - l0 - l1
            ok = (nn > 0.0 and min(l0, min(l1, l2)) >= -BARY_SLACK
                  and max(l0, max(l1, l2)) <= 1.0 + BARY_SLACK)
            if ok:
                l0 = max(l0, 0.0)
                l1 = max(l1, 0.0)
                l2 = max(l2, 0.0)
                sl = l0 + l1 + l2
                l0 /= sl
                l1 /= sl
                l2 /= sl
            else:  # (nearly) degenerate triangle: best of its three edges
                best = np.inf
                for e in range(3):
                    if e == 0:
                        p0, p1, p2, q0, q1, q2 = a0, a1, a2, b0, b1, b2
                    elif e == 1:
                        p0, p1, p2, q0, q1, q2 = b0, b1, b2, c0, c1, c2
                    else:
                        p0, p1, p2, q0, q1, q2 = a0, a1, a2, c0, c1, c2
                    ex, ey, ez = q0 - p0, q1 - p1, q2 - p2
                    ee = ex * ex + ey * ey + ez * ez
                    t = 0.0
                    if ee > 0.0:
                        t = -(ex * p0 + ey * p1 + ez * p2) / ee
                        t = min(1.0, max(0.0, t))
                    x = p0 + t * ex
                    y = p1 + t * ey
                    z = p2 + t * ez
                    dd = x * x + y * y + z * z
                    if dd < best:
                        best = dd
                        if e == 0:
                            l0, l1, l2 = 1.0 - t, t, 0.0
                        elif e == 1:
                            l0, l1, l2 = 0.0, 1.0 - t, t
                        else:
                            l0, l1, l2 = 1.0 - t, 0.0, t
    x = l0 * a0 + l1 * b0 + l2 * c0
    y = l0 * a1 + l1 * b1 + l2 * c1
    z = l0 * a2 + l1 * b2 + l2 * c2
    return l0, l1, l2, x * x + y * y + z * z


@njit_inline
def _opposite_face(m):
    """Vertex indices (i, j, k) of the tetrahedron face opposite vertex m."""
    if m == 0:
        return 1, 2, 3
    if m == 1:
        return 0, 2, 3
    if m == 2:
        return 0, 1, 3
    return 0, 1, 2


@njit_inline
def _face_sides(W, m):
    """The face (i, j, k) of the tetrahedron W[:4] opposite vertex m: (i, its normal
    n = (W[j] - W[i]) x (W[k] - W[i]), s_o = n . (0 - W[i]), s_m = n . (W[m] - W[i])),
    the last two six times the signed volumes of the face with the origin and with
    W[m]."""
    i, j, k = _opposite_face(m)
    ux, uy, uz = W[j, 0] - W[i, 0], W[j, 1] - W[i, 1], W[j, 2] - W[i, 2]
    wx, wy, wz = W[k, 0] - W[i, 0], W[k, 1] - W[i, 1], W[k, 2] - W[i, 2]
    nx = uy * wz - uz * wy
    ny = uz * wx - ux * wz
    nz = ux * wy - uy * wx
    s_o = -(nx * W[i, 0] + ny * W[i, 1] + nz * W[i, 2])
    s_m = nx * (W[m, 0] - W[i, 0]) + ny * (W[m, 1] - W[i, 1]) + nz * (W[m, 2] - W[i, 2])
    return i, nx, ny, nz, s_o, s_m


@njit_inline
def _closest_simplex(W, WA, WB, n, lam, v, l3, vol):
    """Closest point ``v`` (3,) to the origin of the simplex ``W[:n]`` (n in 1..4, A's
    frame).  Writes barycentric weights into ``lam`` and compacts W, WA, WB to the
    vertices of the smallest sub-simplex holding v.  Returns the new vertex count; 4
    means the origin is inside the tetrahedron.  l3 (3,), vol (4,): scratch."""
    for i in range(4):
        lam[i] = 0.0
    if n == 1:
        lam[0] = 1.0
    elif n == 2:
        ex, ey, ez = W[1, 0] - W[0, 0], W[1, 1] - W[0, 1], W[1, 2] - W[0, 2]
        ee = ex * ex + ey * ey + ez * ez
        t = 0.0
        if ee > 0.0:
            t = -(ex * W[0, 0] + ey * W[0, 1] + ez * W[0, 2]) / ee
            t = min(1.0, max(0.0, t))
        lam[0] = 1.0 - t
        lam[1] = t
    elif n == 3:
        l0, l1, l2, dd = _tri_closest(W[0, 0], W[0, 1], W[0, 2], W[1, 0], W[1, 1], W[1, 2],
                                      W[2, 0], W[2, 1], W[2, 2])
        lam[0], lam[1], lam[2] = l0, l1, l2
    else:
        # faces (i, j, k) opposite vertex m
        inside = True
        best = np.inf
        # a flat tetrahedron (6 |volume| <= GJK_FLAT_TOL * longest edge^3) never holds
        # the origin: its face orientations are rounding noise (a flat needle of three
        # nearly equal support points once passed the face tests below with the origin
        # 0.13 m off its plane; regression test test_gjk_flat_tetrahedron_not_inside)
        lmax2 = 0.0
        for i in range(3):
            for j in range(i + 1, 4):
                lmax2 = max(lmax2, (W[j, 0] - W[i, 0]) ** 2 + (W[j, 1] - W[i, 1]) ** 2
                            + (W[j, 2] - W[i, 2]) ** 2)
        e1x, e1y, e1z = W[1, 0] - W[0, 0], W[1, 1] - W[0, 1], W[1, 2] - W[0, 2]
        e2x, e2y, e2z = W[2, 0] - W[0, 0], W[2, 1] - W[0, 1], W[2, 2] - W[0, 2]
        e3x, e3y, e3z = W[3, 0] - W[0, 0], W[3, 1] - W[0, 1], W[3, 2] - W[0, 2]
        vol6 = (e1x * (e2y * e3z - e2z * e3y) + e1y * (e2z * e3x - e2x * e3z)
                + e1z * (e2x * e3y - e2y * e3x))
        if not abs(vol6) > GJK_FLAT_TOL * lmax2 * math.sqrt(lmax2):
            inside = False
        for m in range(4):
            i, nx, ny, nz, s_o, s_m = _face_sides(W, m)
            # the origin is inside iff it is on vertex m's side of every face; when it
            # is not, the closest point is the best over the faces holding the new vertex
            # (testing each, not only those 'facing' the origin, is robust to slivers)
            # a sliver (relative height of m over the face < 1e-10) never counts as
            # holding the origin
            hm = math.sqrt((nx * nx + ny * ny + nz * nz)
                           * ((W[m, 0] - W[i, 0]) ** 2 + (W[m, 1] - W[i, 1]) ** 2
                              + (W[m, 2] - W[i, 2]) ** 2))
            if s_o * s_m < 0.0 or not abs(s_m) > SLIVER_TOL * hm:
                inside = False
        if not inside:
            # the closest point lies on a face holding the new vertex W[3]: the face
            # opposite it is the previous triangle, whose closest point (|v|^2 of the
            # last step) counts as no progress in _gjk anyway
            for m in range(3):
                i, j, k = _opposite_face(m)
                l0, l1, l2, dd = _tri_closest(W[i, 0], W[i, 1], W[i, 2], W[j, 0], W[j, 1],
                                              W[j, 2], W[k, 0], W[k, 1], W[k, 2])
                if dd < best:
                    best = dd
                    for q in range(4):
                        lam[q] = 0.0
                    lam[i], lam[j], lam[k] = l0, l1, l2
        else:
            # barycentric weights from signed volumes
            tot = 0.0
            for m in range(4):
                # volume of (origin, i, j, k) vs (m, i, j, k)
                _, _, _, _, s_o, s_m = _face_sides(W, m)
                vol[m] = s_o / s_m
                tot += vol[m]
            for m in range(4):
                lam[m] = vol[m] / tot if tot > 0.0 else 0.25
    # closest point
    for c in range(3):
        v[c] = 0.0
        for i in range(n):
            v[c] += lam[i] * W[i, c]
    # compact
    k = 0
    for i in range(n):
        if lam[i] > 0.0:
            if k != i:
                for c in range(3):
                    W[k, c] = W[i, c]
                    WA[k, c] = WA[i, c]
                    WB[k, c] = WB[i, c]
                lam[k] = lam[i]
            k += 1
    for i in range(k, 4):
        lam[i] = 0.0
    if k == 0:  # cannot happen with valid weights; keep the first vertex
        lam[0] = 1.0
        k = 1
    return k
