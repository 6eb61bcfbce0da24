"""Newton's method on the minimum of the support function h = h_{A-B} over unit
directions, the polish GJK (gjk._gjk_smooth_polish) and EPA (``_epa_polish``, from
EPA's best face) try on smooth pairs (polish_pairs._smooth_pair, _ellipsoid_box).
The minimum found is left in the workspace's polish rows (gjk_epa_workspace._store_min);
EPA keeps it only under the tests of certificates.py.

Newton's method (_newton_min_support): min over unit u of h_{A-B}(u) is minus the
signed distance in both regimes; the gradient of h on the sphere is the tangential
part of the support point, the Hessian J - h I with J = d support / d u fitted by
least squares to nearby support points (EPA's face vertices with the directions
they were found along, GJK's last supports, then its own steps).  Quadratic where
A - B is smooth and curved (ellipsoid cores): ~3 supports from a 1e-3 gap to a
step below POLISH_STEP_DONE (1e-6 rad, the step it would take next rather than the
one taken).  It gives up on kinks of h (flat faces, edges, rims, segment cores),
which is why only ellipsoid pairs try it (cylinder pairs: kinks on every pair
tried).  Against a run at EPA_REL_TOL 1e-11 on 1500 random pairs per type, its
normals are within 3.8e-4 rad and its distances within 1e-8 * scale.
"""
import math

import numpy as np

from .constants import (EPA_MAX_FACES, EPA_POLISH_ITERS, EPA_POLISH_STEP, NEWTON_DET_MIN,
                        POLISH_STEP_DONE, SUPPORT_TIE)
from .geometry import borrow_args, minkowski_core_xyz
from .gjk_epa_workspace import (_IF, _NVMAX, _PK, _PN, _PW, _T_D, _T_W, _T_WA, _V, _VD, _store_min,
                                borrow_gjk_workspace)
from .jit import njit_inline, njit_kernel


@njit_inline
def _tangent_basis(nx, ny, nz):
    """Orthonormal tangent vectors (e1, e2) at the unit direction n, as six floats:
    e1 from n's two components other than a large x, e2 = n x e1."""
    if abs(nx) < 0.6:
        e1x, e1y, e1z = 0.0, nz, -ny
    else:
        e1x, e1y, e1z = -nz, 0.0, nx
    n1 = math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
    e1x, e1y, e1z = e1x / n1, e1y / n1, e1z / n1
    return (e1x, e1y, e1z, ny * e1z - nz * e1y, nz * e1x - nx * e1z, nx * e1y - ny * e1x)


@njit_kernel
def _newton_min_support(sa, sb, verts, r_ab, t_ab, scale, ws, ns, nx, ny, nz,
                        wx, wy, wz, ax, ay, az):
    """Newton's method for min over unit u of h(u) = h_{A-B}(u), from the unit direction
    n = (nx, ny, nz) with its support point w of A - B and a of A, given ``ns`` samples
    (direction, support point of A - B) near n in the rows PN, PW of ``ws``.

    min h is minus the signed distance of A and B: the depth when EPA runs, the
    distance (negated) when GJK does, so one routine serves both.

    Where the boundary of A - B is smooth and curved at the minimiser (ellipsoid
    cores), EPA's bounds close only by a factor of ~2-3 per step and GJK's by less;
    this converges quadratically.  The gradient of h on the unit sphere is the
    tangential part of the support point; its Hessian is J - h I, J being the
    tangential Jacobian d support / d u (the radii of curvature of A - B), fitted by
    least squares to the support points known around u: the samples and the steps
    taken.  Gives up when the fitted Hessian is not positive definite (flat faces,
    edges, kinks of h, where EPA and GJK are exact or fast), a step is longer than
    EPA_POLISH_STEP rad, h grows, or EPA_POLISH_ITERS steps do not bring the step below
    POLISH_STEP_DONE; the caller then goes on with its own iteration.  On success the
    direction, the difference point and the support points of A and B are left in ws
    t3 rows 15-18 (the caller's d, wa, wb, w stay as they were).
    Returns the number of support evaluations, negated when it gave up."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    fs = ws[0]
    PN, PW = fs[_PN:_PN + _PK], fs[_PW:_PW + _PK]
    if ns < 2:
        return 0
    h = nx * wx + ny * wy + nz * wz
    for k_it in range(EPA_POLISH_ITERS):
        e1x, e1y, e1z, e2x, e2y, e2z = _tangent_basis(nx, ny, nz)
        g1 = e1x * wx + e1y * wy + e1z * wz
        g2 = e2x * wx + e2y * wy + e2z * wz
        # J = C M^-1 from the samples' tangential differences (each sample normalised)
        m11 = m12 = m22 = c11 = c12 = c21 = c22 = 0.0
        for k in range(ns):
            dnx, dny, dnz = PN[k, 0] - nx, PN[k, 1] - ny, PN[k, 2] - nz
            dvx, dvy, dvz = PW[k, 0] - wx, PW[k, 1] - wy, PW[k, 2] - wz
            a1 = e1x * dnx + e1y * dny + e1z * dnz
            a2 = e2x * dnx + e2y * dny + e2z * dnz
            b1 = e1x * dvx + e1y * dvy + e1z * dvz
            b2 = e2x * dvx + e2y * dvy + e2z * dvz
            qq = a1 * a1 + a2 * a2
            if not qq > 0.0:
                continue
            wt = 1.0 / qq
            m11 += wt * a1 * a1
            m12 += wt * a1 * a2
            m22 += wt * a2 * a2
            c11 += wt * b1 * a1
            c12 += wt * b1 * a2
            c21 += wt * b2 * a1
            c22 += wt * b2 * a2
        det = m11 * m22 - m12 * m12
        if not det > NEWTON_DET_MIN * (m11 + m22) ** 2:
            return -k_it            # the samples span one tangent direction only
        i11, i12, i22 = m22 / det, -m12 / det, m11 / det
        h11 = c11 * i11 + c12 * i12 - h
        h22 = c21 * i12 + c22 * i22 - h
        h12 = 0.5 * ((c11 * i12 + c12 * i22) + (c21 * i11 + c22 * i12))
        hd = h11 * h22 - h12 * h12
        if not (h11 > 0.0 and hd > 0.0):
            return -k_it
        s1 = -(h22 * g1 - h12 * g2) / hd
        s2 = -(h11 * g2 - h12 * g1) / hd
        step = math.sqrt(s1 * s1 + s2 * s2)
        if not step <= EPA_POLISH_STEP:
            return -k_it
        if k_it > 0 and step <= POLISH_STEP_DONE:
            # the step it would take is below POLISH_STEP_DONE: the current point is
            # within about that step of the minimum, h within ~h'' step^2 / 2 of it
            # (no support spent on the step itself)
            _store_min(fs, nx, ny, nz, wx, wy, wz, ax, ay, az, ax - wx, ay - wy, az - wz)
            return k_it
        PN[ns, 0], PN[ns, 1], PN[ns, 2] = nx, ny, nz
        PW[ns, 0], PW[ns, 1], PW[ns, 2] = wx, wy, wz
        ns += 1
        mx = nx + s1 * e1x + s2 * e2x
        my = ny + s1 * e1y + s2 * e2y
        mz = nz + s1 * e1z + s2 * e2z
        inv = 1.0 / math.sqrt(mx * mx + my * my + mz * mz)
        mx, my, mz = mx * inv, my * inv, mz * inv
        pax, pay, paz, pbx, pby, pbz = minkowski_core_xyz(
            sa, sb, verts, r_ab, t_ab, mx, my, mz)
        qx, qy, qz = pax - pbx, pay - pby, paz - pbz
        hn = mx * qx + my * qy + mz * qz
        if not hn <= h + SUPPORT_TIE * scale:
            return -(k_it + 1)
        nx, ny, nz, wx, wy, wz, h = mx, my, mz, qx, qy, qz, hn
        ax, ay, az = pax, pay, paz
        if step <= POLISH_STEP_DONE:
            _store_min(fs, nx, ny, nz, wx, wy, wz, ax, ay, az, ax - wx, ay - wy, az - wz)
            return k_it + 1
    return -EPA_POLISH_ITERS


@njit_kernel
def _epa_polish(sa, sb, verts, r_ab, t_ab, scale, ws, f):
    """_newton_min_support started at the normal of EPA's best face f, whose support
    point (ws t3 rows 8-11: d, wa, wb, w) is at hand; its first samples are the face's
    vertices (EPA stored the direction of each, VD).  Same return and results."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    fs = ws[0]
    V, VD = fs[_V:_V + _NVMAX], fs[_VD:_VD + _NVMAX]
    PN, PW = fs[_PN:_PN + _PK], fs[_PW:_PW + _PK]
    F = ws[2][_IF:_IF + EPA_MAX_FACES]
    d, wa, w = fs[_T_D], fs[_T_WA], fs[_T_W]
    ns = np.int64(0)          # typed int64 at once (jit.py, "Literal")
    for q in range(3):
        i = F[f, q]
        if VD[i, 0] != 0.0 or VD[i, 1] != 0.0 or VD[i, 2] != 0.0:
            for c in range(3):
                PN[ns, c] = VD[i, c]
                PW[ns, c] = V[i, c]
            ns += 1
    return _newton_min_support(sa, sb, verts, r_ab, t_ab, scale, ws, ns,
                               d[0], d[1], d[2], w[0], w[1], w[2], wa[0], wa[1], wa[2])
