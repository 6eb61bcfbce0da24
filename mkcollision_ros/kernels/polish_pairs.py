"""Which polish steps GJK and EPA try on a pair of shape codes (the predicates gjk.py
and epa.py name: ``_smooth_pair``, ``_ellipsoid_box``, ``_gjk_newton_pair``,
``_kink_partner``, ``_has_crease``, ``_searched_crease``, ``_kink_side``,
``_face_pair``, ``_epa_face_pair``, ``_crossing_pair``, ``_hull_side``,
``_polish_cap``), and the frame helpers the polish steps share (``_axis_of``,
``_in_side_frame``, ``_hull_dir``).
"""
from .constants import (BOX, CAPSULE, CONVEX, CYLINDER, ELLIPSOID, EPA_KINK_CAP_BOX,
                        EPA_KINK_CAP_CAPSULE, EPA_KINK_NEAR, EPA_POLISH_CAP, SPHERE)
from .jit import njit_inline


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
