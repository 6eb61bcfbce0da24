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

Phases of ``gjk_epa``
  1. GJK on the *cores* (spheres are points, capsules segments, others themselves;
     geometry.support_core).  Sub-simplex solver: Voronoi-region tests (Ericson), face
     weights from cross products, every face holding the new vertex tried (not only
     those facing the origin), and a step that
     does not shrink |v| is undone (robust to the sliver simplices of curved shapes);
     if the duality gap is then still above GJK_POLISH_TOL |v|^2, apart is not proved
     and the pair takes phase 3's fallback (_caps_fallback); likewise when a support
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
     searched instead (_kink_polish, as in EPA below): apart, h is convex and any
     local minimum below zero is the global one.  Once |v| proves that the shapes
     touch (so the exact distance is wanted), the crease search runs from the face
     test's gap below (0.1 |v|^2): near a crease GJK's direction is within ~0.025 rad
     of it by then, 4-7 GJK steps before the gap reaches GJK_POLISH_TOL.  Between a
     box or a cylinder and a sphere or an ellipsoid, GJK also tests a box's face normal
     or a cylinder's axis near its direction once its gap is below 0.1 |v|^2
     (_face_polish, as EPA below, at most EPA_FACE_EVALS supports): a minimum it finds
     with h < 0 is the global one.  Only from that gap: tested at every GJK step, it
     saves no steps and slows the GJK loop of every pair, those it never runs on too.
     Between a convex hull and an ellipsoid, GJK tests the hull's features near its
     direction once its gap is below GJK_POLISH_TOL |v|^2 (_hull_polish): the face of
     the three highest hull vertices (the face test), the crease of the edge of the
     two highest (the search along it), or Newton's method in a vertex's region.
     EPA does not: deeper than the ellipsoid core's radii of curvature, h is not
     convex around the hull's features, and their local minima lie as close as 0.03
     rad (regression scene mkc_hull_face_polish_wrong_basin_ellipsoid_convex).  Even
     with the cap the face test proves (_face_basin), which makes it safe, EPA's test
     of the face of the three highest vertices costs more time than the steps it
     saves: each try is passes over the hull's vertices.
  2. When the cores overlap (origin inside the GJK tetrahedron, or |v| <=
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
  3. If a cap is hit (valleys of equally deep directions, e.g. a sphere centred on a
     cylinder's or cone's axis, two coaxial cylinders), the best upper bound min h(u)
     over the evaluated normals is polished by a pattern search over directions and
     reported; the status is ST_FAILED only if the gap to the EPA lower bound exceeds
     EPA_FAIL_GAP * scale and that lower bound does not by itself prove penetration (a
     pair certainly in contact always yields its contact, e.g. to the pipeline, which
     drops failed pairs).  Then (_caps_fallback) a pair with a closed form takes it
     (analytic.collide_analytic, exact), and any other takes MPR's normal where its
     support value is the smaller upper bound of the depth, and MPR's contact in place
     of FAILED (bench/fuzz.py found both: a tiny capsule inside a large one FAILED, a
     small body deep in a large cylinder or cone up to 2e-5 * scale too deep).
  Witness points: barycentric coordinates of the closest point on the final simplex /
  EPA face, applied to the support points of A and B, then moved out by the radii.
  When the origin's projection falls outside the final EPA face (sliver faces of flat
  or face-to-face contacts), GJK on the pair just pulled apart along the normal gives
  them instead (_witness_by_gjk; regression scenes drake21673_box_box, _convex5).
  Scratch memory: ``gjk_epa`` allocates one workspace per call; the batch kernel
  calls ``gjk_epa_ws`` with one workspace per chunk of pairs (no allocation per pair).

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

from .constants import (BOX, CAPSULE, CONVEX, CYLINDER, ELLIPSOID, EPA_DEGEN_TOL,
                        EPA_FACE_CAP_MAX, EPA_FACE_EVALS, EPA_FACE_TOL, EPA_FAIL_GAP,
                        EPA_KINK_CAP_BOX, EPA_KINK_CAP_CAPSULE, EPA_KINK_ITERS,
                        EPA_KINK_NEAR, EPA_KINK_STEP,
                        EPA_MAX_FACES, EPA_MAX_ITERS, EPA_POLISH_CAP, EPA_VERTEX_CAP_MIN,
                        EPA_POLISH_ITERS, EPA_POLISH_STEP, EPA_POLISH_TOL, EPA_REL_TOL,
                        EPA_WITNESS_SHIFT, GJK_ABS_TOL, GJK_MAX_ITERS,
                        GJK_POLISH_TOL, GJK_REL_TOL, M_GJK_EPA, OUT_DIST, OUT_ITERS,
                        OUT_METHOD, OUT_NORMAL, OUT_PA, OUT_PB, OUT_SIZE, P_ROLL, PLANE,
                        POLISH_STEP_DONE, SPHERE,
                        ST_FAILED, ST_NOT_RUN, ST_PENETRATING, ST_SEPARATED, ST_TOUCHING,
                        TOUCH_TOL)
from .analytic import _point_box, _point_cylinder, classify, collide_analytic
from .boxcyl import BC_MAX_LEVEL, box_cylinder_depth
from .boxell import ellipsoid_box_depth, face_room
from .cylcyl import (cylinders_depth, ellipsoid_cylinder_depth, hull_cylinder_depth,
                     segment_cylinder_depth, sides_crossing)
from .geometry import (borrow_args, borrow_pose, inflation, meet, minkowski_core_xyz,
                       minkowski_full_xyz, shape_scale)
from .hullell import (HE_APART, HE_EXACT, HE_ROWS, HE_UNDECIDED, HE_UNPROVED,
                      ellipsoid_hull_depth, ellipsoid_hull_pair)
from .hullcyl import cylinder_hull_depth, cylinder_hull_pair
from .jit import borrow, njit_inline, njit_kernel
from .mpr import MPR_WS_ROWS, mpr_ws
from .simplex import _closest_simplex, _tri_closest
from .tracebuf import TR_EPA, TR_GJK, TR_HEADER_ROWS, trace_open, trace_reset, trace_rows

# Scratch buffers ``ws`` = (fs, fv, iv) of one GJK/EPA call, allocated once per chunk of
# pairs by the batch kernel and reused pair after pair; no state survives from one pair
# to the next.  Three
# backing arrays only (numba reference-counts every array passed to a function, so a
# tuple of many small arrays costs more per call than the work of an analytic pair):
#   fs float64 (_FS_ROWS, 3): simplex W, WA, WB and their saved copies, 3-vector scratch
#      rows t3 (see below), the growth candidates, EPA vertices V, VA, VB and the unit
#      direction VD whose support each vertex is (zero for the starting tetrahedron),
#      the samples of Newton's method (directions PN, support points of A - B PW),
#      face normals FN
#   fv float64 (_FV_SIZE,): barycentric weights lam / lam_prev, l3, vol, the EPA result
#      res (10), GJK's closest point v (3), face offsets FD
#   iv uint64 (_IV_ROWS, 3): faces F, horizon edges (a, b, face beyond as in ADJ),
#      the flood-fill stack and the alive flags, the new faces and the free face
#      slots, the face adjacency ADJ (4 g + eg: the face g across edge e = F[f, e] ->
#      F[f, (e + 1) % 3], which is g's edge eg), then per vertex u the horizon edge
#      starting at u and the one ending at u of the current step, so each new face
#      finds its neighbours across its two spokes in O(1).  The six lists lie in
#      _epa's flat view of iv (iv.reshape), two per block of rows, each contiguous.
#      Unsigned because numba wraps negative indices (idx + len when idx < 0) only for
#      signed integers: an index loaded from an int64 array costs three more
#      instructions and the view's length kept in a register or spilled (measured:
#      deep GJK/EPA pairs with a cylinder 7-10% faster as uint64, the same results).
#      Mind numba's typing: int64 and uint64 unify to float64, so a variable that takes
#      both (a slot index from ``free`` or from ``nf``) is cast with np.uint64.
# t3 rows (fs[_T3 + k]): 0-2 nrm, pa, pb of gjk_epa; 3 (column 0) the cap a face test
# proved (_face_basin); 4-7 d, wa, wb, w of gjk_epa; 8-11
# d, wa, wb, w of _gjk / _grow_to_tetra / _epa; 12 v_prev (_gjk) or cin (_epa); 13-14
# ud, uwa (_epa; 13 also the shifted t_ab of _witness_by_gjk); 15-18 bw, bwa, bwb, bdir
# (_grow_to_tetra), then d, w, wa, wb of _newton_min_support's result; 19-24 d, wa, wb,
# w, e1, e2 (_polish_min_support).
_NVMAX = EPA_MAX_ITERS + 4
_PK = EPA_POLISH_ITERS + 4    # samples of the local polish: <= 4 given + one per step
_W, _WA, _WB, _WP, _WAP, _WBP = 0, 4, 8, 12, 16, 20
_T3 = 24
_CAND = _T3 + 25
_V = _CAND + 6
_VA = _V + _NVMAX
_VB = _VA + _NVMAX
_VD = _VB + _NVMAX
_PN = _VD + _NVMAX
_PW = _PN + _PK
_FN = _PW + _PK
_FS_ROWS = _FN + EPA_MAX_FACES
_BC_ROWS = BC_MAX_LEVEL + 8   # boxcyl's scratch, in the EPA vertex rows (free then)
assert _V + HE_ROWS <= _FS_ROWS   # hullell's scratch rows likewise, before GJK
_LAM, _LAMP, _L3, _VOL, _RES, _VV = 0, 4, 8, 11, 15, 25
_FD = 28
_FV_SIZE = _FD + EPA_MAX_FACES
_IF = 0
_IE = EPA_MAX_FACES
_IS = _IE + 3 * EPA_MAX_FACES
_IC = _IS + EPA_MAX_FACES
_IA = _IC + EPA_MAX_FACES
_IH = _IA + EPA_MAX_FACES
_IV_ROWS = _IH + _NVMAX


@njit_kernel
def make_gjk_workspace():
    """Fresh scratch buffers for ``gjk_epa_ws``: the tuple ``ws`` = (fs, fv, iv) above
    (a plain tuple: kernels import only numpy, numba and math)."""
    return (np.empty((_FS_ROWS, 3)), np.zeros(_FV_SIZE),
            np.zeros((_IV_ROWS, 3), dtype=np.uint64))


@njit_kernel
def make_gjk_workspace_traced(rows):
    """``make_gjk_workspace()`` with a trace region of ``rows`` (>= TR_HEADER_ROWS) rows
    after fs's working rows (module docstring, "Trace"), its header and options zero:
    the same array types, so ``gjk_epa_ws`` runs the same compiled code."""
    fs = np.empty((_FS_ROWS + rows, 3))
    for r in range(_FS_ROWS, _FS_ROWS + TR_HEADER_ROWS):
        for c in range(3):
            fs[r, c] = 0.0
    return (fs, np.zeros(_FV_SIZE), np.zeros((_IV_ROWS, 3), dtype=np.uint64))


# outcome flags of the GJK loop
_GJK_APART = 0       # converged, origin outside: v is the closest point
_GJK_OVERLAP = 1     # origin inside (or within round-off of) the simplex
_GJK_CAP = 2         # iteration cap hit
_GJK_BOUND = 3       # stopped early: the cores are farther apart than the caller's stop
                     # distance (v is not the closest point; the returned bound is)
_GJK_POLISHED = 4    # apart, minimum found by _newton_min_support (ws t3 rows 15-18)
_GJK_STALL = 5       # no progress in floating point (a sliver simplex) with the duality
                     # gap still above GJK_POLISH_TOL |v|^2: apart is not proved


@njit_inline
def borrow_gjk_workspace(ws):
    """A ``make_gjk_workspace()`` tuple as owner-less views (geometry.borrow_args says
    why); the caller keeps the owner alive."""
    return (borrow(ws[0]), borrow(ws[1]), borrow(ws[2]))


@njit_inline
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit_inline
def _gjk(sa, sb, verts, r_ab, t_ab, scale, ws, stop, polish, trace_on):
    """GJK loop on the cores (geometry.minkowski_core_xyz).

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
    d, wa, wb, w = ws[0][_T3 + 8], ws[0][_T3 + 9], ws[0][_T3 + 10], ws[0][_T3 + 11]
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
    n = 1
    if trace_on:
        trace_rows(fs, _FS_ROWS, TR_GJK, W, n)
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
    v_prev = ws[0][_T3 + 12]
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
        if polish and gap <= 0.1 * vv:
            inv = 1.0 / math.sqrt(vv)
            if face_left > 0:
                # near a box's face normal or a cylinder's axis (within EPA_KINK_NEAR)
                k_f = _face_polish(sa, sb, verts, r_ab, t_ab, scale, ws,
                                   d[0] * inv, d[1] * inv, d[2] * inv)
                if k_f != 0:
                    face_left -= 1
                    it += 1
                    if k_f > 0 and _dot(fs[_T3 + 15], fs[_T3 + 16]) < 0.0:
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
                kc = _kink_side(sa, sb, r_ab, d[0] * inv, d[1] * inv, d[2] * inv, True)
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
                if k_pol > 0 and _dot(fs[_T3 + 15], fs[_T3 + 16]) < 0.0:
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
                trace_rows(fs, _FS_ROWS, TR_GJK, W, n)
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
            trace_rows(fs, _FS_ROWS, TR_GJK, W, n)
        vv = vv_new
    return n, it, flag, 0.0


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


@njit_kernel
def _grow_to_tetra(sa, sb, verts, r_ab, t_ab, scale, ws, n):
    """Grow a simplex W[:n] holding the origin to a tetrahedron by supports of the full
    shapes along directions normal to its affine hull.  Returns the new count (4), or
    -1 when the Minkowski difference is flat there (touching, depth 0); on -1 the unit
    normal of the flat direction is in W[3].  W, WA, WB: the workspace's simplex."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    W, WA, WB = ws[0][_W:_W + 4], ws[0][_WA:_WA + 4], ws[0][_WB:_WB + 4]
    d, wa, wb, w = ws[0][_T3 + 8], ws[0][_T3 + 9], ws[0][_T3 + 10], ws[0][_T3 + 11]
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
        bw, bwa, bwb, bdir = ws[0][_T3 + 15], ws[0][_T3 + 16], ws[0][_T3 + 17], ws[0][_T3 + 18]
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
def _polish_min_support(sa, sb, verts, r_ab, t_ab, scale, ud, uwa, ub, ws):
    """Pattern search for min over unit u of h_{A-B}(u) starting at ``ud`` (3,) with
    value ``ub``; updates ud and uwa (A's support point) in place, returns the value."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ud, uwa, ws = borrow(ud), borrow(uwa), borrow_gjk_workspace(ws)
    d, wa, wb, w = ws[0][_T3 + 19], ws[0][_T3 + 20], ws[0][_T3 + 21], ws[0][_T3 + 22]
    e1, e2 = ws[0][_T3 + 23], ws[0][_T3 + 24]
    step = 1e-2
    it = 0
    while step > 1e-10 and it < 4 * EPA_MAX_ITERS:
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
def _store_min(fs, nx, ny, nz, wx, wy, wz, ax, ay, az, bx, by, bz):
    """A minimum found by a polish (Newton's method, the crease searches, the face
    tests) into ws t3 rows 15-18: direction n, the difference point w, the witnesses
    a on A and b on B."""
    pd, pw, pwa, pwb = fs[_T3 + 15], fs[_T3 + 16], fs[_T3 + 17], fs[_T3 + 18]
    pd[0], pd[1], pd[2] = nx, ny, nz
    pw[0], pw[1], pw[2] = wx, wy, wz
    pwa[0], pwa[1], pwa[2] = ax, ay, az
    pwb[0], pwb[1], pwb[2] = bx, by, bz


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
        if not det > 1e-6 * (m11 + m22) ** 2:
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
        if not hn <= h + 1e-12 * scale:
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
    d, wa, w = fs[_T3 + 8], fs[_T3 + 9], fs[_T3 + 11]
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


@njit_inline
def _kink_partner(code):
    """Whether _kink_polish may run against a shape of this code: a cylinder (whose
    crease and point kinks it searches too), one with no kinks (sphere and ellipsoid
    cores) or a capsule's core (its crease is left to EPA where the two creases cross,
    _kink_side, and the basin cap is EPA_KINK_CAP_CAPSULE).  Boxes, cones and convex
    hulls put creases and flat faces near the minimum that it does not rule out (run
    there, it saves box-cylinder and cylinder-convex pairs nothing)."""
    return code == CYLINDER or code == ELLIPSOID or code == SPHERE or code == CAPSULE


@njit_inline
def _has_crease(code):
    """Whether h has a crease along a great circle of directions from a shape of this
    code: a cylinder's side, a capsule's core, a box's edges (its support is a segment
    along the directions normal to the axis)."""
    return code == CYLINDER or code == CAPSULE or code == BOX


@njit_inline
def _searched_crease(code, other):
    """Whether _kink_polish searches the crease of a shape of this code paired with
    one of code ``other``: a cylinder's, against a _kink_partner; a capsule's, against
    a sphere or an ellipsoid (its core, a segment along z, has the same crease as a
    cylinder's side and no other kink).  Against a box, cone, hull or cylinder, the
    other shape's creases and flat faces near the minimum are not ruled out, as for
    _kink_partner."""
    return ((code == CYLINDER and _kink_partner(other))
            or ((code == CAPSULE or code == BOX)
                and (other == ELLIPSOID or other == SPHERE)))


@njit_inline
def _axis_of(side, axis, r_ab):
    """Body axis ``axis`` (0, 1, 2: x, y, z) of shape A (side 0) or B (side 1), in A's
    frame."""
    if side == 0:
        return (1.0 if axis == 0 else 0.0, 1.0 if axis == 1 else 0.0,
                1.0 if axis == 2 else 0.0)
    return r_ab[0, axis], r_ab[1, axis], r_ab[2, axis]


@njit_inline
def _kink_side(sa, sb, r_ab, dx, dy, dz, apart):
    """Which crease of h the unit direction d is near (|d . axis| < EPA_KINK_NEAR): a
    cylinder's side or a capsule's core (the great circle normal to its axis, z) or a
    box's edges along one of its axes (the circle normal to that axis), of those
    _searched_crease allows for EPA or, ``apart`` (GJK on cores apart, where h is
    convex and a minimum on a crease is the global one whatever the other shape), all
    of them.  Returns 3 side + axis (side 0 for A's crease, 1 for B's), -1 when near
    none, -2 when near two or more, searched or not: where two creases cross (two
    cylinders' circles, a capsule's and a cylinder's, a box's face normal) the minimum
    is likely on a flat face of A - B, which EPA and GJK resolve themselves (deep
    capsule-cylinder pairs there: 13.9 steps by EPA alone, 25.2 with the search along
    the cylinder's crease; two cylinders' sides, or a cylinder's and a hull's edge:
    _crossing_test).  Near one crease that is not searched: -1."""
    found = -1
    for side in range(2):
        code = sa[0] if side == 0 else sb[0]
        if not _has_crease(code):
            continue
        searched = apart or _searched_crease(code, sb[0] if side == 0 else sa[0])
        for axis in range(0 if code == BOX else 2, 3):
            kx, ky, kz = _axis_of(side, axis, r_ab)
            if abs(kx * dx + ky * dy + kz * dz) < EPA_KINK_NEAR:
                if found != -1:
                    return -2
                # near a crease EPA does not search: -2 if near another as well
                found = 3 * side + axis if searched else -3
    return -1 if found == -3 else found


@njit_kernel
def _support_called(sa, sb, verts, r_ab, t_ab, dx, dy, dz):
    """minkowski_core_xyz called, not inlined: for the crease search, which runs on
    few pairs and evaluates few supports, where every inlined copy of all the shapes'
    support mappings lengthened the first compile."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    return minkowski_core_xyz(sa, sb, verts, r_ab, t_ab, dx, dy, dz)


@njit_kernel
def _crease_min(sa, sb, verts, r_ab, t_ab, scale, kx, ky, kz, dx, dy, dz):
    """Secant search for the minimum of h = h_{A-B} along the great circle of
    directions normal to the unit axis k (a crease of a cylinder's or a capsule core's
    support function), from the direction d projected onto it.

    Along the circle, u(t) = cos t n + sin t e (e = k x n), h is smooth between the
    other shape's creases and its derivative is g(t) = w(u(t)) . u'(t), w a support
    point of A - B (any point of the support segment gives the same g, as u' is
    normal to k).  Converged when the next step is below POLISH_STEP_DONE (rad) with
    |g| <= 1e-6 * scale (a crease of the other shape shows as a jump in g: the secant
    closes in on the jump with g still large) and a positive secant slope.  Returns
    (ok, supports evaluated, lowest h evaluated, then at the last point: h, u (3), the
    support points of A and of B (3 each)); ok is False when it gave up."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    c = dx * kx + dy * ky + dz * kz
    nx, ny, nz = dx - c * kx, dy - c * ky, dz - c * kz
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    ok = False
    hlow = np.inf
    hu = ux = uy = uz = pax = pay = paz = pbx = pby = pbz = 0.0
    if not nn > 0.5:
        return (ok, 0, hlow, hu, ux, uy, uz, pax, pay, paz, pbx, pby, pbz)
    nx, ny, nz = nx / nn, ny / nn, nz / nn
    ex, ey, ez = ky * nz - kz * ny, kz * nx - kx * nz, kx * ny - ky * nx
    t = 0.0
    ta = ga = 0.0
    k_it = 0
    while k_it < EPA_KINK_ITERS:
        ct, st = math.cos(t), math.sin(t)
        ux, uy, uz = ct * nx + st * ex, ct * ny + st * ey, ct * nz + st * ez
        pax, pay, paz, pbx, pby, pbz = _support_called(
            sa, sb, verts, r_ab, t_ab, ux, uy, uz)
        qx, qy, qz = pax - pbx, pay - pby, paz - pbz
        hu = ux * qx + uy * qy + uz * qz
        hlow = min(hlow, hu)
        g = (ct * ex - st * nx) * qx + (ct * ey - st * ny) * qy + (ct * ez - st * nz) * qz
        k_it += 1
        if k_it == 1:
            # first step: Newton's with h'' guessed as half the pair's scale
            step = -g / (0.5 * scale)
        else:
            slope = (g - ga) / (t - ta)
            if not slope > 0.0:
                break
            step = -g / slope
            if abs(step) <= POLISH_STEP_DONE:
                ok = abs(g) <= 1e-6 * scale
                break
        step = max(-EPA_KINK_STEP, min(EPA_KINK_STEP, step))
        ta, ga = t, g
        t += step
    return (ok, k_it, hlow, hu, ux, uy, uz, pax, pay, paz, pbx, pby, pbz)


@njit_inline
def _deeper_near(sa, sb, verts, r_ab, t_ab, px, py, pz, ux, uy, uz, cmin, lim):
    """(evaluated, deeper): whether the unit direction p lies within acos(cmin) of u (one
    support is then evaluated there), and whether h(p) < ``lim`` there."""
    if px * ux + py * uy + pz * uz < cmin:
        return 0, False
    pax, pay, paz, pbx, pby, pbz = _support_called(sa, sb, verts, r_ab, t_ab, px, py, pz)
    return 1, px * (pax - pbx) + py * (pay - pby) + pz * (paz - pbz) < lim


@njit_inline
def _kink_points(sa, sb, verts, r_ab, t_ab, ux, uy, uz, lim):
    """Whether h reaches below ``lim`` at a point kink of h within EPA_POLISH_CAP of the
    direction u, for a pair of cylinders: the two cap normals of each and the two
    directions where their creases cross.  Returns (found, supports evaluated)."""
    cmin = math.cos(EPA_POLISH_CAP)
    ox, oy, oz = _axis_of(1, 2, r_ab)
    cx, cy, cz = -oy, ox, 0.0           # z x o (A's axis is z)
    cn = math.sqrt(cx * cx + cy * cy)
    nev = 0
    for m in range(6):
        if m < 2:
            if not cn > 1e-12:
                continue
            px, py, pz = cx / cn, cy / cn, cz / cn
        elif m < 4:
            px, py, pz = _axis_of(0, 2, r_ab)
        else:
            px, py, pz = ox, oy, oz
        if m % 2 == 1:
            px, py, pz = -px, -py, -pz
        ev, deeper = _deeper_near(sa, sb, verts, r_ab, t_ab, px, py, pz, ux, uy, uz,
                                  cmin, lim)
        nev += ev
        if deeper:
            return True, nev
    return False, nev


@njit_inline
def _box_faces_deeper(sa, sb, verts, r_ab, t_ab, side, axis, ux, uy, uz, lim):
    """Whether h reaches below ``lim`` at one of the four face normals of a box (A's if
    side == 0, else B's) on the circle of directions normal to its axis ``axis``, within
    EPA_POLISH_CAP of the unit direction u.  Returns (found, supports evaluated)."""
    cmin = math.cos(EPA_POLISH_CAP)
    nev = 0
    for m in range(4):
        j = (axis + 1 + m // 2) % 3
        px, py, pz = _axis_of(side, j, r_ab)
        if m % 2 == 1:
            px, py, pz = -px, -py, -pz
        ev, deeper = _deeper_near(sa, sb, verts, r_ab, t_ab, px, py, pz, ux, uy, uz,
                                  cmin, lim)
        nev += ev
        if deeper:
            return True, nev
    return False, nev


@njit_inline
def _hull_side(ca, cb):
    """The side (0: A, 1: B) of a convex hull paired with an ellipsoid, whose features
    GJK on cores apart tests (_hull_polish); -1 for other pairs.  Against a sphere (a
    point core) GJK is exact in a few steps already.  Against a cylinder the same tests,
    with the cylinder's direction kept away from its crease and axis, cost EPA steps
    on deep cylinder-convex pairs (the searches along a hull edge's crease that cross
    the cylinder's give up), and against a box or a cone their creases and faces would
    need ruling out as well."""
    if ca == CONVEX and cb == ELLIPSOID:
        return 0
    if cb == CONVEX and ca == ELLIPSOID:
        return 1
    return -1


@njit_inline
def _hull_dir(side, r_ab, dx, dy, dz):
    """The direction, in the hull's own frame, along which the hull on ``side`` gives
    the support of A - B along d (A's frame): d on A, -r_ab^T d on B."""
    if side == 0:
        return dx, dy, dz
    return (-(r_ab[0, 0] * dx + r_ab[1, 0] * dy + r_ab[2, 0] * dz),
            -(r_ab[0, 1] * dx + r_ab[1, 1] * dy + r_ab[2, 1] * dz),
            -(r_ab[0, 2] * dx + r_ab[1, 2] * dy + r_ab[2, 2] * dz))


@njit_inline
def _hull_top3(pts, dx, dy, dz):
    """The three highest vertices of ``pts`` (n >= 3, 3) along d: indices i, j, m and
    heights p1 >= p2 >= p3."""
    p1 = p2 = p3 = -np.inf
    i = j = m = np.int64(0)   # typed int64 at once (jit.py, "Literal")
    for q in range(pts.shape[0]):
        v = pts[q, 0] * dx + pts[q, 1] * dy + pts[q, 2] * dz
        if v > p3:
            if v > p2:
                p3, m = p2, j
                if v > p1:
                    p2, j = p1, i
                    p1, i = v, q
                else:
                    p2, j = v, q
            else:
                p3, m = v, q
    return i, j, m, p1, p2, p3


@njit_kernel
def _hull_polish(sa, sb, verts, r_ab, t_ab, scale, ws, side, dx, dy, dz):
    """The minimum of h = h_{A-B} at a convex hull's feature near the unit direction d
    (GJK's direction), for a hull against an ellipsoid (_hull_side; the
    hull on ``side``) with the cores apart: the face test on the face through the three
    highest vertices along d (_hull_face_test), else the search along the crease of the
    edge of the two highest.

    Why: a hull's support along the directions normal to one of its edges (the arc of
    the great circle normal to the edge between the normals of the two faces through
    it) is that whole edge, so h has a crease along that arc, as along a box's edges
    (_kink_polish), and at a face's normal a point kink, as at a box's.  Of 139 deep
    ellipsoid-convex pairs, 53 have their deepest direction on an edge's crease, 73 on
    a face normal and 13 in a vertex's region.

    The edge: searched if d lies within EPA_KINK_NEAR rad of its crease, also near a
    face's normal that is no minimum (skipping the search within 5e-3 rad of one costs
    0.05 more steps per deep pair, within 0.05 rad 0.6 more).  Then _crease_min along
    the circle normal to the edge, and the minimum is kept only if h there is the
    lowest the search evaluated, the edge is still the hull's support there (its two
    vertices the highest, the third below) and the point h u of A - B lies on the edge
    (the hull's support point slid along the edge to cancel w's part along it stays
    between the two vertices: h then rises on both sides of the crease).  With the
    cores apart h is convex, and a local minimum below zero is the global one (the
    caller checks the sign).

    Returns (k, vertex): k the number of support evaluations, negated when no minimum
    was found, results as _kink_polish's (ws t3 rows 15-18) when one was; vertex True
    when d is in a vertex's region (no face minimum there and far from every edge's
    crease: h is smooth there, and the caller tries Newton's method)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    fs = ws[0]
    v0 = sa[2] if side == 0 else sb[2]
    vn = sa[3] if side == 0 else sb[3]
    if vn < 3:
        return 0, False
    pts = verts[v0:v0 + vn]
    hx, hy, hz = _hull_dir(side, r_ab, dx, dy, dz)
    i, j, m, p1, p2, _ = _hull_top3(pts, hx, hy, hz)
    k_f = _hull_face_test(sa, sb, verts, r_ab, t_ab, scale, ws, side, i, j, m,
                          hx, hy, hz)
    if k_f > 0:
        return 1, False
    ex, ey, ez = pts[i, 0] - pts[j, 0], pts[i, 1] - pts[j, 1], pts[i, 2] - pts[j, 2]
    le = math.sqrt(ex * ex + ey * ey + ez * ez)
    if not (le > 1e-9 * scale and p1 - p2 < EPA_KINK_NEAR * le):
        return k_f, True
    # the edge's direction (from j to i) in A's frame
    ex, ey, ez = ex / le, ey / le, ez / le
    if side == 0:
        kx, ky, kz = ex, ey, ez
    else:
        kx = r_ab[0, 0] * ex + r_ab[0, 1] * ey + r_ab[0, 2] * ez
        ky = r_ab[1, 0] * ex + r_ab[1, 1] * ey + r_ab[1, 2] * ez
        kz = r_ab[2, 0] * ex + r_ab[2, 1] * ey + r_ab[2, 2] * ez
    r = _crease_min(sa, sb, verts, r_ab, t_ab, scale, kx, ky, kz, dx, dy, dz)
    ok, nev, hlow, hu, ux, uy, uz, pax, pay, paz, pbx, pby, pbz = r
    nev += abs(k_f)
    if not (ok and hu <= hlow + 1e-12 * scale):
        return -nev, False
    # the edge still the support along u
    hx, hy, hz = _hull_dir(side, r_ab, ux, uy, uz)
    i2, j2, _, q1, _, q3 = _hull_top3(pts, hx, hy, hz)
    if not (((i2 == i and j2 == j) or (i2 == j and j2 == i)) and q3 < q1 - 1e-12 * scale):
        return -nev, False
    # slide the hull's point along the edge to cancel w's part along it; it must stay
    # on the edge (between j and i)
    s = (pax - pbx) * kx + (pay - pby) * ky + (paz - pbz) * kz
    jx, jy, jz = pts[j, 0], pts[j, 1], pts[j, 2]
    if side == 0:
        pax, pay, paz = pax - s * kx, pay - s * ky, paz - s * kz
        tpar = (pax - jx) * kx + (pay - jy) * ky + (paz - jz) * kz
    else:
        pbx, pby, pbz = pbx + s * kx, pby + s * ky, pbz + s * kz
        tpar = ((pbx - t_ab[0]) * kx + (pby - t_ab[1]) * ky + (pbz - t_ab[2]) * kz
                - (r_ab[0, 0] * jx + r_ab[0, 1] * jy + r_ab[0, 2] * jz) * kx
                - (r_ab[1, 0] * jx + r_ab[1, 1] * jy + r_ab[1, 2] * jz) * ky
                - (r_ab[2, 0] * jx + r_ab[2, 1] * jy + r_ab[2, 2] * jz) * kz)
    if not (-1e-12 * scale <= tpar <= le + 1e-12 * scale):
        return -nev, False
    _store_min(fs, ux, uy, uz, pax - pbx, pay - pby, paz - pbz, pax, pay, paz, pbx, pby,
               pbz)
    return nev, False


_SIN_CAP = math.sin(EPA_POLISH_CAP)


@njit_kernel
def _kink_polish(sa, sb, verts, r_ab, t_ab, scale, ws, side, axis):
    """Minimum of h(u) = h_{A-B}(u) over the great circle of directions normal to the
    axis of a cylinder or a capsule (z), or to a box's axis ``axis`` (A's if side == 0,
    else B's), from EPA's best face normal d (ws t3 row 8), by _crease_min; then checks
    that it is the minimum over all directions near it.

    Why: along those directions the cylinder's support is a whole segment of its side
    (a capsule's: its core segment, grown by the radius), so its support function has
    a crease there.  When the deepest direction lies on the crease (measured: 436 of
    939 deep cylinder-cylinder pairs, 571 of 963 deep ellipsoid-cylinder pairs), A - B
    has a ruled strip there, curved across; EPA then closes its bounds by a factor of
    ~2 per step (~30 steps against ~17 where the minimum is on a flat face) and
    Newton's method in two dimensions gives up on the crease.  A box's support along
    directions normal to one of its axes is an edge along that axis, so the same
    holds for its edges (measured: 357 of 960 deep ellipsoid-box pairs have their
    deepest direction on an edge's crease, 28 GJK + EPA steps on average against 15
    on a face normal).

    Kept only if h there is the lowest the search evaluated, the point h u lies on
    A - B's support segment (the cylinder's support point slid along its side by the
    axial part of w - h u stays within the side, within +-prm[1] along the axis for
    both shapes; a box's edge within +-prm[axis]: then h rises on both sides of the
    crease), for a box, no face normal within EPA_POLISH_CAP of the minimum deeper (the
    crease's circle passes through four of them, where h has kinks the secant does not
    see), and, when the other shape is a cylinder too, nothing nearby is deeper: the
    minimum along its crease (searched from d as well where that crease passes within
    EPA_POLISH_CAP of the first search's minimum, as farther the basin test covers it;
    the deeper of the two converged minima is the candidate, and a search that gave up
    but went deeper rejects it) and the point kinks of _kink_points.  Where two creases
    pass close by, each has a minimum of its own (without this check, 4 of 40,000 deep
    random cylinder-cylinder and capsule-cylinder pairs keep a minimum up to 4.3e-4 *
    scale shallower than the deepest direction, on the other crease 0.13-0.29 rad away;
    regression scene mkc_crease_polish_other_crease_cylinder_cylinder).  EPA then
    applies _polish_is_global as to Newton's method; GJK on cores apart needs no such
    test (h is convex there: a minimum on the sphere below zero is the global one).
    None of those checks is needed when the first search's minimum is the depth by
    _ball_certified (a witness with a ball of radius h inside the other shape's core):
    the search ends there.  Results as _newton_min_support's (ws t3 rows 15-18:
    direction, difference point, witnesses on A and B, the cylinder's one slid to that
    point), stored only when it succeeds (a minimum EPA holds pending its basin test
    stays there otherwise); returns the number of support evaluations, negated when it
    gave up."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    fs = ws[0]
    d = fs[_T3 + 8]
    tol = EPA_REL_TOL * scale
    kx, ky, kz = _axis_of(side, axis, r_ab)
    r = _crease_min(sa, sb, verts, r_ab, t_ab, scale, kx, ky, kz, d[0], d[1], d[2])
    nev = r[1]
    ok = False
    pax = pay = paz = pbx = pby = pbz = 0.0
    if r[0]:
        # the depth itself (_ball_certified): no other crease or kink can be deeper
        ok, pax, pay, paz, pbx, pby, pbz = _crease_slid(sa, sb, t_ab, scale, r, side, axis,
                                                        kx, ky, kz)
        if ok and _ball_certified(sa, sb, r_ab, t_ab, r[3] - tol, r[4], r[5], r[6], pax,
                                  pay, paz, pbx, pby, pbz):
            _store_min(fs, r[4], r[5], r[6], pax - pbx, pay - pby, paz - pbz, pax, pay,
                       paz, pbx, pby, pbz)
            return nev
    both = sa[0] == CYLINDER and sb[0] == CYLINDER
    ox, oy, oz = _axis_of(1 - side, 2, r_ab)
    # the other cylinder's crease is searched only where it passes within the basin cap
    # (EPA_POLISH_CAP) of the minimum found: farther, _polish_is_global's test covers it
    if both and not (r[0] and abs(r[4] * ox + r[5] * oy + r[6] * oz) > _SIN_CAP):
        r2 = _crease_min(sa, sb, verts, r_ab, t_ab, scale, ox, oy, oz,
                         d[0], d[1], d[2])
        nev += r2[1]
        if r2[0] and (not r[0] or r2[3] < r[3]):
            r, r2 = r2, r
            side = 1 - side
            kx, ky, kz = ox, oy, oz
            # the witnesses of the other crease's minimum (those of the first search's
            # are at hand otherwise)
            ok, pax, pay, paz, pbx, pby, pbz = _crease_slid(sa, sb, t_ab, scale, r, side,
                                                            axis, kx, ky, kz)
        if r[0] and r2[2] < r[3] - tol:
            return -nev                 # the other search went deeper without converging
    if not (r[0] and ok):
        return -nev
    hu, ux, uy, uz = r[3], r[4], r[5], r[6]
    if (sa[0] if side == 0 else sb[0]) == BOX:
        found, nk = _box_faces_deeper(sa, sb, verts, r_ab, t_ab, side, axis,
                                      ux, uy, uz, hu - tol)
        nev += nk
        if found:
            return -nev
    if both:
        found, nk = _kink_points(sa, sb, verts, r_ab, t_ab, ux, uy, uz, hu - tol)
        nev += nk
        if found:
            return -nev
    _store_min(fs, ux, uy, uz, pax - pbx, pay - pby, paz - pbz, pax, pay, paz, pbx, pby,
               pbz)
    return nev


@njit_inline
def _crease_slid(sa, sb, t_ab, scale, r, side, axis, kx, ky, kz):
    """_kink_polish's witnesses for the minimum r of _crease_min along the crease of the
    shape on ``side`` (axis k): (ok, a (3), b (3)).  The cylinder's (capsule's, box's)
    point slides along its axis to cancel w's axial part, so that a - b = h u; ok when
    h there is the lowest the search evaluated and the point stays on the side
    (segment, edge), within +-prm[1] along the axis (a box: +-prm[axis]): then h rises
    on both sides of the crease."""
    hlow, hu = r[2], r[3]
    pax, pay, paz, pbx, pby, pbz = r[7], r[8], r[9], r[10], r[11], r[12]
    if not hu <= hlow + 1e-12 * scale:
        return False, pax, pay, paz, pbx, pby, pbz
    s = -((pax - pbx) * kx + (pay - pby) * ky + (paz - pbz) * kz)
    if side == 0:
        pax, pay, paz = pax + s * kx, pay + s * ky, paz + s * kz
        ax_ = pax * kx + pay * ky + paz * kz
        hh = sa[1][axis] if sa[0] == BOX else sa[1][1]
    else:
        pbx, pby, pbz = pbx - s * kx, pby - s * ky, pbz - s * kz
        ax_ = (pbx - t_ab[0]) * kx + (pby - t_ab[1]) * ky + (pbz - t_ab[2]) * kz
        hh = sb[1][axis] if sb[0] == BOX else sb[1][1]
    return abs(ax_) <= hh + 1e-12 * scale, pax, pay, paz, pbx, pby, pbz


@njit_inline
def _polish_is_global(V, F, FN, FD, nf, n, hmin, planes, cap, first):
    """Whether the local minimum h(n) found by _epa_polish or _kink_polish is the global
    one, up to the polytope's resolution.  The ray from the origin along any unit
    direction u leaves the polytope (which lies inside A - B) through some face g, at
    the distance FD[g] / (u . FN[g]), and h(u) is at least that distance.  So h(u) <
    hmin = h(n) - tol needs an exit face with FD[g] < hmin.  Inside a cap of ``cap`` rad
    around n (EPA_POLISH_CAP; EPA_KINK_CAP_CAPSULE for a minimum on a capsule's crease:
    at 0.5 rad, 2 of 100,000 deep random ellipsoid-capsule pairs keep a crease minimum
    up to 4e-5 * scale shallower than a smooth one 0.09-0.19 rad off the crease, both in
    a valley flat to 1e-4 * scale), the minimum the polish converged to is taken to be
    the only one; outside it, no direction may reach deeper than hmin:

    * ``planes``: u must lie within acos(FD[g] / hmin) of FN[g] for such a face g, so
      every such cap must lie within the cap around n.  Used where h has no creases
      (sphere and ellipsoid cores only) and by _kink_polish, which searches the
      creases and point kinks nearby itself.  Sharper than the vertex test: the faces
      along a cylinder's side span ~1.2 rad from the minimum with their planes within
      the gain of it, which fail the vertex test on every deep cylinder pair polished
      on the crease.
    * else every such face must lie, with all three vertices, in the cap around n.
      With the plane test there, Newton's method on an ellipsoid against a cylinder or
      a capsule keeps a smooth minimum 0.24-0.40 rad from a deeper one on the other
      shape's crease or cap normal (3 of 200,000 deep random pairs).

    A face deeper than hmin beyond the cap means another basin may be deeper (e.g. an
    ellipsoid-cone pair whose polished minimum is 2e-4 * scale too shallow, its normal
    2.8 rad off): EPA goes on.

    Returns -1 when the minimum passes, else the index of a face that fails; EPA
    passes it back as ``first`` (-1 for none) at the next test of the same minimum."""
    cmin = math.cos(cap)
    for k in range(-1, nf):
        # the face that failed the last test of this minimum first (EPA repeats the test
        # at every step while the polytope grows; that face is often still there)
        f = first if k < 0 else k
        if f < 0 or (k >= 0 and f == first) or not FD[f] < hmin:
            continue
        if planes:
            if not FD[f] > 0.0:
                return f
            c = min(1.0, FN[f, 0] * n[0] + FN[f, 1] * n[1] + FN[f, 2] * n[2])
            r = FD[f] / hmin
            # acos(c) + acos(r) > cap, without acos: r lies in (0, 1), so the sum lies
            # in [0, pi] once acos(c) <= cap (< pi / 2), where cos decreases
            if c < cmin or c * r - math.sqrt((1.0 - c * c) * (1.0 - r * r)) < cmin:
                return f
        else:
            for q in range(3):
                i = F[f, q]
                vn = math.sqrt(V[i, 0] ** 2 + V[i, 1] ** 2 + V[i, 2] ** 2)
                if V[i, 0] * n[0] + V[i, 1] * n[1] + V[i, 2] * n[2] < cmin * vn:
                    return f
    return -1


@njit_inline
def _face_point(sa, sb, verts, r_ab, t_ab, side, nx, ny, nz):
    """One support of A - B along the unit direction n (A's frame), the outward normal
    of a face of the shape on ``side`` (A's face: n; B's: -n in B's own terms).
    Returns h = n . (a - b), the other shape's support point in the face shape's frame
    (3), and the support points a and b (A's frame, 3 each)."""
    pax, pay, paz, pbx, pby, pbz = _support_called(sa, sb, verts, r_ab, t_ab,
                                                   nx, ny, nz)
    h = nx * (pax - pbx) + ny * (pay - pby) + nz * (paz - pbz)
    if side == 0:
        qx, qy, qz = pbx, pby, pbz
    else:
        qx, qy, qz = _in_side_frame(1, r_ab, t_ab, pax, pay, paz)
    return h, qx, qy, qz, pax, pay, paz, pbx, pby, pbz


@njit_inline
def _face_minimum(fs, side, nx, ny, nz, h, pax, pay, paz, pbx, pby, pbz):
    """Store the minimum at a face's normal n (ws t3 rows 15-18: direction, difference
    point h n, witnesses on A and B): the other shape's point, and on the face that
    point moved onto the face's plane."""
    if side == 0:
        _store_min(fs, nx, ny, nz, h * nx, h * ny, h * nz, pbx + h * nx, pby + h * ny,
                   pbz + h * nz, pbx, pby, pbz)
    else:
        _store_min(fs, nx, ny, nz, h * nx, h * ny, h * nz, pax, pay, paz, pax - h * nx,
                   pay - h * ny, paz - h * nz)


@njit_inline
def _face_pair(ca, cb):
    """Whether GJK on cores apart tries _face_polish on this pair of shape codes: a box
    or a cylinder against a sphere or an ellipsoid (EPA's rule: _epa_face_pair; against
    other shapes GJK's use is not measured).  A convex hull's faces: _hull_polish, near
    GJK's end only."""
    faced = ca == BOX or ca == CYLINDER or cb == BOX or cb == CYLINDER
    round_ = ca == SPHERE or ca == ELLIPSOID or cb == SPHERE or cb == ELLIPSOID
    return faced and round_


@njit_inline
def _epa_face_pair(ca, cb):
    """Whether EPA tries _face_polish on this pair of shape codes: a _face_pair (a box
    or a cylinder against a sphere or an ellipsoid), or two cylinders.  The face
    test's first-order rise and the basin it proves (_face_basin) hold whatever the
    other shape (they use one point of it, not its smoothness), but against a box or
    a convex hull the test costs more than it saves (bench/dev/ab_deep.py; against a hull,
    with its faces tested as well, see _face_basin), and cones are not measured."""
    return _face_pair(ca, cb) or (ca == CYLINDER and cb == CYLINDER)


@njit_inline
def _crossing_pair(ca, cb):
    """Whether EPA tries _crossing_test on this pair of shape codes: a cylinder
    against a cylinder or a convex hull."""
    return ((ca == CYLINDER and (cb == CYLINDER or cb == CONVEX))
            or (cb == CYLINDER and ca == CONVEX))


@njit_kernel
def _crossing_test(sa, sb, verts, r_ab, t_ab, scale, ws, best, dx, dy, dz):
    """Whether the minimum of h = h_{A-B} is exactly where a cylinder's side crosses
    the other shape's segment (a cylinder's side, or a convex hull's edge) near EPA's
    best face normal d (a _crossing_pair; the hull's edge through two of the best
    face's support points).

    Why: along a direction n normal to a cylinder's axis the cylinder's support is a
    whole segment of its side (the crease of h, _kink_side), along n normal to a hull's
    edge the hull's may be that edge; where two such creases cross, n is normal to both
    segments and the two supports make a parallelogram face of A - B (segment minus
    segment), as flat as a box's face.  So the face test's reasoning (_face_polish)
    holds on it: n is a local minimum iff the foot of the origin on the face's plane
    (the pair of closest points of the two segments' lines) lies inside the face,
    1e-7 * scale inside its sides, and _face_basin proves the cap around n in which no
    direction is deeper (the disc about the foot inside the parallelogram: its distance
    to the sides, the segments' parameters' distances to their ends times the sine of
    the angle between the segments).  Measured on deep pairs (pure-Python count,
    bench.common.pair_cases seed 11): the minimum lies there in 168 of 317
    cylinder-convex pairs (a hull edge against the side) and in ~27% of cylinder pairs;
    without the test, EPA finds such a face only by its four corners.  A hull's edge is
    checked to be its support along n by a pass over its vertices; a cylinder's side
    is its support along every n normal to its axis.

    Results as _face_polish's (ws t3 rows 15-18, the cap in row 3): 1 when n is a
    minimum, -1 when the foot falls outside the face, 0 when d is near no crossing."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    fs = ws[0]
    cs = 0 if sa[0] == CYLINDER else 1          # the cylinder's side (A's if both)
    os_ = 1 - cs
    ocode = sb[0] if cs == 0 else sa[0]
    ax, ay, az = _axis_of(cs, 2, r_ab)
    if not abs(ax * dx + ay * dy + az * dz) < EPA_KINK_NEAR:
        return 0
    # the other segment: direction (bx, by, bz) and half-length lb, A's frame
    ncand = 1 if ocode == CYLINDER else 3
    F = ws[2][_IF:_IF + EPA_MAX_FACES]
    P = ws[0][_VA:_VA + _NVMAX] if os_ == 0 else ws[0][_VB:_VB + _NVMAX]
    for e in range(ncand):
        if ocode == CYLINDER:
            bx, by, bz = _axis_of(os_, 2, r_ab)
            lb = (sb[1] if os_ == 1 else sa[1])[1]
            px = py = pz = 0.0
        else:
            # an edge of the best face's support points on the hull (two distinct)
            i0 = F[best, e]
            i1 = F[best, (e + 1) % 3]
            px, py, pz = P[i0, 0], P[i0, 1], P[i0, 2]
            bx, by, bz = P[i1, 0] - px, P[i1, 1] - py, P[i1, 2] - pz
            lb = 0.5 * math.sqrt(bx * bx + by * by + bz * bz)
            if not lb > 1e-7 * scale:
                continue
            bx, by, bz = 0.5 * bx / lb, 0.5 * by / lb, 0.5 * bz / lb
        nx, ny, nz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
        sn = math.sqrt(nx * nx + ny * ny + nz * nz)
        if not sn > 1e-6:
            continue
        nx, ny, nz = nx / sn, ny / sn, nz / sn
        c = nx * dx + ny * dy + nz * dz
        if c < 0.0:
            nx, ny, nz, c = -nx, -ny, -nz, -c
        if not c * c > 1.0 - EPA_KINK_NEAR * EPA_KINK_NEAR:
            continue
        # the segments' midpoints: the cylinder's side along n (A's) or -n (B's)
        mcx, mcy, mcz = _side_mid(cs, sa, sb, r_ab, t_ab, nx, ny, nz)
        if ocode == CYLINDER:
            mox, moy, moz = _side_mid(os_, sa, sb, r_ab, t_ab, nx, ny, nz)
        else:
            mox, moy, moz = px + lb * bx, py + lb * by, pz + lb * bz
            if not _hull_edge_on_top(sa, sb, verts, r_ab, t_ab, scale, os_, px, py, pz,
                                     nx, ny, nz):
                return -1
        # A's and B's segments: m + s k, |s| <= l
        if cs == 0:
            max_, may_, maz_, kax, kay, kaz, la_ = mcx, mcy, mcz, ax, ay, az, sa[1][1]
            mbx, mby, mbz, kbx, kby, kbz, lb_ = mox, moy, moz, bx, by, bz, lb
        else:
            max_, may_, maz_, kax, kay, kaz, la_ = mox, moy, moz, bx, by, bz, lb
            mbx, mby, mbz, kbx, kby, kbz, lb_ = mcx, mcy, mcz, ax, ay, az, sb[1][1]
        ox, oy, oz = max_ - mbx, may_ - mby, maz_ - mbz
        h = nx * ox + ny * oy + nz * oz
        # s ka - t kb = h n - (ma - mb) =: g, solved on ka and kb
        gx, gy, gz = h * nx - ox, h * ny - oy, h * nz - oz
        ga = gx * kax + gy * kay + gz * kaz
        gb = gx * kbx + gy * kby + gz * kbz
        cab = kax * kbx + kay * kby + kaz * kbz
        den = 1.0 - cab * cab                     # sn * sn, the sine squared
        s_ = (ga - cab * gb) / den
        t_ = (cab * ga - gb) / den
        rin = sn * min(la_ - abs(s_), lb_ - abs(t_))
        if not (h > 0.0 and rin >= 1e-7 * scale):
            return -1
        _store_min(fs, nx, ny, nz, h * nx, h * ny, h * nz, max_ + s_ * kax,
                   may_ + s_ * kay, maz_ + s_ * kaz, mbx + t_ * kbx, mby + t_ * kby,
                   mbz + t_ * kbz)
        fs[_T3 + 3, 0] = _face_basin(rin, h)
        return 1
    return 0


@njit_inline
def _cylinders_crossing(sa, sb, r_ab, t_ab, scale, fs):
    """_crossing_test for two cylinders, whatever EPA's best face: whether the
    parallelogram face their sides make normal to both axes (cylcyl.sides_crossing)
    holds a minimum of h, stored as _crossing_test stores it (ws t3 rows 15-18, the cap
    in row 3).  (cylcyl.cylinders_depth has certified the pairs where a witness's ball
    reaches h before GJK; here the others, whose balls a cap cuts short.)

    Why at once: it is the only crossing face two cylinders' difference has, so its
    normal n (normal to both axes) needs no search: along +-n both supports are side
    segments and h(+-n) = r_a + r_b -+ n . t (t: B's centre in A's frame), so the
    lower of the two is the one with n . t >= 0, and the foot of the origin on either
    face lies at the same segment parameters (the difference of the two faces is a
    shift along n): where it falls outside the lower face, it falls outside the
    other as well.  So one test, with no support, decides it before EPA's normal
    comes near n: EPA holds the minimum from its first step, and its per-step test
    (_crossing_test, a call that mostly finds d near no crossing) does not run for this
    pair.  Axes parallel within 1e-6: no face."""
    nx, ny, h, s, u, sn = sides_crossing(sa, sb, r_ab, t_ab)
    if not sn > 0.0:
        return False
    ra, la, rb, lb = sa[1][0], sa[1][1], sb[1][0], sb[1][1]
    bx, by, bz = r_ab[0, 2], r_ab[1, 2], r_ab[2, 2]
    rin = sn * min(la - abs(s), lb - abs(u))
    if not (h > 0.0 and rin >= 1e-7 * scale):
        return False
    _store_min(fs, nx, ny, 0.0, h * nx, h * ny, 0.0, ra * nx, ra * ny, s,
               t_ab[0] - rb * nx + u * bx, t_ab[1] - rb * ny + u * by, t_ab[2] + u * bz)
    fs[_T3 + 3, 0] = _face_basin(rin, h)
    return True


@njit_inline
def _side_mid(side, sa, sb, r_ab, t_ab, nx, ny, nz):
    """The midpoint (A's frame) of the side segment of the cylinder on ``side`` that is
    its support along n (A's; -n for B's), n normal to its axis."""
    prm = sa[1] if side == 0 else sb[1]
    if side == 0:
        ux, uy = nx, ny
    else:
        ux = -(r_ab[0, 0] * nx + r_ab[1, 0] * ny + r_ab[2, 0] * nz)
        uy = -(r_ab[0, 1] * nx + r_ab[1, 1] * ny + r_ab[2, 1] * nz)
    q = prm[0] / math.sqrt(ux * ux + uy * uy)
    ux, uy = q * ux, q * uy
    if side == 0:
        return ux, uy, 0.0
    return (r_ab[0, 0] * ux + r_ab[0, 1] * uy + t_ab[0],
            r_ab[1, 0] * ux + r_ab[1, 1] * uy + t_ab[1],
            r_ab[2, 0] * ux + r_ab[2, 1] * uy + t_ab[2])


@njit_inline
def _hull_edge_on_top(sa, sb, verts, r_ab, t_ab, scale, side, px, py, pz, nx, ny, nz):
    """Whether no vertex of the hull on ``side`` lies above its point p (A's frame)
    along its outward direction for n (n on A, -n on B), 1e-12 * scale allowed: a
    pass over its vertices."""
    v0 = sa[2] if side == 0 else sb[2]
    vn = sa[3] if side == 0 else sb[3]
    pts = verts[v0:v0 + vn]
    hx, hy, hz = _hull_dir(side, r_ab, nx, ny, nz)
    qx, qy, qz = _in_side_frame(side, r_ab, t_ab, px, py, pz)
    return _none_above(pts, hx, hy, hz, hx * qx + hy * qy + hz * qz + 1e-12 * scale)


@njit_inline
def _none_above(pts, hx, hy, hz, top):
    """Whether no point of pts (n, 3) lies above the height ``top`` along (hx, hy,
    hz): one pass."""
    for q in range(pts.shape[0]):
        if hx * pts[q, 0] + hy * pts[q, 1] + hz * pts[q, 2] > top:
            return False
    return True


@njit_inline
def _in_side_frame(side, r_ab, t_ab, x, y, z):
    """A point of A's frame in the frame of the shape on ``side``."""
    if side == 0:
        return x, y, z
    ox, oy, oz = x - t_ab[0], y - t_ab[1], z - t_ab[2]
    return (r_ab[0, 0] * ox + r_ab[1, 0] * oy + r_ab[2, 0] * oz,
            r_ab[0, 1] * ox + r_ab[1, 1] * oy + r_ab[2, 1] * oz,
            r_ab[0, 2] * ox + r_ab[1, 2] * oy + r_ab[2, 2] * oz)


@njit_inline
def _core_depth(side, sa, sb, r_ab, t_ab, x, y, z):
    """The signed depth of the point x (A's frame) in the core of the shape on ``side``
    when that core is a cylinder or a box: _core_inradius inside, minus the distance
    to the core outside (analytic's point-against-core distances, negated); -inf for
    every other shape."""
    code = sa[0] if side == 0 else sb[0]
    prm = sa[1] if side == 0 else sb[1]
    if code != CYLINDER and code != BOX:
        return -np.inf
    px, py, pz = _in_side_frame(side, r_ab, t_ab, x, y, z)
    if code == CYLINDER:
        return -_point_cylinder(prm[0], prm[1], px, py, pz)[0]
    return -_point_box(prm[0], prm[1], prm[2], px, py, pz)[0]


@njit_inline
def _core_inradius(side, sa, sb, r_ab, t_ab, x, y, z):
    """The radius of a ball about the point x (A's frame) inside the core of the shape
    on ``side``: a cylinder's (its radius less x's distance from the axis, or its
    half-height less |x_z|, the smaller) or a box's (the least gap to its faces); -inf
    where x lies outside that core and for every other shape (a sphere's or a
    capsule's core, a point or a segment, holds no ball; an ellipsoid's core has no
    closed form for it, and a hull's would need its face planes)."""
    r = _core_depth(side, sa, sb, r_ab, t_ab, x, y, z)
    return r if r >= 0.0 else -np.inf


@njit_inline
def _rolling_ball(side, sa, sb, r_ab, x, y, z, nx, ny, nz):
    """The largest ball inside an ellipsoid's core that touches the core at its point
    x (A's frame), where the core's outward normal is the unit n (A's frame): (centre,
    radius) in A's frame; the point x itself with radius 0 for every other shape.

    Why it holds: with semi-axes a_i (c the least) the ellipsoid's point p has the
    outward normal along g = (p_i / a_i^2), and the points q = p - t g, 0 <= t < c^2,
    have p as their nearest point on the surface: the nearest point of an inner q is
    the one root t in (-inf, c^2) of sum (a_i q_i / (a_i^2 - t))^2 = 1 (the sum rises
    with t there), and t is that root.  So the ball about q of radius t |g| touches at
    p and lies inside; as t -> c^2 the radius tends to c^2 |g| = c^2 / |D m| (m the
    unit normal, D = diag(a_i): p = D^2 m / |D m|).  That is c at the ends of the
    shortest axis and c^2 / a, the radius that rolls freely anywhere (shapes.py,
    P_ROLL), at the ends of the longest.  The core is the ellipsoid's inner parallel
    body at P_ROLL (geometry.py), which holds that ball less P_ROLL about the same
    centre, touching the core at x = p - P_ROLL m."""
    code = sa[0] if side == 0 else sb[0]
    if code != ELLIPSOID:
        return x, y, z, 0.0
    prm = sa[1] if side == 0 else sb[1]
    a, b, c = prm[0], prm[1], prm[2]
    # the normal in the ellipsoid's frame (A's own, or rotated by r_ab^T for B)
    mx, my, mz = nx, ny, nz
    if side == 1:
        mx = r_ab[0, 0] * nx + r_ab[1, 0] * ny + r_ab[2, 0] * nz
        my = r_ab[0, 1] * nx + r_ab[1, 1] * ny + r_ab[2, 1] * nz
        mz = r_ab[0, 2] * nx + r_ab[1, 2] * ny + r_ab[2, 2] * nz
    cmin = min(a, min(b, c))
    rho = (1.0 - 1e-12) * cmin * cmin / math.sqrt(
        a * a * mx * mx + b * b * my * my + c * c * mz * mz) - prm[P_ROLL]
    if not rho > 0.0:
        return x, y, z, 0.0
    return x - rho * nx, y - rho * ny, z - rho * nz, rho


@njit_kernel
def _ball_certified(sa, sb, r_ab, t_ab, hmin, nx, ny, nz, ax, ay, az, bx, by, bz):
    """Whether a direction n with h(n) = hmin + tol and witnesses a (on A's core) and b
    (on B's) gives the depth, within tol, with no test of EPA's polytope: true when a
    ball about b inside A's core, or about a inside B's core (_core_inradius), has a
    radius of at least hmin, or when an ellipsoid's ball does as much (below).

    Why it holds: if the ball of radius rho about a point b of B lies in A, then A - B
    holds the ball of radius rho about the origin (that ball minus b), so h(u) >= rho
    along every unit u: the depth, min_u h(u), is at least rho, and at most h(n).  So
    no test of the polytope is needed, nor that n is a local minimum, whatever creases
    and faces the shapes have nearby.  (On the cores, as EPA runs: a core's point b,
    and the ball inside the other core.)  It applies where the depth is small beside
    the containing shape's size (a ball of radius h(n) must fit): of the deep pairs of
    bench.common.pair_cases (depth > 1e-3 * scale, up to ~0.6 * scale; pure-Python
    count, 400 cases, seed 5) it takes 81 of 190 cylinder-cylinder pairs and 27 of 193
    cylinder-convex ones (the face and crossing tests' minima and the crease search's).
    The crease search is not taken sooner for it (from a gain of 1e-2 * scale): that
    costs steps where only certified minima are kept, and is wrong where the basin test
    keeps the others (regression scene
    mkc_early_crease_search_wrong_basin_ellipsoid_cylinder).

    An ellipsoid's core holds no ball about a point with a closed form, but it holds
    the largest ball touching it at its witness (_rolling_ball): A' - B' lies in A - B
    for any parts A' of A and B' of B, so with A' and B' each that ball or the witness
    point (radius 0), the depth is at least rho_a + rho_b - |q_a - q_b|, and against
    a box's or a cylinder's whole core (a ball about q of radius rho against it: the
    core grown by rho, which holds the ball of radius rho + _core_depth(q) about q) at
    least rho + _core_depth(q).  At the minimum (w = h n) the first is h wherever the
    balls' radii add up to h.  On the deep pairs of bench.common's cases (2,000 per
    row, at the reported minima) the ellipsoid's ball certifies 590
    of 961 ellipsoid-box pairs where the ball of radius P_ROLL alone (the core's
    point) does 502, 708 of 992 ellipsoid-cylinder (598), 847 of 988
    ellipsoid-ellipsoid."""
    sa, sb, r_ab, t_ab = borrow_pose(sa, sb, r_ab, t_ab)
    if _core_inradius(0, sa, sb, r_ab, t_ab, bx, by, bz) >= hmin:
        return True
    if _core_inradius(1, sa, sb, r_ab, t_ab, ax, ay, az) >= hmin:
        return True
    if sa[0] != ELLIPSOID and sb[0] != ELLIPSOID:
        return False
    qax, qay, qaz, rha = _rolling_ball(0, sa, sb, r_ab, ax, ay, az, nx, ny, nz)
    qbx, qby, qbz, rhb = _rolling_ball(1, sa, sb, r_ab, bx, by, bz, -nx, -ny, -nz)
    ex, ey, ez = qax - qbx, qay - qby, qaz - qbz
    if rha + rhb - math.sqrt(ex * ex + ey * ey + ez * ez) >= hmin:
        return True
    if sa[0] == ELLIPSOID and rha + _core_depth(1, sa, sb, r_ab, t_ab, qax, qay, qaz) >= hmin:
        return True
    return (sb[0] == ELLIPSOID
            and rhb + _core_depth(0, sa, sb, r_ab, t_ab, qbx, qby, qbz) >= hmin)


@njit_inline
def _pending_bound(sa, sb, r_ab, t_ab, fs, tol):
    """The bound EPA holds a minimum a polish stored (ws t3 rows 15-18: n, w, a, b) to:
    h(n) - tol, which no face of its polytope outside the basin cap may undercut
    (_polish_is_global), or -inf when _ball_certified proves it the depth."""
    n, w, a, b = fs[_T3 + 15], fs[_T3 + 16], fs[_T3 + 17], fs[_T3 + 18]
    hmin = _dot(n, w) - tol
    if _ball_certified(sa, sb, r_ab, t_ab, hmin, n[0], n[1], n[2], a[0], a[1], a[2], b[0],
                       b[1], b[2]):
        return -np.inf
    return hmin


@njit_inline
def _face_polish(sa, sb, verts, r_ab, t_ab, scale, ws, dx, dy, dz):
    """Whether the minimum of h = h_{A-B} is exactly at the normal of a box's face or a
    cylinder's cap near the unit direction d (EPA's best face normal, within
    EPA_KINK_NEAR rad of it), for a _face_pair (GJK) or an _epa_face_pair (EPA).

    Why: the deepest direction of an ellipsoid against a box lies on a face normal of
    the box in about half of the deep random pairs (measured: 511 of 960), and on a
    cylinder's axis in some (51 of 400 deep ellipsoid-cylinder pairs).  There h has a
    point kink (the box's support is a whole face, a cylinder's the whole cap) and A - B
    a flat face, but the other shape's curvature leaves EPA's vertices near that face
    slightly off it, and EPA takes ~11 steps to close its bounds.  The test needs one
    support point: at the face normal f, h rises to first order in every direction iff
    the other shape's support point projects into the face (for a tangent t, the face
    adds max over the face of t . x, the other shape's point subtracts t . p): inside
    the face's rectangle, or the cap's disc, by 1e-7 * scale.  Then f is a local minimum
    and the support point with its projection onto the face are the witnesses.  The
    argument uses one point of the other shape, not its smoothness, so it holds
    against any shape (the other shape's support being a whole segment or face, the
    point found is one of it: then h rises faster still).

    Results as _newton_min_support's (ws t3 rows 15-18: direction, difference point,
    witnesses on A and B); returns 1 (the support evaluated) when f is a minimum, -1
    when the point projects outside the face, 0 when d is near no face normal.  In GJK
    on cores apart (h < 0 at f) the local minimum is the global one (h is convex
    there).  EPA then applies _polish_is_global with the plane test under the cap
    the test proves (ws t3 row 3, _face_basin).  Another local minimum may lie close
    by, so no fixed cap is safe: at 0.5 rad, 1 of 100,000 random ellipsoid-cylinder
    pairs keeps a minimum on a cylinder's axis 0.31 rad from a deeper one, 9e-4 * scale
    below it (regression scene mkc_face_polish_wrong_basin_ellipsoid_cylinder).
    A convex hull's faces: _hull_face_test.

    Inlined: only the test whether d is near a face normal, which fails at most of
    the EPA steps it runs at; the face test itself is a call (_face_test)."""
    for side in range(2):
        code = sa[0] if side == 0 else sb[0]
        if code != BOX and code != CYLINDER:
            continue
        # the face's outward normal is d on A, -d on B
        sg = 1.0 if side == 0 else -1.0
        cbest = 0.0
        k = np.int64(0)       # typed int64 at once (jit.py, "Literal")
        for axis in range(0 if code == BOX else 2, 3):
            kx, ky, kz = _axis_of(side, axis, r_ab)
            c = sg * (kx * dx + ky * dy + kz * dz)
            if abs(c) > abs(cbest):
                cbest = c
                k = axis
        if not cbest * cbest > 1.0 - EPA_KINK_NEAR * EPA_KINK_NEAR:
            continue
        return _face_test(sa, sb, verts, r_ab, t_ab, scale, ws, side, k,
                          sg * (1.0 if cbest > 0.0 else -1.0))
    return 0


@njit_kernel
def _face_test(sa, sb, verts, r_ab, t_ab, scale, ws, side, k, s):
    """_face_polish's test at the face normal s * axis k of the box or cylinder on
    ``side`` (s = +-1): 1 if it is a minimum (results in ws t3 rows 15-18, the cap it
    proves in row 3: _face_basin), else -1."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    fs = ws[0]
    code = sa[0] if side == 0 else sb[0]
    kx, ky, kz = _axis_of(side, k, r_ab)
    nx, ny, nz = s * kx, s * ky, s * kz
    h, qx, qy, qz, pax, pay, paz, pbx, pby, pbz = _face_point(
        sa, sb, verts, r_ab, t_ab, side, nx, ny, nz)
    prm = sa[1] if side == 0 else sb[1]
    # the radius of the largest disc about q's foot inside the face
    if code == BOX:
        rin = face_room(prm, k, qx, qy, qz)
    else:
        rin = prm[0] - math.sqrt(qx * qx + qy * qy)
    if not rin >= 1e-7 * scale:
        return -1
    _face_minimum(fs, side, nx, ny, nz, h, pax, pay, paz, pbx, pby, pbz)
    fs[_T3 + 3, 0] = _face_basin(rin, h)
    return 1


@njit_inline
def _face_basin(rin, h):
    """The cap around a face's normal n (rad) in which no direction is deeper than n,
    for a minimum of the face test with h = h(n) > 0 and a disc of radius rin about
    the other shape's point's foot inside the face.

    Why it holds: with F the face and p the other shape's support point (B's; for a
    face of B, A's, with the signs turned), h_{A-B}(u) >= h_F(u) - p . u for every u,
    since F lies in A and p in B.  F - p is a flat piece of the plane at height h
    along n holding the disc of radius rin about the point h n, so h_{A-B}(u) >=
    h cos t + rin sin t for u at angle t from n, which is >= h while tan(t / 2) <=
    rin / h.  It holds for any other shape (no smoothness used); EPA takes it as the
    cap of _polish_is_global's plane test (capped at EPA_FACE_CAP_MAX, inside the pi /
    2 that test needs).  0 when h <= 0 (GJK on cores apart needs no cap).  Against a
    single point the bound is exact along the tilt toward the face's nearest side, so
    the cap is the whole basin there (tests/test_gjk_epa.py checks both).

    The same holds on a convex hull's face (rin: the foot's least distance to the
    triangle's edges); EPA does not test hull faces with it, as the test costs more
    time than it saves (module docstring, phase 1)."""
    if not h > 0.0:
        return 0.0
    return min(2.0 * math.atan(rin / h), EPA_FACE_CAP_MAX)


@njit_kernel
def _hull_face_test(sa, sb, verts, r_ab, t_ab, scale, ws, side, i, j, m, hx, hy,
                    hz):
    """_face_polish on a convex hull (the shape on ``side``; (hx, hy, hz) GJK's
    direction in the hull's frame, i, j, m the three highest vertices along it):
    whether the minimum of h is exactly at the normal of the face through i, j, m.
    That plane is a face of the hull if no vertex lies above it, and is tested if its
    normal lies within EPA_KINK_NEAR rad of the direction (else 0).  One support along
    that normal; the other shape's point must project into the triangle i, j, m,
    1e-7 * scale inside each edge (a face with more than three vertices, a quad of a
    box-like mesh, is tested on that triangle only: a point that projects elsewhere in
    the face fails the test, and GJK goes on).  Returns and results as
    _face_polish's."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    fs = ws[0]
    v0 = sa[2] if side == 0 else sb[2]
    vn = sa[3] if side == 0 else sb[3]
    pts = verts[v0:v0 + vn]
    ax, ay, az = pts[j, 0] - pts[i, 0], pts[j, 1] - pts[i, 1], pts[j, 2] - pts[i, 2]
    bx, by, bz = pts[m, 0] - pts[i, 0], pts[m, 1] - pts[i, 1], pts[m, 2] - pts[i, 2]
    nx, ny, nz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not nn > 0.0:
        return 0
    nx, ny, nz = nx / nn, ny / nn, nz / nn
    c = nx * hx + ny * hy + nz * hz
    if c < 0.0:
        # orient the normal outward (along d), the triangle counterclockwise about it
        nx, ny, nz, c = -nx, -ny, -nz, -c
        j, m = m, j
    if not c * c > 1.0 - EPA_KINK_NEAR * EPA_KINK_NEAR:
        return 0
    if not _none_above(pts, nx, ny, nz,
                       nx * pts[i, 0] + ny * pts[i, 1] + nz * pts[i, 2] + 1e-12 * scale):
        return 0
    # the face's outward normal is its normal in A's frame on A, minus it on B
    if side == 0:
        ux, uy, uz = nx, ny, nz
    else:
        ux = -(r_ab[0, 0] * nx + r_ab[0, 1] * ny + r_ab[0, 2] * nz)
        uy = -(r_ab[1, 0] * nx + r_ab[1, 1] * ny + r_ab[1, 2] * nz)
        uz = -(r_ab[2, 0] * nx + r_ab[2, 1] * ny + r_ab[2, 2] * nz)
    h, qx, qy, qz, pax, pay, paz, pbx, pby, pbz = _face_point(
        sa, sb, verts, r_ab, t_ab, side, ux, uy, uz)
    eps = 1e-7 * scale
    for e in range(3):
        a_ = i if e == 0 else (j if e == 1 else m)
        b_ = j if e == 0 else (m if e == 1 else i)
        ex, ey, ez = pts[b_, 0] - pts[a_, 0], pts[b_, 1] - pts[a_, 1], pts[b_, 2] - pts[a_, 2]
        rx, ry, rz = qx - pts[a_, 0], qy - pts[a_, 1], qz - pts[a_, 2]
        sd = (nx * (ey * rz - ez * ry) + ny * (ez * rx - ex * rz)
              + nz * (ex * ry - ey * rx))
        if not sd >= eps * math.sqrt(ex * ex + ey * ey + ez * ez):
            return -1
    _face_minimum(fs, side, ux, uy, uz, h, pax, pay, paz, pbx, pby, pbz)
    return 1


@njit_inline
def _take_polished(fs, d, w, wa, wb):
    """Copy the polished minimum (ws t3 rows 15-18: direction, difference point,
    support points of A and B) into EPA's d, w, wa, wb."""
    for c in range(3):
        d[c] = fs[_T3 + 15, c]
        w[c] = fs[_T3 + 16, c]
        wa[c] = fs[_T3 + 17, c]
        wb[c] = fs[_T3 + 18, c]


@njit_inline
def _smooth_pair(ca, cb):
    """Whether GJK and EPA should try _newton_min_support on this pair of shape codes:
    one is an ellipsoid (its core makes h smooth and curved around whole regions of
    directions) and neither is a box or a convex hull (their flat faces put the minimum
    on a kink of h, where the fit fails after spending supports: it costs 4-7% of the
    time on ellipsoid-box and -convex pairs and gains nothing).  On pairs without an
    ellipsoid, e.g. two cylinders, the fit finds kinks on every pair tried, with
    one exception EPA makes: two cylinders where its best face's normal is near
    neither side's crease (_kink_side -1).  There h is smooth but at the caps'
    normals, and the deepest direction is mostly a rim against a rim, which EPA takes
    longest to close on and Newton's method shortens (EPA_POLISH_CAP's basin test then
    as for an ellipsoid against a cylinder, the vertex test of _polish_is_global); the
    depths it gives stay within EPA_REL_TOL * scale of EPA's face bound.  Against a
    capsule it saves no steps."""
    if ca != ELLIPSOID and cb != ELLIPSOID:
        return False
    return ca != BOX and ca != CONVEX and cb != BOX and cb != CONVEX


@njit_inline
def _polish_cap(kc, capsule, box):
    """The basin cap of _polish_is_global (rad) for a minimum found by _kink_polish on
    the crease kc (_kink_side) or, kc < 0, by Newton's method, of a pair with a capsule
    or a box (whose creases are the searched ones)."""
    if kc >= 0 and capsule:
        return EPA_KINK_CAP_CAPSULE
    if kc >= 0 and box:
        return EPA_KINK_CAP_BOX
    return EPA_POLISH_CAP


@njit_inline
def _ellipsoid_box(ca, cb):
    """An ellipsoid and a box, in either order: GJK and EPA try Newton's method on
    their cores in a vertex's region of the box only (_kink_side finds the edges'
    creases and the face normals, where two of them cross).  EPA keeps the minimum
    under the plane test in the cap that no crease of the box crosses (_vertex_cap),
    or, nearer a crease than EPA_VERTEX_CAP_MIN, if a ball proves it.  With the cap
    short of the edges, that basin test is a single one: it need not rule out the
    nearby edges' creases."""
    return (ca == ELLIPSOID and cb == BOX) or (ca == BOX and cb == ELLIPSOID)


@njit_inline
def _gjk_newton_pair(ca, cb):
    """Whether GJK on cores apart tries Newton's method where h is smooth (away from
    the creases _kink_side finds): the pairs EPA polishes so (_smooth_pair), an
    ellipsoid with a box (_ellipsoid_box), and an ellipsoid with a convex hull
    (_hull_side: its features first, _gjk_smooth_polish)."""
    return _smooth_pair(ca, cb) or _ellipsoid_box(ca, cb) or _hull_side(ca, cb) >= 0


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


@njit_inline
def _edge_of(F, g, a, b):
    """Index e of the edge {a, b} of face g (either direction), or -1."""
    for e in range(3):
        p, q = F[g, e], F[g, (e + 1) % 3]
        if (p == a and q == b) or (p == b and q == a):
            return e
    return -1


@njit_inline
def _vertex_cap(sa, sb, r_ab, n):
    """The basin cap (rad) of _polish_is_global's plane test for a minimum n that
    Newton's method found between an ellipsoid and a box in a vertex's region: n's
    angle to the nearest of the box's three creases (the great circles normal to its
    axes), at most EPA_POLISH_CAP; 0 when that is below EPA_VERTEX_CAP_MIN.

    Why: inside that cap the box's support is one vertex, so h there is a point's
    against the ellipsoid's core, as for a sphere against an ellipsoid (whose minimum
    EPA keeps under the plane test and EPA_POLISH_CAP, _smooth_pair): no crease or
    face normal of the box lies in it, and the plane test proves that no direction
    outside it is deeper.  A cap crossing a crease would need the edges and faces
    there ruled out as well (as _kink_polish does).  Below EPA_VERTEX_CAP_MIN only a
    ball (_ball_certified) keeps the minimum."""
    side = 0 if sa[0] == BOX else 1
    smin = 1.0
    for axis in range(3):
        kx, ky, kz = _axis_of(side, axis, r_ab)
        smin = min(smin, abs(kx * n[0] + ky * n[1] + kz * n[2]))
    cap = min(EPA_POLISH_CAP, math.asin(smin))
    return cap if cap >= EPA_VERTEX_CAP_MIN else 0.0


@njit_kernel
def _trace_polytope(fs, V, F, alive, nv, nf):
    """Record EPA's polytope (vertices V[:nv], the live faces among F[:nf]) in fs's
    trace region (TR_EPA, module docstring)."""
    nlive = 0
    for f in range(nf):
        if alive[f]:
            nlive += 1
    r = trace_open(fs, _FS_ROWS, TR_EPA, nv, nlive)
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


@njit_kernel
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
    cin = ws[0][_T3 + 12]
    for c in range(3):
        cin[c] = 0.0
    for i in range(4):
        for c in range(3):
            V[i, c] = W[i, c]
            VA[i, c] = WA[i, c]
            VB[i, c] = WB[i, c]
            VD[i, c] = 0.0
            cin[c] += 0.25 * W[i, c]
    nv = 4
    nf = 4
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
    d, wa, wb, w = ws[0][_T3 + 8], ws[0][_T3 + 9], ws[0][_T3 + 10], ws[0][_T3 + 11]
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
    ud, uwa = ws[0][_T3 + 13], ws[0][_T3 + 14]
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
    p_fail = -1                         # a face that failed its last test
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
            p_cap = fs[_T3 + 3, 0]
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
                p_cap = fs[_T3 + 3, 0]
                p_h = _pending_bound(sa, sb, r_ab, t_ab, fs, tol)
                p_fail = -1
        if pend:
            p_fail = _polish_is_global(V, F, FN, FD, nf, fs[_T3 + 15], p_h, p_planes,
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
            kc = _kink_side(sa, sb, r_ab, d[0], d[1], d[2], False)
            # an ellipsoid and a box, near none of the box's creases: Newton's method in
            # a vertex's region (_vertex_cap), unless a minimum is pending already
            vtx = eb and kc == -1 and not pend
            if kc >= 0 or ((smooth or two_cyl or vtx) and kc == -1):
                tries -= 1
                polish_at *= 0.01
                if kc >= 0:
                    k_pol = _kink_polish(sa, sb, verts, r_ab, t_ab, scale, ws,
                                         kc // 3, kc % 3)
                else:
                    k_pol = _epa_polish(sa, sb, verts, r_ab, t_ab, scale, ws, best)
                n_pol += abs(k_pol)
                cap = _polish_cap(kc, capsule, box)
                if k_pol > 0 and vtx:
                    cap = _vertex_cap(sa, sb, r_ab, fs[_T3 + 15])
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
                    p_fail = _polish_is_global(V, F, FN, FD, nf, fs[_T3 + 15], p_h,
                                               p_planes, p_cap, -1)
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
        clean = min(m0, min(m1, m2)) >= -1e-9 and max(m0, max(m1, m2)) <= 1.0 + 1e-9
        # far outside the face means a sliver face: the clamped closest point instead
        # (as for a degenerate face)
        on_face = min(m0, min(m1, m2)) > -0.1 and max(m0, max(m1, m2)) < 1.1
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


@njit_kernel
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
    t2 = ws[0][_T3 + 13]
    for c in range(3):
        t2[c] = t_ab[c] + sh * res[1 + c]
    n, it, flag, _ = _gjk(sa, sb, verts, r_ab, t2, scale, ws, math.inf, False, False)
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


@njit_inline
def _core_out(out, res, ra, rb, pa, pb, iters, scale):
    """The result row (_set_out) from a depth of the cores, res = [depth, n (3), pa (3),
    pb (3)] in A's frame (EPA's or boxcyl's): the witnesses moved out by the inflation
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


@njit_kernel
def gjk_epa_ws(sa, sb, verts, r_ab, t_ab, out, ws, cutoff):
    """``gjk_epa`` with caller-provided scratch buffers ``ws`` (make_gjk_workspace()).

    ``cutoff`` (m, >= 0, may be inf): distances up to max(cutoff, the touching band)
    are exact; a pair GJK proves farther apart than that is returned at once as
    ST_SEPARATED with ``distance`` a certified lower bound (> cutoff), the separating
    direction as normal and the current simplex points (moved out by the radii) as
    witness points, which then are not the closest points (a cylinder with a cylinder,
    a capsule, an ellipsoid or a hull: cylcyl's separating planes likewise, before GJK;
    an ellipsoid and a box: boxell's face and edge planes).  A
    pipeline that wants contacts only passes 0 and saves the GJK steps that would
    refine a distance it throws away (as MuJoCo's collision pass, which reports no
    distances, does)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    ws = borrow_gjk_workspace(ws)
    out = borrow(out)
    nrm, pa, pb = ws[0][_T3 + 0], ws[0][_T3 + 1], ws[0][_T3 + 2]
    # a trace region (module docstring, "Trace"): its options, then reset
    trace_on = ws[0].shape[0] >= _FS_ROWS + TR_HEADER_ROWS
    iterate = False
    if trace_on:
        iterate = ws[0][_FS_ROWS + 1, 0] > 0.0
        trace_reset(ws[0], _FS_ROWS)
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
    fan = HE_UNDECIDED
    if not iterate and (sa[0] == CYLINDER or sb[0] == CYLINDER):
        # a cylinder with a cylinder, a capsule, an ellipsoid or a hull (cylcyl), or a
        # box (boxcyl: the exact depth in closed form): cores that overlap get their
        # depth certified (cylcyl: one core's point as deep inside the cylinder as h
        # along the normal there, by a ball); cores that a plane (a cap's, the side's
        # tangent plane, the sides' crossing; for a box, the line of centres or one of
        # boxcyl's candidate directions) proves apart by more than the cutoff and the
        # touching band end with that gap as the distance bound, as GJK would stop
        # there too.  Either without GJK or EPA; else GJK and EPA
        other = sb[0] if sa[0] == CYLINDER else sa[0]
        d = 0.0
        if other == CYLINDER:
            d = cylinders_depth(sa, sb, verts, r_ab, t_ab, scale, res)
        elif other == BOX:
            d = box_cylinder_depth(sa, sb, r_ab, t_ab, scale, fs[_V:_V + _BC_ROWS], res)
        elif other == CAPSULE:
            d = segment_cylinder_depth(sa, sb, r_ab, t_ab, scale, res)
        elif other == ELLIPSOID:
            d = ellipsoid_cylinder_depth(sa, sb, r_ab, t_ab, scale, res)
        elif other == CONVEX:
            if cylinder_hull_pair(sa, sb):
                # the hull's fan stored (hullcyl): as the ellipsoid's below
                fan = cylinder_hull_depth(sa, sb, verts, r_ab, t_ab, scale, False,
                                          ra + rb + band, fs[_V:_V + HE_ROWS],
                                          fv[_FD:_FD + 8], res)
                if fan == HE_EXACT or fan == HE_APART:
                    return _core_out(out, res, ra, rb, pa, pb, np.int64(1), scale)
            if fan == HE_UNDECIDED:
                d = hull_cylinder_depth(sa, sb, verts, r_ab, t_ab, scale, res)
        if d > 0.0 or (d < 0.0 and -d - ra - rb > band):
            return _core_out(out, res, ra, rb, pa, pb, np.int64(1), scale)
    elif not iterate and _ellipsoid_box(sa[0], sb[0]):
        # an ellipsoid and a box (boxell): the core depth at a box face certified by a
        # ball, the cores' exact distance over a face, an edge or a vertex, or a plane
        # proving them farther apart than the cutoff and the touching band
        d, exact = ellipsoid_box_depth(sa, sb, r_ab, t_ab, scale, ra + rb + band, res)
        if exact or (d < 0.0 and -d - ra - rb > band):
            return _core_out(out, res, ra, rb, pa, pb, np.int64(1), scale)
    elif not iterate and ellipsoid_hull_pair(sa, sb):
        # an ellipsoid and a small hull with its normal fan stored (hullell): the exact
        # depth when a cheap test proves the pair overlapping; without that proof, again
        # after GJK once it finds the cores overlapping (below, in place of EPA); or a
        # hull face's plane proving the cores farther apart than the cutoff and the
        # touching band
        fan = ellipsoid_hull_depth(sa, sb, verts, r_ab, t_ab, scale, False, ra + rb + band,
                                   fs[_V:_V + HE_ROWS], fv[_FD:_FD + 8], res)
        if fan == HE_EXACT or fan == HE_APART:
            return _core_out(out, res, ra, rb, pa, pb, np.int64(1), scale)
    # phase 1: cores
    n, it, flag, bound = _gjk(sa, sb, verts, r_ab, t_ab, scale, ws,
                              ra + rb + band,
                              _gjk_newton_pair(sa[0], sb[0])
                              or _has_crease(sa[0]) or _has_crease(sb[0]), trace_on)
    iters = it
    if flag == _GJK_POLISHED:
        # cores apart, closest points from Newton's method: pb - pa == dist * n exactly
        pd, pw = fs[_T3 + 15], fs[_T3 + 16]
        pwa, pwb = fs[_T3 + 17], fs[_T3 + 18]
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
                if off > 0.0 and cx * nrm[0] + cy * nrm[1] + cz * nrm[2] > 0.99:
                    nrm[0], nrm[1], nrm[2] = cx, cy, cz
                    vn = off
        for c in range(3):
            pa[c] += ra * nrm[c]
            pb[c] -= rb * nrm[c]
        st = _set_out(out, vn - ra - rb, nrm[0], nrm[1], nrm[2], pa, pb, iters, scale)
        if flag == _GJK_CAP and st != ST_FAILED:
            # accept the estimate only when the last duality gap was small
            d, wa, wb, w = ws[0][_T3 + 4], ws[0][_T3 + 5], ws[0][_T3 + 6], ws[0][_T3 + 7]
            for c in range(3):
                d[c] = -v[c]
            ax_, ay_, az_, bx_, by_, bz_ = minkowski_core_xyz(
                sa, sb, verts, r_ab, t_ab, d[0], d[1], d[2])
            wa[0], wa[1], wa[2] = ax_, ay_, az_
            wb[0], wb[1], wb[2] = bx_, by_, bz_
            w[0], w[1], w[2] = ax_ - bx_, ay_ - by_, az_ - bz_
            if (vn * vn - _dot(v, w)) / vn > 1e-6 * scale:
                st = ST_FAILED
        if flag == _GJK_STALL:
            st = _caps_fallback(sa, sb, verts, r_ab, t_ab, scale, out, st, ws, True)
        return st
    if fan == HE_UNPROVED:
        # GJK found the cores overlapping: the fan's exact depth in place of EPA
        if sa[0] == CYLINDER or sb[0] == CYLINDER:
            fan = cylinder_hull_depth(sa, sb, verts, r_ab, t_ab, scale, True,
                                      ra + rb + band, fs[_V:_V + HE_ROWS],
                                      fv[_FD:_FD + 8], res)
        else:
            fan = ellipsoid_hull_depth(sa, sb, verts, r_ab, t_ab, scale, True,
                                       ra + rb + band, fs[_V:_V + HE_ROWS],
                                       fv[_FD:_FD + 8], res)
        if fan == HE_EXACT:
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
        st = _caps_fallback(sa, sb, verts, r_ab, t_ab, scale, out, st, ws, False)
    return st


@njit_kernel
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
    pa, pb = ws[0][_T3 + 1], ws[0][_T3 + 2]
    pa[0], pb[0] = meet(ax, bx, -h * nx)
    pa[1], pb[1] = meet(ay, by, -h * ny)
    pa[2], pb[2] = meet(az, bz, -h * nz)
    return _set_out(out, -h, nx, ny, nz, pa, pb, np.int64(iters), scale)
