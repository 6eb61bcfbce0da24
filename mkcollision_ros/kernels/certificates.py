"""The tests that decide whether a polished minimum of h = h_{A-B} is the depth:
  * ``_polish_is_global``: no direction outside a cap around the minimum's normal can be
    deeper by EPA's polytope (its faces' planes, or their vertices);
  * ``_ball_certified``: a ball inside one core about the other core's witness (or an
    ellipsoid's rolling ball, ``_rolling_ball``) proves the depth at once, with no test
    of the polytope (``_core_depth``, ``_core_inradius``);
  * ``_face_basin``: the cap a face test proves around a face's normal;
  * ``_vertex_cap``: the cap for a box vertex's minimum against an ellipsoid;
  * ``_pending_bound``: the bound EPA holds a pending minimum to.
Frames and units: gjk_epa.py.  The why of each: its docstring.
"""
import math

import numpy as np

from .constants import (BOX, CYLINDER, ELLIPSOID, EPA_FACE_CAP_MAX, EPA_POLISH_CAP,
                        EPA_VERTEX_CAP_MIN, P_ROLL, ROLL_SHRINK)
from .geometry import borrow_pose
from .gjk_epa_workspace import _T_MIN_D, _T_MIN_W, _T_MIN_WA, _T_MIN_WB, _dot
from .jit import njit_inline, njit_kernel
from .pairs.sphere_shape import _point_box, _point_cylinder
from .polish_pairs import _axis_of, _in_side_frame


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
    rho = (1.0 - ROLL_SHRINK) * cmin * cmin / math.sqrt(
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
    if _core_inradius(np.int64(0), sa, sb, r_ab, t_ab, bx, by, bz) >= hmin:
        return True
    if _core_inradius(np.int64(1), sa, sb, r_ab, t_ab, ax, ay, az) >= hmin:
        return True
    if sa[0] != ELLIPSOID and sb[0] != ELLIPSOID:
        return False
    qax, qay, qaz, rha = _rolling_ball(np.int64(0), sa, sb, r_ab, ax, ay, az, nx, ny, nz)
    qbx, qby, qbz, rhb = _rolling_ball(np.int64(1), sa, sb, r_ab, bx, by, bz, -nx, -ny, -nz)
    ex, ey, ez = qax - qbx, qay - qby, qaz - qbz
    if rha + rhb - math.sqrt(ex * ex + ey * ey + ez * ez) >= hmin:
        return True
    if (sa[0] == ELLIPSOID
            and rha + _core_depth(np.int64(1), sa, sb, r_ab, t_ab, qax, qay, qaz) >= hmin):
        return True
    return (sb[0] == ELLIPSOID
            and rhb + _core_depth(np.int64(0), sa, sb, r_ab, t_ab, qbx, qby, qbz) >= hmin)


@njit_inline
def _pending_bound(sa, sb, r_ab, t_ab, fs, tol):
    """The bound EPA holds a minimum a polish stored (ws t3 rows 15-18: n, w, a, b) to:
    h(n) - tol, which no face of its polytope outside the basin cap may undercut
    (_polish_is_global), or -inf when _ball_certified proves it the depth."""
    n, w, a, b = fs[_T_MIN_D], fs[_T_MIN_W], fs[_T_MIN_WA], fs[_T_MIN_WB]
    hmin = _dot(n, w) - tol
    if _ball_certified(sa, sb, r_ab, t_ab, hmin, n[0], n[1], n[2], a[0], a[1], a[2], b[0],
                       b[1], b[2]):
        return -np.inf
    return hmin


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
    the cap is the whole basin there (tests/test_polish_faces.py checks both).

    The same holds on a convex hull's face (rin: the foot's least distance to the
    triangle's edges); EPA does not test hull faces with it, as the test costs more
    time than it saves (gjk.py's docstring)."""
    if not h > 0.0:
        return 0.0
    return min(2.0 * math.atan(rin / h), EPA_FACE_CAP_MAX)


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
