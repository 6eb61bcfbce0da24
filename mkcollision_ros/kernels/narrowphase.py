"""Narrow-phase dispatcher (one pair) and batch kernel (many pairs, world frame).

``collide_pair`` puts a pair in the canonical order (code_a <= code_b, so a plane is
always B), calls the method's kernel in A's frame, and maps the answer back when it had
to swap: the normal flips, the witness points exchange and return to A's frame.
``collide_batch`` splits the pairs into contiguous blocks, one per thread (jit.n_blocks), and
runs them with ``prange``; each block allocates one set of scratch buffers
(``make_workspace``: poses, a result row, the GJK/EPA buffers) and reuses it pair after
pair, so the per-pair path allocates nothing.  Each pair writes only its own row of
``out`` / ``status`` and no state survives between pairs, so the result does not depend
on the thread count.

Route of one pair in ``collide_world_ws`` (behind collide_batch):
  1. Two bodies without a plane whose bounding spheres (P_RADIUS about the body origins)
     are apart by more than max(cutoff, TOUCH_TOL * scale) end SEPARATED with that gap,
     whatever the method (never with cutoff inf, which the API's collide passes).
  2. Methods auto and analytic: a shape against a half-space, a sphere against a shape
     with a sphere-* closed form, and two capsules are solved in the world frame.
  3. Otherwise B's pose in A's frame (r_ab, t_ab), then the method's kernel; a pair out
     of canonical order goes through collide_pair_ws (_run_ordered on the swapped pair).
  collide_pair / collide_pair_ws skip step 1 and run the closed forms of step 2 in A's
  frame (analytic.collide_analytic).

Pair table, method auto.  Shape codes in canonical order (constants.py): sphere 0,
ellipsoid 1, box 2, capsule 3, cylinder 4, cone 5, convex 6, plane 7.
  CF     a closed form: exact at any distance, no fallback.
  G      gjk_epa.gjk_epa_ws: GJK on the cores (gjk._gjk); EPA on the cores (epa._epa)
         when they overlap; _caps_fallback when GJK stalls or EPA hits its caps (the
         pair's closed form by analytic.collide_analytic, else mpr.mpr_ws).
  G-pre  a pair kernel that gjk_epa_ws runs before GJK.  It returns one outcome code
         (constants.PRE_*): PRE_EXACT, a certified core depth ("depth") or an exact
         distance; PRE_APART, a plane proving the cores farther apart than
         max(cutoff, touching band), that gap a certified lower bound ("apart");
         PRE_UNDECIDED (and the fan kernels' PRE_UNPROVED) continues with G.
  A margin grows the core (kernels/geometry.py) and changes no route but
  sphere-ellipsoid's here (and the ellipsoid methods', below).

  pair                 first answer (kernels/pairs/ for a G-pre kernel or closed form)
                       covers; then
  sphere-sphere        sphere_shape.sphere_world                   CF
  sphere-ellipsoid     sphere_shape.sphere_world                   CF if the ellipsoid has
                                                                   no margin; with one, G
  sphere-box           sphere_shape.sphere_world                   CF
  sphere-capsule       sphere_shape.sphere_world                   CF
  sphere-cylinder      sphere_shape.sphere_world                   CF
  sphere-cone          sphere_shape.sphere_world                   CF
  sphere-convex        G                                           -
  sphere-plane         _half_space_world                           CF
  ellipsoid-ellipsoid  G                                           -
  ellipsoid-box        G-pre ellipsoid_box.collide_ellipsoid_box   depth at a face, the
                                                                   exact distance over a
                                                                   face, edge or vertex,
                                                                   or apart; then G
  ellipsoid-capsule    G                                           -
  ellipsoid-cylinder   G-pre ellipsoid_cylinder.                   depth or apart; then G
                         collide_ellipsoid_cylinder
  ellipsoid-cone       G                                           -
  ellipsoid-convex     G-pre ellipsoid_convex.                     a hull with its fan
                         collide_ellipsoid_convex                  stored: PRE_EXACT,
                                                                   PRE_APART; PRE_UNPROVED:
                                                                   G, and once GJK finds
                                                                   the cores overlapping,
                                                                   this kernel again in
                                                                   place of EPA; no fan or
                                                                   PRE_UNDECIDED: G
  ellipsoid-plane      _half_space_world                           CF
  box-box              _box_box: box_box.collide_box_box           cores overlapping: exact
                                                                   depth; apart by more
                                                                   than max(cutoff,
                                                                   touching band): SAT's
                                                                   lower bound; else G
  box-capsule          analytic.closed_form_ordered                CF (box_capsule.
                                                                   collide_box_capsule; out
                                                                   of order:
                                                                   collide_analytic)
  box-cylinder         G-pre box_cylinder.collide_box_cylinder     depth or apart; then G
  box-cone             G                                           -
  box-convex           G                                           -
  box-plane            _half_space_world                           CF
  capsule-capsule      capsule_capsule.capsule_capsule_world       CF
  capsule-cylinder     G-pre capsule_cylinder.                     depth or apart; then G
                         collide_capsule_cylinder
  capsule-cone         G                                           -
  capsule-convex       G                                           -
  capsule-plane        _half_space_world                           CF
  cylinder-cylinder    G-pre cylinder_cylinder.                    depth or apart; then G
                         collide_cylinder_cylinder
  cylinder-cone        G                                           -
  cylinder-convex      G-pre cylinder_convex.                      as ellipsoid-convex, but
                         collide_cylinder_convex                   no fan or PRE_UNDECIDED:
                                                                   G-pre cylinder_convex.
                                                                   collide_cylinder_convex_
                                                                   ball (depth or apart),
                                                                   then G
  cylinder-plane       _half_space_world                           CF
  cone-cone            G                                           -
  cone-convex          G                                           -
  cone-plane           _half_space_world                           CF
  convex-convex        G                                           -
  convex-plane         _half_space_world                           CF
  plane-plane          none                                        ST_NOT_RUN (every method)
A traced GJK/EPA workspace with its iterate option set skips the G-pre kernels
(gjk_epa.py, "Trace").  The row's method code is M_ANALYTIC for a closed form (SAT's
included), M_GJK_EPA for G and its G-pre kernels, the requested code after step 1.

Inside G, by pair (the predicates in polish_pairs.py): GJK on cores apart tries
_face_polish (_face_pair; polish_faces.py), _kink_polish near a crease (_has_crease;
polish_crease.py), Newton's method (_gjk_smooth_polish: _hull_polish first for
_hull_side; polish_newton.py) for _gjk_newton_pair; EPA tries _cylinders_crossing (two
cylinders), _face_polish (_epa_face_pair), _crossing_test (_crossing_pair), _kink_polish
(_searched_crease) and _epa_polish (_smooth_pair, two cylinders, _ellipsoid_box), each
minimum kept under certificates._polish_is_global; gjk._witness_by_gjk where EPA's
witness points leave its face.  A flat core difference through the origin
(_grow_to_tetra) has core depth 0.  ST_FAILED: GJK's or EPA's cap hit with a wide gap
(for EPA, when its lower bound does not prove the contact and _caps_fallback's MPR finds
none), or a non-finite result.

Other methods (step 1 runs first for each):
  M_GJK_EPA            G on every pair without a plane, G-pre kernels included (no closed
                       form, no SAT first); a plane: ST_NOT_RUN
  M_MPR                mpr.mpr_ws on every pair without a plane; a SEPARATED answer inside
                       the touching band is settled by G (the touching rule; the row keeps
                       M_MPR); a plane: ST_NOT_RUN
  M_ANALYTIC           the CF rows above with the same functions (sphere-ellipsoid only
                       without margin); every other pair, box-box included, ST_NOT_RUN
  M_ELLIPSOID_EXACT    two spheres or ellipsoids, neither with a margin: the status of
                       ellipsoid.ellipsoid_exact, distance, normal and witness points from
                       G (metres); every other pair ST_NOT_RUN
  M_ELLIPSOID_SAMPLED  likewise with ellipsoid.ellipsoid_sampled at
                       ELLIPSOID_SAMPLED_SUBDIV subdivisions
Unknown codes give ST_NOT_RUN.  A row that did not run holds zeros, the normal +z and
the requested method code.
"""
import math

import numpy as np

from .analytic import closed_form_ordered, collide_analytic
from .constants import (BOX, CAPSULE, M_ANALYTIC, M_AUTO, M_ELLIPSOID_EXACT,
                        M_ELLIPSOID_SAMPLED, M_GJK_EPA, M_MPR, NP_CHUNK, OUT_DIST, OUT_ITERS,
                        OUT_METHOD, OUT_NORMAL, OUT_PA, OUT_PB, OUT_SIZE, P_MARGIN, P_RADIUS,
                        PLANE, SPHERE, ST_NOT_RUN, ST_SEPARATED, TOUCH_TOL)
from .ellipsoid import ellipsoid_exact, ellipsoid_sampled
from .geometry import (borrow_args, quat_entries, quat_rotate_xyz, quat_to_matrix_into,
                       shape_scale, support_full_xyz)
from .gjk_epa import gjk_epa_ws
from .gjk_epa_workspace import borrow_gjk_workspace, make_gjk_workspace
from .jit import borrow, keep_alive, n_blocks, njit_inline, njit_kernel, njit_parallel, njit_separate, prange
from .mpr import MPR_WS_ROWS, mpr_ws
from .pairs.box_box import collide_box_box
from .pairs.capsule_capsule import capsule_capsule_world
from .pairs.core_distance import classify
from .pairs.sphere_shape import has_point_form, sphere_world

# subdivision level passed to ellipsoid_sampled by the dispatcher
ELLIPSOID_SAMPLED_SUBDIV = 3

# Scratch buffers ``ws`` of one chunk of pairs, a plain tuple (m, rows, gjk) of few
# arrays (numba reference-counts each array passed to a function): m float64
# (_POSE_ROWS + MPR_WS_ROWS, 3) = world rotations ra (rows 0-2), rb (3-5), the relative
# pose r_ab (6-8) / t_ab (9), the swapped pose r_ba (10-12) / t_ba (13), then mpr_ws's
# scratch; rows float64 (2, OUT_SIZE) = result rows row and tmp; gjk =
# gjk_epa_workspace.make_gjk_workspace().
_POSE_ROWS = 14


@njit_kernel
def make_workspace():
    """Fresh scratch buffers for ``collide_pair_ws`` / ``collide_world_ws``."""
    return (np.empty((_POSE_ROWS + MPR_WS_ROWS, 3)), np.empty((2, OUT_SIZE)),
            make_gjk_workspace())


@njit_inline
def _borrow_ws(ws):
    """The workspace as owner-less views (geometry.borrow_args says why)."""
    return borrow(ws[0]), borrow(ws[1]), borrow_gjk_workspace(ws[2])


@njit_kernel
def _has_closed_form(code_a, code_b, prm_b):
    """True when analytic.closed_form_ordered handles the ordered pair (code_a <=
    code_b): a half-space B with any other shape, sphere with sphere, box, capsule,
    cylinder, cone or an ellipsoid without margin, capsule with capsule, box with
    capsule."""
    if code_b == PLANE:
        return code_a != PLANE
    if code_a == SPHERE:
        return code_b == SPHERE or has_point_form(code_b, prm_b)
    return code_b == CAPSULE and (code_a == CAPSULE or code_a == BOX)


@njit_kernel
def _blank(out, method):
    for c in range(OUT_SIZE):
        out[c] = 0.0
    out[OUT_NORMAL + 2] = 1.0
    out[OUT_METHOD] = method


@njit_inline
def _box_box(sa, sb, verts, r_ab, t_ab, out, ws, cutoff):
    """Two boxes, method auto: overlapping cores get SAT's exact depth; cores that an
    axis separates by more than the cutoff (and the touching band) keep SAT's lower
    bound, as GJK would stop there too (gjk_epa.gjk_epa_ws); the rest get GJK's exact
    distance."""
    st = collide_box_box(sa, sb, r_ab, t_ab, out)
    if st != ST_NOT_RUN:
        return st
    if out[OUT_DIST] > max(cutoff, TOUCH_TOL * shape_scale(sa, sb)):
        return ST_SEPARATED
    _blank(out, np.int64(M_AUTO))   # not a Literal-typed second compile (jit.py)
    return gjk_epa_ws(sa, sb, verts, r_ab, t_ab, out, ws[2], cutoff)


@njit_inline
def _mpr(sa, sb, verts, r_ab, t_ab, out, ws, cutoff):
    """Method MPR on an ordered pair without a plane."""
    st = mpr_ws(sa, sb, verts, r_ab, t_ab, out, ws[0][_POSE_ROWS:])
    if st == ST_SEPARATED and out[OUT_DIST] <= TOUCH_TOL * shape_scale(sa, sb):
        # MPR's distance for a separated pair is only a lower bound, so within the
        # touching band it cannot tell touching from apart: GJK decides, and the one
        # touching rule holds on this path too.
        iters = out[OUT_ITERS]
        st = gjk_epa_ws(sa, sb, verts, r_ab, t_ab, out, ws[2], cutoff)
        out[OUT_ITERS] += iters
        out[OUT_METHOD] = M_MPR
    return st


@njit_separate
def _run_ordered(sa, sb, verts, r_ab, t_ab, method, out, ws, cutoff):
    """Run ``method`` on a pair already in canonical order; result in A's frame.
    ``cutoff`` (m): see gjk_epa.gjk_epa_ws (closed forms are exact at any distance)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    out, ws = borrow(out), _borrow_ws(ws)
    has_plane = sa[0] == PLANE or sb[0] == PLANE
    if method == M_AUTO and sa[0] == BOX and sb[0] == BOX:
        return _box_box(sa, sb, verts, r_ab, t_ab, out, ws, cutoff)
    if method == M_AUTO or method == M_ANALYTIC:
        # (the guard saves a call that would only find no closed form)
        st = (collide_analytic(sa, sb, verts, r_ab, t_ab, out)
              if _has_closed_form(sa[0], sb[0], sb[1]) else ST_NOT_RUN)
        if st != ST_NOT_RUN or method == M_ANALYTIC or has_plane:
            if st == ST_NOT_RUN:
                _blank(out, method)
            return st
        return gjk_epa_ws(sa, sb, verts, r_ab, t_ab, out, ws[2], cutoff)
    if method == M_GJK_EPA:
        return gjk_epa_ws(sa, sb, verts, r_ab, t_ab, out, ws[2], cutoff)
    if method == M_MPR:
        if has_plane:
            return ST_NOT_RUN
        return _mpr(sa, sb, verts, r_ab, t_ab, out, ws, cutoff)
    if method == M_ELLIPSOID_EXACT or method == M_ELLIPSOID_SAMPLED:
        # The ellipsoid test decides the status (touching or not); its own distance is
        # in the unit-sphere frame of A, so the metric distance, normal and witness
        # points come from GJK/EPA on the same pair.
        if method == M_ELLIPSOID_EXACT:
            st = ellipsoid_exact(sa, sb, r_ab, t_ab, out)
        else:
            st = ellipsoid_sampled(sa, sb, r_ab, t_ab, np.int64(ELLIPSOID_SAMPLED_SUBDIV), out)
        if st == ST_NOT_RUN:
            return st
        iters = out[OUT_ITERS]
        gjk_epa_ws(sa, sb, verts, r_ab, t_ab, out, ws[2], cutoff)
        out[OUT_ITERS] += iters
        out[OUT_METHOD] = method
        return st
    return ST_NOT_RUN


@njit_kernel
def collide_pair(sa, sb, verts, r_ab, t_ab, method, out):
    """Collide one pair with the given method code; result row in A's frame.

    sa, sb  shape tuples (code int64, prm float64[8], v0 int64, vn int64)
    verts   float64 (M, 3) convex vertices (body frames)
    r_ab    float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    method  int64 method code (constants.M_*)
    out     float64 (OUT_SIZE,): signed distance (m, < 0 penetrating), unit normal A -> B,
            witness points pa on A and pb on B (A's frame), iterations, method code
    Returns the status code (constants.ST_*).  Allocates its scratch buffers; loops over
    many pairs use ``collide_pair_ws`` with one ``make_workspace()``.
    """
    return collide_pair_ws(sa, sb, verts, r_ab, t_ab, method, out, make_workspace(),
                           math.inf)


@njit_separate
def collide_pair_ws(sa, sb, verts, r_ab, t_ab, method, out, ws, cutoff):
    """``collide_pair`` with caller-provided scratch buffers ``ws`` (make_workspace());
    ``r_ab``/``t_ab`` may be ws[0][6:9]/ws[0][9] (only r_ba, t_ba, tmp, gjk are written).
    ``cutoff`` (m, may be inf): farther pairs may stop at a distance lower bound
    (gjk_epa.gjk_epa_ws)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    out, ws = borrow(out), _borrow_ws(ws)
    _blank(out, method)
    if sa[0] <= sb[0]:
        st = _run_ordered(sa, sb, verts, r_ab, t_ab, method, out, ws, cutoff)
        if st == ST_NOT_RUN:
            _blank(out, method)
        return st
    # swap to canonical order: solve (B, A) in B's frame, then map back
    r_ba = ws[0][10:13]
    t_ba = ws[0][13]
    for i in range(3):
        for j in range(3):
            r_ba[i, j] = r_ab[j, i]
    for i in range(3):
        t_ba[i] = -(r_ab[0, i] * t_ab[0] + r_ab[1, i] * t_ab[1] + r_ab[2, i] * t_ab[2])
    tmp = ws[1][1]
    _blank(tmp, method)
    st = _run_ordered(sb, sa, verts, r_ba, t_ba, method, tmp, ws, cutoff)
    if st == ST_NOT_RUN:
        _blank(out, method)
        return st
    out[OUT_DIST] = tmp[OUT_DIST]
    for i in range(3):
        n = 0.0
        pa = t_ab[i]
        pb = t_ab[i]
        for j in range(3):
            n -= r_ab[i, j] * tmp[OUT_NORMAL + j]
            pa += r_ab[i, j] * tmp[OUT_PB + j]
            pb += r_ab[i, j] * tmp[OUT_PA + j]
        out[OUT_NORMAL + i] = n
        out[OUT_PA + i] = pa
        out[OUT_PB + i] = pb
    out[OUT_ITERS] = tmp[OUT_ITERS]
    out[OUT_METHOD] = tmp[OUT_METHOD]
    return st


@njit_inline
def _half_space_world(code_s, prm_s, vr_s, verts, pos_s, quat_s, prm_p, pos_p, quat_p,
                      shape_is_a, out):
    """A shape against a half-space (n . x <= d + m in the plane body's frame, m its
    margin), straight in the world frame: the plane's normal n goes to the world, -n
    into the shape's frame for its support point p, and the signed distance is n . p -
    (d + m), p taken from the plane body's origin.  The same closed form as
    plane_shape.collide_shape_plane, without the relative pose and the way back from A's frame,
    which take about a third of such a pair's time (results within 7.4e-15 * scale of
    plane_shape.collide_shape_plane's).  A sphere's
    support point needs no rotation and a capsule's only its axis (the rotation's third
    column), so those two skip the way into the body frame and back.  Writes ``out``
    (world; normal from A to B: -n when the shape is A, n when it is B; the point on
    the plane is p - dist n) and returns the signed distance (m)."""
    nx, ny, nz = quat_rotate_xyz(quat_p, prm_p[0], prm_p[1], prm_p[2], np.bool_(False))
    if code_s == SPHERE:
        # no rotation: the support point is the centre less the radius along n
        rad = prm_s[0] + prm_s[P_MARGIN]
        sx, sy, sz = -rad * nx, -rad * ny, -rad * nz
    elif code_s == CAPSULE:
        # the segment's end on -n's side (its axis is the body's third column), less
        # the radius along n
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_entries(quat_s)
        rad = prm_s[0] + prm_s[P_MARGIN]
        h = prm_s[1] if nx * r02 + ny * r12 + nz * r22 <= 0.0 else -prm_s[1]
        sx, sy, sz = h * r02 - rad * nx, h * r12 - rad * ny, h * r22 - rad * nz
    else:
        ux, uy, uz = quat_rotate_xyz(quat_s, -nx, -ny, -nz, np.bool_(True))
        sx, sy, sz = support_full_xyz(code_s, prm_s, verts, vr_s[0], vr_s[1], ux, uy, uz)
        sx, sy, sz = quat_rotate_xyz(quat_s, sx, sy, sz, np.bool_(False))
    # from the plane body's origin, not the world's (bodies far from the origin)
    ex = sx + (pos_s[0] - pos_p[0])
    ey = sy + (pos_s[1] - pos_p[1])
    ez = sz + (pos_s[2] - pos_p[2])
    dist = nx * ex + ny * ey + nz * ez - (prm_p[3] + prm_p[P_MARGIN])
    px, py, pz = pos_s[0] + sx, pos_s[1] + sy, pos_s[2] + sz
    qx, qy, qz = px - dist * nx, py - dist * ny, pz - dist * nz
    out[OUT_DIST] = dist
    if shape_is_a:
        out[OUT_NORMAL], out[OUT_NORMAL + 1], out[OUT_NORMAL + 2] = -nx, -ny, -nz
        out[OUT_PA], out[OUT_PA + 1], out[OUT_PA + 2] = px, py, pz
        out[OUT_PB], out[OUT_PB + 1], out[OUT_PB + 2] = qx, qy, qz
    else:
        out[OUT_NORMAL], out[OUT_NORMAL + 1], out[OUT_NORMAL + 2] = nx, ny, nz
        out[OUT_PA], out[OUT_PA + 1], out[OUT_PA + 2] = qx, qy, qz
        out[OUT_PB], out[OUT_PB + 1], out[OUT_PB + 2] = px, py, pz
    out[OUT_ITERS] = 1.0
    out[OUT_METHOD] = M_ANALYTIC
    return dist


@njit_inline
def collide_world_ws(code_a, prm_a, vr_a, code_b, prm_b, vr_b, verts, pos_a, quat_a,
                     pos_b, quat_b, method, out, ws, cutoff):
    """One pair from world poses, with caller-provided scratch buffers ``ws``
    (make_workspace()) and a distance ``cutoff`` (m, may be inf; see collide_batch).

    prm_* float64 (8,), vr_* int64 (2,) (first vertex, count), pos_* float64 (3,) m,
    quat_* float64 (4,) xyzw unit; ``out`` (OUT_SIZE,) in the WORLD frame.  Returns the
    status code.

    Inlined (with analytic.closed_form_ordered and analytic._ordered) into the batch
    loop: a call that passes arrays costs numba a reference-count call per array even
    on borrowed views, and those calls would be half of a closed-form pair's time.

    Bounding spheres first: two bounded bodies whose bounding spheres (P_RADIUS about
    the body origins) are apart by more than the cutoff and the touching band end here
    with that gap as the certified distance bound (the same pre-test as MuJoCo's),
    normal along the centre line, pa and pb on the two spheres.  A shape against a
    half-space, by method auto or analytic, is solved in the world frame
    (_half_space_world), and so are a sphere against a shape with a sphere-* closed
    form (sphere_shape.sphere_world) and two capsules (capsule_capsule.capsule_capsule_world):
    for these the relative pose costs as much as the closed form itself."""
    if code_a != PLANE and code_b != PLANE:
        dx, dy, dz = pos_b[0] - pos_a[0], pos_b[1] - pos_a[1], pos_b[2] - pos_a[2]
        dc = math.sqrt(dx * dx + dy * dy + dz * dz)
        gap = dc - prm_a[P_RADIUS] - prm_b[P_RADIUS]
        if gap > max(cutoff, TOUCH_TOL * (prm_a[P_RADIUS] + prm_b[P_RADIUS])):
            _blank(out, method)
            out[OUT_DIST] = gap
            out[OUT_NORMAL], out[OUT_NORMAL + 1], out[OUT_NORMAL + 2] = dx / dc, dy / dc, dz / dc
            for i in range(3):
                out[OUT_PA + i] = pos_a[i] + prm_a[P_RADIUS] * out[OUT_NORMAL + i]
                out[OUT_PB + i] = pos_b[i] - prm_b[P_RADIUS] * out[OUT_NORMAL + i]
            return ST_SEPARATED
    if method == M_AUTO or method == M_ANALYTIC:
        # the pairs solved in the world frame, by the kind of closed form
        half_space = (code_a == PLANE) != (code_b == PLANE)
        sphere_a = code_a == SPHERE and _has_closed_form(np.int64(SPHERE), code_b, prm_b)
        sphere_b = code_b == SPHERE and _has_closed_form(np.int64(SPHERE), code_a, prm_a)
        capsules = code_a == CAPSULE and code_b == CAPSULE
        if half_space or sphere_a or sphere_b or capsules:
            scale = shape_scale((code_a, prm_a, vr_a[0], vr_a[1]),
                                (code_b, prm_b, vr_b[0], vr_b[1]))
            # one call site each, its roles picked by the order (an inlined copy of
            # each closed form fewer for the first compile)
            a_first = code_b == PLANE if half_space else sphere_a
            code_s, code_o = (code_a, code_b) if a_first else (code_b, code_a)
            prm_s, prm_o = (prm_a, prm_b) if a_first else (prm_b, prm_a)
            pos_s, pos_o = (pos_a, pos_b) if a_first else (pos_b, pos_a)
            quat_s, quat_o = (quat_a, quat_b) if a_first else (quat_b, quat_a)
            if half_space:
                vr_s = vr_a if a_first else vr_b
                dist = _half_space_world(code_s, prm_s, vr_s, verts, pos_s, quat_s, prm_o,
                                         pos_o, quat_o, a_first, out)
            elif sphere_a or sphere_b:
                dist = sphere_world(prm_s, code_o, prm_o, pos_s, pos_o, quat_o, a_first, out)
            else:
                dist = capsule_capsule_world(prm_a, prm_b, pos_a, quat_a, pos_b, quat_b,
                                             scale, out)
            return classify(dist, scale)
    ra = ws[0][0:3]
    rb = ws[0][3:6]
    quat_to_matrix_into(quat_a, ra)
    quat_to_matrix_into(quat_b, rb)
    r_ab = ws[0][6:9]
    t_ab = ws[0][9]
    for i in range(3):
        t_ab[i] = (ra[0, i] * (pos_b[0] - pos_a[0]) + ra[1, i] * (pos_b[1] - pos_a[1])
                   + ra[2, i] * (pos_b[2] - pos_a[2]))
        for j in range(3):
            r_ab[i, j] = ra[0, i] * rb[0, j] + ra[1, i] * rb[1, j] + ra[2, i] * rb[2, j]
    sa = (code_a, prm_a, vr_a[0], vr_a[1])
    sb = (code_b, prm_b, vr_b[0], vr_b[1])
    row = ws[1][0]
    if ((method == M_AUTO or method == M_ANALYTIC) and code_a <= code_b
            and _has_closed_form(code_a, code_b, prm_b)):
        # fast path, same result as collide_pair_ws: fewer call levels (each passes
        # arrays, whose reference counts numba updates on every call)
        st = classify(closed_form_ordered(sa, sb, verts, r_ab, t_ab, row),
                      shape_scale(sa, sb))
    elif method == M_AUTO and code_a == BOX and code_b == BOX:
        st = _box_box(sa, sb, verts, r_ab, t_ab, row, ws, cutoff)
    elif code_a <= code_b and code_b != PLANE and (method == M_AUTO or method == M_GJK_EPA):
        # no closed form (or none asked for): straight to GJK/EPA, where
        # collide_pair_ws would go after three calls that pass ~80 words of array
        # structs each (about a quarter of an apart cylinder pair's time)
        st = gjk_epa_ws(sa, sb, verts, r_ab, t_ab, row, ws[2], cutoff)
    elif code_a <= code_b and code_b != PLANE and method == M_MPR:
        st = _mpr(sa, sb, verts, r_ab, t_ab, row, ws, cutoff)
    else:
        st = collide_pair_ws(sa, sb, verts, r_ab, t_ab, method, row, ws, cutoff)
    out[OUT_DIST] = row[OUT_DIST]
    for i in range(3):
        n = 0.0
        pa = pos_a[i]
        pb = pos_a[i]
        for j in range(3):
            n += ra[i, j] * row[OUT_NORMAL + j]
            pa += ra[i, j] * row[OUT_PA + j]
            pb += ra[i, j] * row[OUT_PB + j]
        out[OUT_NORMAL + i] = n
        out[OUT_PA + i] = pa
        out[OUT_PB + i] = pb
    out[OUT_ITERS] = row[OUT_ITERS]
    out[OUT_METHOD] = row[OUT_METHOD]
    return st


@njit_separate
def _collide_block(codes, params, vrange, verts, pairs, pos_w, quat_w, method, cutoff,
                   out, status, lo, hi):
    """Pairs [lo, hi) of ``collide_batch`` with one scratch workspace, in a plain loop:
    the same loop inside numba's parallel region (the outlined prange body) runs a
    closed-form pair at twice the cost."""
    # owner-less views: no atomic reference counting on the per-pair path (jit.borrow)
    codes, params, vrange, verts = borrow(codes), borrow(params), borrow(vrange), borrow(verts)
    pairs, pos_w, quat_w = borrow(pairs), borrow(pos_w), borrow(quat_w)
    out, status = borrow(out), borrow(status)
    own = make_workspace()
    ws = _borrow_ws(own)
    for k in range(lo, hi):
        i = pairs[k, 0]
        j = pairs[k, 1]
        status[k] = collide_world_ws(codes[i], params[i], vrange[i], codes[j], params[j],
                                     vrange[j], verts, pos_w[i], quat_w[i], pos_w[j],
                                     quat_w[j], method, out[k], ws, cutoff)
    keep_alive(own)


@njit_parallel
def _collide_batch(codes, params, vrange, verts, pairs, pos_w, quat_w, method, cutoff,
                   out, status, nb):
    """``collide_batch`` in ``nb`` blocks, block b the pairs [b P / nb, (b + 1) P / nb).

    numba's parallel launch rather than jit.run_blocks: it hands the blocks over in
    ~3 us, where Python threads take 0.1-0.3 ms, as much as a 1,000-body scene's whole
    narrow phase on two threads.  It costs ~25 s of the first compile (LLVM optimises
    ``_collide_block``'s linked code again for the parallel wrapper)."""
    n_pairs = pairs.shape[0]
    for blk in prange(nb):
        _collide_block(codes, params, vrange, verts, pairs, pos_w, quat_w, method, cutoff,
                       out, status, blk * n_pairs // nb, (blk + 1) * n_pairs // nb)


def collide_batch(codes, params, vrange, verts, pairs, pos_w, quat_w, method, cutoff,
                  out, status):
    """Collide every pair (i, j) of ``pairs``; results in the WORLD frame.

    codes  int64 (N,)        shape codes          params float64 (N, 8) parameter rows
    vrange int64 (N, 2)      convex vertex ranges verts  float64 (M, 3) body frames
    pairs  int64 (P, 2)      shape indices (A, B)
    pos_w  float64 (N, 3)    positions (m)        quat_w float64 (N, 4) xyzw, unit
    method int64             method code (constants.M_*)
    cutoff float64 (m, >= 0) distances up to max(cutoff, the touching band) are exact;
                             np.inf: every distance exact (the API's collide/distance).
                             A pair farther apart may be reported SEPARATED with a
                             certified lower bound (> cutoff) as its distance, the
                             separating direction as normal and witness points that are
                             not the closest (gjk_epa.gjk_epa_ws); the pipeline passes
                             its reach, max(contact_margin, proximity), query_contacts 0.
    out    float64 (P, OUT_SIZE)  written: signed distance, normal A -> B, pa, pb (world)
    status int64 (P,)        written: status codes (constants.ST_*)
    Pairs run in contiguous blocks, one per numba thread (none smaller than NP_CHUNK),
    one scratch workspace per block (_collide_block); each pair writes only its own slot
    and no state survives from pair to pair: deterministic for any number of threads.
    A Python function around the parallel kernel ``_collide_batch``, which is given the
    block count (a kernel asking numba for its thread count cannot be cached).  One
    block runs ``_collide_block`` straight, the same compiled loop without the parallel
    launch, which costs ~3 us a call (an empty batch takes 2.7 us without it), paid by
    small scenes every frame.
    """
    nb = n_blocks(pairs.shape[0], NP_CHUNK)
    if nb == 1:
        _collide_block(codes, params, vrange, verts, pairs, pos_w, quat_w, method, cutoff,
                       out, status, 0, pairs.shape[0])
    else:
        _collide_batch(codes, params, vrange, verts, pairs, pos_w, quat_w, method, cutoff,
                       out, status, nb)
