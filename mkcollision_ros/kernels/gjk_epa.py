"""GJK distance and EPA penetration depth on support mappings (signed distance of two
convex shapes).

References
  * E. G. Gilbert, D. W. Johnson, S. S. Keerthi, "A fast procedure for computing the
    distance between complex objects in three-dimensional space", IEEE J. Robotics and
    Automation 4(2), 1988 (GJK).
  * G. van den Bergen, "Proximity queries and penetration depth computation on 3D game
    objects", GDC 2001 (the Expanding Polytope Algorithm, EPA; the duality-gap stopping
    rule of GJK).
  * C. Ericson, "Real-Time Collision Detection", 2005, sec. 5.1 (closest point of a
    triangle / tetrahedron by Voronoi regions), used as the sub-simplex solver.

Frames and units: everything is in A's frame, metres.  B's pose in A is ``r_ab`` (3, 3)
and ``t_ab`` (3,).  The Minkowski difference is ``A - B``.  Result rows follow
constants.OUT_*: signed distance (negative = penetrating), unit normal from A to B,
witness points ``pa`` on A and ``pb`` on B with ``pb - pa == dist * normal``.

Phases of ``gjk_epa`` (one module each; kernels/narrowphase.py's pair table says
which pairs come here and which pair kernel (kernels/pairs/) runs first):
  1. GJK on the *cores* (gjk.py), with Newton's method, the crease search and the face
     tests near its end on cores apart (polish_newton.py, polish_crease.py,
     polish_faces.py; which pairs try which: polish_pairs.py).
  2. When the cores overlap, EPA on the cores (epa.py): depth = core depth + r_a + r_b
     exactly, with the same polish steps and the tests that keep their minima
     (certificates.py).
  3. If a cap is hit (valleys of equally deep directions, e.g. a sphere centred on a
     cylinder's or cone's axis, two coaxial cylinders), the best upper bound min h(u)
     over the evaluated normals is polished by a pattern search over directions
     (epa._polish_min_support) and reported; the status is ST_FAILED only if the gap to the
     EPA lower bound exceeds
     EPA_FAIL_GAP * scale and that lower bound does not by itself prove penetration (a
     pair certainly in contact always yields its contact, e.g. to the pipeline, which
     drops failed pairs).  Then (_caps_fallback, below) a pair with a closed form takes it
     (analytic.collide_analytic, exact), and any other takes MPR's normal where its
     support value is the smaller upper bound of the depth, and MPR's contact in place
     of FAILED (the cases that need them: a tiny capsule inside a large one, where EPA
     fails, and a small body deep in a large cylinder or cone, where EPA's depth can be
     up to 2e-5 * scale too deep).
  Witness points: barycentric coordinates of the closest point on the final simplex /
  EPA face, applied to the support points of A and B, then moved out by the radii.
  When the origin's projection falls outside the final EPA face (sliver faces of flat
  or face-to-face contacts), GJK on the pair just pulled apart along the normal gives
  them instead (gjk._witness_by_gjk; regression scenes drake21673_box_box, _convex5).
  Scratch memory: ``gjk_epa`` allocates one workspace per call; the batch kernel
  calls ``gjk_epa_ws`` with one workspace per chunk of pairs (no allocation per pair;
  the layout: gjk_epa_workspace.py).

Trace (for visual debugging, mkcollision_ros/trace.py): a workspace whose fs has at
least _FS_ROWS + TR_HEADER_ROWS rows (make_gjk_workspace_traced) makes ``gjk_epa_ws``
record its iterations in the fs rows from _FS_ROWS on, a trace region as
kernels/tracebuf.py lays out: the GJK simplex of the
cores (TR_GJK: the first support point, then the simplex after each step that changed
it; the last record is GJK's final simplex, the tetrahedron when the cores overlap),
then EPA's polytope (TR_EPA: its vertices and live faces at the start of each step,
from the tetrahedron on; the last record is the final polytope, whose nearest face is
EPA's lower bound).  GJK's run inside _witness_by_gjk (a shifted pair) is not recorded.
With the options row's column 0 > 0, the closed forms of ``gjk_epa_ws`` (cylinder
pairs, an ellipsoid and a box, an ellipsoid or a cylinder and a small hull) are skipped
so that GJK/EPA iterate and get recorded; the result is then GJK/EPA's own.  Options
zero: the results do not depend on the trace.


Measured accuracy against coal 3.0.3 (gjk_tolerance 1e-12, epa_tolerance 1e-10, see
tests/test_gjk_epa.py; max |ours - coal| / scale over random pairs where coal itself is
trustworthy; scale = sum of bounding radii):
  * polytopes (box, convex) and sphere/capsule pairs: <= 1e-15 (exact to round-off);
  * penetrating smooth pairs (ellipsoid, cylinder, cone with anything): <= ~1e-6, and
    typically 1e-9; the residual is mostly coal's (its EPA stops early, often failing
    outright at tolerances below 1e-10).  Our own bound gap is < EPA_REL_TOL * scale =
    1e-8 * scale whenever EPA converges without Newton's method (with it: a stationary
    point of h to a POLISH_STEP_DONE = 1e-6 rad step, and the cap test) (EPA_REL_TOL
    1e-8 rather than 1e-10 cuts EPA's work on smooth shapes ~2-3x and stays 100x
    inside the issue's 1e-6 * scale; the normal of a smooth contact is then within
    ~sqrt(2e-8) ~ 1.4e-4 rad of the exact one, its support value within 1e-8 * scale of
    the depth).  Every reported depth is within EPA_REL_TOL * scale of h_{A-B}(normal),
    the upper bound its normal certifies: equal to it when a polish ended EPA (Newton's
    method, a crease or face minimum) or after the caps' pattern search, EPA's nearest
    face distance (the lower bound) when EPA's own gap closed (tests/test_gjk_epa.py
    checks distance == -h(normal) to 1e-7 * scale).
    GJK stays at 1e-12: separated normals must agree to ~1e-6 between inputs that
    differ by round-off (tests/test_narrowphase_api.py, batch vs single calls).
  * disagreements are settled by certificates in the tests (coal's sphere-cylinder
    path is wrong for spheres inside a cylinder; coal's normals are ~1e-3 rad off on
    ellipsoids and cones).
"""
import math

import numpy as np

from .analytic import collide_analytic
from .constants import (BOX, CAPSULE, CONVEX, CYLINDER, ELLIPSOID, EPA_FAIL_GAP, GJK_CAP_GAP,
                        M_GJK_EPA, OUT_DIST, OUT_ITERS, OUT_METHOD, OUT_NORMAL, OUT_PA, OUT_PB,
                        OUT_SIZE, PLANE, PLANE_NORMAL_COS, PRE_APART, PRE_EXACT, PRE_UNDECIDED,
                        PRE_UNPROVED, ST_FAILED, ST_NOT_RUN, ST_PENETRATING, ST_SEPARATED,
                        ST_TOUCHING, TOUCH_TOL)
from .epa import _epa, _grow_to_tetra
from .geometry import (borrow_args, inflation, meet, minkowski_core_xyz, minkowski_full_xyz,
                       shape_scale)
from .gjk import (_GJK_BOUND, _GJK_CAP, _GJK_OVERLAP, _GJK_POLISHED, _GJK_STALL, _gjk,
                  _witness_by_gjk)
from .gjk_epa_workspace import (_BC_ROWS, _FD, _FS_ROWS, _LAM, _RES, _T_EST_D, _T_EST_W, _T_EST_WA,
                                _T_EST_WB, _T_MIN_D, _T_MIN_W, _T_MIN_WA, _T_MIN_WB, _T_NRM, _T_PA,
                                _T_PB, _V, _VV, _W, _WA, _WB, _dot, borrow_gjk_workspace,
                                make_gjk_workspace)
from .jit import borrow, njit_inline, njit_kernel, njit_separate
from .mpr import MPR_WS_ROWS, mpr_ws
from .pairs.box_cylinder import collide_box_cylinder
from .pairs.capsule_cylinder import collide_capsule_cylinder
from .pairs.core_distance import classify
from .pairs.cylinder_convex import (collide_cylinder_convex, collide_cylinder_convex_ball,
                                    cylinder_hull_pair)
from .pairs.cylinder_cylinder import collide_cylinder_cylinder
from .pairs.ellipsoid_box import collide_ellipsoid_box
from .pairs.ellipsoid_convex import collide_ellipsoid_convex, ellipsoid_hull_pair
from .pairs.ellipsoid_cylinder import collide_ellipsoid_cylinder
from .pairs.normal_fan import HE_ROWS
from .polish_pairs import _ellipsoid_box, _gjk_newton_pair, _has_crease
from .tracebuf import TR_HEADER_ROWS, trace_reset


@njit_kernel
def _set_out(out, dist, nx, ny, nz, pa, pb, iters, scale):
    """Fill a result row in A's frame and return the status by the touching rule."""
    out, pa, pb = borrow(out), borrow(pa), borrow(pb)
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    ok = nn > 0.0 and math.isfinite(nn) and math.isfinite(dist)
    for c in range(3):
        ok = ok and math.isfinite(pa[c]) and math.isfinite(pb[c])
    if not ok:
        for c in range(OUT_SIZE):
            out[c] = 0.0
        out[OUT_NORMAL + 2] = 1.0
        out[OUT_ITERS] = iters
        out[OUT_METHOD] = M_GJK_EPA
        return ST_FAILED
    out[OUT_DIST] = dist
    out[OUT_NORMAL] = nx / nn
    out[OUT_NORMAL + 1] = ny / nn
    out[OUT_NORMAL + 2] = nz / nn
    for c in range(3):
        out[OUT_PA + c] = pa[c]
        out[OUT_PB + c] = pb[c]
    out[OUT_ITERS] = iters
    out[OUT_METHOD] = M_GJK_EPA
    tol = TOUCH_TOL * scale
    if abs(dist) <= tol:
        return ST_TOUCHING
    if dist < -tol:
        return ST_PENETRATING
    return ST_SEPARATED


@njit_kernel
def _fallback_normal(t_ab, nrm):
    """A unit direction from A towards B (t_ab), or +z when the centres coincide."""
    tn = math.sqrt(_dot(t_ab, t_ab))
    if tn > 0.0:
        for c in range(3):
            nrm[c] = t_ab[c] / tn
    else:
        nrm[0], nrm[1], nrm[2] = 0.0, 0.0, 1.0


@njit_inline
def _core_out(out, res, ra, rb, pa, pb, iters, scale):
    """The result row (_set_out) from a depth of the cores, res = [depth, n (3), pa (3),
    pb (3)] in A's frame (EPA's or box_cylinder's): the witnesses moved out by the inflation
    radii ra, rb along n, the depth grown by ra + rb."""
    for c in range(3):
        pa[c] = res[4 + c] + ra * res[1 + c]
        pb[c] = res[7 + c] - rb * res[1 + c]
    return _set_out(out, -res[0] - ra - rb, res[1], res[2], res[3], pa, pb, iters, scale)


@njit_kernel
def gjk_epa(sa, sb, verts, r_ab, t_ab, out):
    """Signed distance of two convex shapes by GJK (apart or cores apart) and EPA (cores
    overlapping).

    sa, sb  shape tuples (code int64, prm float64[8], v0 int64, vn int64)
    verts   float64 (M, 3) convex vertices, body frames
    r_ab    float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    out     float64 (OUT_SIZE,) result row in A's frame, written in full (never NaN)
    Returns the status ST_SEPARATED / ST_TOUCHING / ST_PENETRATING, ST_FAILED when an
    iteration cap was hit without a usable answer, ST_NOT_RUN for planes.
    Allocates its scratch buffers; batch callers use ``gjk_epa_ws``.
    """
    return gjk_epa_ws(sa, sb, verts, r_ab, t_ab, out, make_gjk_workspace(), math.inf)


@njit_separate
def gjk_epa_ws(sa, sb, verts, r_ab, t_ab, out, ws, cutoff):
    """``gjk_epa`` with caller-provided scratch buffers ``ws`` (make_gjk_workspace()).

    ``cutoff`` (m, >= 0, may be inf): distances up to max(cutoff, the touching band)
    are exact; a pair GJK proves farther apart than that is returned at once as
    ST_SEPARATED with ``distance`` a certified lower bound (> cutoff), the separating
    direction as normal and the current simplex points (moved out by the radii) as
    witness points, which then are not the closest points (a cylinder with a cylinder,
    a capsule, an ellipsoid or a hull: the cylinder pair kernels' separating planes
    likewise, before GJK;
    an ellipsoid and a box: ellipsoid_box's face and edge planes).  A
    pipeline that wants contacts only passes 0 and saves the GJK steps that would
    refine a distance it throws away (as MuJoCo's collision pass, which reports no
    distances, does)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    out = borrow(out)
    nrm, pa, pb = ws[0][_T_NRM], ws[0][_T_PA], ws[0][_T_PB]
    # a trace region (module docstring, "Trace"): its options, then reset
    trace_on = ws[0].shape[0] >= _FS_ROWS + TR_HEADER_ROWS
    iterate = False
    if trace_on:
        iterate = ws[0][_FS_ROWS + 1, 0] > 0.0
        trace_reset(ws[0], np.int64(_FS_ROWS))
    _fallback_normal(t_ab, nrm)
    for c in range(3):
        pa[c] = 0.0
        pb[c] = 0.0
    if sa[0] == PLANE or sb[0] == PLANE:
        for c in range(OUT_SIZE):
            out[c] = 0.0
        for c in range(3):
            out[OUT_NORMAL + c] = nrm[c]
        out[OUT_METHOD] = M_GJK_EPA
        return ST_NOT_RUN
    scale = shape_scale(sa, sb)
    # distances up to this are exact; a pair proved farther apart stops there
    band = max(cutoff, TOUCH_TOL * scale)
    fs, fv = ws[0], ws[1]
    W, WA, WB = fs[_W:_W + 4], fs[_WA:_WA + 4], fs[_WB:_WB + 4]
    lam, v = fv[_LAM:_LAM + 4], fv[_VV:_VV + 3]
    ra = inflation(sa[0], sa[1])
    rb = inflation(sb[0], sb[1])
    res = ws[1][_RES:_RES + 10]
    # what a pair kernel run before GJK decides (constants.PRE_*): a certified depth or an
    # exact distance, or a plane proving the cores farther apart than ``stop`` (the
    # cutoff and the touching band beyond the inflation radii: GJK would stop there too)
    stop = ra + rb + band
    pre = PRE_UNDECIDED
    if not iterate and (sa[0] == CYLINDER or sb[0] == CYLINDER):
        # a cylinder with a cylinder, a capsule, an ellipsoid or a hull (pairs/), or a
        # box (box_cylinder: the exact depth in closed form): cores that overlap get their
        # depth certified (cylinder_common: one core's point as deep inside the cylinder as h
        # along the normal there, by a ball), or a plane (a cap's, the side's tangent
        # plane, the sides' crossing; for a box, the line of centres or one of
        # box_cylinder's candidate directions) proves them apart
        other = sb[0] if sa[0] == CYLINDER else sa[0]
        if other == CYLINDER:
            pre = collide_cylinder_cylinder(sa, sb, verts, r_ab, t_ab, scale, stop, res)
        elif other == BOX:
            pre = collide_box_cylinder(sa, sb, r_ab, t_ab, scale, fs[_V:_V + _BC_ROWS], stop,
                                       res)
        elif other == CAPSULE:
            pre = collide_capsule_cylinder(sa, sb, r_ab, t_ab, scale, stop, res)
        elif other == ELLIPSOID:
            pre = collide_ellipsoid_cylinder(sa, sb, r_ab, t_ab, scale, stop, res)
        elif other == CONVEX:
            if cylinder_hull_pair(sa, sb):
                # the hull's fan stored (cylinder_convex): as the ellipsoid's below
                pre = collide_cylinder_convex(sa, sb, verts, r_ab, t_ab, scale,
                                              np.bool_(False), stop, fs[_V:_V + HE_ROWS],
                                              fv[_FD:_FD + 8], res)
            if pre == PRE_UNDECIDED:
                pre = collide_cylinder_convex_ball(sa, sb, verts, r_ab, t_ab, scale, stop, res)
    elif not iterate and _ellipsoid_box(sa[0], sb[0]):
        # an ellipsoid and a box (ellipsoid_box): the core depth at a box face certified by a
        # ball, the cores' exact distance over a face, an edge or a vertex, or a face plane
        # proving them apart
        pre = collide_ellipsoid_box(sa, sb, r_ab, t_ab, scale, stop, res)
    elif not iterate and ellipsoid_hull_pair(sa, sb):
        # an ellipsoid and a small hull with its normal fan stored (ellipsoid_convex): the exact
        # depth when a cheap test proves the pair overlapping; without that proof
        # (PRE_UNPROVED), again after GJK once it finds the cores overlapping (below, in
        # place of EPA); or a hull face's plane proving the cores apart
        pre = collide_ellipsoid_convex(sa, sb, verts, r_ab, t_ab, scale, np.bool_(False), stop,
                                       fs[_V:_V + HE_ROWS], fv[_FD:_FD + 8], res)
    if pre == PRE_EXACT or pre == PRE_APART:
        return _core_out(out, res, ra, rb, pa, pb, np.int64(1), scale)
    # phase 1: cores
    n, it, flag, bound = _gjk(sa, sb, verts, r_ab, t_ab, scale, ws, stop,
                              _gjk_newton_pair(sa[0], sb[0])
                              or _has_crease(sa[0]) or _has_crease(sb[0]), trace_on)
    iters = it
    if flag == _GJK_POLISHED:
        # cores apart, closest points from Newton's method: pb - pa == dist * n exactly
        pd, pw = fs[_T_MIN_D], fs[_T_MIN_W]
        pwa, pwb = fs[_T_MIN_WA], fs[_T_MIN_WB]
        dist = -_dot(pd, pw)
        for c in range(3):
            nrm[c] = pd[c]
            qa, qb = meet(pwa[c], pwb[c], dist * pd[c])
            pa[c] = qa + ra * pd[c]
            pb[c] = qb - rb * pd[c]
        return _set_out(out, dist - ra - rb, nrm[0], nrm[1], nrm[2], pa, pb, iters, scale)
    vn = math.sqrt(_dot(v, v))
    if flag != _GJK_OVERLAP:
        for c in range(3):
            for i in range(n):
                pa[c] += lam[i] * WA[i, c]
                pb[c] += lam[i] * WB[i, c]
        for c in range(3):
            nrm[c] = -v[c] / vn  # v = pa - pb, normal from A to B
        if flag == _GJK_BOUND:
            vn = bound
        elif n == 3 and lam[0] > 0.0 and lam[1] > 0.0 and lam[2] > 0.0:
            # v is the origin's projection onto the triangle's plane.  When the pair is
            # nearly touching |v| is tiny and its direction carries the rounding of the
            # barycentric sum; the plane's normal from the edges does not, and the
            # plane's offset is the same distance, better conditioned.
            e1x, e1y, e1z = W[1, 0] - W[0, 0], W[1, 1] - W[0, 1], W[1, 2] - W[0, 2]
            e2x, e2y, e2z = W[2, 0] - W[0, 0], W[2, 1] - W[0, 1], W[2, 2] - W[0, 2]
            cx, cy, cz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
            cn = math.sqrt(cx * cx + cy * cy + cz * cz)
            if cn > 0.0:
                cx, cy, cz = cx / cn, cy / cn, cz / cn
                if cx * nrm[0] + cy * nrm[1] + cz * nrm[2] < 0.0:
                    cx, cy, cz = -cx, -cy, -cz
                off = -(cx * W[0, 0] + cy * W[0, 1] + cz * W[0, 2])
                if off > 0.0 and cx * nrm[0] + cy * nrm[1] + cz * nrm[2] > PLANE_NORMAL_COS:
                    nrm[0], nrm[1], nrm[2] = cx, cy, cz
                    vn = off
        for c in range(3):
            pa[c] += ra * nrm[c]
            pb[c] -= rb * nrm[c]
        st = _set_out(out, vn - ra - rb, nrm[0], nrm[1], nrm[2], pa, pb, iters, scale)
        if flag == _GJK_CAP and st != ST_FAILED:
            # accept the estimate only when the last duality gap was small
            d, wa, wb, w = ws[0][_T_EST_D], ws[0][_T_EST_WA], ws[0][_T_EST_WB], ws[0][_T_EST_W]
            for c in range(3):
                d[c] = -v[c]
            ax_, ay_, az_, bx_, by_, bz_ = minkowski_core_xyz(
                sa, sb, verts, r_ab, t_ab, d[0], d[1], d[2])
            wa[0], wa[1], wa[2] = ax_, ay_, az_
            wb[0], wb[1], wb[2] = bx_, by_, bz_
            w[0], w[1], w[2] = ax_ - bx_, ay_ - by_, az_ - bz_
            if (vn * vn - _dot(v, w)) / vn > GJK_CAP_GAP * scale:
                st = ST_FAILED
        if flag == _GJK_STALL:
            st = _caps_fallback(sa, sb, verts, r_ab, t_ab, scale, out, st, ws, np.bool_(True))
        return st
    if pre == PRE_UNPROVED:
        # GJK found the cores overlapping: the fan's exact depth in place of EPA
        if sa[0] == CYLINDER or sb[0] == CYLINDER:
            pre = collide_cylinder_convex(sa, sb, verts, r_ab, t_ab, scale, np.bool_(True),
                                          stop, fs[_V:_V + HE_ROWS], fv[_FD:_FD + 8], res)
        else:
            pre = collide_ellipsoid_convex(sa, sb, verts, r_ab, t_ab, scale, np.bool_(True),
                                           stop, fs[_V:_V + HE_ROWS], fv[_FD:_FD + 8], res)
        if pre == PRE_EXACT:
            return _core_out(out, res, ra, rb, pa, pb, np.int64(iters + 1), scale)
    # phase 2: EPA on the cores.  The full Minkowski difference is the core one grown
    # by a ball of radius ra + rb, so depth = core depth + ra + rb exactly.
    if n < 4:
        n = _grow_to_tetra(sa, sb, verts, r_ab, t_ab, scale, ws, n)
        if n < 0:
            # flat core difference through the origin: core depth 0, normal across it
            for c in range(3):
                for i in range(4):
                    if lam[i] > 0.0:
                        pa[c] += lam[i] * WA[i, c]
                        pb[c] += lam[i] * WB[i, c]
            nn = math.sqrt(W[3, 0] ** 2 + W[3, 1] ** 2 + W[3, 2] ** 2)
            if nn > 0.0:
                for c in range(3):
                    nrm[c] = W[3, c] / nn
            if _dot(nrm, t_ab) < 0.0:
                for c in range(3):
                    nrm[c] = -nrm[c]
            for c in range(3):
                pa[c] += ra * nrm[c]
                pb[c] = pa[c] - ra * nrm[c] - rb * nrm[c]
            return _set_out(out, -(ra + rb), nrm[0], nrm[1], nrm[2], pa, pb, iters,
                            scale)
    for c in range(10):
        res[c] = 0.0
    it, conv, gap, clean = _epa(sa, sb, verts, r_ab, t_ab, scale, ws)
    iters += it
    if not clean and math.isfinite(res[0]):
        # witnesses off the best face, or the caps' pattern-searched bound (its support
        # points need not face each other: two coaxial cylinders of unequal heights)
        iters += _witness_by_gjk(sa, sb, verts, r_ab, t_ab, scale, ws, res)
    st = _core_out(out, res, ra, rb, pa, pb, iters, scale)
    # caps hit with a wide gap: still a contact when EPA's lower bound on the depth
    # (res[0] - gap, certified: the polytope lies inside A - B) alone proves
    # penetration; the depth reported is then the pattern-searched upper bound.  In the
    # valleys that hit the caps (coaxial bodies of revolution: a ring of equally deep
    # directions the polytope cannot enclose to tolerance) that bound is the exact
    # depth (tests/test_gjk_epa.py::test_coaxial_valleys_are_penetrating).  FAILED only
    # when the pair may not touch at all.
    if (not conv and not gap <= EPA_FAIL_GAP * scale
            and not res[0] - gap + ra + rb > TOUCH_TOL * scale):
        st = ST_FAILED
    if not conv:
        st = _caps_fallback(sa, sb, verts, r_ab, t_ab, scale, out, st, ws, np.bool_(False))
    return st


@njit_separate
def _caps_fallback(sa, sb, verts, r_ab, t_ab, scale, out, st, ws, stalled):
    """EPA hit its caps (phase 3: a valley of nearly equally deep directions that the
    polytope cannot enclose to tolerance, such as a small body deep inside a large
    body of revolution, where the pattern-searched bound can stay ~1e-5 * scale too
    deep), or GJK stalled (``stalled``: a sliver simplex, e.g. a long capsule's core
    against a tiny body, made no progress while the duality gap was wide, so its
    "apart" is not proved): the pair's closed form when it has one
    (analytic.collide_analytic, exact), else MPR on the whole shapes.  When MPR finds
    contact, its normal is taken if h_{A-B} there is smaller than the depth ``out``
    holds (both are support values at a unit direction, upper bounds of the depth);
    after a stall, the one of MPR's and GJK's normals with the smaller h, with the
    touching rule's status; a FAILED pair that
    MPR finds in contact keeps the smaller bound with that status.  ``out`` (A's
    frame, method M_GJK_EPA; iterations: MPR's supports added) and the returned status
    stay as they were, iterations too, when neither applies.  Scratch: the EPA vertex
    rows and face offsets of ``ws``, free once EPA has ended (and unused after GJK)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws, out = borrow_gjk_workspace(ws), borrow(out)
    tmp = ws[1][_FD:_FD + OUT_SIZE]
    iters = out[OUT_ITERS]
    sc = collide_analytic(sa, sb, verts, r_ab, t_ab, tmp)
    if sc != ST_NOT_RUN:
        for c in range(OUT_SIZE):
            out[c] = tmp[c]
        out[OUT_ITERS] = iters + tmp[OUT_ITERS]
        out[OUT_METHOD] = M_GJK_EPA
        return sc
    sm = mpr_ws(sa, sb, verts, r_ab, t_ab, tmp, ws[0][_V:_V + MPR_WS_ROWS])
    iters += tmp[OUT_ITERS] + 1
    if sm != ST_PENETRATING and sm != ST_TOUCHING:
        return st
    nx, ny, nz = tmp[OUT_NORMAL], tmp[OUT_NORMAL + 1], tmp[OUT_NORMAL + 2]
    ax, ay, az, bx, by, bz = minkowski_full_xyz(sa, sb, verts, r_ab, t_ab, nx, ny, nz)
    h = nx * (ax - bx) + ny * (ay - by) + nz * (az - bz)
    if stalled:
        # GJK's own normal is an upper bound too (h there): the smaller of the two
        gx, gy, gz = out[OUT_NORMAL], out[OUT_NORMAL + 1], out[OUT_NORMAL + 2]
        qx, qy, qz, px, py, pz = minkowski_full_xyz(sa, sb, verts, r_ab, t_ab, gx, gy, gz)
        hg = gx * (qx - px) + gy * (qy - py) + gz * (qz - pz)
        iters += 1
        if hg < h:
            nx, ny, nz, h = gx, gy, gz, hg
            ax, ay, az, bx, by, bz = qx, qy, qz, px, py, pz
    if not (stalled or -h > out[OUT_DIST]):
        if st == ST_FAILED:
            # EPA's own bound is the smaller one: the pair is in contact (MPR)
            out[OUT_ITERS] = iters
            return classify(out[OUT_DIST], scale)
        return st
    pa, pb = ws[0][_T_PA], ws[0][_T_PB]
    pa[0], pb[0] = meet(ax, bx, -h * nx)
    pa[1], pb[1] = meet(ay, by, -h * ny)
    pa[2], pb[2] = meet(az, bz, -h * nz)
    return _set_out(out, -h, nx, ny, nz, pa, pb, np.int64(iters), scale)
