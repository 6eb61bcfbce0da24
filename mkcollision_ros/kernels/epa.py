"""EPA penetration depth of two convex shapes whose cores overlap: phase 2 of
gjk_epa.gjk_epa_ws (``_epa``), the growth of GJK's simplex to a tetrahedron
(``_grow_to_tetra``), the polytope's faces (``_face_setup``, ``_face_plane``,
``_edge_of``), its trace records (``_trace_polytope``) and the pattern search of the
caps (``_polish_min_support``).

Reference: G. van den Bergen, "Proximity queries and penetration depth computation on
3D game objects", GDC 2001.  Frames, units and the workspace ``ws``: gjk_epa.py and
gjk_epa_workspace.py.  The polish steps EPA tries and the tests that keep their
minima: polish_newton.py, polish_crease.py, polish_faces.py, certificates.py; which
pairs try which: polish_pairs.py.

When the cores overlap (origin inside the GJK tetrahedron, or |v| <=
EPA_DEGEN_TOL * scale), EPA on the *cores*: the full difference is the core one
grown by a ball of radius r_a + r_b, so depth = core depth + r_a + r_b exactly.
The simplex is grown to a tetrahedron by supports normal to its affine hull (a
flat core difference, e.g. two crossing capsule axes, gives core depth 0 with the
flat direction as normal).  EPA: pop the face nearest the origin, add the support
point along its normal, remove the faces it sees (flood fill over the stored face
adjacency from that face, so a step costs the seen faces, not all faces), close the
horizon with new faces and link them to their neighbours; stop when the support gain <
EPA_REL_TOL * scale.  Fixed buffers: EPA_MAX_ITERS vertices, EPA_MAX_FACES faces.
With an ellipsoid (same rule), at a gain of EPA_POLISH_TOL * scale (and once
more 100x closer if it gives up) Newton's method is tried from the best face's
normal, and its minimum kept only if no direction outside a cap of
EPA_POLISH_CAP around its normal can be deeper by EPA's faces (_polish_is_global:
another basin could be deeper; regression scene
mkc_epa_polish_wrong_basin_ellipsoid_cone).  With a cylinder (and the other
shape a cylinder, capsule, sphere or ellipsoid, _kink_partner) or a capsule (and
the other shape a sphere or an ellipsoid; _searched_crease) or a box (against a
sphere or an ellipsoid), when the best face's normal is near the crease of the
cylinder's side, the capsule's core (the great circle normal to its axis) or one
of the box's edge directions, the minimum along that crease is searched instead
(_kink_polish, secant steps on h's derivative along the circle), with the checks
across the crease and, between two cylinders, against the other crease and the
point kinks nearby, and the same cap test (with a capsule, a cap of 0.05 rad,
EPA_KINK_CAP_CAPSULE; on a box's crease 0.1 rad, EPA_KINK_CAP_BOX: regression scenes
mkc_crease_polish_wrong_basin_ellipsoid_capsule and _ellipsoid_box); on 100,000
deep random pairs per row no depth is off EPA's own by more than 1.2e-8 * scale.
Between a box or a cylinder and a sphere or an ellipsoid, and between two
cylinders (_epa_face_pair), when the best face's normal is near a box's face
normal or a cylinder's axis, one support point there tells whether that normal is
a minimum (_face_polish: the other shape's point projects into the face), from a
gain of EPA_FACE_TOL * scale, and proves a cap around it with no deeper direction
(_face_basin), the cap of the test below (no fixed cap is safe: regression scene
mkc_face_polish_wrong_basin_ellipsoid_cylinder).
A minimum whose cap test fails stays a candidate and is tested again at every
later step as the polytope grows: it is taken as soon as the test passes, or
dropped when EPA finds a direction deeper by more than the tolerance.  Two
cylinders have one crossing face, normal to both axes, so EPA tests it once at its
start, with no support (_cylinders_crossing), not at every step from its best face.

Caps: when EPA hits EPA_MAX_ITERS or EPA_MAX_FACES, the best upper bound min h(u) over
the evaluated normals is polished by the pattern search ``_polish_min_support`` and
reported with the lower bound (gjk_epa.py, phase 3).
"""
import math

import numpy as np

from .certificates import _pending_bound, _polish_is_global, _vertex_cap
from .constants import (BARY_SLACK, BOX, CAPSULE, CYLINDER, ELLIPSOID, EPA_DEGEN_TOL,
                        EPA_FACE_EVALS, EPA_FACE_TOL, EPA_MAX_FACES, EPA_MAX_ITERS,
                        EPA_PATTERN_STEP, EPA_PATTERN_STEP_MIN, EPA_POLISH_RETRY, EPA_POLISH_TOL,
                        EPA_REL_TOL, EPA_SLIVER_BARY, SPHERE)
from .geometry import borrow_args, meet, minkowski_core_xyz
from .gjk_epa_workspace import (_CAND, _FD, _FN, _FS_ROWS, _IA, _IC, _IE, _IF, _IH, _IS, _L3,
                                _NVMAX, _RES, _T_BEST_DIR, _T_BEST_W, _T_BEST_WA, _T_BEST_WB,
                                _T_CIN, _T_D, _T_FACE_CAP, _T_MIN_D, _T_PAT_D, _T_PAT_E1,
                                _T_PAT_E2, _T_PAT_W, _T_PAT_WA, _T_PAT_WB, _T_UD, _T_UWA, _T_W,
                                _T_WA, _T_WB, _V, _VA, _VB, _VD, _W, _WA, _WB, _dot,
                                _take_polished, borrow_gjk_workspace)
from .jit import borrow, njit_inline, njit_kernel, njit_separate
from .polish_crease import _kink_polish
from .polish_faces import _crossing_test, _cylinders_crossing, _face_polish
from .polish_newton import _epa_polish, _tangent_basis
from .polish_pairs import (_crossing_pair, _ellipsoid_box, _epa_face_pair, _kink_side, _polish_cap,
                           _searched_crease, _smooth_pair)
from .simplex import _tri_closest
from .tracebuf import TR_EPA, TR_HEADER_ROWS, trace_open


@njit_kernel
def _grow_to_tetra(sa, sb, verts, r_ab, t_ab, scale, ws, n):
    """Grow a simplex W[:n] holding the origin to a tetrahedron by supports of the full
    shapes along directions normal to its affine hull.  Returns the new count (4), or
    -1 when the Minkowski difference is flat there (touching, depth 0); on -1 the unit
    normal of the flat direction is in W[3].  W, WA, WB: the workspace's simplex."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    W, WA, WB = ws[0][_W:_W + 4], ws[0][_WA:_WA + 4], ws[0][_WB:_WB + 4]
    d, wa, wb, w = ws[0][_T_D], ws[0][_T_WA], ws[0][_T_WB], ws[0][_T_W]
    cand = ws[0][_CAND:_CAND + 6]
    tol = EPA_DEGEN_TOL * scale
    while n < 4:
        # candidate directions orthogonal to the hull of W[:n]
        ndir = 0
        for k in range(6):
            for c in range(3):
                cand[k, c] = 0.0
        if n == 1:
            for k in range(3):
                cand[2 * k, k] = 1.0
                cand[2 * k + 1, k] = -1.0
            ndir = 6
        elif n == 2:
            ex, ey, ez = W[1, 0] - W[0, 0], W[1, 1] - W[0, 1], W[1, 2] - W[0, 2]
            ax, ay, az = abs(ex), abs(ey), abs(ez)
            if ax <= ay and ax <= az:
                ux, uy, uz = 0.0, -ez, ey
            elif ay <= az:
                ux, uy, uz = ez, 0.0, -ex
            else:
                ux, uy, uz = -ey, ex, 0.0
            px = ey * uz - ez * uy
            py = ez * ux - ex * uz
            pz = ex * uy - ey * ux
            cand[0, 0], cand[0, 1], cand[0, 2] = ux, uy, uz
            cand[1, 0], cand[1, 1], cand[1, 2] = -ux, -uy, -uz
            cand[2, 0], cand[2, 1], cand[2, 2] = px, py, pz
            cand[3, 0], cand[3, 1], cand[3, 2] = -px, -py, -pz
            ndir = 4
        else:
            ux, uy, uz = W[1, 0] - W[0, 0], W[1, 1] - W[0, 1], W[1, 2] - W[0, 2]
            wx, wy, wz = W[2, 0] - W[0, 0], W[2, 1] - W[0, 1], W[2, 2] - W[0, 2]
            nx = uy * wz - uz * wy
            ny = uz * wx - ux * wz
            nz = ux * wy - uy * wx
            cand[0, 0], cand[0, 1], cand[0, 2] = nx, ny, nz
            cand[1, 0], cand[1, 1], cand[1, 2] = -nx, -ny, -nz
            ndir = 2
        best = -1.0
        bw, bwa, bwb, bdir = ws[0][_T_BEST_W], ws[0][_T_BEST_WA], ws[0][_T_BEST_WB], ws[0][_T_BEST_DIR]
        for c in range(3):
            bdir[c] = 0.0
        for k in range(ndir):
            dn = math.sqrt(cand[k, 0] ** 2 + cand[k, 1] ** 2 + cand[k, 2] ** 2)
            if not dn > 0.0:
                continue
            for c in range(3):
                d[c] = cand[k, c] / dn
            ax_, ay_, az_, bx_, by_, bz_ = minkowski_core_xyz(
                sa, sb, verts, r_ab, t_ab, d[0], d[1], d[2])
            wa[0], wa[1], wa[2] = ax_, ay_, az_
            wb[0], wb[1], wb[2] = bx_, by_, bz_
            w[0], w[1], w[2] = ax_ - bx_, ay_ - by_, az_ - bz_
            # distance of w from the affine hull of W[:n], measured along d
            off = (w[0] - W[0, 0]) * d[0] + (w[1] - W[0, 1]) * d[1] + (w[2] - W[0, 2]) * d[2]
            if n == 1:
                off = math.sqrt((w[0] - W[0, 0]) ** 2 + (w[1] - W[0, 1]) ** 2
                                + (w[2] - W[0, 2]) ** 2)
            if off > best:
                best = off
                for c in range(3):
                    bw[c] = w[c]
                    bwa[c] = wa[c]
                    bwb[c] = wb[c]
                    bdir[c] = d[c]
        if not best > tol:
            if n == 3:
                for c in range(3):
                    W[3, c] = cand[0, c]
            else:
                for c in range(3):
                    W[3, c] = bdir[c]
            return -1
        for c in range(3):
            W[n, c] = bw[c]
            WA[n, c] = bwa[c]
            WB[n, c] = bwb[c]
        n += 1
    return n


@njit_inline
def _face_setup(V, F, FN, FD, f, cin):
    """Normal (outward, away from the interior point cin) and origin distance of face f.
    Returns False for a degenerate (zero-area) face."""
    if _face_plane(V, F, FN, FD, f, cin):
        F[f, 1], F[f, 2] = F[f, 2], F[f, 1]
        FN[f, 0], FN[f, 1], FN[f, 2] = -FN[f, 0], -FN[f, 1], -FN[f, 2]
        FD[f] = -FD[f]
    return FD[f] < np.inf


@njit_inline
def _face_plane(V, F, FN, FD, f, cin):
    """Unit normal FN[f] and origin distance FD[f] of face f as wound (F[f] is not
    written: EPA's new faces are set up in a loop that stores nothing else, and a
    conditional write of F there cost 12% of a deep GJK/EPA pair); a degenerate
    (zero-area) face gets FN = 0, FD = inf.  Returns True when the winding faces the
    interior point cin (the caller then flips it, _face_setup)."""
    i, j, k = F[f, 0], F[f, 1], F[f, 2]
    ux, uy, uz = V[j, 0] - V[i, 0], V[j, 1] - V[i, 1], V[j, 2] - V[i, 2]
    wx, wy, wz = V[k, 0] - V[i, 0], V[k, 1] - V[i, 1], V[k, 2] - V[i, 2]
    nx = uy * wz - uz * wy
    ny = uz * wx - ux * wz
    nz = ux * wy - uy * wx
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not nn > 0.0:
        FN[f, 0], FN[f, 1], FN[f, 2] = 0.0, 0.0, 0.0
        FD[f] = np.inf
        return False
    inv = 1.0 / nn        # one division, not three (three would be a third of EPA's step)
    nx *= inv
    ny *= inv
    nz *= inv
    FN[f, 0], FN[f, 1], FN[f, 2] = nx, ny, nz
    FD[f] = nx * V[i, 0] + ny * V[i, 1] + nz * V[i, 2]
    return nx * (V[i, 0] - cin[0]) + ny * (V[i, 1] - cin[1]) + nz * (V[i, 2] - cin[2]) < 0.0


@njit_kernel
def _polish_min_support(sa, sb, verts, r_ab, t_ab, scale, ud, uwa, ub, ws):
    """Pattern search for min over unit u of h_{A-B}(u) starting at ``ud`` (3,) with
    value ``ub``; updates ud and uwa (A's support point) in place, returns the value."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ud, uwa, ws = borrow(ud), borrow(uwa), borrow_gjk_workspace(ws)
    d, wa, wb, w = ws[0][_T_PAT_D], ws[0][_T_PAT_WA], ws[0][_T_PAT_WB], ws[0][_T_PAT_W]
    e1, e2 = ws[0][_T_PAT_E1], ws[0][_T_PAT_E2]
    step = EPA_PATTERN_STEP
    it = 0
    while step > EPA_PATTERN_STEP_MIN and it < 4 * EPA_MAX_ITERS:
        e1[0], e1[1], e1[2], e2[0], e2[1], e2[2] = _tangent_basis(ud[0], ud[1], ud[2])
        improved = False
        for m in range(8):
            ang = m * (math.pi / 4.0)
            ca, sn = math.cos(ang) * step, math.sin(ang) * step
            for c in range(3):
                d[c] = ud[c] + ca * e1[c] + sn * e2[c]
            dn = math.sqrt(_dot(d, d))
            for c in range(3):
                d[c] /= dn
            ax_, ay_, az_, bx_, by_, bz_ = minkowski_core_xyz(
                sa, sb, verts, r_ab, t_ab, d[0], d[1], d[2])
            wa[0], wa[1], wa[2] = ax_, ay_, az_
            wb[0], wb[1], wb[2] = bx_, by_, bz_
            w[0], w[1], w[2] = ax_ - bx_, ay_ - by_, az_ - bz_
            it += 1
            hd = _dot(d, w)
            if hd < ub:
                ub = hd
                for c in range(3):
                    ud[c] = d[c]
                    uwa[c] = wa[c]
                improved = True
                break
        if not improved:
            step *= 0.5
    return ub


@njit_inline
def _edge_of(F, g, a, b):
    """Index e of the edge {a, b} of face g (either direction), or -1."""
    for e in range(3):
        p, q = F[g, e], F[g, (e + 1) % 3]
        if (p == a and q == b) or (p == b and q == a):
            return e
    return -1


@njit_kernel
def _trace_polytope(fs, V, F, alive, nv, nf):
    """Record EPA's polytope (vertices V[:nv], the live faces among F[:nf]) in fs's
    trace region (TR_EPA, gjk_epa.py, "Trace")."""
    nlive = np.int64(0)
    for f in range(nf):
        if alive[f]:
            nlive += 1
    r = trace_open(fs, np.int64(_FS_ROWS), np.int64(TR_EPA), nv, nlive)
    if r < 0:
        return
    for i in range(nv):
        for c in range(3):
            fs[r + i, c] = V[i, c]
    r += nv
    for f in range(nf):
        if alive[f]:
            for c in range(3):
                fs[r, c] = float(F[f, c])
            r += 1


@njit_separate
def _epa(sa, sb, verts, r_ab, t_ab, scale, ws):
    """Expanding Polytope Algorithm on the full shapes from the tetrahedron W[:4] (which
    holds the origin; W, WA, WB of the workspace ``ws``).  Writes ws[1][_RES:_RES + 10] (10,) =
    [depth, nx, ny, nz, pa(3), pb(3)] (normal =
    outward normal of A - B at its boundary point closest to the origin = A to B) and
    returns (iterations, converged)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    nvmax = EPA_MAX_ITERS + 4
    fs, fv, iv = ws[0], ws[1], ws[2]
    W, WA, WB, res = fs[_W:_W + 4], fs[_WA:_WA + 4], fs[_WB:_WB + 4], fv[_RES:_RES + 10]
    V, VA, VB = fs[_V:_V + _NVMAX], fs[_VA:_VA + _NVMAX], fs[_VB:_VB + _NVMAX]
    VD = fs[_VD:_VD + _NVMAX]
    FN, FD = fs[_FN:_FN + EPA_MAX_FACES], fv[_FD:_FD + EPA_MAX_FACES]
    F, edges = iv[_IF:_IF + EPA_MAX_FACES], iv[_IE:_IE + 3 * EPA_MAX_FACES]
    ADJ = iv[_IA:_IA + EPA_MAX_FACES]
    # the 1-D lists as contiguous runs of the flat buffer (a column view iv[:, c] is
    # typed with a run-time stride: an index multiplication per access and more spilled
    # registers)
    ivf = iv.reshape(iv.size)
    stack = ivf[3 * _IS:3 * _IS + EPA_MAX_FACES]
    alive = ivf[3 * _IS + EPA_MAX_FACES:3 * _IS + 2 * EPA_MAX_FACES]
    newf = ivf[3 * _IC:3 * _IC + EPA_MAX_FACES]
    free = ivf[3 * _IC + EPA_MAX_FACES:3 * _IC + 2 * EPA_MAX_FACES]
    h_from = ivf[3 * _IH:3 * _IH + _NVMAX]
    h_to = ivf[3 * _IH + _NVMAX:3 * _IH + 2 * _NVMAX]
    cin = ws[0][_T_CIN]
    for c in range(3):
        cin[c] = 0.0
    for i in range(4):
        for c in range(3):
            V[i, c] = W[i, c]
            VA[i, c] = WA[i, c]
            VB[i, c] = WB[i, c]
            VD[i, c] = 0.0
            cin[c] += 0.25 * W[i, c]
    nv = np.int64(4)   # typed int64 at once (jit.py, "Literal")
    nf = np.int64(4)
    F[0, 0], F[0, 1], F[0, 2] = 0, 1, 2
    F[1, 0], F[1, 1], F[1, 2] = 0, 3, 1
    F[2, 0], F[2, 1], F[2, 2] = 0, 2, 3
    F[3, 0], F[3, 1], F[3, 2] = 1, 3, 2
    for f in range(4):
        _face_setup(V, F, FN, FD, f, cin)
        alive[f] = True
    # adjacency of the tetrahedron; every edge must appear reversed in its neighbour
    # (consistent outward orientation), else the start is degenerate and EPA cannot
    # run on it.  _face_setup flips all four faces of a negatively oriented tetrahedron
    # and none of a positive one: for those two layouts the adjacency is a fixed table
    # (what the search below finds, at ~4% of a penetrating pair); a mixed layout (a
    # flat start) goes through the search, which rejects it.
    n_flip = int(F[0, 1] == 2) + int(F[1, 1] == 1) + int(F[2, 1] == 3) + int(F[3, 1] == 2)
    # (entries 4 g + eg: face g across the edge, which is g's edge eg)
    if n_flip == 0:
        ADJ[0, 0], ADJ[0, 1], ADJ[0, 2] = 6, 14, 8
        ADJ[1, 0], ADJ[1, 1], ADJ[1, 2] = 10, 12, 0
        ADJ[2, 0], ADJ[2, 1], ADJ[2, 2] = 2, 13, 4
        ADJ[3, 0], ADJ[3, 1], ADJ[3, 2] = 5, 9, 1
    elif n_flip == 4:
        ADJ[0, 0], ADJ[0, 1], ADJ[0, 2] = 10, 12, 4
        ADJ[1, 0], ADJ[1, 1], ADJ[1, 2] = 2, 14, 8
        ADJ[2, 0], ADJ[2, 1], ADJ[2, 2] = 6, 13, 0
        ADJ[3, 0], ADJ[3, 1], ADJ[3, 2] = 1, 9, 5
    else:
        for f in range(4):
            for e in range(3):
                a, b = F[f, e], F[f, (e + 1) % 3]
                for g in range(4):
                    eg = _edge_of(F, g, a, b) if g != f else -1
                    if eg >= 0:
                        ADJ[f, e] = 4 * g + eg
                        if F[g, (eg + 1) % 3] != a:
                            return 0, False, np.inf, False
    nfree = 0
    d, wa, wb, w = ws[0][_T_D], ws[0][_T_WA], ws[0][_T_WB], ws[0][_T_W]
    tol = EPA_REL_TOL * scale
    polished = False
    # Newton's method (see _smooth_pair for which pairs try it): at a gain of
    # EPA_POLISH_TOL * scale, and once more 100x closer if it gave up
    polish_at = EPA_POLISH_TOL * scale
    # and along a cylinder's side where the best face's normal is near it (_kink_polish)
    smooth = _smooth_pair(sa[0], sb[0])
    creaseless = ((sa[0] == ELLIPSOID or sa[0] == SPHERE)
                  and (sb[0] == ELLIPSOID or sb[0] == SPHERE))
    kinks = _searched_crease(sa[0], sb[0]) or _searched_crease(sb[0], sa[0])
    capsule = sa[0] == CAPSULE or sb[0] == CAPSULE     # its crease, if one is searched
    box = sa[0] == BOX or sb[0] == BOX                  # likewise
    tries = 2 if (smooth or kinks) else 0
    two_cyl = sa[0] == CYLINDER and sb[0] == CYLINDER
    eb = _ellipsoid_box(sa[0], sb[0])
    n_pol = 0
    vis_tol = EPA_DEGEN_TOL * scale
    best = 0
    it = 0
    converged = False
    # best upper bound on the depth: min over evaluated unit directions of h(d)
    ub = np.inf
    ud, uwa = ws[0][_T_UD], ws[0][_T_UWA]
    for c in range(3):
        ud[c] = 0.0
        uwa[c] = 0.0
    lb = 0.0
    # a polished minimum whose basin test failed: tested again at every later step, as
    # the polytope grows (ws t3 rows 15-18 keep it until the next successful polish)
    pend = False
    p_planes = False
    p_cap = 0.0
    p_h = 0.0
    p_fail = np.int64(-1)               # a face that failed its last test
    # the test of a face normal (_face_polish): from a gain of EPA_FACE_TOL * scale, at
    # most EPA_FACE_EVALS supports
    face_left = EPA_FACE_EVALS if _epa_face_pair(sa[0], sb[0]) else 0
    face_at = EPA_FACE_TOL * scale
    # and of a parallelogram face of A - B (_crossing_test): from the same gain, at most
    # EPA_FACE_EVALS tests
    cross_left = EPA_FACE_EVALS if _crossing_pair(sa[0], sb[0]) else 0
    if two_cyl:
        # two cylinders have one crossing face, normal to both axes, whatever EPA's
        # best face: tested now, once, with no support (_cylinders_crossing), and not
        # at every step
        pend = _cylinders_crossing(sa, sb, r_ab, t_ab, scale, fs)
        cross_left = 0
        if pend:
            p_planes = True
            p_cap = fs[_T_FACE_CAP, 0]
            p_h = _pending_bound(sa, sb, r_ab, t_ab, fs, tol)
    trace_on = fs.shape[0] >= _FS_ROWS + TR_HEADER_ROWS
    while True:
        if trace_on:
            _trace_polytope(fs, V, F, alive, nv, nf)
        # face closest to the origin
        best = np.int64(-1)   # typed int64 at once (jit.py, "Literal")
        bd = np.inf
        for f in range(nf):
            if FD[f] < bd:          # dead and degenerate faces hold FD = inf
                bd = FD[f]
                best = f
        if best < 0:
            break
        if it >= EPA_MAX_ITERS or nv >= nvmax:
            break
        for c in range(3):
            d[c] = FN[best, c]
        ax_, ay_, az_, bx_, by_, bz_ = minkowski_core_xyz(
            sa, sb, verts, r_ab, t_ab, d[0], d[1], d[2])
        wa[0], wa[1], wa[2] = ax_, ay_, az_
        wb[0], wb[1], wb[2] = bx_, by_, bz_
        w[0], w[1], w[2] = ax_ - bx_, ay_ - by_, az_ - bz_
        hd = _dot(d, w)
        lb = FD[best]
        if hd < ub:
            ub = hd
            for c in range(3):
                ud[c] = d[c]
                uwa[c] = wa[c]
        gain = hd - FD[best]
        if gain <= tol:
            converged = True
            break
        if pend and ub < p_h:
            pend = False                # a direction deeper than it was found
        if not pend and gain <= face_at and (face_left > 0 or cross_left > 0):
            # near a box's face normal or a cylinder's axis, or where a cylinder's side
            # crosses another segment (a flat face of A - B): is the minimum on it?
            k_f = 0
            if face_left > 0:
                k_f = _face_polish(sa, sb, verts, r_ab, t_ab, scale, ws, d[0], d[1],
                                   d[2])
                face_left -= abs(k_f)
                n_pol += abs(k_f)
            if cross_left > 0 and k_f <= 0:
                k_f = _crossing_test(sa, sb, verts, r_ab, t_ab, scale, ws, best,
                                     d[0], d[1], d[2])
                cross_left -= abs(k_f)
                n_pol += abs(k_f)
            if k_f > 0:
                # a minimum in the cap _face_basin proves: the global one once no face
                # of the polytope can reach deeper outside that cap
                pend = True
                p_planes = True
                p_cap = fs[_T_FACE_CAP, 0]
                p_h = _pending_bound(sa, sb, r_ab, t_ab, fs, tol)
                p_fail = np.int64(-1)
        if pend:
            p_fail = _polish_is_global(V, F, FN, FD, nf, fs[_T_MIN_D], p_h, p_planes,
                                       p_cap, p_fail)
            if p_fail < 0:
                _take_polished(fs, d, w, wa, wb)
                polished = True
                converged = True
                break
        if tries > 0 and gain <= polish_at:
            # close to the minimum: Newton's method where the boundary is smooth, the
            # secant along a cylinder's side near its crease; where they give up EPA
            # goes on, and they are tried once more 100x closer.  Two cylinders with
            # the normal near neither crease: Newton's method too (two_cyl; see
            # _smooth_pair); another cylinder pair keeps its tries for later steps
            kc = _kink_side(sa, sb, r_ab, d[0], d[1], d[2], np.bool_(False))
            # an ellipsoid and a box, near none of the box's creases: Newton's method in
            # a vertex's region (_vertex_cap), unless a minimum is pending already
            vtx = eb and kc == -1 and not pend
            if kc >= 0 or ((smooth or two_cyl or vtx) and kc == -1):
                tries -= 1
                polish_at *= EPA_POLISH_RETRY
                if kc >= 0:
                    k_pol = _kink_polish(sa, sb, verts, r_ab, t_ab, scale, ws,
                                         kc // 3, kc % 3)
                else:
                    k_pol = _epa_polish(sa, sb, verts, r_ab, t_ab, scale, ws, best)
                n_pol += abs(k_pol)
                cap = _polish_cap(kc, capsule, box)
                if k_pol > 0 and vtx:
                    cap = _vertex_cap(sa, sb, r_ab, fs[_T_MIN_D])
                if k_pol > 0 and not cap > 0.0:
                    # a vertex's minimum near a crease: kept only if a ball proves it
                    if _pending_bound(sa, sb, r_ab, t_ab, fs, tol) == -np.inf:
                        _take_polished(fs, d, w, wa, wb)
                        polished = True
                        converged = True
                        break
                elif k_pol > 0:
                    pend = True
                    p_planes = kc >= 0 or creaseless or vtx
                    p_cap = cap
                    p_h = _pending_bound(sa, sb, r_ab, t_ab, fs, tol)
                    p_fail = _polish_is_global(V, F, FN, FD, nf, fs[_T_MIN_D], p_h,
                                               p_planes, p_cap, np.int64(-1))
                    if p_fail < 0:
                        _take_polished(fs, d, w, wa, wb)
                        polished = True
                        converged = True
                        break
        it += 1
        # faces seen from w: a flood fill over the face adjacency from the best face,
        # so the removed region is connected (a disk) and the polytope stays a
        # manifold; its work is the seen faces and their rim, not all faces.  The rim
        # edges (a, b) of seen faces, with the unseen face g beyond, form the horizon.
        alive[best] = False
        FD[best] = np.inf
        free[nfree] = best
        nfree += 1
        stack[0] = best
        ns = 1
        ne = 0
        while ns > 0:
            ns -= 1
            f = stack[ns]
            for e in range(3):
                pg = ADJ[f, e]
                g = pg >> np.uint64(2)
                if not alive[g]:
                    continue            # seen in this step (or stale): interior edge
                # height of w over g's plane, from its stored offset (a degenerate face
                # holds FN = 0, FD = inf: never seen).  A face reached twice is tested
                # twice (the same answer): cheaper than tagging visits (~2%)
                sg = FN[g, 0] * w[0] + FN[g, 1] * w[1] + FN[g, 2] * w[2] - FD[g]
                if sg > vis_tol:
                    alive[g] = False
                    FD[g] = np.inf
                    free[nfree] = g
                    nfree += 1
                    stack[ns] = g
                    ns += 1
                    continue
                edges[ne, 0] = F[f, e]
                edges[ne, 1] = F[f, (e + 1) % 3]
                edges[ne, 2] = pg
                ne += 1
        # room for the new faces?
        if ne > nfree + (EPA_MAX_FACES - nf):
            break
        nvu = np.uint64(nv)
        for c in range(3):
            V[nv, c] = w[c]
            VA[nv, c] = wa[c]
            VB[nv, c] = wb[c]
            VD[nv, c] = d[c]
        # one new face (a, b, new vertex) per horizon edge, in the freed slots first;
        # a face wound toward the interior (w nearly in the plane of a horizon edge's
        # neighbour) is flipped after the loop (_face_plane)
        inward = False
        for q in range(ne):
            if nfree > 0:
                nfree -= 1
                f = free[nfree]
            else:
                f = np.uint64(nf)
                nf += 1
            F[f, 0] = edges[q, 0]
            F[f, 1] = edges[q, 1]
            F[f, 2] = nv
            alive[f] = True
            inward |= _face_plane(V, F, FN, FD, f, cin)
            newf[q] = f
            h_from[edges[q, 0]] = q
            h_to[edges[q, 1]] = q
        if inward:
            for q in range(ne):
                _face_setup(V, F, FN, FD, newf[q], cin)
        # adjacency: across the horizon edge (a, b), the old face g (whose edge eg it
        # is, stored with g); across the spoke (b, new vertex), the new face of the
        # horizon edge starting at b; across (new vertex, a), the one of the edge
        # ending at a (the horizon is a loop).  As built, every new face is (a, b, nv),
        # so those spokes are its neighbours' edges 2 and 1 (O(1) each, no search: a
        # search over the horizon costs, with the best-face scan, 5-13% of a
        # penetrating pair's time; g's edge comes with the twin index, where a search
        # of it costs ~9% of a deep box-cylinder pair's EPA).  If _face_setup flipped
        # some, the twins are looked up.
        for q in range(ne):
            f = newf[q]
            a, b, pg = edges[q, 0], edges[q, 1], edges[q, 2]
            g = pg >> np.uint64(2)
            eg = pg & np.uint64(3)
            if not inward:
                ADJ[g, eg] = np.uint64(4) * f
                ADJ[f, 0] = pg
                ADJ[f, 1] = np.uint64(4) * newf[h_from[b]] + np.uint64(2)
                ADJ[f, 2] = np.uint64(4) * newf[h_to[a]] + np.uint64(1)
                continue
            for e in range(3):
                p, r = F[f, e], F[f, (e + 1) % 3]
                if p != nvu and r != nvu:
                    ADJ[g, eg] = np.uint64(4) * f + np.uint64(e)
                    ADJ[f, e] = pg
                else:
                    nb = newf[h_from[b]] if (p == b or r == b) else newf[h_to[a]]
                    ADJ[f, e] = np.uint64(4) * nb + np.uint64(max(_edge_of(F, nb, p, r), 0))
        nv += 1
    if best < 0:
        return it, False, np.inf, False
    if polished:
        # the minimiser's support points are the witnesses (unique where h is smooth)
        dep = _dot(d, w)
        res[0] = dep
        for c in range(3):
            res[1 + c] = d[c]
            res[4 + c], res[7 + c] = meet(wa[c], wb[c], -(dep * d[c]))
        return it + n_pol, True, dep - lb, True
    # witness: projection of the origin on the best face, in barycentric coordinates
    i, j, k = F[best, 0], F[best, 1], F[best, 2]
    dep = FD[best]
    l3 = ws[1][_L3:_L3 + 3]
    # barycentric coordinates of the projection p = dep * n of the origin on the face
    # (cross products, unclamped so that pb - pa == -dep * n holds exactly even if p
    # strays by round-off outside the face); closest triangle point if degenerate
    px, py, pz = dep * FN[best, 0], dep * FN[best, 1], dep * FN[best, 2]
    ux, uy, uz = V[j, 0] - V[i, 0], V[j, 1] - V[i, 1], V[j, 2] - V[i, 2]
    wx, wy, wz = V[k, 0] - V[i, 0], V[k, 1] - V[i, 1], V[k, 2] - V[i, 2]
    nx = uy * wz - uz * wy
    ny = uz * wx - ux * wz
    nz = ux * wy - uy * wx
    nn = nx * nx + ny * ny + nz * nz
    clean = False
    on_face = False
    if nn > 0.0:
        bx, by, bz = V[j, 0] - px, V[j, 1] - py, V[j, 2] - pz
        cx, cy, cz = V[k, 0] - px, V[k, 1] - py, V[k, 2] - pz
        ax, ay, az = V[i, 0] - px, V[i, 1] - py, V[i, 2] - pz
        m0 = (nx * (by * cz - bz * cy) + ny * (bz * cx - bx * cz)
              + nz * (bx * cy - by * cx)) / nn
        m1 = (nx * (cy * az - cz * ay) + ny * (cz * ax - cx * az)
              + nz * (cx * ay - cy * ax)) / nn
        m2 = 1.0 - m0 - m1
        # inside the face: the witnesses are convex combinations of support points
        clean = min(m0, min(m1, m2)) >= -BARY_SLACK and max(m0, max(m1, m2)) <= 1.0 + BARY_SLACK
        # far outside the face means a sliver face: the clamped closest point instead
        # (as for a degenerate face)
        on_face = (min(m0, min(m1, m2)) > -EPA_SLIVER_BARY
                   and max(m0, max(m1, m2)) < 1.0 + EPA_SLIVER_BARY)
        if on_face:
            l3[0], l3[1], l3[2] = m0, m1, m2
    if not on_face:
        l3[0], l3[1], l3[2], dd = _tri_closest(V[i, 0], V[i, 1], V[i, 2], V[j, 0], V[j, 1],
                                               V[j, 2], V[k, 0], V[k, 1], V[k, 2])
    res[0] = dep
    for c in range(3):
        res[1 + c] = FN[best, c]
        res[4 + c] = l3[0] * VA[i, c] + l3[1] * VA[j, c] + l3[2] * VA[k, c]
        res[7 + c] = l3[0] * VB[i, c] + l3[1] * VB[j, c] + l3[2] * VB[k, c]
    # enforce pb - pa == -dep * n (exact already unless the clamped point was used),
    # splitting any correction between the two points
    for c in range(3):
        res[4 + c], res[7 + c] = meet(res[4 + c], res[7 + c], -(dep * FN[best, c]))
    if not converged and ub < np.inf:
        # caps hit (a valley of equally deep directions, e.g. a point on a cone's axis):
        # polish the upper bound h(ud) by a pattern search over directions, report it
        ub = _polish_min_support(sa, sb, verts, r_ab, t_ab, scale, ud, uwa, ub, ws)
        res[0] = ub
        for c in range(3):
            res[1 + c] = ud[c]
            res[4 + c] = uwa[c]
            res[7 + c] = uwa[c] - ub * ud[c]
        clean = False       # B's point above need not lie on B: the caller redoes both
    return it + n_pol, converged, ub - lb, clean
