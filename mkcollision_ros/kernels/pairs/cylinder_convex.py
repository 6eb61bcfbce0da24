"""A cylinder and a convex hull before GJK and EPA, by two kernels:
  * ``collide_cylinder_convex``: a small hull with its fan stored, in closed form and
    1-D root searches: the exact depth of the cylinder C and the hull B over B's
    normal fan, as ellipsoid_convex.py does for an ellipsoid (the fan's helpers:
    normal_fan.py), by the notes below;
  * ``collide_cylinder_convex_ball``: any hull, the core depth certified by the ball of
    cylinder_common.py from the hull's lowest vertex under each cap and its point
    nearest the cylinder's axis (its docstring).
gjk_epa.gjk_epa_ws calls ``collide_cylinder_convex`` first for such a pair when the hull
has its fan stored; where it decides nothing, or with no fan,
``collide_cylinder_convex_ball``; then GJK and EPA run as for any pair.

The problem, in C's frame (axis z, radius R, half-height H): the depth is min over unit
n of f(n) = h_C(n) + h_B(-n), with h_C(n) = R |n_xy| + H |n_z|.  C's normal fan is its
two caps' normals (the poles), its side's (the equator, a great circle) and its two
rims' (the open hemispheres between); B's is its faces' normals, its edges' arcs and its
vertices' cones.  The minimiser lies in a cell of the two fans' common refinement and is
a critical point of f restricted to it:

  * a pole, n = +-z: f = H -+ (B's lowest / highest z), whatever B's feature there;
  * a face of B, n = -m: f = h_C(-m) + B's offset along m;
  * the equator in a vertex's cone: f = R - n . v, least at n = v_xy / |v_xy|, where it
    is R - |v_xy| (counts if B's support along -n is attained at v);
  * the equator crossing an edge's arc: n = +-(z x e) / |z x e|, the one in the arc;
  * a rim's hemisphere in an edge's arc: there C is the rim's disk, a flat ellipsoid
    (squared semi-axes R^2, R^2, 0) centred at +-H z, and f on the arc is ellipsoid_convex's edge
    problem for it (normal_fan._plane_feet: the disk projected along the edge is an ellipse
    of semi-axes R and R |e_z|); a root counts if its n lies in the arc and in that
    hemisphere;
  * a rim's hemisphere in a vertex's cone: none.  There C's support is a rim point r
    and f(n) = n . (r(n) - v); along the meridian through n, r stays put, so a critical
    point (n parallel to r - v, f = |r - v| > 0) is a maximum along it, never a minimum.
    (The boundary of A - B there is a curve, the rim less v, whose nearest point to the
    origin inside lies at one of its ends' cells.)

Pruning (U the least value found so far, from the faces' and the poles'): an edge's arc
is skipped where f's tangent planes at its ends, the subgradients (s_i - v) . n with s_i
C's support point at n_i, clear U over the chord between the ends (closed form from the
faces' values; within the fan's tolerance, constants.HE_FAN_SLACK), else over the arc
itself (normal_fan._planes_on_arc).  An arc reaches a hemisphere only through an end in it
(it is shorter than pi), so each edge solves at most the rims its ends' normals face;
where the arc crosses the equator at w, a rim's part runs from its end to w and is
bounded likewise by the planes there (at w C's support point on that rim, R w + s H z).
A side-vertex candidate below L, the depth in C of the deepest hull vertex inside C,
cannot lie in its vertex's cone (the depth is at least L), so it is not checked.

The rims' candidates skip the negative feet, and the rim-vertex cells hold no minimum
only where f > 0, so all of it holds only for a pair that overlaps.  The kernel proves
that where it is cheap (a hull vertex inside C, C's centre inside B, or C's point
nearest B's origin inside B); else by GJK's boolean form on B - C in C's frame
(_cyl_gjk: sign tests pick each step's sub-simplex and direction, with no closest point
solved), which ends at a tetrahedron holding the origin or at a plane proving the
pair apart.  In bench/vs_mujoco.py's cylinder-convex row it decides all 202 pairs the
cheap proofs leave (107 overlapping in 7.6 steps on average, 95 apart in 8.5, ~50 ns a
step), where gjk_epa_ws's GJK takes ~0.3 us a step (its closest-point solve) and would
send the overlapping ones back here a second time.  Only where it decides nothing (a
gap within the caller's ``stop``, a flat tetrahedron, the cap) gjk_epa_ws runs GJK
first and calls the kernel again once GJK has found the cores overlapping, in place of
EPA.  Before that, C's centre's offsets below the face planes: the plane it
lies farthest beyond, the side's tangent plane toward B's centre, the caps' planes,
and in the face pass any face's plane, with B wholly beyond it by more than the
caller's ``stop``, end the call with that gap as a bound (as GJK's first separating
plane).  Near-degenerate edges (nearly square to the axis or along it: the projected
rim a near-segment or a near-circle) and non-converging searches decide nothing
(PRE_UNDECIDED): GJK and EPA take the pair.

The answer is for C and B's core (no rolling radius: a cylinder's core is itself):
res = [U, n, pa, pb] as ellipsoid_convex's, the witnesses exact for the feature pair found (a
rim point and the point U back along n; a vertex and the side's point level with it;
an edge's point on the side's line; a cap's point over B's lowest vertex).

Measured (pure Python, the first 300 of bench/dev/deep_pairs.py's cylinder-convex cases,
overlap given where GJK/EPA found it): every overlapping pair decided, depths within
7.7e-9 * scale and normals within 1.5e-4 rad of GJK/EPA's (EPA's own tolerance).  On
the row's deep pairs, per pair: ~43 faces, ~64 edges of which ~1.6 pass the chord bound
and ~0.9 the arc bound, ~0.3 rim root searches.  The unpredictable branches (a face
normal's sign along the axis, whether a vertex lies inside C) are copysign and max:
as branches they cost ~0.4 us per pair in mispredictions.  Figures of time:
BENCHMARKS.md.
"""
import math

import numpy as np

from ..constants import (CYLINDER, EPA_REL_TOL, FAN_MAX_POINTS, GJK_FLAT_TOL, HC_GJK_ITERS,
                         HE_BALL_ITERS, HE_FAN_SLACK, HE_SUPPORT_TOL, PARALLEL_SIN, PRE_APART,
                         PRE_EXACT, PRE_UNDECIDED, PRE_UNPROVED)
from ..geometry import borrow_args, cylinder_inradius
from ..jit import borrow, njit_inline, njit_separate
from .cylinder_common import (_cap_normal, _cap_test, _certified_out, _cover, _frame,
                              _past_side, _side_normal, pre_outcome)
from .normal_fan import (HE_FACES, HE_MAX_FACES, HE_V, _in_arc, _plane_feet, _planes_on_arc,
                         _vertex_top, face_apart_out, fan_run, fan_stored, hull_pose, least_offset,
                         plane_foot)


@njit_inline
def cylinder_hull_pair(sa, sb):
    """A cylinder and a hull with its fan stored (hull.fan_rows), either order."""
    return ((sa[0] == CYLINDER and fan_stored(sb[0], sb[1]))
            or (sb[0] == CYLINDER and fan_stored(sa[0], sa[1])))


@njit_inline
def _cyl_point(big_r, big_h, dx, dy, dz):
    """A point of the cylinder's support set along d (its own frame): the rim point, the
    side's middle (d_z = 0) or the cap's centre (d_xy = 0)."""
    s = math.sqrt(dx * dx + dy * dy)
    z = big_h if dz > 0.0 else (-big_h if dz < 0.0 else 0.0)
    if s > 0.0:
        return big_r * dx / s, big_r * dy / s, z
    return 0.0, 0.0, z


@njit_inline
def _out(res, side, r_ab, t_ab, h, nx, ny, nz, ax, ay, az, bx, by, bz):
    """res = [h, n, pa, pb] in A's frame from n (from C to B), C's point a and B's point
    b, all in C's frame."""
    res[0] = h
    if side == 0:
        res[1], res[2], res[3] = nx, ny, nz
        res[4], res[5], res[6] = ax, ay, az
        res[7], res[8], res[9] = bx, by, bz
        return
    # A is the hull: C's frame into A's, the normal reversed
    for c in range(3):
        res[1 + c] = -(r_ab[c, 0] * nx + r_ab[c, 1] * ny + r_ab[c, 2] * nz)
        res[4 + c] = r_ab[c, 0] * bx + r_ab[c, 1] * by + r_ab[c, 2] * bz + t_ab[c]
        res[7 + c] = r_ab[c, 0] * ax + r_ab[c, 1] * ay + r_ab[c, 2] * az + t_ab[c]


@njit_inline
def _apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my, mz, big_r,
               big_h, gap):
    """normal_fan.face_apart_out for C."""
    sx, sy, sz = _cyl_point(big_r, big_h, -mx, -my, -mz)
    face_apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my, mz, sx, sy,
                   sz, gap)


@njit_inline
def _cap_point(big_r, big_h, s, x, y):
    """The point of C's cap (s = +-1) nearest to (x, y) in the axes' plane."""
    q = math.sqrt(x * x + y * y)
    k = big_r / q if q > big_r else 1.0
    return k * x, k * y, s * big_h


@njit_inline
def _toward_origin(ax, ay, az, ex, ey, ez):
    """The direction (e x a_o) x e toward the origin o, normal to the line through a
    along e (a_o = -a): a_o |e|^2 - e (e . a_o), no cross products."""
    ee = ex * ex + ey * ey + ez * ez
    ea = -(ex * ax + ey * ay + ez * az)
    return -ax * ee - ex * ea, -ay * ee - ey * ea, -az * ee - ez * ea


@njit_inline
def _triangle_step(ax, ay, az, bx, by, bz, cx, cy, cz):
    """GJK's step on the triangle a (newest), b, c with the origin o: the smallest of
    its sub-simplices holding a whose Voronoi region holds o, by sign tests alone, and
    the direction from it toward o.  Returns (n, the simplex's other points b, c, the
    direction): n = 1 (a alone), 2 (a, b) or 3 (a, b, c ordered so that the direction
    is (b - a) x (c - a))."""
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    nx = aby * acz - abz * acy
    ny = abz * acx - abx * acz
    nz = abx * acy - aby * acx
    # beyond the edge a c (its outward normal in the plane: n x ac)?
    if -((ny * acz - nz * acy) * ax + (nz * acx - nx * acz) * ay
         + (nx * acy - ny * acx) * az) > 0.0:
        if -(acx * ax + acy * ay + acz * az) > 0.0:
            dx, dy, dz = _toward_origin(ax, ay, az, acx, acy, acz)
            return 2, cx, cy, cz, 0.0, 0.0, 0.0, dx, dy, dz
        edge = True
    else:
        # beyond the edge a b (outward normal ab x n)?
        edge = -((aby * nz - abz * ny) * ax + (abz * nx - abx * nz) * ay
                 + (abx * ny - aby * nx) * az) > 0.0
    if edge:
        if -(abx * ax + aby * ay + abz * az) > 0.0:
            dx, dy, dz = _toward_origin(ax, ay, az, abx, aby, abz)
            return 2, bx, by, bz, 0.0, 0.0, 0.0, dx, dy, dz
        return 1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -ax, -ay, -az
    # over the face: toward o along its normal, the points ordered to match
    if -(nx * ax + ny * ay + nz * az) > 0.0:
        return 3, bx, by, bz, cx, cy, cz, nx, ny, nz
    return 3, cx, cy, cz, bx, by, bz, -nx, -ny, -nz


@njit_inline
def _cyl_gjk(V, fl, nf, nvx, big_r, big_h, t0, t1, t2, need):
    """Whether C and the hull B overlap or are apart, by GJK's boolean form on B - C in
    C's frame (B's vertices the rows of V, C's support in closed form): each step
    keeps the sub-simplex whose Voronoi region holds the origin and looks along the
    direction from it toward the origin, by sign tests alone (no closest point, no
    barycentric weights), until the support point along that direction d falls short
    of the origin (a separating plane of normal -d) or a tetrahedron holds the origin.

    Returns (1, ...) for the overlap (the origin inside a tetrahedron of B - C's
    points, not flat); (2, gap, n, u) for a plane proving the cores more than ``need``
    apart (n unit, from C toward B; u the hull vertex nearest C along n); (0, ...)
    undecided (a gap up to ``need``, a degenerate direction, the cap)."""
    # from B's origin (t, a point near the middle of B - C) toward the origin
    dx, dy, dz = -t0, -t1, -t2
    if not dx * dx + dy * dy + dz * dz > 0.0:
        dx = 1.0
    n = 0
    ax = ay = az = bx = by = bz = cx = cy = cz = 0.0
    for _ in range(HE_BALL_ITERS):
        # B - C's support point along d: B's vertex u less C's support point along -d
        top, u = _vertex_top(V, fl, nf, nvx, dx, dy, dz)
        s = math.sqrt(dx * dx + dy * dy)
        k = big_r / s if s > 0.0 else 0.0
        hz = math.copysign(big_h, dz)
        wd = top + k * (dx * dx + dy * dy) + hz * dz
        if wd < 0.0:
            # all of B - C lies below the plane d . x = wd < 0
            dn = math.sqrt(dx * dx + dy * dy + dz * dz)
            gap = -wd / dn
            if gap > need:
                return 2, gap, -dx / dn, -dy / dn, -dz / dn, u
            return 0, 0.0, 0.0, 0.0, 0.0, u
        wx, wy, wz = V[u, 0] + k * dx, V[u, 1] + k * dy, V[u, 2] + hz
        if n == 0:
            n = 1
            ax, ay, az = wx, wy, wz
            dx, dy, dz = -wx, -wy, -wz
        elif n == 1:
            bx, by, bz = ax, ay, az
            ax, ay, az = wx, wy, wz
            ex, ey, ez = bx - ax, by - ay, bz - az
            if -(ex * ax + ey * ay + ez * az) > 0.0:
                n = 2
                dx, dy, dz = _toward_origin(ax, ay, az, ex, ey, ez)
            else:
                dx, dy, dz = -ax, -ay, -az
        elif n == 2:
            n, bx, by, bz, cx, cy, cz, dx, dy, dz = _triangle_step(wx, wy, wz, ax, ay, az,
                                                                   bx, by, bz)
            ax, ay, az = wx, wy, wz
        else:
            # the tetrahedron w, a, b, c: the origin lies on w's side of the triangle
            # a, b, c (d its normal); the faces through w with their outward normals
            px, py, pz = ax - wx, ay - wy, az - wz
            qx, qy, qz = bx - wx, by - wy, bz - wz
            rx, ry, rz = cx - wx, cy - wy, cz - wz
            # w a b: (a - w) x (b - w); w b c; w c a
            if -((py * qz - pz * qy) * wx + (pz * qx - px * qz) * wy
                 + (px * qy - py * qx) * wz) > 0.0:
                n, bx, by, bz, cx, cy, cz, dx, dy, dz = _triangle_step(
                    wx, wy, wz, ax, ay, az, bx, by, bz)
            elif -((qy * rz - qz * ry) * wx + (qz * rx - qx * rz) * wy
                   + (qx * ry - qy * rx) * wz) > 0.0:
                n, bx, by, bz, cx, cy, cz, dx, dy, dz = _triangle_step(
                    wx, wy, wz, bx, by, bz, cx, cy, cz)
            elif -((ry * pz - rz * py) * wx + (rz * px - rx * pz) * wy
                   + (rx * py - ry * px) * wz) > 0.0:
                n, bx, by, bz, cx, cy, cz, dx, dy, dz = _triangle_step(
                    wx, wy, wz, cx, cy, cz, ax, ay, az)
            else:
                # inside the three faces through w, and beyond a b c toward w: the
                # tetrahedron holds the origin unless it is flat (its faces' signs
                # then rounding noise)
                vol6 = (px * (qy * rz - qz * ry) + py * (qz * rx - qx * rz)
                        + pz * (qx * ry - qy * rx))
                ll = max(px * px + py * py + pz * pz, max(qx * qx + qy * qy + qz * qz,
                                                          rx * rx + ry * ry + rz * rz))
                if abs(vol6) > GJK_FLAT_TOL * ll * math.sqrt(ll):
                    return 1, 0.0, 0.0, 0.0, 0.0, u
                return 0, 0.0, 0.0, 0.0, 0.0, u
            ax, ay, az = wx, wy, wz
        if not dx * dx + dy * dy + dz * dz > 0.0:
            return 0, 0.0, 0.0, 0.0, 0.0, u
    return 0, 0.0, 0.0, 0.0, 0.0, np.uint64(0)


@njit_separate
def collide_cylinder_convex(sa, sb, verts, r_ab, t_ab, scale, overlap, stop, rows, roots,
                            res):
    """The exact depth of a cylinder and a hull's core with its fan stored (either
    order; B's pose r_ab, t_ab in A's frame), by the module notes; arguments and outcomes
    as ellipsoid_convex.collide_ellipsoid_convex's (``rows`` >= normal_fan.HE_ROWS rows)."""
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    rows, roots, res = borrow(rows), borrow(roots), borrow(res)
    side = 0 if sa[0] == CYLINDER else 1
    cyl = sa[1] if side == 0 else sb[1]
    hull = sb if side == 0 else sa
    v0, vn = hull[2], hull[3]
    nf, ne, nvx, fnr, fe, fl = fan_run(hull[1], v0, vn, verts)
    if vn > FAN_MAX_POINTS or nf > HE_MAX_FACES:
        return PRE_UNDECIDED
    # the hull's pose in C's frame
    r00, r01, r02, r10, r11, r12, r20, r21, r22, t0, t1, t2 = hull_pose(side, r_ab, t_ab)
    big_r, big_h = cyl[0], cyl[1]
    r2 = big_r * big_r
    V = rows[HE_V:HE_V + vn]
    M = rows[HE_FACES:HE_FACES + nf]            # m, C's frame
    Q = rows[HE_FACES + nf:HE_FACES + 2 * nf]   # (f(-m), offset, R / |m_xy|)
    X = rows[HE_FACES + 2 * nf:HE_FACES + 2 * nf + vn]   # per vertex (|v_xy|, -, -)
    pts = verts[v0:v0 + vn]
    tol = HE_SUPPORT_TOL * scale
    # C's centre c in the hull's frame and its offset below each face's plane (as
    # ellipsoid_convex): all positive proves the overlap; the least is tried as a separating plane
    omin, fmin = least_offset(verts, fl, fnr, nf, r00, r01, r02, r10, r11, r12, r20, r21,
                              r22, t0, t1, t2, Q)
    if not omin > 0.0:
        fx, fy, fz = verts[fnr + fmin, 0], verts[fnr + fmin, 1], verts[fnr + fmin, 2]
        mx = r00 * fx + r01 * fy + r02 * fz
        my = r10 * fx + r11 * fy + r12 * fz
        mz = r20 * fx + r21 * fy + r22 * fz
        hC = big_r * math.sqrt(mx * mx + my * my) + big_h * abs(mz)
        if -(hC + omin) > stop:
            _apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my, mz,
                       big_r, big_h, -(hC + omin))
            return PRE_APART
    inside = omin > 0.0
    # the vertices in C's frame, the lowest and the highest, and L, the depth in C of
    # the deepest one inside (A - B holds C - v, so the depth is at least that); row
    # indices as uint64, as ellipsoid_convex's (no wraparound checks: ~3% of the kernel's time)
    zlo, zhi = np.inf, -np.inf
    ilo = ihi = np.uint64(0)
    L = 0.0
    # and the least extent along the side's normal toward B's centre, h (horizontal)
    hl = math.sqrt(t0 * t0 + t1 * t1)
    hx, hy = (t0 / hl, t1 / hl) if hl > 0.0 else (1.0, 0.0)
    smin, imin = np.inf, np.uint64(0)
    for i in range(nvx):
        u = np.uint64(int(fl[nf + i]))
        px, py, pz = pts[u, 0], pts[u, 1], pts[u, 2]
        x0 = r00 * px + r01 * py + r02 * pz + t0
        x1 = r10 * px + r11 * py + r12 * pz + t1
        x2 = r20 * px + r21 * py + r22 * pz + t2
        V[u, 0], V[u, 1], V[u, 2] = x0, x1, x2
        if x2 < zlo:
            zlo, ilo = x2, u
        if x2 > zhi:
            zhi, ihi = x2, u
        sd = x0 * hx + x1 * hy
        if sd < smin:
            smin, imin = sd, u
        # (no branch: whether a vertex lies inside is random)
        rho = math.sqrt(x0 * x0 + x1 * x1)
        X[u, 0] = rho
        L = max(L, min(big_h - abs(x2), big_r - rho))
    inside = inside or L > 0.0
    # B wholly beyond the side's tangent plane at R h
    if smin - big_r > stop:
        u = imin
        _out(res, side, r_ab, t_ab, big_r - smin, hx, hy, 0.0, big_r * hx, big_r * hy,
             min(max(V[u, 2], -big_h), big_h), V[u, 0], V[u, 1], V[u, 2])
        return PRE_APART
    # B wholly above the top cap's plane or below the bottom's
    for si in range(2):
        gap = zlo - big_h if si == 0 else -zhi - big_h
        if gap > stop:
            s = 1.0 if si == 0 else -1.0
            u = ilo if si == 0 else ihi
            ax, ay, az = _cap_point(big_r, big_h, s, V[u, 0], V[u, 1])
            _out(res, side, r_ab, t_ab, -gap, 0.0, 0.0, s, ax, ay, az, V[u, 0], V[u, 1],
                 V[u, 2])
            return PRE_APART
    # the pruning below holds only for a pair that overlaps: proved by the caller (GJK),
    # a hull vertex inside C, C's centre inside B, or else C's point nearest B's origin
    # inside B (half of the deep pairs the first two leave, in the benchmark's row;
    # the loop ends at the first face it lies beyond, so it is cheap where it fails)
    if not (overlap or inside):
        rho = math.sqrt(t0 * t0 + t1 * t1)
        k = big_r / rho if rho > big_r else 1.0
        q0, q1, q2 = k * t0 - t0, k * t1 - t1, min(max(t2, -big_h), big_h) - t2
        # in the hull's frame: r^T (q - t)
        h0 = r00 * q0 + r10 * q1 + r20 * q2
        h1 = r01 * q0 + r11 * q1 + r21 * q2
        h2 = r02 * q0 + r12 * q1 + r22 * q2
        proved = True
        for f in range(nf):
            if not (verts[fnr + f, 0] * h0 + verts[fnr + f, 1] * h1
                    + verts[fnr + f, 2] * h2 < fl[f]):
                proved = False
                break
        if not proved:
            # else GJK's boolean form on B - C (_cyl_gjk)
            g, gap, mx, my, mz, u = _cyl_gjk(V, fl, nf, nvx, big_r, big_h, t0, t1, t2,
                                             stop)
            if g == 0:
                return PRE_UNPROVED
            if g == 2:
                ax, ay, az = _cyl_point(big_r, big_h, mx, my, mz)
                _out(res, side, r_ab, t_ab, -gap, mx, my, mz, ax, ay, az, V[u, 0],
                     V[u, 1], V[u, 2])
                return PRE_APART
    # the best candidate: its value U, normal n and C's witness a (B's is a - U n)
    U = np.inf
    nx = ny = nz = ax = ay = az = 0.0
    for f in range(nf):
        fx, fy, fz = verts[fnr + f, 0], verts[fnr + f, 1], verts[fnr + f, 2]
        mx = r00 * fx + r01 * fy + r02 * fz
        my = r10 * fx + r11 * fy + r12 * fz
        mz = r20 * fx + r21 * fy + r22 * fz
        sm = math.sqrt(mx * mx + my * my)
        val = Q[f, 1] + big_r * sm + big_h * abs(mz)
        if not val > 0.0:
            # C wholly beyond the face's plane (or NaN)
            if -val > stop:
                _apart_out(res, side, r_ab, t_ab, pts, fl, nf, nvx, fx, fy, fz, mx, my,
                           mz, big_r, big_h, -val)
                return PRE_APART
            return PRE_UNDECIDED
        M[f, 0], M[f, 1], M[f, 2] = mx, my, mz
        Q[f, 0], Q[f, 2] = val, big_r / sm if sm > 0.0 else 0.0
        if val < U:
            U = val
            nx, ny, nz = -mx, -my, -mz
            ax, ay, az = _cyl_point(big_r, big_h, nx, ny, nz)
    # the poles: a cap over B's lowest vertex (n = z) or under its highest (n = -z)
    for si in range(2):
        val = big_h - zlo if si == 0 else big_h + zhi
        if val < U:
            s = 1.0 if si == 0 else -1.0
            u = ilo if si == 0 else ihi
            U = val
            nx, ny, nz = 0.0, 0.0, s
            ax, ay, az = V[u, 0], V[u, 1], s * big_h
    # the side against a vertex: n = v_xy / |v_xy|, f = R - |v_xy|, a candidate only
    # at least L (else it is not in the vertex's cone)
    for i in range(nvx):
        u = np.uint64(int(fl[nf + i]))
        rho = X[u, 0]
        val = big_r - rho
        if not (val < U and val >= L - tol and rho > 0.0):
            continue
        mx, my = V[u, 0] / rho, V[u, 1] / rho
        # in the vertex's cone: B's support along -n attained at it (within tol)
        if _vertex_top(V, fl, nf, nvx, -mx, -my, 0.0)[0] > -rho + tol:
            continue
        U = val
        nx, ny, nz = mx, my, 0.0
        ax, ay, az = big_r * mx, big_r * my, V[u, 2]
    slack = tol + HE_FAN_SLACK * scale
    for e in range(ne):
        q = fe + 4 * e
        f1, f2 = np.uint64(int(fl[q + 2])), np.uint64(int(fl[q + 3]))
        # f on the arc is at least the larger of its tangent planes at the ends,
        # P_i(n) = (s_i - v) . n, v the edge's point; P_1(n2) = o2 - s_1 . m2 with v on
        # face 2's plane (within the fan's tolerance), P_2(n1) likewise.  Over the chord
        # the larger is least where the two cross, at the weights (d2, d1) of their
        # gaps d_i = g_i - P_j(n_i) >= 0, and the arc lies beyond the chord (f is
        # homogeneous and > 0)
        g1, g2 = Q[f1, 0], Q[f2, 0]
        m1x, m1y, m1z = M[f1, 0], M[f1, 1], M[f1, 2]
        m2x, m2y, m2z = M[f2, 0], M[f2, 1], M[f2, 2]
        # C's support points along -m1, -m2: s_i = -(k_i m_i,x, k_i m_i,y, H sgn m_i,z)
        # (copysign: no branch on the signs, which are random; +-H alike at m_i,z = 0)
        k1, k2 = Q[f1, 2], Q[f2, 2]
        z1, z2 = math.copysign(big_h, -m1z), math.copysign(big_h, -m2z)
        mxy = m1x * m2x + m1y * m2y
        c12 = Q[f2, 1] + k1 * mxy - z1 * m2z
        c21 = Q[f1, 1] + k2 * mxy - z2 * m1z
        d1, d2 = g1 - c21, g2 - c12
        if (d1 >= 0.0 and d2 >= 0.0 and d1 + d2 > 0.0
                and d2 * g1 + d1 * c12 >= (U - slack) * (d1 + d2)):
            continue
        ia, ib = int(fl[q]), int(fl[q + 1])
        vx, vy, vz = V[ia, 0], V[ia, 1], V[ia, 2]
        n1x, n1y, n1z = -m1x, -m1y, -m1z
        n2x, n2y, n2z = -m2x, -m2y, -m2z
        s1x, s1y, s1z = -k1 * m1x - vx, -k1 * m1y - vy, z1 - vz
        s2x, s2y, s2z = -k2 * m2x - vx, -k2 * m2y - vy, z2 - vz
        c12 = s1x * n2x + s1y * n2y + s1z * n2z
        c21 = s2x * n1x + s2y * n1y + s2z * n1z
        if _planes_on_arc(s1x, s1y, s1z, s2x, s2y, s2z, n1x, n1y, n1z, n2x, n2y, n2z,
                          g1 - c21, c12 - g2) >= U - tol:
            continue
        # the arc's great circle: basis p = n1, q = e x p; n2 = cq p + sq q
        ex, ey, ez = V[ib, 0] - vx, V[ib, 1] - vy, V[ib, 2] - vz
        el = math.sqrt(ex * ex + ey * ey + ez * ez)
        ex, ey, ez = ex / el, ey / el, ez / el
        px, py, pz = n1x, n1y, n1z
        qx, qy, qz = ey * pz - ez * py, ez * px - ex * pz, ex * py - ey * px
        cq = n2x * px + n2y * py + n2z * pz
        sq = n2x * qx + n2y * qy + n2z * qz
        # the side: the equator meets the circle at +-w, w = z x e / |z x e|
        wl = math.sqrt(ex * ex + ey * ey)
        if not wl > PARALLEL_SIN:
            return PRE_UNDECIDED
        wx, wy = -ey / wl, ex / wl
        ap, aq = wx * px + wy * py, wx * qx + wy * qy
        if not _in_arc(ap, aq, cq, sq):
            wx, wy, ap, aq = -wx, -wy, -ap, -aq
        cross = _in_arc(ap, aq, cq, sq)
        fw = big_r - (wx * vx + wy * vy)
        if cross:
            val = fw
            if val < U:
                # B's witness: the edge's point b = v + lam e on the side's line at R w,
                # t . b = 0 for t = z x w (t . e = -|z x e| != 0)
                lam = (wy * vx - wx * vy) / (wx * ey - wy * ex)
                lam = min(max(lam, 0.0), el)
                U = val
                nx, ny, nz = wx, wy, 0.0
                ax, ay, az = vx + lam * ex + val * wx, vy + lam * ey + val * wy, vz + lam * ez
        # the rims: C is the disk of the cap at s H there (its squared semi-axes R^2,
        # R^2, 0), for the part of the arc in the hemisphere s n_z > 0
        for si in range(2):
            s = 1.0 if si == 0 else -1.0
            if not (s * n1z > 0.0 or s * n2z > 0.0):
                continue
            if cross:
                # this rim's part of the arc runs from the end in its hemisphere to w,
                # where f's tangent plane is the rim's (C's support point R w + s H z):
                # the larger of the two planes bounds f over it
                if s * n1z > 0.0:
                    sex, sey, sez, nex, ney, nez, ge = s1x, s1y, s1z, n1x, n1y, n1z, g1
                else:
                    sex, sey, sez, nex, ney, nez, ge = s2x, s2y, s2z, n2x, n2y, n2z, g2
                swx, swy, swz = big_r * wx - vx, big_r * wy - vy, s * big_h - vz
                if _planes_on_arc(sex, sey, sez, swx, swy, swz, nex, ney, nez, wx, wy, 0.0,
                                  ge - (swx * nex + swy * ney + swz * nez),
                                  sex * wx + sey * wy - fw) >= U - tol:
                    continue
            dz = vz - s * big_h
            g11 = r2 * (px * px + py * py)
            g12 = r2 * (px * qx + py * qy)
            g22 = r2 * (qx * qx + qy * qy)
            wp, wq = px * vx + py * vy + pz * dz, qx * vx + qy * vy + qz * dz
            k, ux, uy, P0, P1, lam0, lam1 = _plane_feet(g11, g12, g22, wp, wq, U, scale,
                                                        roots)
            if k < 0:
                return PRE_UNDECIDED
            for r in range(k):
                val, bp, bq = plane_foot(roots[r], P0, P1, lam0, lam1, ux, uy)
                if not val < U:
                    continue
                mx, my, mz = bp * px + bq * qx, bp * py + bq * qy, bp * pz + bq * qz
                rho = math.sqrt(mx * mx + my * my)
                if not (s * mz > 0.0 and rho > 0.0 and _in_arc(bp, bq, cq, sq)):
                    continue
                U = val
                nx, ny, nz = mx, my, mz
                ax, ay, az = big_r * mx / rho, big_r * my / rho, s * big_h
    if not math.isfinite(U):
        return PRE_UNDECIDED
    _out(res, side, r_ab, t_ab, U, nx, ny, nz, ax, ay, az, ax - U * nx, ay - U * ny,
         az - U * nz)
    return PRE_EXACT


@njit_inline
def _shadow_closest(ax, ay, bx, by):
    """The point of the segment [a, b] (2-D) nearest the origin, as (t, x, y) with
    t in [0, 1] its parameter from a."""
    ex, ey = bx - ax, by - ay
    ee = ex * ex + ey * ey
    t = 0.0
    if ee > 0.0:
        t = min(1.0, max(0.0, -(ax * ex + ay * ey) / ee))
    return t, ax + t * ex, ay + t * ey


@njit_separate
def _cylinder_convex_ball_bound(sa, sb, verts, r_ab, t_ab, scale, res):
    """The core depth (> 0) of a convex hull and a cylinder (either order), certified by
    the ball of cylinder_common.py, with res (10,) as _cylinder_cylinder_bound's, or minus
    the gap (< 0) when
    a plane proves the cores apart (as _cylinder_cylinder_bound); 0 (res untouched) when
    neither.  The hull's points are its vertices (verts, body frame) and their convex
    combinations; the candidates are hull points in the cylinder's frame:
      - for each cap, the hull's lowest vertex p under the cap's plane: h along the
        cap's normal is its gap to the plane, exactly, and a gap <= 0 proves the cores
        apart; p's ball certifies h, or where the side cuts it short, _cover's bound
        from the segments p to the vertex nearest the axis, to the highest vertex and
        to their midpoint;
      - against the side, q = the hull's point nearest the cylinder's axis, i.e. the
        point of the hull's shadow on the plane square to the axis nearest the axis's
        foot: GJK in two dimensions over the shadow (its support is the hull's along a
        horizontal direction, one pass over the vertices; the simplex at most a
        segment, whose two vertices are hull points, so q lifts to a hull point).  At
        its end, the support pass along -m (m = q_xy / |q_xy|) gives h along the side
        normal at q, R - min over the hull of m . x, and q's ball certifies it where the
        caps leave the ball whole, else _cover's bound from the segments q to the
        hull's lowest and highest vertices and to the last support point; a pass whose
        minimum lies beyond R proves the cores apart.  The shadow holding the axis's
        foot (a triangle of the simplex around it) leaves no side candidate.
    Nothing depends on the 2-D GJK's converging: any hull point's ball is a lower bound
    and any support pass an upper one; only their meeting within EPA_REL_TOL * scale
    certifies.  The side is what a hull's corner or edge pressed into a cylinder takes;
    a cylinder's rim pressed into a hull's face (its normal the face's) is left to GJK
    and EPA, as no hull faces are kept.
    Measured on bench/dev/deep_pairs.py's 2,000 cylinder-convex cases (this function run
    with NUMBA_DISABLE_JIT, GJK + EPA the reference): 240 of the 953 pairs whose
    cores overlap by more than 1e-3 * scale certified (183 by a ball, 170 of them by the
    side and 13 by a cap, the rest by _cover; and 17 pairs overlapping less), depths
    within 9.3e-9 * scale of EPA's (its nearest face), normals within 2.2e-4 rad; 856
    of the 2,000 proved apart, 457 of them pairs whose bounding spheres overlap (those
    the batch kernel hands to GJK)."""
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    res = borrow(res)
    side = 0 if sa[0] != CYLINDER else 1
    hull = sa if side == 0 else sb
    cyl = sb[1] if side == 0 else sa[1]
    big_r, big_h = cyl[0], cyl[1]
    cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz = _frame(side, r_ab, t_ab)
    pts = verts[hull[2]:hull[2] + hull[3]]
    nv = pts.shape[0]
    if nv == 0:
        return 0.0
    tol = EPA_REL_TOL * scale
    # one pass: the lowest and highest vertices and the one nearest the axis
    zlo, zhi, rmin = math.inf, -math.inf, math.inf
    ilo = ihi = inear = np.int64(0)
    for i in range(nv):
        x, y, z = _hull_point(pts, i, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
        if z < zlo:
            zlo, ilo = z, i
        if z > zhi:
            zhi, ihi = z, i
        rr = x * x + y * y
        if rr < rmin:
            rmin, inear = rr, i
    for si in range(2):
        s = 2.0 * si - 1.0
        i = ilo if s > 0.0 else ihi
        px, py, pz = _hull_point(pts, i, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
        d = _cap_test(res, side, r_ab, t_ab, s, big_r, big_h, tol, px, py, pz)
        if d != 0.0:
            return d
        # its ball cut short by the side: the cover (_cover) from p to the vertex
        # nearest the axis, to the highest (along -s z) and to their midpoint
        ax, ay, az = _hull_point(pts, inear, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
        tx, ty, tz = _hull_point(pts, ihi if s > 0.0 else ilo, cx, cy, cz, ux, uy, uz, vx,
                                 vy, vz, kx, ky, kz)
        h = big_h - s * pz
        if _cover(np.bool_(False), s, px, py, pz, big_r, big_h, ax - px, ay - py, az - pz, tx - px,
                  ty - py, tz - pz, 0.5 * (ax + tx) - px, 0.5 * (ay + ty) - py,
                  0.5 * (az + tz) - pz) >= h - tol:
            nx, ny, nz = _cap_normal(side, r_ab, s)
            _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, px, py, pz)
            return h
    # the side: GJK on the shadow, the simplex [a, b] (b used when two), q on it
    ax, ay, az = _hull_point(pts, inear, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
    bx = by = bz = 0.0
    two = False
    qx, qy, qz = ax, ay, az
    for _ in range(HC_GJK_ITERS):
        qq = qx * qx + qy * qy
        if not qq > 0.0:
            return 0.0
        # the hull's support along -q_xy (min over the vertices of q_xy . x)
        dx = qx * ux + qy * uy
        dy = qx * vx + qy * vy
        dz = qx * kx + qy * ky
        low = math.inf
        j = np.int64(0)
        for i in range(nv):
            val = pts[i, 0] * dx + pts[i, 1] * dy + pts[i, 2] * dz
            if val < low:
                low, j = val, i
        q = math.sqrt(qq)
        g = (qx * cx + qy * cy + low) / q       # min over the hull of m . x
        wx, wy, wz = _hull_point(pts, j, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz)
        if g > big_r:
            # the hull lies beyond the side's tangent plane along m: cores apart
            return _past_side(res, g, side, r_ab, t_ab, qx / q, qy / q, big_r, big_h,
                              wx, wy, wz)
        if q - g <= tol:
            # q's support plane: q is the shadow's nearest point; h = R - g along m
            h = big_r - g
            ball = cylinder_inradius(big_r, big_h, qx, qy, qz)
            if not (ball > 0.0 and ball >= h - tol):
                # cut short by a cap: the cover (_cover) from q to the hull's lowest
                # and highest vertices and to w
                lx, ly, lz = _hull_point(pts, ilo, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx,
                                         ky, kz)
                tx, ty, tz = _hull_point(pts, ihi, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx,
                                         ky, kz)
                ball = _cover(np.bool_(True), 0.0, qx, qy, qz, big_r, big_h, lx - qx, ly - qy,
                              lz - qz, tx - qx, ty - qy, tz - qz, wx - qx, wy - qy, wz - qz)
            if not (ball > 0.0 and ball >= h - tol):
                return 0.0
            nx, ny, nz = _side_normal(side, r_ab, qx / q, qy / q)
            _certified_out(res, h, nx, ny, nz, side, r_ab, t_ab, qx, qy, qz)
            return h
        if not two:
            t, sx, sy = _shadow_closest(ax, ay, wx, wy)
            if t >= 1.0:
                ax, ay, az = wx, wy, wz
            elif t > 0.0:
                bx, by, bz = wx, wy, wz
                two = True
        else:
            # the origin inside the triangle a, b, w: the shadow holds the axis's foot
            c1 = (bx - ax) * (-ay) - (by - ay) * (-ax)
            c2 = (wx - bx) * (-by) - (wy - by) * (-bx)
            c3 = (ax - wx) * (-wy) - (ay - wy) * (-wx)
            if (c1 >= 0.0 and c2 >= 0.0 and c3 >= 0.0) or (c1 <= 0.0 and c2 <= 0.0
                                                            and c3 <= 0.0):
                return 0.0
            t, sx, sy = _shadow_closest(ax, ay, wx, wy)
            t2, sx2, sy2 = _shadow_closest(bx, by, wx, wy)
            if sx2 * sx2 + sy2 * sy2 < sx * sx + sy * sy:
                # the edge b w: a <- b
                t, sx, sy = t2, sx2, sy2
                ax, ay, az = bx, by, bz
            if t >= 1.0:
                ax, ay, az = wx, wy, wz
                two = False
            elif t > 0.0:
                bx, by, bz = wx, wy, wz
            else:
                two = False
        if not sx * sx + sy * sy < qq:
            return 0.0              # no progress (round-off): no side candidate
        if two:
            ex, ey, ez = bx - ax, by - ay, bz - az
            qx, qy, qz = ax + t * ex, ay + t * ey, az + t * ez
        else:
            qx, qy, qz = ax, ay, az
    return 0.0


@njit_inline
def collide_cylinder_convex_ball(sa, sb, verts, r_ab, t_ab, scale, stop, res):
    """What gjk_epa.gjk_epa_ws learns before GJK for any convex hull and a cylinder, by the
    ball (constants.PRE_*): PRE_EXACT with res[:10] the cores' certified depth, normal and
    points (_cylinder_convex_ball_bound), PRE_APART when a plane proves the cores farther
    apart than ``stop`` (m; res the bound), else PRE_UNDECIDED."""
    return pre_outcome(_cylinder_convex_ball_bound(sa, sb, verts, r_ab, t_ab, scale, res), stop)


@njit_inline
def _hull_point(pts, i, cx, cy, cz, ux, uy, uz, vx, vy, vz, kx, ky, kz):
    """Vertex i of pts (the hull's frame) in the cylinder's frame (c, u, v, k: the
    hull's centre and axes there, as _frame gives them)."""
    p0, p1, p2 = pts[i, 0], pts[i, 1], pts[i, 2]
    return (cx + p0 * ux + p1 * vx + p2 * kx, cy + p0 * uy + p1 * vy + p2 * ky,
            cz + p0 * uz + p1 * vz + p2 * kz)
