"""Ellipsoid-ellipsoid intersection tests in the unit-sphere frame of body A.

Frame.  Body i is M_i(unit ball) with M_i = R_i diag(a_i, b_i, c_i) plus a translation.
In A's frame M_A = diag(a, b, c) and M_B = r_ab diag(a', b', c') + t_ab, so

    T = inv(M_A) M_B :  u  ->  L u + c,   L = diag(1/a) r_ab diag(a'),  c = t_ab / a

maps B's unit sphere into the frame where A is the unit ball ("T frame", units of A's
semi-axes, dimensionless).  T is an affine bijection, so the bodies intersect iff the
ellipsoid E = {L u + c : |u| <= 1} meets the unit ball, i.e. iff the distance from the
origin to E is <= 1 (origin inside E included).

* ``ellipsoid_exact``: axes and radii of E from the eigen-decomposition of L L^T; the
  origin's distance to E by bisection on the Lagrange multiplier of the closest-point
  problem (D. Eberly, "Distance from a Point to an Ellipse, an Ellipsoid, or a
  Hyperellipsoid", Geometric Tools, 2013), at most ELL_MAX_ITERS steps (it stops earlier
  when float64 cannot split the bracket).
* ``ellipsoid_sampled``: the classic approximate test: map points of a subdivided
  icosahedron on B's unit sphere by T and report contact if any lands within distance 1
  of the origin, plus a point-in test of the origin in E.  Sample points are generated
  on the fly (no cache): each of the 20 icosahedron faces is cut into a k x k
  triangular grid, k = 2**n_subdiv (class-I geodesic subdivision of frequency k), and
  each grid point is projected onto the sphere; edge points are visited once per face
  (duplicates only cost time).  Level n visits 20 (k+1)(k+2)/2 points (n = 0: 60, the
  12 vertices with repeats; n = 4: 3060 visits of 2562 distinct points).

Containment.  A inside B: the origin is inside E while possibly no sample of E's surface
is within 1 of the origin -- the sample-only test misses this; the origin point-in test
catches it.  B inside A: every sample of E is within 1, so samples catch it.  The
remaining misses of the sampled test are shallow partial overlaps where the overlap
lens falls between samples (measured in docs/narrowphase-notes.md).

Outputs (``out`` float64[OUT_SIZE], A's frame):
  out[OUT_DIST]  the signed gap *in the T frame* (dimensionless, NOT metres):
                 distance(origin, E) - 1, or -1 when the origin is inside E (the exact
                 test does not measure how deep); the sampled test writes
                 min over samples of |T p| - 1 (an upper bound of the exact gap) or -1.
  normal         approximate unit normal A -> B: the T-frame direction from the origin
                 to E's nearest point, mapped back with the inverse transpose of
                 diag(1/a) (exact at touching, approximate otherwise); the direction to
                 B's centre when the origin is inside E.
  pa, pb         points on A's and on B's surface (the T-frame nearest points mapped
                 back); when the origin is inside E, pa is on A's surface towards B's
                 centre and pb is B's centre.  pb - pa == dist * normal does NOT hold
                 for these methods.
The status follows the touching rule on the T-frame gap with the T-frame scale
1 + (largest radius of E).  The dispatcher computes metric depth/normal with GJK/EPA.

Shapes: SPHERE (equal radii) and ELLIPSOID only; any other code, or a nonzero margin (a
grown ellipsoid is no longer an ellipsoid), returns ST_NOT_RUN.
"""
import math

import numpy as np

from .constants import (ELLIPSOID, ELL_MAX_ITERS, JACOBI_OFF_TOL, JACOBI_SWEEPS, M_ELLIPSOID_EXACT,
                        M_ELLIPSOID_SAMPLED, OUT_DIST, OUT_ITERS, OUT_METHOD, OUT_NORMAL, OUT_PA,
                        OUT_PB, P_MARGIN, SPHERE, ST_NOT_RUN, ST_PENETRATING, ST_SEPARATED,
                        ST_TOUCHING, TOUCH_TOL)
from .jit import njit_kernel, njit_separate

_G = (1.0 + 5.0 ** 0.5) / 2.0
ICO_VERTS = np.array([
    [-1.0, _G, 0.0], [1.0, _G, 0.0], [-1.0, -_G, 0.0], [1.0, -_G, 0.0],
    [0.0, -1.0, _G], [0.0, 1.0, _G], [0.0, -1.0, -_G], [0.0, 1.0, -_G],
    [_G, 0.0, -1.0], [_G, 0.0, 1.0], [-_G, 0.0, -1.0], [-_G, 0.0, 1.0]])
ICO_FACES = np.array([
    [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
    [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
    [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
    [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], dtype=np.int64)


@njit_kernel
def _radii(s):
    """Semi-axes (3,) of a SPHERE/ELLIPSOID tuple, or zeros when not applicable."""
    r = np.zeros(3)
    code = s[0]
    prm = s[1]
    if prm[P_MARGIN] != 0.0:
        return r
    if code == SPHERE:
        r[0] = prm[0]
        r[1] = prm[0]
        r[2] = prm[0]
    elif code == ELLIPSOID:
        r[0] = prm[0]
        r[1] = prm[1]
        r[2] = prm[2]
    return r


@njit_kernel
def _t_map(ra, rb, r_ab, t_ab):
    """L (3, 3) and c (3,) of T(u) = L u + c (module docstring)."""
    lmat = np.empty((3, 3))
    c = np.empty(3)
    for i in range(3):
        c[i] = t_ab[i] / ra[i]
        for j in range(3):
            lmat[i, j] = r_ab[i, j] * rb[j] / ra[i]
    return lmat, c


@njit_kernel
def _classify(gap, scale):
    tol = TOUCH_TOL * scale
    if gap > tol:
        return ST_SEPARATED
    if gap >= -tol:
        return ST_TOUCHING
    return ST_PENETRATING


@njit_kernel
def _write_back(ra, x_near, u_dir, gap, method, iters, out):
    """Map T-frame points back to A's frame: pa = D u_dir (on A), pb = D x_near (on B);
    normal = normalised D^{-1} u_dir (inverse transpose of D^{-1})."""
    n = np.empty(3)
    for i in range(3):
        n[i] = u_dir[i] / ra[i]
    nn = math.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    out[OUT_DIST] = gap
    for i in range(3):
        out[OUT_NORMAL + i] = n[i] / nn
        out[OUT_PA + i] = ra[i] * u_dir[i]
        out[OUT_PB + i] = ra[i] * x_near[i]
    out[OUT_ITERS] = iters
    out[OUT_METHOD] = method


@njit_kernel
def _unit_or_z(v):
    o = np.empty(3)
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if n > 0.0:
        for m in range(3):
            o[m] = v[m] / n
    else:
        o[0] = 0.0
        o[1] = 0.0
        o[2] = 1.0
    return o


@njit_kernel
def _solve3(lmat, b):
    """Solve L x = b (3x3) by Cramer's rule (L is well conditioned up to the axis
    ratios; fine for the point-in test)."""
    a = lmat
    det = (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
           - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
           + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]))
    x = np.empty(3)
    for k in range(3):
        m = a.copy()
        for i in range(3):
            m[i, k] = b[i]
        x[k] = (m[0, 0] * (m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1])
                - m[0, 1] * (m[1, 0] * m[2, 2] - m[1, 2] * m[2, 0])
                + m[0, 2] * (m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0])) / det
    return x


@njit_kernel
def _point_ellipsoid(y, s):
    """Closest point of the solid ellipsoid sum (x_i / s_i)^2 <= 1 (axis aligned, s (3,)
    > 0) to the point y (3,) outside it, by bisection on the Lagrange multiplier t of
    x_i = s_i^2 y_i / (s_i^2 + t): g(t) = sum (s_i y_i / (s_i^2 + t))^2 - 1 is
    decreasing on t >= 0 with g(0) > 0 and g(|s*y|) <= 0.  Returns (x, steps)."""
    z = np.empty(3)
    for i in range(3):
        z[i] = s[i] * abs(y[i])
    lo = 0.0
    hi = math.sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2])
    steps = 0
    for it in range(ELL_MAX_ITERS):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        steps += 1
        g = -1.0
        for i in range(3):
            q = z[i] / (s[i] * s[i] + mid)
            g += q * q
        if g > 0.0:
            lo = mid
        elif g < 0.0:
            hi = mid
        else:
            lo = mid
            hi = mid
            break
    t = 0.5 * (lo + hi)
    x = np.empty(3)
    for i in range(3):
        x[i] = s[i] * s[i] * y[i] / (s[i] * s[i] + t)
    return x, steps


@njit_kernel
def _sym_eig3(m):
    """Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations.
    Returns (eigenvalues (3,), eigenvectors as columns (3, 3))."""
    a = m.copy()
    v = np.eye(3)
    for sweep in range(JACOBI_SWEEPS):
        off = a[0, 1] * a[0, 1] + a[0, 2] * a[0, 2] + a[1, 2] * a[1, 2]
        diag = a[0, 0] * a[0, 0] + a[1, 1] * a[1, 1] + a[2, 2] * a[2, 2]
        if off <= JACOBI_OFF_TOL * diag:
            break
        for p in range(2):
            for q in range(p + 1, 3):
                if a[p, q] == 0.0:
                    continue
                theta = (a[q, q] - a[p, p]) / (2.0 * a[p, q])
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                sn = t * c
                for k in range(3):
                    akp = a[k, p]
                    akq = a[k, q]
                    a[k, p] = c * akp - sn * akq
                    a[k, q] = sn * akp + c * akq
                for k in range(3):
                    apk = a[p, k]
                    aqk = a[q, k]
                    a[p, k] = c * apk - sn * aqk
                    a[q, k] = sn * apk + c * aqk
                for k in range(3):
                    vkp = v[k, p]
                    vkq = v[k, q]
                    v[k, p] = c * vkp - sn * vkq
                    v[k, q] = sn * vkp + c * vkq
    w = np.empty(3)
    for i in range(3):
        w[i] = a[i, i]
    return w, v


@njit_separate
def ellipsoid_exact(sa, sb, r_ab, t_ab, out):
    """Exact ellipsoid-ellipsoid contact test in A's unit-sphere (T) frame.

    sa, sb  shape tuples (code int64, prm float64[8], v0 int64, vn int64), SPHERE or
            ELLIPSOID without margin; anything else returns ST_NOT_RUN
    r_ab    float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    out     float64[OUT_SIZE]; OUT_DIST is the T-frame gap (module docstring), normal and
            points are approximate; method M_ELLIPSOID_EXACT, iterations = bisection steps
    Returns the status under the touching rule on the T-frame gap.
    """
    ra = _radii(sa)
    rb = _radii(sb)
    if ra[0] <= 0.0 or rb[0] <= 0.0:
        return ST_NOT_RUN
    lmat, c = _t_map(ra, rb, r_ab, t_ab)
    # E = {L u + c}: with L L^T = U diag(s^2) U^T, E = {U diag(s) w + c : |w| <= 1}
    llt = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            llt[i, j] = lmat[i, 0] * lmat[j, 0] + lmat[i, 1] * lmat[j, 1] + lmat[i, 2] * lmat[j, 2]
    _, u = _sym_eig3(llt)
    # radii as |L^T u_i| rather than sqrt(eigenvalue): accurate for thin E (axis
    # ratios up to 1e6 make the small eigenvalue of L L^T lose ~1e-4 relative)
    s = np.empty(3)
    for i in range(3):
        acc = 0.0
        for j in range(3):
            g = lmat[0, j] * u[0, i] + lmat[1, j] * u[1, i] + lmat[2, j] * u[2, i]
            acc += g * g
        s[i] = math.sqrt(acc)
    smax = max(s[0], max(s[1], s[2]))
    scale = 1.0 + smax
    # origin relative to E's centre, in E's axes: y = U^T (0 - c)
    y = np.empty(3)
    for i in range(3):
        y[i] = -(u[0, i] * c[0] + u[1, i] * c[1] + u[2, i] * c[2])
    smin = min(s[0], min(s[1], s[2]))
    if not smin > 0.0:
        return ST_NOT_RUN
    inside = 0.0
    for i in range(3):
        inside += (y[i] / s[i]) ** 2
    if inside <= 1.0:
        # origin in E: B contains A's centre; depth not measured
        gap = -1.0
        dir_c = _unit_or_z(c)
        _write_back(ra, c, dir_c, gap, np.int64(M_ELLIPSOID_EXACT), 0.0, out)
        return _classify(gap, scale)
    x, steps = _point_ellipsoid(y, s)
    # back to the T frame: nearest point of E
    xt = np.empty(3)
    for i in range(3):
        xt[i] = c[i] + u[i, 0] * x[0] + u[i, 1] * x[1] + u[i, 2] * x[2]
    dist = math.sqrt(xt[0] * xt[0] + xt[1] * xt[1] + xt[2] * xt[2])
    gap = dist - 1.0
    _write_back(ra, xt, _unit_or_z(xt), gap, np.int64(M_ELLIPSOID_EXACT), float(steps), out)
    return _classify(gap, scale)


@njit_separate
def ellipsoid_sampled(sa, sb, r_ab, t_ab, n_subdiv, out):
    """Approximate (sampled) ellipsoid-ellipsoid test in A's unit-sphere frame.

    sa, sb    shape tuples, SPHERE or ELLIPSOID without margin (else ST_NOT_RUN)
    r_ab      float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    n_subdiv  int64 >= 0, icosahedron subdivision level (frequency 2**n_subdiv)
    out       float64[OUT_SIZE]; OUT_DIST = T-frame gap estimate (module docstring);
              method M_ELLIPSOID_SAMPLED, iterations = sample points visited
    Returns ST_PENETRATING/ST_TOUCHING when a sample lands within the unit ball or the
    origin lies in E (touching rule on the gap estimate), else ST_SEPARATED.
    """
    ra = _radii(sa)
    rb = _radii(sb)
    if ra[0] <= 0.0 or rb[0] <= 0.0 or n_subdiv < 0:
        return ST_NOT_RUN
    lmat, c = _t_map(ra, rb, r_ab, t_ab)
    smax = 0.0
    for i in range(3):
        smax = max(smax, math.sqrt(lmat[i, 0] ** 2 + lmat[i, 1] ** 2 + lmat[i, 2] ** 2))
    scale = 1.0 + smax
    # point-in: origin in E  <=>  |L^{-1}(0 - c)| <= 1
    ui = _solve3(lmat, -c)
    if ui[0] * ui[0] + ui[1] * ui[1] + ui[2] * ui[2] <= 1.0:
        dir_c = _unit_or_z(c)
        _write_back(ra, c, dir_c, -1.0, np.int64(M_ELLIPSOID_SAMPLED), 0.0, out)
        return _classify(-1.0, scale)
    k = 1 << n_subdiv
    best = np.inf
    best_p = np.zeros(3)
    visited = 0
    p = np.empty(3)
    q = np.empty(3)
    for f in range(20):
        a0 = ICO_VERTS[ICO_FACES[f, 0]]
        a1 = ICO_VERTS[ICO_FACES[f, 1]]
        a2 = ICO_VERTS[ICO_FACES[f, 2]]
        for i in range(k + 1):
            for j in range(k + 1 - i):
                b1 = i / k
                b2 = j / k
                b0 = 1.0 - b1 - b2
                for m in range(3):
                    p[m] = b0 * a0[m] + b1 * a1[m] + b2 * a2[m]
                pn = math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
                for m in range(3):
                    q[m] = c[m] + (lmat[m, 0] * p[0] + lmat[m, 1] * p[1]
                                   + lmat[m, 2] * p[2]) / pn
                visited += 1
                d2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2]
                if d2 < best:
                    best = d2
                    for m in range(3):
                        best_p[m] = q[m]
        if best <= 1.0:
            break   # contact found: stop at the end of this face
    gap = math.sqrt(best) - 1.0
    _write_back(ra, best_p, _unit_or_z(best_p), gap, np.int64(M_ELLIPSOID_SAMPLED),
                float(visited), out)
    return _classify(gap, scale)
