"""An ellipsoid and a small convex hull in closed form and 1-D root searches, before GJK
and EPA: the exact depth of the ellipsoid E and the hull B over B's normal fan
(gjk_epa.gjk_epa_ws calls collide_ellipsoid_convex first for such a pair when the hull has
its fan stored, mkcollision_ros.hull.fan_rows; where it decides nothing GJK and EPA
run as for any pair).

Why: on overlapping ellipsoid-hull pairs EPA needs ~16 supports of A - B when the
minimum lies at a hull face, ~30 at an edge and ~47 at a vertex, each a pass over the
hull's points; the fan needs one pass over the faces, bounds for most edges and
vertices, and a few Newton searches.

The problem, in E's frame (E centred at the origin, squared semi-axes l_i): the depth
is min over unit n of f(n) = h_E(n) + h_B(-n), h the support function.  B's normal fan
splits the sphere of directions into its faces' normals (points), its edges' arcs and
its vertices' cones; the minimiser lies in one of them and is a critical point of f
restricted to it.  So the candidates are (the feet: normal_fan.py):

  * each face's outward normal m, at n = -m: f = sqrt(m^T L m) + B's offset along m;
  * each edge's arc: with v the edge's point, f(n) = h_E(n) - n . v on the arc, whose
    critical points are the normals of E projected along the edge (an ellipse) at the
    feet of the normals from v's projection to it;
  * each vertex's cone: the same for E itself and the vertex.

Pruning (every bound rigorous; U the least value found so far, starting from the
faces'):
  * an edge: f on its arc is at least the larger of its tangent planes at the arc's
    ends (f is convex and homogeneous), taken over the chord between the ends (a closed
    form from the faces' values alone, where the two cross; within the fan's
    tolerance, HE_FAN_SLACK), and where that does not clear U, over the arc itself
    (each plane on its side of their crossing: a sinusoid's least value over an arc);
  * a vertex u inside E: A - B holds E - u, so the depth is at least u's depth in E,
    at least (1 - rho_u) a_min (rho the ellipsoid norm, a the semi-axes) and exactly
    the distance to u's foot right of the pole once that is solved (L below, the largest
    such bound).  u's own foot is at most (1 - rho_u) a_max away, so it is searched
    only if that reaches L;
  * the roots between the poles: their value is at least l0 / sqrt(l2) (the rolling
    radius), at least |P_0| l1 / (l1 - l0) (the foot lies on the far side along the
    least axis), and for a vertex outside E at least 2 r_roll + (rho - 1) a_min (the
    inner normal crosses the rolling ball, then reaches the vertex); a two-term bound
    of the secular equation (the point outside the evolute) shows there are none
    before any search.

The pruning skips the negative feet of vertices outside E, so it holds only if E and B
overlap.  The kernel proves that first where it is cheap: a hull vertex inside E or E's
centre inside B (85% of the deep pairs of bench/dev/deep_pairs.py's cases); else by GJK in
E's unit-ball frame (E scaled to the unit ball by its inverse semi-axes, an affine map:
the hull's image is a hull, so GJK there is a point against a polytope, on the
vertices already in E's frame, with no square root per support).  That GJK decides the
rest of the row's overlapping pairs in 1.4 steps on average and proves its pairs apart
with bounding spheres overlapping that no face plane ends in 0.7 (bench/vs_mujoco.py's
ellipsoid-convex row).  Only where it decides nothing (its plane's gap within the
caller's ``stop``, the cap) gjk_epa_ws runs GJK on the cores and calls the kernel again
once GJK has found them overlapping, in place of EPA.
Before all that, E's centre's offsets below the face planes (three products per
face): the plane it lies farthest beyond is tried first for a separating plane, and
one with E's core beyond it by more than the caller's ``stop`` ends the call with that
gap as a bound (else GJK gives the distance); so does any face's in the full face
pass.  Of the 715 pairs apart with bounding spheres overlapping in bench/vs_mujoco.py's
row, 600 have such a face and the first one tried is one for 556.  On near-degenerate
input (equal semi-axes, a point on an axis plane, a search that does not converge) it
decides nothing.

The answer is for E's core, which is E shrunk by its rolling radius (geometry.py), and
B's core, the hull of its points: res = [U - r, n, pa, pb] as ellipsoid_box's.

Measured on bench/dev/deep_pairs.py's 1,016 deep ellipsoid-convex pairs: every pair
decided, the depth within 9.5e-9 * scale and the normal within 4e-4 rad of GJK/EPA's
(EPA's own tolerance).  Figures of time: BENCHMARKS.md.
"""
import math

import numpy as np

from ..constants import (ELLIPSOID, FAN_MAX_POINTS, HE_BALL_ITERS, HE_BALL_TOL, HE_FAN_SLACK,
                         HE_POLE_SEP, HE_PROGRESS_RTOL, HE_SUPPORT_TOL, HE_WEIGHT_FLOOR, PRE_APART,
                         PRE_EXACT, PRE_UNDECIDED, PRE_UNPROVED, P_ROLL)
from ..geometry import borrow_args
from ..jit import borrow, njit_inline, njit_separate
from ..simplex import _closest_simplex
from .normal_fan import (HE_FACES, HE_MAX_FACES, HE_V, HE_X, _in_arc, _plane_feet, _planes_on_arc,
                         _root_right, _roots_mid, _vertex_top, face_apart_out, fan_run, fan_stored,
                         hull_pose, least_offset, plane_foot)


@njit_inline
def ellipsoid_hull_pair(sa, sb):
    """An ellipsoid and a hull with its fan, either order."""
    return ((sa[0] == ELLIPSOID and fan_stored(sb[0], sb[1]))
            or (sb[0] == ELLIPSOID and fan_stored(sa[0], sa[1])))


@njit_inline
def _unit_ball_test(V, fl, nf, nvx, b0, b1, b2, need, W, v, l3, lam, vol):
    """Whether E and the hull overlap or are apart, decided in E's unit-ball frame:
    there E (semi-axes 1 / b) is the unit ball and the hull's image x_hat = b x (x its
    vertices in E's frame, the rows of V) is again a hull, so GJK for the point of that
    hull nearest the origin decides the pair as far as it is run: a convex combination
    v of the images with |v| < 1 is a point of B inside E; a direction v with the
    images' least v . x_hat = m > |v| gives a plane between them.  That plane's normal
    in E's frame is n ~ b v (the images' plane v . x_hat = c is (b v) . x = c there),
    and the gap between E and B across it is (m - |v|) / |b v| (E's support along n is
    |v| / |b v|, B's least n . x is m / |b v|).

    Returns (1, ...) for the overlap; (2, gap, n) once a plane proves a gap above
    ``need`` (n unit, from E toward B); (0, ...) undecided (the nearest point found
    with the gap at most ``need``, or the cap).  W (4, 3), v, l3 (3,), lam, vol (4,):
    scratch for the simplex."""
    # start at the vertex whose image is nearest the origin
    best, u0 = np.inf, int(fl[nf])
    for i in range(nvx):
        u = int(fl[nf + i])
        x0, x1, x2 = b0 * V[u, 0], b1 * V[u, 1], b2 * V[u, 2]
        rr = x0 * x0 + x1 * x1 + x2 * x2
        if rr < best:
            best, u0 = rr, u
    W[0, 0], W[0, 1], W[0, 2] = b0 * V[u0, 0], b1 * V[u0, 1], b2 * V[u0, 2]
    v[0], v[1], v[2] = W[0, 0], W[0, 1], W[0, 2]
    n = 1
    for _ in range(HE_BALL_ITERS):
        vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        if vv < 1.0 - HE_BALL_TOL:
            return 1, 0.0, 0.0, 0.0, 0.0
        # the images' support along -v: their least v . x_hat = (b v) . x
        cx, cy, cz = b0 * v[0], b1 * v[1], b2 * v[2]
        top, w = _vertex_top(V, fl, nf, nvx, -cx, -cy, -cz)
        m = -top
        vn = math.sqrt(vv)
        if m > vn:
            cn = math.sqrt(cx * cx + cy * cy + cz * cz)
            gap = (m - vn) / cn
            if gap > need:
                return 2, gap, cx / cn, cy / cn, cz / cn
        # no progress: v is the nearest point (within rounding)
        if vv - m <= HE_PROGRESS_RTOL * vv:
            return 0, 0.0, 0.0, 0.0, 0.0
        W[n, 0], W[n, 1], W[n, 2] = b0 * V[w, 0], b1 * V[w, 1], b2 * V[w, 2]
        n = _closest_simplex(W, W, W, n + 1, lam, v, l3, vol)
    return 0, 0.0, 0.0, 0.0, 0.0


@njit_inline
def _apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my, mz, a0, a1,
               a2, hA, roll, gap):
    """face_apart_out for E (hA = h_E(m), a the squared semi-axes)."""
    # E's core's support point along -m, E's frame: -L m / hA + roll m
    ih = 1.0 / hA
    face_apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my, mz,
                   (roll - a0 * ih) * mx, (roll - a1 * ih) * my, (roll - a2 * ih) * mz,
                   gap)


@njit_separate
def collide_ellipsoid_convex(sa, sb, verts, r_ab, t_ab, scale, overlap, stop, rows, roots,
                             res):
    """The exact depth of an ellipsoid's core and a hull with its fan stored (either
    order; B's pose r_ab, t_ab in A's frame), by the module notes.  ``overlap``: the
    caller has proved that the pair overlaps (GJK on the cores).  ``stop`` (m): a face
    plane proving the cores farther apart than this ends the call (as GJK's).  ``rows``
    (>= HE_ROWS, 3) and ``roots`` (>= 8,) are scratch.  Returns

    * PRE_EXACT with res[:10] = [h, n (3), pa (3), pb (3)] in A's frame (h the cores'
      depth, n from A to B, pa and pb on the two cores, pb - pa == -h n);
    * PRE_APART with res = [-g, n, pa, pb]: the cores are at least g > stop apart, n
      normal to a plane that separates them (a hull face's or _unit_ball_test's), pa
      and pb points of the cores (_apart_out);
    * PRE_UNPROVED (without ``overlap``, when neither a hull vertex inside E, E's
      centre inside B nor _unit_ball_test decides) or PRE_UNDECIDED otherwise, res
      untouched."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    rows, roots, res = borrow(rows), borrow(roots), borrow(res)
    side = 0 if sa[0] == ELLIPSOID else 1
    ell = sa[1] if side == 0 else sb[1]
    hull = sb if side == 0 else sa
    v0, vn = hull[2], hull[3]
    nf, ne, nvx, fnr, fe, fl = fan_run(hull[1], v0, vn, verts)
    if vn > FAN_MAX_POINTS or nf > HE_MAX_FACES:
        return PRE_UNDECIDED
    # the hull's pose in E's frame
    r00, r01, r02, r10, r11, r12, r20, r21, r22, t0, t1, t2 = hull_pose(side, r_ab, t_ab)
    a0, a1, a2 = ell[0] ** 2, ell[1] ** 2, ell[2] ** 2
    roll = ell[P_ROLL]
    V = rows[HE_V:HE_V + vn]
    W = rows[HE_FACES:HE_FACES + nf]
    M = rows[HE_FACES + nf:HE_FACES + 2 * nf]
    Q = rows[HE_FACES + 2 * nf:HE_FACES + 3 * nf]
    X = rows[HE_X:HE_X + vn]
    pts = verts[v0:v0 + vn]
    tol = HE_SUPPORT_TOL * scale
    # E's centre c in the hull's frame, and its offset below each face's plane, o - f . c
    # (= o + m . t): c inside all of them proves the overlap, and the plane it lies
    # farthest beyond is the one that most often proves the pair apart, before the
    # vertices and the full face pass are paid for
    omin, fmin = least_offset(verts, fl, fnr, nf, r00, r01, r02, r10, r11, r12, r20, r21,
                              r22, t0, t1, t2, Q)
    if not omin > 0.0:
        fx, fy, fz = verts[fnr + fmin, 0], verts[fnr + fmin, 1], verts[fnr + fmin, 2]
        mx = r00 * fx + r01 * fy + r02 * fz
        my = r10 * fx + r11 * fy + r12 * fz
        mz = r20 * fx + r21 * fy + r22 * fz
        hA = math.sqrt(a0 * mx * mx + a1 * my * my + a2 * mz * mz)
        # E's core (E less the rolling ball) lies roll - (hA + o) beyond the plane
        if roll - (hA + omin) > stop:
            _apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my, mz,
                       a0, a1, a2, hA, roll, roll - (hA + omin))
            return PRE_APART
    inside = omin > 0.0
    amin = math.sqrt(min(a0, min(a1, a2)))
    amax = math.sqrt(max(a0, max(a1, a2)))
    rroll = amin * amin / amax
    i0_, i1_, i2_ = 1.0 / a0, 1.0 / a1, 1.0 / a2
    # L: a lower bound on the depth, the largest (1 - rho) a_min of an inside vertex,
    # raised to a vertex's exact depth in E (its foot right of the pole) once found
    L = 0.0
    for i in range(nvx):
        u = np.uint64(int(fl[nf + i]))
        px, py, pz = pts[u, 0], pts[u, 1], pts[u, 2]
        x0 = r00 * px + r01 * py + r02 * pz + t0
        x1 = r10 * px + r11 * py + r12 * pz + t1
        x2 = r20 * px + r21 * py + r22 * pz + t2
        V[u, 0], V[u, 1], V[u, 2] = x0, x1, x2
        rho = math.sqrt(x0 * x0 * i0_ + x1 * x1 * i1_ + x2 * x2 * i2_)
        X[u, 0] = rho
        # (no branch: whether a vertex lies inside is random; outside, the term is <= 0)
        L = max(L, (1.0 - rho) * amin)
    # the pruning below skips negative feet, so the pair must be known to overlap: by
    # the caller (GJK), a hull vertex inside E (L > 0), E's centre inside B, or else
    # GJK in E's unit-ball frame, which may as well find a plane proving the pair apart
    if not (overlap or inside or L > 0.0):
        # (its simplex in the face rows W and M, not yet written)
        ball, gap, nx, ny, nz = _unit_ball_test(
            V, fl, nf, nvx, 1.0 / ell[0], 1.0 / ell[1], 1.0 / ell[2], stop - roll,
            rows[HE_FACES:HE_FACES + 4], rows[HE_FACES + nf], rows[HE_FACES + nf + 1],
            roots[0:4], roots[4:8])
        if ball == 0:
            return PRE_UNPROVED
        if ball == 2:
            # the hull's outward normal toward E, m = -n (E's frame), f in the hull's
            mx, my, mz = -nx, -ny, -nz
            fx = r00 * mx + r10 * my + r20 * mz
            fy = r01 * mx + r11 * my + r21 * mz
            fz = r02 * mx + r12 * my + r22 * mz
            hA = math.sqrt(a0 * mx * mx + a1 * my * my + a2 * mz * mz)
            _apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my, mz,
                       a0, a1, a2, hA, roll, roll + gap)
            return PRE_APART
    U = np.inf
    bx = by = bz = 0.0
    for f in range(nf):
        fx, fy, fz = verts[fnr + f, 0], verts[fnr + f, 1], verts[fnr + f, 2]
        mx = r00 * fx + r01 * fy + r02 * fz
        my = r10 * fx + r11 * fy + r12 * fz
        mz = r20 * fx + r21 * fy + r22 * fz
        hA = math.sqrt(a0 * mx * mx + a1 * my * my + a2 * mz * mz)
        off = Q[f, 1]
        val = hA + off
        if not val > 0.0:
            # E wholly beyond the face's plane (or NaN)
            if roll - val > stop:
                _apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my,
                           mz, a0, a1, a2, hA, roll, roll - val)
                return PRE_APART
            return PRE_UNDECIDED
        # per face: L m (E's support point along n = -m is -L m / hA), m, hA, o, f(n)
        W[f, 0], W[f, 1], W[f, 2] = a0 * mx, a1 * my, a2 * mz
        M[f, 0], M[f, 1], M[f, 2] = mx, my, mz
        Q[f, 0], Q[f, 2] = hA, val
        if val < U:
            U = val
            bx, by, bz = -mx, -my, -mz
    slack = tol + HE_FAN_SLACK * scale
    for e in range(ne):
        q = fe + 4 * e
        f1, f2 = np.uint64(int(fl[q + 2])), np.uint64(int(fl[q + 3]))
        # f on the arc is at least the larger of its tangent planes at the arc's ends,
        # P_i(n) = (s_i - v) . n (s_i E's support point at n_i, v the edge's point).
        # P_1 is g1 at n1 and s_1 . n2 + o2 at n2 (v on face 2's plane, within the
        # fan's tolerance), P_2 likewise, and g_j - P_i(n_j) = (h1 h2 - m1^T L m2) / h_i:
        # the two cross on the chord at the weights (h2, h1), where both are
        # (h2 g1 + m1^T L m2 + h1 o2) / (h1 + h2), the least of their larger over the
        # chord, and so over the arc (f is homogeneous; the arc lies beyond the chord)
        h1, h2 = Q[f1, 0], Q[f2, 0]
        w12 = W[f1, 0] * M[f2, 0] + W[f1, 1] * M[f2, 1] + W[f1, 2] * M[f2, 2]
        if h2 * Q[f1, 2] + w12 + h1 * Q[f2, 1] >= (U - slack) * (h1 + h2):
            continue
        ia, ib = int(fl[q]), int(fl[q + 1])
        vx, vy, vz = V[ia, 0], V[ia, 1], V[ia, 2]
        # the arc's ends n1, n2, f there, and E's support points there less v
        n1x, n1y, n1z = -M[f1, 0], -M[f1, 1], -M[f1, 2]
        n2x, n2y, n2z = -M[f2, 0], -M[f2, 1], -M[f2, 2]
        g1, g2 = Q[f1, 2], Q[f2, 2]
        i1, i2 = 1.0 / h1, 1.0 / h2
        s1x, s1y, s1z = -W[f1, 0] * i1 - vx, -W[f1, 1] * i1 - vy, -W[f1, 2] * i1 - vz
        s2x, s2y, s2z = -W[f2, 0] * i2 - vx, -W[f2, 1] * i2 - vy, -W[f2, 2] * i2 - vz
        c12 = s1x * n2x + s1y * n2y + s1z * n2z
        c21 = s2x * n1x + s2y * n1y + s2z * n1z
        # tighter: the larger of the two planes over the arc itself
        if _planes_on_arc(s1x, s1y, s1z, s2x, s2y, s2z, n1x, n1y, n1z, n2x, n2y, n2z,
                          g1 - c21, c12 - g2) >= U - tol:
            continue
        # the 2-D problem in the plane normal to the edge: basis p = n1, q = e x p
        ex, ey, ez = V[ib, 0] - vx, V[ib, 1] - vy, V[ib, 2] - vz
        el = math.sqrt(ex * ex + ey * ey + ez * ez)
        ex, ey, ez = ex / el, ey / el, ez / el
        px, py, pz = n1x, n1y, n1z
        qx, qy, qz = ey * pz - ez * py, ez * px - ex * pz, ex * py - ey * px
        g11 = a0 * px * px + a1 * py * py + a2 * pz * pz
        g12 = a0 * px * qx + a1 * py * qy + a2 * pz * qz
        g22 = a0 * qx * qx + a1 * qy * qy + a2 * qz * qz
        wp, wq = px * vx + py * vy + pz * vz, qx * vx + qy * vy + qz * vz
        k, ux, uy, P0, P1, lam0, lam1 = _plane_feet(g11, g12, g22, wp, wq, U, scale, roots)
        if k < 0:
            return PRE_UNDECIDED
        for r in range(k):
            val, ap, aq = plane_foot(roots[r], P0, P1, lam0, lam1, ux, uy)
            if not val < U:
                continue
            nx, ny, nz = ap * px + aq * qx, ap * py + aq * qy, ap * pz + aq * qz
            # in the edge's arc: between n1 = p and n2 on their great circle (the plane
            # normal to the edge), where B's support along -n is attained at v
            if not _in_arc(ap, aq, n2x * px + n2y * py + n2z * pz,
                           n2x * qx + n2y * qy + n2z * qz):
                continue
            U = val
            bx, by, bz = nx, ny, nz
    # the axes sorted by their squared lengths
    lam = (a0, a1, a2)
    i0, i1, i2 = 0, 1, 2
    if lam[i0] > lam[i1]:
        i0, i1 = i1, i0
    if lam[i1] > lam[i2]:
        i1, i2 = i2, i1
    if lam[i0] > lam[i1]:
        i0, i1 = i1, i0
    l0, l1, l2 = lam[i0], lam[i1], lam[i2]
    if not (l1 - l0 > HE_POLE_SEP * l2 and l2 - l1 > HE_POLE_SEP * l2):
        return PRE_UNDECIDED
    lmid = l0 / math.sqrt(l2)
    kmid = l1 / (l1 - l0)
    for i in range(nvx):
        u = np.uint64(int(fl[nf + i]))
        P0 = V[u, i0]
        # a root between the poles is a foot y on the far side along the least axis:
        # |y - x| >= |y_0| + |x_0| > |x_0| l1 / (l1 - l0)
        rho = X[u, 0]
        # (bitwise, not short-circuit: branches on whether a vertex lies inside are
        # random, and mispredicted cost ~5% of a deep pair's kernel time, measured)
        ins = rho < 1.0
        j0 = ins & ((1.0 - rho) * amax >= L - tol)
        mid = ((lmid < U) & (abs(P0) * kmid < U)
               & (ins | (2.0 * rroll + (rho - 1.0) * amin < U)))
        if not (j0 or mid):
            continue
        P1, P2 = V[u, i1], V[u, i2]
        x0, x1, x2 = V[u, 0], V[u, 1], V[u, 2]
        w0, w1, w2 = l0 * P0 * P0, l1 * P1 * P1, l2 * P2 * P2
        small = HE_WEIGHT_FLOOR * l2 * scale * scale
        if not (w0 > small and w1 > small and w2 > small):
            return PRE_UNDECIDED
        k = 0
        if j0:
            roots[0], ok = _root_right(l0, l1, l2, w0, w1, w2)
            if not ok:
                return PRE_UNDECIDED
            k = 1
        if mid:
            km = _roots_mid(l0, l1, l2, w0, w1, w2, roots, k)
            if km < 0:
                return PRE_UNDECIDED
            k += km
        for r in range(k):
            tt = roots[r]
            N0, N1, N2 = P0 / (l0 + tt), P1 / (l1 + tt), P2 / (l2 + tt)
            nn = math.sqrt(N0 * N0 + N1 * N1 + N2 * N2)
            val = -tt * nn
            if r == 0 and j0:
                L = max(L, val)         # the vertex's depth in E: the depth is >= it
            if not (val < U and val >= L - tol):
                continue
            c = (N0 / nn, N1 / nn, N2 / nn)
            nx = c[0] if i0 == 0 else (c[1] if i1 == 0 else c[2])
            ny = c[0] if i0 == 1 else (c[1] if i1 == 1 else c[2])
            nz = c[0] if i0 == 2 else (c[1] if i1 == 2 else c[2])
            # in the vertex's cone: B's support along -n attained at it (within tol)
            if (_vertex_top(V, fl, nf, nvx, -nx, -ny, -nz)[0]
                    > -(nx * x0 + ny * x1 + nz * x2) + tol):
                continue
            U = val
            bx, by, bz = nx, ny, nz
    hA = math.sqrt(a0 * bx * bx + a1 * by * by + a2 * bz * bz)
    ih = 1.0 / hA
    # E's support point along n, and B's, U back along n
    ex, ey, ez = a0 * bx * ih, a1 * by * ih, a2 * bz * ih
    if not math.isfinite(U):
        return PRE_UNDECIDED
    if side == 0:
        res[0] = U - roll
        res[1], res[2], res[3] = bx, by, bz
        res[4], res[5], res[6] = ex - roll * bx, ey - roll * by, ez - roll * bz
        res[7], res[8], res[9] = ex - U * bx, ey - U * by, ez - U * bz
        return PRE_EXACT
    # back to A's (the hull's) frame: n from A to B is -r_ab n
    hx, hy, hz = ex - U * bx, ey - U * by, ez - U * bz
    res[0] = U - roll
    for c in range(3):
        nA = -(r_ab[c, 0] * bx + r_ab[c, 1] * by + r_ab[c, 2] * bz)
        res[1 + c] = nA
        res[4 + c] = r_ab[c, 0] * hx + r_ab[c, 1] * hy + r_ab[c, 2] * hz + t_ab[c]
        res[7 + c] = (r_ab[c, 0] * ex + r_ab[c, 1] * ey + r_ab[c, 2] * ez + t_ab[c]
                      + roll * nA)
    return PRE_EXACT
