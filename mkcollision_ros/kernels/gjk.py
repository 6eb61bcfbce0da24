"""GJK distance on the cores of two convex shapes given by their support mappings:
phase 1 of gjk_epa.gjk_epa_ws (``_gjk``), its polish near the end on cores apart
(``_gjk_smooth_polish``) and GJK on a pair pulled apart for EPA's witness points
(``_witness_by_gjk``).

References: Gilbert, Johnson, Keerthi 1988 (GJK); van den Bergen 2001 (the
duality-gap stopping rule); Ericson 2005, sec. 5.1 (the sub-simplex solver,
simplex.py).  Frames, units and the workspace ``ws``: gjk_epa.py and
gjk_epa_workspace.py.  Which pairs try which polish: polish_pairs.py.

GJK on the *cores* (spheres are points, capsules segments, others themselves;
geometry.support_core).  Sub-simplex solver: Voronoi-region tests (Ericson), face
weights from cross products, every face holding the new vertex tried (not only
those facing the origin), and a step that
does not shrink |v| is undone (robust to the sliver simplices of curved shapes);
if the duality gap is then still above GJK_POLISH_TOL |v|^2, apart is not proved
and the pair takes phase 3's fallback (gjk_epa._caps_fallback); likewise when a support
repeats a simplex vertex with the gap that wide (v then round-off near the
origin: a needle-thin difference, e.g. a long cone or capsule core against a
tiny body at its centre).
Stop on the duality gap |v|^2 - v.w <= max(GJK_REL_TOL |v|^2, GJK_ABS_TOL scale |v|),
or, when the caller gave a distance cutoff (``gjk_epa_ws``), as soon as a support
plane proves the pair farther apart than the cutoff (v.w / |v| is a lower bound).
When the cores are apart, subtract the inflation radii: exact for spheres,
capsules, ellipsoids (grown from their inner parallel body, geometry.py) and
margins even when the full shapes penetrate.
With an ellipsoid (and no convex hull, _smooth_pair, _ellipsoid_box), GJK on
curved cores closes its gap slowly (~25 steps to 1e-12 between two ellipsoids):
once the gap is below GJK_POLISH_TOL |v|^2, Newton's method (_newton_min_support,
below) is tried from the current direction (~14 steps in all between two
ellipsoids).  Where that direction is near a crease of h (a cylinder's side, a
capsule's core or a box's edges, _kink_side) the minimum along the crease is
searched instead (polish_crease._kink_polish, as in EPA): apart, h is convex and any
local minimum below zero is the global one.  Once |v| proves that the shapes
touch (so the exact distance is wanted), the crease search runs from the face
test's gap below (0.1 |v|^2): near a crease GJK's direction is within ~0.025 rad
of it by then, 4-7 GJK steps before the gap reaches GJK_POLISH_TOL.  Between a
box or a cylinder and a sphere or an ellipsoid, GJK also tests a box's face normal
or a cylinder's axis near its direction once its gap is below 0.1 |v|^2
(polish_faces._face_polish, as EPA, at most EPA_FACE_EVALS supports): a minimum it finds
with h < 0 is the global one.  Only from that gap: tested at every GJK step, it
saves no steps and slows the GJK loop of every pair, those it never runs on too.
Between a convex hull and an ellipsoid, GJK tests the hull's features near its
direction once its gap is below GJK_POLISH_TOL |v|^2 (polish_faces._hull_polish): the face of
the three highest hull vertices (the face test), the crease of the edge of the
two highest (the search along it), or Newton's method in a vertex's region.
EPA does not: deeper than the ellipsoid core's radii of curvature, h is not
convex around the hull's features, and their local minima lie as close as 0.03
rad (regression scene mkc_hull_face_polish_wrong_basin_ellipsoid_convex).  Even
with the cap the face test proves (_face_basin), which makes it safe, EPA's test
of the face of the three highest vertices costs more time than the steps it
saves: each try is passes over the hull's vertices.
"""
import math

import numpy as np

from .constants import (EPA_DEGEN_TOL, EPA_FACE_EVALS, EPA_WITNESS_SHIFT, GJK_ABS_TOL,
                        GJK_FACE_TOL, GJK_MAX_ITERS, GJK_POLISH_TOL, GJK_REL_TOL)
from .geometry import borrow_args, meet, minkowski_core_xyz
from .gjk_epa_workspace import (_FS_ROWS, _L3, _LAM, _LAMP, _PK, _PN, _PW, _T_D, _T_MIN_D,
                                _T_MIN_W, _T_SHIFT, _T_VPREV, _T_W, _T_WA, _T_WB, _VOL, _VV, _W,
                                _WA, _WAP, _WB, _WBP, _WP, _dot, borrow_gjk_workspace)
from .jit import borrow, njit_kernel, njit_separate
from .polish_crease import _kink_polish
from .polish_faces import _face_polish, _hull_polish
from .polish_newton import _newton_min_support
from .polish_pairs import _face_pair, _gjk_newton_pair, _hull_side, _kink_side
from .simplex import _closest_simplex
from .tracebuf import TR_GJK, trace_rows

# outcome flags of the GJK loop
_GJK_APART = 0       # converged, origin outside: v is the closest point
_GJK_OVERLAP = 1     # origin inside (or within round-off of) the simplex
_GJK_CAP = 2         # iteration cap hit
_GJK_BOUND = 3       # stopped early: the cores are farther apart than the caller's stop
                     # distance (v is not the closest point; the returned bound is)
_GJK_POLISHED = 4    # apart, minimum found by _newton_min_support (ws t3 rows 15-18)
_GJK_STALL = 5       # no progress in floating point (a sliver simplex) with the duality
                     # gap still above GJK_POLISH_TOL |v|^2: apart is not proved


@njit_separate
def _gjk(sa, sb, verts, r_ab, t_ab, scale, ws, stop, polish, trace_on):
    """GJK loop on the cores (geometry.minkowski_core_xyz).  A separate kernel (jit.py),
    called once a pair by gjk_epa_ws and by _witness_by_gjk: inlined, its ~4,700
    statements were compiled twice.

    Writes into the workspace ``ws``: W, WA, WB float64 (4, 3), the simplex of A - B and
    the support points of A and B (A's frame), lam (4,) barycentric weights, v (3,) the
    closest point of the simplex.
    ``stop`` (m, may be inf): as soon as a support plane proves the distance > stop
    (v.w / |v| > stop), return _GJK_BOUND with that lower bound.
    ``polish`` True: once the duality gap is below 0.1 |v|^2, for a _face_pair, the
    face test (_face_polish) where the direction is near a face normal, and, when |v|
    < ``stop`` (the shapes touch), the crease search where it is near a crease; once
    the gap is below GJK_POLISH_TOL |v|^2, the crease search or _newton_min_support
    from the current direction with the last few supports as samples (ellipsoid
    cores: GJK needs ~25 steps to 1e-12 there), or between a convex hull and an
    ellipsoid the tests of the hull's features (_hull_polish); on success return
    _GJK_POLISHED, else go on.
    ``trace_on`` True: the simplices are recorded in ws[0]'s trace region (module
    docstring, "Trace").
    Returns (vertex count, iterations, flag _GJK_APART/_GJK_OVERLAP/_GJK_CAP/_GJK_BOUND/
    _GJK_STALL, the lower bound v.w / |v| for _GJK_BOUND, else 0).
    Inlined into its two callers: as a called function it costs ~0.3 us more per deep
    pair (bench/dev/deep_pairs.py), more than the call itself (its ~75 words of array
    structs) can explain.  _epa stays a call: inlined, it is hardly faster on cylinders
    and slower on ellipsoids."""
    fs, fv = ws[0], ws[1]
    W, WA, WB = fs[_W:_W + 4], fs[_WA:_WA + 4], fs[_WB:_WB + 4]
    lam, v = fv[_LAM:_LAM + 4], fv[_VV:_VV + 3]
    d, wa, wb, w = ws[0][_T_D], ws[0][_T_WA], ws[0][_T_WB], ws[0][_T_W]
    for q in range(4):
        lam[q] = 0.0
    tn = math.sqrt(_dot(t_ab, t_ab))
    if tn > 0.0:
        for c in range(3):
            d[c] = t_ab[c]
    else:
        d[0], d[1], d[2] = 1.0, 0.0, 0.0
    ax_, ay_, az_, bx_, by_, bz_ = minkowski_core_xyz(
        sa, sb, verts, r_ab, t_ab, d[0], d[1], d[2])
    wa[0], wa[1], wa[2] = ax_, ay_, az_
    wb[0], wb[1], wb[2] = bx_, by_, bz_
    w[0], w[1], w[2] = ax_ - bx_, ay_ - by_, az_ - bz_
    for c in range(3):
        W[0, c] = w[c]
        WA[0, c] = wa[c]
        WB[0, c] = wb[c]
        v[c] = w[c]
    lam[0] = 1.0
    n = np.int64(1)
    if trace_on:
        trace_rows(fs, np.int64(_FS_ROWS), np.int64(TR_GJK), W, n)
    if tn > 0.0:
        # the centre line may already separate them: h_{A-B}(t/|t|) < -stop (the first
        # support is along it; MuJoCo's GJK makes the same test before its first step)
        ht = _dot(d, w) / tn
        if -ht > stop:
            for c in range(3):
                v[c] = d[c] * (ht / tn)
            return n, 0, _GJK_BOUND, -ht
    zero2 = (EPA_DEGEN_TOL * scale) ** 2
    vv = _dot(v, v)
    W_prev, WA_prev, WB_prev = fs[_WP:_WP + 4], fs[_WAP:_WAP + 4], fs[_WBP:_WBP + 4]
    lam_prev = fv[_LAMP:_LAMP + 4]
    v_prev = ws[0][_T_VPREV]
    it = 0
    flag = _GJK_CAP
    PN, PW = fs[_PN:_PN + _PK], fs[_PW:_PW + _PK]
    nsamp = 0
    # the face test (_face_polish) at the current direction near the end (with the
    # polish below), at most EPA_FACE_EVALS supports: a minimum it finds with h < 0 is
    # the global one (cores apart, h convex)
    face_left = EPA_FACE_EVALS if (polish and _face_pair(sa[0], sb[0])) else 0
    # the crease search from the face test's gap (0.1 |v|^2) when |v| proves that the
    # shapes touch (a distance they need exactly; contacts-mode pairs apart keep their
    # early separation certificate): near a crease GJK's direction is within 0.025 rad
    # of it by then, and the search ends GJK 4-7 steps before GJK_POLISH_TOL would
    crease_early = polish
    stop2 = stop * stop
    while it < GJK_MAX_ITERS:
        if vv <= zero2:
            flag = _GJK_OVERLAP
            break
        it += 1
        for c in range(3):
            d[c] = -v[c]
        ax_, ay_, az_, bx_, by_, bz_ = minkowski_core_xyz(
            sa, sb, verts, r_ab, t_ab, d[0], d[1], d[2])
        wa[0], wa[1], wa[2] = ax_, ay_, az_
        wb[0], wb[1], wb[2] = bx_, by_, bz_
        w[0], w[1], w[2] = ax_ - bx_, ay_ - by_, az_ - bz_
        vw = _dot(v, w)
        if vw > stop * math.sqrt(vv):
            return n, it, _GJK_BOUND, vw / math.sqrt(vv)
        gap = vv - vw
        if gap <= GJK_REL_TOL * vv or gap <= GJK_ABS_TOL * scale * math.sqrt(vv):
            flag = _GJK_APART
            break
        if polish and gap <= GJK_FACE_TOL * vv:
            inv = 1.0 / math.sqrt(vv)
            if face_left > 0:
                # near a box's face normal or a cylinder's axis (within EPA_KINK_NEAR)
                k_f = _face_polish(sa, sb, verts, r_ab, t_ab, scale, ws,
                                   d[0] * inv, d[1] * inv, d[2] * inv)
                if k_f != 0:
                    face_left -= 1
                    it += 1
                    if k_f > 0 and _dot(fs[_T_MIN_D], fs[_T_MIN_W]) < 0.0:
                        return n, it, _GJK_POLISHED, 0.0
            # near the end: the last 4 supports (this one included, which the fit
            # skips) are the samples
            slot = nsamp % 4
            for c in range(3):
                PN[slot, c] = d[c] * inv
                PW[slot, c] = w[c]
            nsamp += 1
            last = gap <= GJK_POLISH_TOL * vv
            if last or (crease_early and vv < stop2):
                polish = not last
                # near a crease of h (a cylinder's side, a capsule's core, a box's
                # edges: _kink_side), the minimum along it, from this gap on once the
                # shapes are proved to touch; else, at GJK_POLISH_TOL, Newton's method
                # where h is smooth.  Apart, h is convex and any local minimum below
                # zero is the global one, so no basin test is needed
                kc = _kink_side(sa, sb, r_ab, d[0] * inv, d[1] * inv, d[2] * inv, np.bool_(True))
                k_pol = 0
                if kc >= 0:
                    crease_early = False
                    for c in range(3):
                        d[c] *= inv
                    k_pol = _kink_polish(sa, sb, verts, r_ab, t_ab, scale, ws,
                                         kc // 3, kc % 3)
                elif last and kc == -1 and _gjk_newton_pair(sa[0], sb[0]):
                    k_pol = _gjk_smooth_polish(sa, sb, verts, r_ab, t_ab, scale, ws,
                                               min(nsamp, 4), d[0] * inv, d[1] * inv,
                                               d[2] * inv, w[0], w[1], w[2], wa[0], wa[1],
                                               wa[2])
                if k_pol > 0 and _dot(fs[_T_MIN_D], fs[_T_MIN_W]) < 0.0:
                    return n, it + k_pol, _GJK_POLISHED, 0.0
                it += abs(k_pol)
        dup = False
        for i in range(n):
            if W[i, 0] == w[0] and W[i, 1] == w[1] and W[i, 2] == w[2]:
                dup = True
        if dup:
            # a repeated support proves the gap closed, unless round-off made v (then
            # tiny, near the origin) a direction of noise: the gap tells
            flag = _GJK_STALL if gap > GJK_POLISH_TOL * vv else _GJK_APART
            break
        # keep the current simplex in case the update makes no progress
        n_prev = n
        for q in range(4):
            lam_prev[q] = lam[q]
            for c in range(3):
                W_prev[q, c] = W[q, c]
                WA_prev[q, c] = WA[q, c]
                WB_prev[q, c] = WB[q, c]
        for c in range(3):
            v_prev[c] = v[c]
            W[n, c] = w[c]
            WA[n, c] = wa[c]
            WB[n, c] = wb[c]
        n += 1
        n = _closest_simplex(W, WA, WB, n, lam, v, ws[1][_L3:_L3 + 3], ws[1][_VOL:_VOL + 4])
        if n == 4:
            flag = _GJK_OVERLAP
            if trace_on:
                trace_rows(fs, np.int64(_FS_ROWS), np.int64(TR_GJK), W, n)
            break
        vv_new = _dot(v, v)
        if vv_new >= vv:
            # no progress in floating point (a sliver simplex): keep the better one
            n = n_prev
            for q in range(4):
                lam[q] = lam_prev[q]
                for c in range(3):
                    W[q, c] = W_prev[q, c]
                    WA[q, c] = WA_prev[q, c]
                    WB[q, c] = WB_prev[q, c]
            for c in range(3):
                v[c] = v_prev[c]
            if vv <= zero2:
                flag = _GJK_OVERLAP
            elif gap > GJK_POLISH_TOL * vv:
                flag = _GJK_STALL
            else:
                flag = _GJK_APART
            break
        if trace_on:
            trace_rows(fs, np.int64(_FS_ROWS), np.int64(TR_GJK), W, n)
        vv = vv_new
    return n, it, flag, 0.0


@njit_kernel
def _gjk_smooth_polish(sa, sb, verts, r_ab, t_ab, scale, ws, ns, nx, ny, nz,
                       wx, wy, wz, ax, ay, az):
    """GJK's polish near the end on cores apart, away from the creases _kink_side
    finds: _newton_min_support (same arguments and return), but between a convex hull
    and an ellipsoid first the tests of the hull's features near n (_hull_polish),
    Newton's method only in a vertex's region.  A function of its own so that _gjk's
    loop, inlined into its callers, stays lean: with the hull's branch written into
    it, deep pairs of rows that never take the branch take 4-7% more time
    (capsule-cylinder, cylinder-cylinder, cylinder-convex, box-cylinder,
    sphere-convex; bench/dev/ab_deep.py, identical results)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    side = _hull_side(sa[0], sb[0])
    if side < 0:
        return _newton_min_support(sa, sb, verts, r_ab, t_ab, scale, ws, ns,
                                   nx, ny, nz, wx, wy, wz, ax, ay, az)
    k, vertex = _hull_polish(sa, sb, verts, r_ab, t_ab, scale, ws, side, nx, ny, nz)
    if not vertex:
        return k
    kn = _newton_min_support(sa, sb, verts, r_ab, t_ab, scale, ws, ns,
                             nx, ny, nz, wx, wy, wz, ax, ay, az)
    return kn + abs(k) if kn > 0 else kn - abs(k)


@njit_separate
def _witness_by_gjk(sa, sb, verts, r_ab, t_ab, scale, ws, res):
    """Witness points for an EPA result whose origin projection fell outside its face
    (sliver faces of flat or face-to-face contacts; the barycentric witnesses would then
    leave the shapes).  B's core is moved out along the normal by the depth plus
    EPA_WITNESS_SHIFT * scale, just apart, and GJK gives the closest points there
    (convex combinations of support points: on the cores); B's point is moved back and
    the pair is made to satisfy pb - pa == -depth * n by splitting the remainder (at most
    ~the shift).  Updates res[4:10] (A's frame) and returns the GJK iterations, or 0
    and leaves res as it is when GJK does not report the shapes apart."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws, res = borrow_gjk_workspace(ws), borrow(res)
    dep = res[0]
    sh = dep + EPA_WITNESS_SHIFT * scale
    t2 = ws[0][_T_SHIFT]
    for c in range(3):
        t2[c] = t_ab[c] + sh * res[1 + c]
    n, it, flag, _ = _gjk(sa, sb, verts, r_ab, t2, scale, ws, math.inf, np.bool_(False),
                          np.bool_(False))
    if flag != _GJK_APART and flag != _GJK_STALL:
        return 0
    fs, fv = ws[0], ws[1]
    for c in range(3):
        pa = 0.0
        pb = 0.0
        for i in range(n):
            pa += fv[_LAM + i] * fs[_WA + i, c]
            pb += fv[_LAM + i] * fs[_WB + i, c]
        pb -= sh * res[1 + c]
        res[4 + c], res[7 + c] = meet(pa, pb, -(dep * res[1 + c]))
    return it
