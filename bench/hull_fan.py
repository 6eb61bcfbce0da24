"""A prototype, not used by the product: the exact depth of an ellipsoid and a convex hull
from the hull's normal fan, against GJK/EPA on the same deep pairs (session 41).

Why: deep pairs are 92% of the ellipsoid-convex row's time (bench/regimes.py), and EPA
needs ~23 supports on them whatever its per-step cost.  The idea, in A's (the
ellipsoid's) frame: f(n) = h_E(n) + h_B(-n) over unit n, and min f = -signed distance.
B's normal fan splits the sphere into its faces' normals (points), its edges' arcs and
its vertices' cones; the minimiser lies inside one of them and is a critical point of f
restricted to it.  So the candidates are:

  * each face's normal: f there (one square root);
  * each edge's arc: the 2-D problem of E projected along the edge and the edge's point,
    whose critical points are the feet of the normals from the point to the ellipse;
  * each vertex's cone: the 3-D problem of E and the vertex (the same, one dimension up).

Both are roots t of the secular equation sum_i w_i / (l_i + t)^2 = 1 (l_i the squared
semi-axes, w_i = l_i P_i^2 for the point P in the ellipsoid's axes); a root gives the
normal N_i = P_i / (l_i + t) and the value -t |N|, kept only if B's support along -n is
attained at that edge or vertex.  Only the root right of the least pole and the two
between the two least poles can be local minima (the Hessian of the distance on the
surface is I + t D^-1 on the tangent plane), so the others are never searched.

Pruning (every bound rigorous; U the best value so far):
  * an edge: g >= max of its tangent planes at the arc's ends, taken over the chord
    between the ends (|x| <= 1 there, g homogeneous), a closed form per edge; where
    that fails, the same maximum over the arc itself (each plane on its side of their
    crossing, a sinusoid's least value over an arc);
  * a vertex's foot right of the pole: A - B holds E - u for every vertex u, so the
    depth is at least u's depth in E when u is inside: at least (1 - rho_u) a_min (the
    ball about u inside E; rho the ellipsoid norm) and exactly the foot's distance
    once solved.  A vertex's own foot is at most (1 - rho) a_max away, so it is
    searched only if that reaches the largest such bound L, and kept only if >= L;
  * the roots between the poles: their value is at least l0 / sqrt(l2) (the rolling
    radius), at least |P_0| l1 / (l1 - l0) (the foot lies on the far side along the
    least axis), and for a vertex outside E at least 2 r_roll + (rho - 1) a_min (the
    inner normal crosses the rolling ball, then reaches the vertex); a two-term bound
    of the secular equation (the point outside the evolute) shows there are none.

The pruning assumes the pair penetrates (outside vertices' negative feet are skipped), so
the kernel proves it: a hull vertex inside E or E's centre inside B, else the midpoint
of the answer's witness points inside both (checked at the end: the answer found under
the assumption is then exact); else it returns undecided, as it does on near-degenerate
input (equal semi-axes, a point on an axis plane, a search that fails).  A kernel in the product
would hand those to GJK/EPA, as boxell.py does.

    PYTHONPATH=. .venv/bin/python bench/hull_fan.py [--n 1000]

Prints: decided pairs, the largest depth and normal differences against the saved GJK/EPA
reference (``bench/deep_pairs.py --save ellipsoid-convex`` writes it), edge and vertex
solves per pair, the time per pair of the prototype (one thread, a numba loop over the
pairs; the hulls' faces and edges are data, as a table would hold them), of the batch
kernel's GJK/EPA on the same pairs, and of the two together (GJK/EPA on the undecided
pairs), alternated round by round.
"""
import argparse
import collections
import itertools
import math
import os
import sys
import time

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.common import relative_poses  # noqa: E402
from bench.deep_pairs import load_cases  # noqa: E402
from bench.regimes import subset  # noqa: E402
from mkcollision_ros.kernels.constants import M_GJK_EPA, OUT_SIZE  # noqa: E402
from mkcollision_ros.kernels.narrowphase import collide_batch  # noqa: E402

ITERS = 60          # cap of every 1-D root search
ROOT_RTOL = 1e-13   # a root's last Newton step, relative (the depth needs ~1e-10)
DMIN_RTOL = 1e-12   # the search for phi's minimum between two poles gives up here


@numba.njit(cache=False)
def _phi(l0, l1, l2, w0, w1, w2, t):
    a, b, c = 1.0 / (l0 + t), 1.0 / (l1 + t), 1.0 / (l2 + t)
    a2, b2, c2 = w0 * a * a, w1 * b * b, w2 * c * c
    return (a2 + b2 + c2 - 1.0, -2.0 * (a2 * a + b2 * b + c2 * c),
            6.0 * (a2 * a * a + b2 * b * b + c2 * c * c))


@numba.njit(cache=False)
def _newton_from(l0, l1, l2, w0, w1, w2, t):
    """Newton's method on phi from t with phi(t) >= 0 on a convex, monotone branch of
    phi: the steps move toward the root and never pass it (no bracket needed)."""
    for _ in range(ITERS):
        r = _phi(l0, l1, l2, w0, w1, w2, t)
        if not r[0] > 0.0:
            return t, True
        tn = t - r[0] / r[1]
        if abs(tn - t) <= ROOT_RTOL * (abs(t) + l0):
            return tn, True
        t = tn
    return t, False


@numba.njit(cache=False)
def _root_right(l0, l1, l2, w0, w1, w2):
    """The root of sum w_i / (l_i + t)^2 = 1 right of the pole -l0 (l0 the least):
    phi is convex and decreasing there, and >= 0 at -l0 + sqrt(w0) (its first term
    alone is 1 there)."""
    return _newton_from(l0, l1, l2, w0, w1, w2, -l0 + math.sqrt(w0))


@numba.njit(cache=False)
def _roots_mid(l0, l1, l2, w0, w1, w2, out):
    """The roots of phi between the poles -l1 and -l0 (phi convex, +inf at both):
    0 or 2, in out[0:2]; returns the count, -1 if a search failed."""
    gap = l1 - l0
    # with the third term dropped phi is no larger, and that one's least value is
    # ((w0^1/3 + w1^1/3)^3 / gap^2 - 1): no root if it is > 0 ((.)^3 >= w0 + w1 first)
    if w0 + w1 > gap * gap:
        return 0
    c0, c1 = np.cbrt(w0), np.cbrt(w1)
    if (c0 + c1) ** 3 > gap * gap * (1.0 + 1e-9):
        return 0
    # Newton's method on phi' (increasing) from the two-term minimiser, in the bracket,
    # until a point with phi <= 0 (then two roots) or a proof that phi > 0 (none)
    lo = -l1 + 1e-9 * gap
    hi = -l0 - 1e-9 * gap
    t = -l0 - gap * c0 / (c0 + c1)
    for _ in range(ITERS):
        r = _phi(l0, l1, l2, w0, w1, w2, t)
        if not r[0] > 0.0:
            break
        if r[1] < 0.0:
            lo = t
        else:
            hi = t
        # phi convex: its least value (in [lo, hi]) is >= phi(t) - |phi'(t)| (hi - lo)
        if r[0] - abs(r[1]) * (hi - lo) > 0.0:
            return 0
        tn = t - r[1] / r[2]
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= DMIN_RTOL * abs(t):
            return -1                   # a minimum too close to 0 to tell
        t = tn
    else:
        return -1                       # neither found
    # phi(t) <= 0: t lies between the roots.  phi >= 0 at s0 = -l1 + sqrt(w1) and at
    # s1 = -l0 - sqrt(w0) (a term alone is 1 there); if s0 < t < s1, they lie beyond
    # the roots, and phi, convex, is monotone from each to its root
    s0 = -l1 + math.sqrt(w1)
    s1 = -l0 - math.sqrt(w0)
    if not (s0 < t < s1):
        return -1
    out[0], ok = _newton_from(l0, l1, l2, w0, w1, w2, s0)
    if not ok:
        return -1
    out[1], ok = _newton_from(l0, l1, l2, w0, w1, w2, s1)
    if not ok:
        return -1
    return 2


@numba.njit(cache=False)
def _f_at(V, nv, nx, ny, nz):
    """h_B(-n): the largest -n . v over the first nv vertices V (A's frame)."""
    best = -np.inf
    for u in range(nv):
        s = -(nx * V[u, 0] + ny * V[u, 1] + nz * V[u, 2])
        if s > best:
            best = s
    return best


@numba.njit(cache=False)
def _sinus_min(wx, wy, wz, px, py, pz, qx, qy, qz):
    """min over the great-circle arc from unit p to unit q (angle < pi) of w . n."""
    a = wx * px + wy * py + wz * pz
    b = wx * qx + wy * qy + wz * qz
    m = min(a, b)
    # the arc's plane normal c = p x q; -w's projection in the arc?
    cx, cy, cz = py * qz - pz * qy, pz * qx - px * qz, px * qy - py * qx
    cc = cx * cx + cy * cy + cz * cz
    if not cc > 0.0:
        return m
    k = (wx * cx + wy * cy + wz * cz) / cc
    ux, uy, uz = -(wx - k * cx), -(wy - k * cy), -(wz - k * cz)
    uu = math.sqrt(ux * ux + uy * uy + uz * uz)
    if not uu > 0.0:
        return m
    # u in the arc: p x u and u x q along c
    s1 = cx * (py * uz - pz * uy) + cy * (pz * ux - px * uz) + cz * (px * uy - py * ux)
    s2 = cx * (uy * qz - uz * qy) + cy * (uz * qx - ux * qz) + cz * (ux * qy - uy * qx)
    if s1 >= 0.0 and s2 >= 0.0:
        return min(m, -uu)
    return m


@numba.njit(cache=False)
def ellipsoid_hull_depth(radii, R, t, pts, fn, fo, edges, V, FS, out, res, scale):
    """min f for the ellipsoid of ``radii`` (A, at the origin of its frame) and the hull
    of ``pts`` (B's frame; faces ``fn``, ``fo``, edges ``edges`` of hull_data) posed by
    R, t in A's frame: res = [-min f, n, pa, pb] (as gjk_epa's rows); returns (decided,
    edge solves, vertex solves).  Scratch: V (>= nv, 3) the vertices in A's frame, FS
    (>= nf, 8) per face E's support point at n = -m, f(n), n and B's offset; out (8,)
    roots."""
    a0, a1, a2 = radii[0] ** 2, radii[1] ** 2, radii[2] ** 2
    amin = math.sqrt(min(a0, min(a1, a2)))
    amax = math.sqrt(max(a0, max(a1, a2)))
    rroll = amin * amin / amax
    nv = pts.shape[0]
    for u in range(nv):
        for c in range(3):
            V[u, c] = R[c, 0] * pts[u, 0] + R[c, 1] * pts[u, 1] + R[c, 2] * pts[u, 2] + t[c]
    tol = 1e-12 * scale
    U = np.inf
    bx = by = bz = 0.0
    cin = np.inf        # the least offset of B's face planes from E's centre
    for f in range(fn.shape[0]):
        mx = R[0, 0] * fn[f, 0] + R[0, 1] * fn[f, 1] + R[0, 2] * fn[f, 2]
        my = R[1, 0] * fn[f, 0] + R[1, 1] * fn[f, 1] + R[1, 2] * fn[f, 2]
        mz = R[2, 0] * fn[f, 0] + R[2, 1] * fn[f, 1] + R[2, 2] * fn[f, 2]
        hA = math.sqrt(a0 * mx * mx + a1 * my * my + a2 * mz * mz)
        off = fo[f] + mx * t[0] + my * t[1] + mz * t[2]
        cin = min(cin, off)
        val = hA + off
        # n = -m; E's support point there, -a m / hA
        ih = 1.0 / hA
        FS[f, 0], FS[f, 1], FS[f, 2], FS[f, 3] = -a0 * mx * ih, -a1 * my * ih, -a2 * mz * ih, val
        FS[f, 4], FS[f, 5], FS[f, 6], FS[f, 7] = -mx, -my, -mz, off
        if val < U:
            U = val
            bx, by, bz = -mx, -my, -mz
    # L: a lower bound on the depth, the largest (1 - rho) a_min of an inside vertex,
    # raised to a vertex's exact depth in E (its foot right of the pole) once found
    L = 0.0
    i0_, i1_, i2_ = 1.0 / a0, 1.0 / a1, 1.0 / a2
    for u in range(nv):
        rho = math.sqrt(V[u, 0] * V[u, 0] * i0_ + V[u, 1] * V[u, 1] * i1_
                        + V[u, 2] * V[u, 2] * i2_)
        if rho < 1.0:
            L = max(L, (1.0 - rho) * amin)
    # the pruning below skips the negative feet, so the pair must be proved to overlap:
    # a hull vertex inside E (L > 0) or E's centre inside B now, else the midpoint of
    # the answer's witnesses in both at the end
    proved = L > 0.0 or cin > 0.0
    n_e = 0
    n_v = 0
    for e in range(edges.shape[0]):
        ia, ib, f1, f2 = edges[e, 0], edges[e, 1], edges[e, 2], edges[e, 3]
        vx, vy, vz = V[ia, 0], V[ia, 1], V[ia, 2]
        # the arc's ends n1 = -m1, n2 = -m2, f there, and E's support points there
        n1x, n1y, n1z = FS[f1, 4], FS[f1, 5], FS[f1, 6]
        n2x, n2y, n2z = FS[f2, 4], FS[f2, 5], FS[f2, 6]
        g1, g2 = FS[f1, 3], FS[f2, 3]
        s1x, s1y, s1z = FS[f1, 0] - vx, FS[f1, 1] - vy, FS[f1, 2] - vz
        s2x, s2y, s2z = FS[f2, 0] - vx, FS[f2, 1] - vy, FS[f2, 2] - vz
        # tangent planes of g at the arc's ends (s_i . n), over the chord (|x| <= 1)
        c12 = s1x * n2x + s1y * n2y + s1z * n2z
        c21 = s2x * n1x + s2y * n1y + s2z * n1z
        den = (g1 - c21) + (g2 - c12)
        if den > 0.0:
            al = (g2 - c12) / den
            lb = al * g1 + (1.0 - al) * c12
        else:
            lb = min(g1, g2)
        if lb >= U - tol:
            continue
        # tighter: max of the two tangent planes over the arc itself, each on its side
        # of their crossing (a sinusoid's least value over an arc)
        d1, d2 = g1 - c21, c12 - g2
        if d1 >= 0.0 and d2 <= 0.0 and d1 - d2 > 0.0:
            cx, cy, cz = d1 * n2x - d2 * n1x, d1 * n2y - d2 * n1y, d1 * n2z - d2 * n1z
            cn = math.sqrt(cx * cx + cy * cy + cz * cz)
            cx, cy, cz = cx / cn, cy / cn, cz / cn
            lb = min(_sinus_min(s1x, s1y, s1z, n1x, n1y, n1z, cx, cy, cz),
                     _sinus_min(s2x, s2y, s2z, cx, cy, cz, n2x, n2y, n2z))
            if lb >= U - tol:
                continue
        n_e += 1
        # the 2-D problem in the plane normal to the edge: basis p, q
        ex, ey, ez = V[ib, 0] - vx, V[ib, 1] - vy, V[ib, 2] - vz
        el = math.sqrt(ex * ex + ey * ey + ez * ez)
        ex, ey, ez = ex / el, ey / el, ez / el
        px, py, pz = n1x, n1y, n1z          # n1 is normal to the edge
        qx, qy, qz = ey * pz - ez * py, ez * px - ex * pz, ex * py - ey * px
        g11 = a0 * px * px + a1 * py * py + a2 * pz * pz
        g12 = a0 * px * qx + a1 * py * qy + a2 * pz * qz
        g22 = a0 * qx * qx + a1 * qy * qy + a2 * qz * qz
        # eigen of [[g11, g12], [g12, g22]]
        tr_ = 0.5 * (g11 + g22)
        dd = math.sqrt(0.25 * (g11 - g22) ** 2 + g12 * g12)
        lam0, lam1 = tr_ - dd, tr_ + dd
        if not lam1 - lam0 > 1e-9 * lam1:
            return False, n_e, n_v
        # eigenvector of lam0
        if abs(g11 - lam0) > abs(g22 - lam0):
            ux, uy = -g12, g11 - lam0
        else:
            ux, uy = g22 - lam0, -g12
        un = math.sqrt(ux * ux + uy * uy)
        ux, uy = ux / un, uy / un
        # the ellipse's axes e0 = u (lam0), e1 = (-uy, ux); the point P is v's
        # projection (on the arc g(n) = h_E(n) - n . v)
        wp, wq = px * vx + py * vy + pz * vz, qx * vx + qy * vy + qz * vz
        P0 = ux * wp + uy * wq
        P1 = -uy * wp + ux * wq
        w0, w1 = lam0 * P0 * P0, lam1 * P1 * P1
        if not (w0 > 1e-24 * lam1 * scale * scale and w1 > 1e-24 * lam1 * scale * scale):
            return False, n_e, n_v
        k = 0
        if P0 * P0 / lam0 + P1 * P1 / lam1 < 1.0:
            out[0], ok = _root_right(lam0, lam1, lam1, w0, w1, 0.0)
            if not ok:
                return False, n_e, n_v
            k = 1
        if lam0 / math.sqrt(lam1) < U and abs(P0) * lam1 < U * (lam1 - lam0):
            km = _roots_mid(lam0, lam1, lam1, w0, w1, 0.0, out[k:])
            if km < 0:
                return False, n_e, n_v
            k += km
        for r in range(k):
            tt = out[r]
            N0, N1 = P0 / (lam0 + tt), P1 / (lam1 + tt)
            nn = math.sqrt(N0 * N0 + N1 * N1)
            val = -tt * nn
            if not val < U:
                continue
            c0, c1 = N0 / nn, N1 / nn
            # back to the plane basis, then 3-D
            ap, aq = ux * c0 - uy * c1, uy * c0 + ux * c1
            nx, ny, nz = ap * px + aq * qx, ap * py + aq * qy, ap * pz + aq * qz
            # in the edge's arc: B's support along -n attained at v (within tol)
            if _f_at(V, nv, nx, ny, nz) > -(nx * vx + ny * vy + nz * vz) + tol:
                continue
            U = val
            bx, by, bz = nx, ny, nz
    lam = (a0, a1, a2)
    # sorted order of the axes
    i0, i1, i2 = 0, 1, 2
    if lam[i0] > lam[i1]:
        i0, i1 = i1, i0
    if lam[i1] > lam[i2]:
        i1, i2 = i2, i1
    if lam[i0] > lam[i1]:
        i0, i1 = i1, i0
    l0, l1, l2 = lam[i0], lam[i1], lam[i2]
    if not (l1 - l0 > 1e-9 * l2 and l2 - l1 > 1e-9 * l2):
        return False, n_e, n_v
    for u in range(nv):
        x = (V[u, 0], V[u, 1], V[u, 2])
        rho = math.sqrt(x[0] * x[0] * i0_ + x[1] * x[1] * i1_ + x[2] * x[2] * i2_)
        j0 = rho < 1.0 and (1.0 - rho) * amax >= L - tol
        # a root between the poles is a foot x on the far side along the least axis:
        # |x - v| >= |x_0| + |P_0| > |P_0| l1 / (l1 - l0)
        mid = (l0 / math.sqrt(l2) < U and abs(x[i0]) * l1 < U * (l1 - l0)
               and (rho < 1.0 or 2.0 * rroll + (rho - 1.0) * amin < U))
        if not (j0 or mid):
            continue
        n_v += 1
        P0, P1, P2 = x[i0], x[i1], x[i2]
        w0, w1, w2 = l0 * P0 * P0, l1 * P1 * P1, l2 * P2 * P2
        sm = 1e-24 * l2 * scale * scale
        if not (w0 > sm and w1 > sm and w2 > sm):
            return False, n_e, n_v
        k = 0
        if j0:
            out[0], ok = _root_right(l0, l1, l2, w0, w1, w2)
            if not ok:
                return False, n_e, n_v
            k = 1
        if mid:
            km = _roots_mid(l0, l1, l2, w0, w1, w2, out[k:])
            if km < 0:
                return False, n_e, n_v
            k += km
        for r in range(k):
            tt = out[r]
            N0, N1, N2 = P0 / (l0 + tt), P1 / (l1 + tt), P2 / (l2 + tt)
            nn = math.sqrt(N0 * N0 + N1 * N1 + N2 * N2)
            val = -tt * nn
            if r == 0 and j0:
                L = max(L, val)         # the vertex's depth in E: depth >= it
            if not (val < U and val >= L - tol):
                continue
            c = (N0 / nn, N1 / nn, N2 / nn)
            # back to axes x, y, z
            nx = c[0] if i0 == 0 else (c[1] if i1 == 0 else c[2])
            ny = c[0] if i0 == 1 else (c[1] if i1 == 1 else c[2])
            nz = c[0] if i0 == 2 else (c[1] if i1 == 2 else c[2])
            if _f_at(V, nv, nx, ny, nz) > -(nx * x[0] + ny * x[1] + nz * x[2]) + tol:
                continue
            U = val
            bx, by, bz = nx, ny, nz
    hA = math.sqrt(a0 * bx * bx + a1 * by * by + a2 * bz * bz)
    if not proved:
        # pa = E's support along n, pb = pa - U n; their midpoint q
        ih = 1.0 / hA
        qx = a0 * bx * ih - 0.5 * U * bx
        qy = a1 * by * ih - 0.5 * U * by
        qz = a2 * bz * ih - 0.5 * U * bz
        if not qx * qx * i0_ + qy * qy * i1_ + qz * qz * i2_ <= 1.0:
            return False, n_e, n_v
        for f in range(fn.shape[0]):
            if -(FS[f, 4] * qx + FS[f, 5] * qy + FS[f, 6] * qz) > FS[f, 7]:
                return False, n_e, n_v
    res[0] = -U
    res[1], res[2], res[3] = bx, by, bz
    res[4], res[5], res[6] = a0 * bx / hA, a1 * by / hA, a2 * bz / hA
    for c in range(3):
        res[7 + c] = res[4 + c] - U * res[1 + c]
    return True, n_e, n_v


def hull_data(P):
    """Faces (outward unit normals, offsets) and edges (a, b, face, face) of the hull of
    P by brute force over triples (points in general position: triangular faces)."""
    F = []
    for i, j, k in itertools.combinations(range(len(P)), 3):
        m = np.cross(P[j] - P[i], P[k] - P[i])
        mm = np.linalg.norm(m)
        if mm < 1e-12:
            continue
        m /= mm
        s = P @ m - m @ P[i]
        if np.all(s <= 1e-12):
            F.append((i, j, k, m, m @ P[i]))
        elif np.all(s >= -1e-12):
            F.append((i, k, j, -m, -(m @ P[i])))
    ef = collections.defaultdict(list)
    for fi, (i, j, k, m, o) in enumerate(F):
        for a, b in ((i, j), (j, k), (k, i)):
            ef[(min(a, b), max(a, b))].append(fi)
    E = np.array([(a, b, f[0], f[1]) for (a, b), f in ef.items()], np.int64)
    return np.array([f[3] for f in F]), np.array([f[4] for f in F]), E


@numba.njit(cache=False)
def run_all(radii, rot, tr, P, vr, FN, FO, fr, E, er, res, dec, ne, nv, scale, reps):
    V = np.empty((128, 3))
    FS = np.empty((256, 8))
    out = np.empty(8)
    for _ in range(reps):
        for k in range(rot.shape[0]):
            d, a, b = ellipsoid_hull_depth(radii[k], rot[k], tr[k], P[vr[k, 0]:vr[k, 1]],
                                           FN[fr[k, 0]:fr[k, 1]], FO[fr[k, 0]:fr[k, 1]],
                                           E[er[k, 0]:er[k, 1]], V, FS, out, res[k],
                                           scale[k])
            dec[k] = d
            ne[k] = a
            nv[k] = b


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=1000, help="deep pairs to take")
    ap.add_argument("--cases", default="/tmp/mkc_deep_pairs")
    ap.add_argument("--reps", type=int, default=10, help="calls per timed round")
    ap.add_argument("--rounds", type=int, default=21, help="alternated rounds")
    args = ap.parse_args()
    numba.set_num_threads(1)
    row = "ellipsoid-convex"
    shapes, table, pairs, pos, quat = load_cases(args.cases, row)
    rot, tr = relative_poses(pos, quat)
    scale = table.params[0::2, 7] + table.params[1::2, 7]
    ref = np.load(os.path.join(args.cases, f"ref_{row}_gjk_epa.npz"))
    sel = np.flatnonzero(ref["out"][:, 0] < -1e-3 * scale)[:args.n]
    Ps, FNs, FOs, Es, vr, fr, er = [], [], [], [], [], [], []
    cv = cf = ce = 0
    for k in sel:
        P = np.array(shapes[2 * k + 1]["points"])
        fn, fo, E = hull_data(P)
        Ps.append(P)
        FNs.append(fn)
        FOs.append(fo)
        Es.append(E)
        vr.append((cv, cv + len(P)))
        fr.append((cf, cf + len(fn)))
        er.append((ce, ce + len(E)))
        cv, cf, ce = cv + len(P), cf + len(fn), ce + len(E)
    radii = np.array([shapes[2 * k]["radii"] for k in sel])
    data = (radii, rot[sel].copy(), tr[sel].copy(), np.concatenate(Ps), np.array(vr),
            np.concatenate(FNs), np.concatenate(FOs), np.array(fr), np.concatenate(Es),
            np.array(er))
    n = len(sel)
    res = np.zeros((n, 10))
    dec = np.zeros(n, np.bool_)
    ne, nv = np.zeros(n, np.int64), np.zeros(n, np.int64)
    run_all(*data, res, dec, ne, nv, scale[sel], 1)
    ro = ref["out"][sel]
    err = np.abs(res[:, 0] - ro[:, 0]) / scale[sel]
    ang = np.arccos(np.clip(np.sum(res[:, 1:4] * ro[:, 1:4], 1), -1.0, 1.0))
    print(f"{n} deep {row} pairs: {dec.sum()} decided; against GJK/EPA's reference, depth "
          f"max {err[dec].max():.1e} * scale, normal max {ang[dec].max():.1e} rad; "
          f"per pair {ne.mean():.2f} edge and {nv.mean():.2f} vertex solves")
    # the prototype, the batch kernel's GJK/EPA on all the pairs and on the undecided
    # ones (what the product would add after the prototype's early exit), alternated
    # round by round, the fastest round of each (timings here wander by tens of per
    # cent from one second to the next)
    def batch_args(idx):
        tab, sp, spos, squat = subset(shapes, pos, quat, idx)[1:]
        out, st = np.zeros((len(idx), OUT_SIZE)), np.zeros(len(idx), np.int64)
        return (tab.codes, tab.params, tab.vrange, tab.verts, sp, spos, squat, M_GJK_EPA,
                np.inf, out, st)

    b_all, b_und = batch_args(sel), batch_args(sel[~dec])
    collide_batch(*b_all)
    collide_batch(*b_und)
    ts, te, tu = [], [], []
    for _ in range(args.rounds):
        t0 = time.perf_counter()
        run_all(*data, res, dec, ne, nv, scale[sel], args.reps)
        t1 = time.perf_counter()
        for _ in range(args.reps):
            collide_batch(*b_all)
        t2 = time.perf_counter()
        for _ in range(args.reps):
            collide_batch(*b_und)
        t3 = time.perf_counter()
        ts.append((t1 - t0) / args.reps / n)
        te.append((t2 - t1) / args.reps / n)
        tu.append((t3 - t2) / args.reps / n)
    both = min(ts) + min(tu)
    print(f"per pair: prototype {min(ts) * 1e6:.3f} us (early exits included), the batch "
          f"kernel's GJK/EPA {min(te) * 1e6:.3f} us: ratio {min(ts) / min(te):.2f}; with "
          f"GJK/EPA on the undecided pairs too {both * 1e6:.3f} us: ratio "
          f"{both / min(te):.2f} (fastest of {args.rounds} alternated rounds of "
          f"{args.reps}; medians' ratio {np.median(np.add(ts, tu)) / np.median(te):.2f})")


if __name__ == "__main__":
    main()
