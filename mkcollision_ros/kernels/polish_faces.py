"""The face tests: whether the minimum of h = h_{A-B} lies exactly at a box's face
normal or a cylinder's axis (``_face_polish``, ``_face_test``), a convex hull's face
(``_hull_face_test``), or where a cylinder's side crosses another cylinder's side or a
hull's edge (``_crossing_test``; two cylinders' one crossing face at EPA's start,
``_cylinders_crossing``); and the polish of a hull's features against an ellipsoid on
cores apart (``_hull_polish``: the face test on the face of the three highest
vertices, else the crease search along the edge of the two highest).

Each test needs one support point: at a face's normal h rises to first order in every
direction iff the other shape's support point projects into the face, and the cap it
proves (certificates._face_basin) is EPA's basin cap for it.  A minimum is left in the
workspace's polish rows (gjk_epa_workspace._store_min), the cap in t3 row 3.  The why
and the measurements: each function's docstring.
"""
import math

import numpy as np

from .certificates import _face_basin
from .constants import (AXES_SIN_MIN, BOX, CYLINDER, EPA_KINK_NEAR, EPA_MAX_FACES, FACE_MIN_EDGE,
                        FACE_MIN_RADIUS, SUPPORT_TIE)
from .geometry import borrow_args
from .gjk_epa_workspace import (_IF, _NVMAX, _T_FACE_CAP, _VA, _VB, _store_min,
                                borrow_gjk_workspace)
from .jit import njit_inline, njit_kernel
from .pairs.cylinder_cylinder import sides_crossing
from .pairs.ellipsoid_box import face_room
from .polish_crease import _crease_min, _support_called
from .polish_pairs import _axis_of, _hull_dir, _in_side_frame


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
    if not (le > FACE_MIN_EDGE * scale and p1 - p2 < EPA_KINK_NEAR * le):
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
    if not (ok and hu <= hlow + SUPPORT_TIE * scale):
        return -nev, False
    # the edge still the support along u
    hx, hy, hz = _hull_dir(side, r_ab, ux, uy, uz)
    i2, j2, _, q1, _, q3 = _hull_top3(pts, hx, hy, hz)
    if not (((i2 == i and j2 == j) or (i2 == j and j2 == i)) and q3 < q1 - SUPPORT_TIE * scale):
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
    if not (-SUPPORT_TIE * scale <= tpar <= le + SUPPORT_TIE * scale):
        return -nev, False
    _store_min(fs, ux, uy, uz, pax - pbx, pay - pby, paz - pbz, pax, pay, paz, pbx, pby,
               pbz)
    return nev, False


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
        qx, qy, qz = _in_side_frame(np.int64(1), r_ab, t_ab, pax, pay, paz)
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
    ax, ay, az = _axis_of(cs, np.int64(2), r_ab)
    if not abs(ax * dx + ay * dy + az * dz) < EPA_KINK_NEAR:
        return 0
    # the other segment: direction (bx, by, bz) and half-length lb, A's frame
    ncand = 1 if ocode == CYLINDER else 3
    F = ws[2][_IF:_IF + EPA_MAX_FACES]
    P = ws[0][_VA:_VA + _NVMAX] if os_ == 0 else ws[0][_VB:_VB + _NVMAX]
    for e in range(ncand):
        if ocode == CYLINDER:
            bx, by, bz = _axis_of(os_, np.int64(2), r_ab)
            lb = (sb[1] if os_ == 1 else sa[1])[1]
            px = py = pz = 0.0
        else:
            # an edge of the best face's support points on the hull (two distinct)
            i0 = F[best, e]
            i1 = F[best, (e + 1) % 3]
            px, py, pz = P[i0, 0], P[i0, 1], P[i0, 2]
            bx, by, bz = P[i1, 0] - px, P[i1, 1] - py, P[i1, 2] - pz
            lb = 0.5 * math.sqrt(bx * bx + by * by + bz * bz)
            if not lb > FACE_MIN_RADIUS * scale:
                continue
            bx, by, bz = 0.5 * bx / lb, 0.5 * by / lb, 0.5 * bz / lb
        nx, ny, nz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
        sn = math.sqrt(nx * nx + ny * ny + nz * nz)
        if not sn > AXES_SIN_MIN:
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
        if not (h > 0.0 and rin >= FACE_MIN_RADIUS * scale):
            return -1
        _store_min(fs, nx, ny, nz, h * nx, h * ny, h * nz, max_ + s_ * kax,
                   may_ + s_ * kay, maz_ + s_ * kaz, mbx + t_ * kbx, mby + t_ * kby,
                   mbz + t_ * kbz)
        fs[_T_FACE_CAP, 0] = _face_basin(rin, h)
        return 1
    return 0


@njit_inline
def _cylinders_crossing(sa, sb, r_ab, t_ab, scale, fs):
    """_crossing_test for two cylinders, whatever EPA's best face: whether the
    parallelogram face their sides make normal to both axes
    (cylinder_cylinder.sides_crossing) holds a minimum of h, stored as _crossing_test
    stores it (ws t3 rows 15-18, the cap in row 3).
    (cylinder_cylinder.collide_cylinder_cylinder has certified the pairs where a
    witness's ball reaches h before GJK; here the others, whose balls a cap cuts
    short.)

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
    if not (h > 0.0 and rin >= FACE_MIN_RADIUS * scale):
        return False
    _store_min(fs, nx, ny, 0.0, h * nx, h * ny, 0.0, ra * nx, ra * ny, s,
               t_ab[0] - rb * nx + u * bx, t_ab[1] - rb * ny + u * by, t_ab[2] + u * bz)
    fs[_T_FACE_CAP, 0] = _face_basin(rin, h)
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
    return _none_above(pts, hx, hy, hz, hx * qx + hy * qy + hz * qz + SUPPORT_TIE * scale)


@njit_inline
def _none_above(pts, hx, hy, hz, top):
    """Whether no point of pts (n, 3) lies above the height ``top`` along (hx, hy,
    hz): one pass."""
    for q in range(pts.shape[0]):
        if hx * pts[q, 0] + hy * pts[q, 1] + hz * pts[q, 2] > top:
            return False
    return True


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
    if not rin >= FACE_MIN_RADIUS * scale:
        return -1
    _face_minimum(fs, side, nx, ny, nz, h, pax, pay, paz, pbx, pby, pbz)
    fs[_T_FACE_CAP, 0] = _face_basin(rin, h)
    return 1


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
                       nx * pts[i, 0] + ny * pts[i, 1] + nz * pts[i, 2] + SUPPORT_TIE * scale):
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
    eps = FACE_MIN_RADIUS * scale
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
