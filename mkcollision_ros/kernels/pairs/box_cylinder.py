"""Exact penetration depth of a box and a cylinder whose cores overlap, in closed form
with a certificate, instead of GJK and EPA (gjk_epa.gjk_epa_ws calls it first for such a
pair; where it cannot certify that the cores overlap and what the depth is, it returns
PRE_UNDECIDED and GJK and EPA run as for any pair).

The problem.  In the cylinder's frame (axis z, radius r, half height hc) let the box
have centre c, unit axes a_i and half extents e_i.  For a unit direction m (from the
box to the cylinder) the support function of box - cylinder is

    f(m) = c . m + sum_i e_i |a_i . m| + r sqrt(m_x^2 + m_y^2) + hc |m_z|,

and when the origin lies inside box - cylinder the depth is min f over the unit sphere
(minus the signed distance; the minimiser is the contact normal).

Where a positive minimum can lie.  f is smooth except on the three great circles
a_i . m = 0 (the box's edges), the crease m_z = 0 (the cylinder's side) and the poles
m = +-z (its caps).  Inside a cell of that arrangement f is the support function of a
flat disc (a box vertex plus the rim), and the support function of a flat convex set
has no positive local minimum on the sphere (along the disc's zero-curvature direction
its second derivative is -f < 0).  So a positive minimum lies
  1. at a box face normal +-a_i (a box face against a rim point),
  2. at +-(z x a_i)/|z x a_i| (a box edge against a side line: a flat parallelogram),
  3. at a pole +-z (a box vertex against a cap),
  4. on a box circle, between its kinks (a box edge against a rim point), or
  5. on the crease, between its kinks: there f = (box vertex w) . m + r, whose minimum
     along the crease is at m = -(w_x, w_y, 0) / |(w_x, w_y)|.
Types 1, 2, 3 and 5 are 22 candidate directions in closed form; f is evaluated at each
(those values are exact depths of some direction, so their least, UB, bounds the depth
from above).  Each box circle is then bounded from below, arc by arc, and the answer is
certified when no circle can hold a value below UB - EPA_REL_TOL * scale; type 4 is
found there, where an arc's bound fails (the nearest boundary point of an ellipse).

Proof of overlap, without GJK.  The reasoning above needs the origin inside box -
cylinder, i.e. f > 0 on the whole sphere.  The candidates and the circles' bounds give
f >= UB - tol > 0 on the box circles, the crease and the poles; inside a cell, f is
the support function g of the cell's flat disc, convex and positively homogeneous on
R^3, so if f < 0 somewhere in the cell, g's least value over the cell's cone is either
on its border (excluded) or g's global minimum over the sphere, at -x / |x| for x the
disc's point nearest the origin, which then lies in the cell (_cells_positive tests the
16 cells).  A pair that only touches fails one of these (f ~ 0 over the normal cone of
the touching point), and GJK/EPA handle it.

Proof of separation, without GJK.  f(m) < 0 for a unit m means every point of box -
cylinder lies at least -f(m) below the origin along m: the cores are at least that far
apart.  So the first test, f along the line of centres, and the candidates, which
hold the box's face normals and the pole as a separating axis test would, end most
pairs apart with that gap as the distance bound (_apart_out; gjk_epa.gjk_epa_ws takes
it in contacts mode when it clears the touching band, as cylinder_common's planes).  Measured
(pure Python, bench/dev/deep_pairs.py's 2,000 box-cylinder cases, both orders): 925 of the
961 pairs apart end here (of those, GJK would end about half at its first support and
take 4-8 steps on the rest); no bound lies above GJK's exact distance by more than
1.1e-13 m, at scales of about 1 m (inside GJK's own tolerance, 1e-12 * scale).

The bound on a box circle.  On the circle normal to a_i, in the plane of a_j, a_k,
f is the support function of a 2-D convex set: the box's rectangle plus the projected
side line plus the projected rim (an ellipse).  Its kinks (+-a_j, +-a_k and the two
crease crossings) cut it into at most 8 arcs on which the rectangle's vertex W and the
side line's end are fixed; on an arc f(d) = W . d + h_E(d), h_E the ellipse's support
function.  A crude bound (min of W . d over the arc plus the least of h_E over it,
where |d . z| is largest) drops most arcs.  On the rest, with the exact support points p, q of the
set at the arc's two ends, f >= max(p . d, q . d) over the arc (both are points of the
set), whose least value is closed form (at an end, at the direction normal to q - p, or
opposite p or q); an arc whose bound is too low is halved, at most BC_MAX_LEVEL times.
At a minimum of type 1 or 2 on the circle, the end's support point is exact and f rises
to first order into the arc, so the bound does too and is certified.  At a minimum
inside an arc (type 4) the chord's sag stays below it: after two halvings the arc's set
(rectangle vertex plus side-line end plus the projected rim, an ellipse) gives the
exact least support value over all directions, its distance from the origin to the
ellipse's boundary (_ellipse_floor): a bound for the arc, and the arc's minimum when
its direction lies on the arc.  A kink minimum whose first-order rise vanishes, or an
arc whose ellipse minimum lies outside it and below UB, is left to EPA.

Measured (pure-Python runs of gjk_epa_ws on bench.common.pair_cases("box",
"cylinder", 400, seed=3), 204 penetrating pairs): 200 certified (85 of type 2, 64 of
type 1, 17 each of types 3, 4 and 5), 4 left to EPA; depths within 9.8e-9 * scale of
EPA's (EPA's own tolerance: it reports its nearest face, below the true depth),
normals within 3e-4 rad (EPA's error on the curved ones).

Witness points (pb - pa == -depth * n exactly, after meet): types 1 and 4, the rim
point and its translate on the box face or edge; type 2, the crossing of the box edge
and the side line (a 2x2 solve); types 3 and 5, the box vertex and its translate on the
cylinder.  When
the winning direction's features are not the expected ones (a box axis within 1e-9 of
normal to it, a face normal along the crease or the axis), 0 is returned and EPA runs:
axis-aligned scenes keep EPA's handling of face-to-face contacts.
"""
import math

from ..constants import (BC_FEAT, BC_MAX_LEVEL, BC_ROOT_ITERS, BC_ROOT_STOP, BOX, DIV_FLOOR,
                         EPA_REL_TOL, NO_DIRECTION, SUPPORT_TIE)
from ..geometry import borrow_pose, meet
from ..jit import borrow, njit_inline, njit_separate
from .cylinder_common import pre_outcome


@njit_inline
def _f(A, c, e, r, hc, mx, my, mz):
    """f(m) above; A (3, 3) the box axes as rows, c its centre, e its half extents."""
    v = c[0] * mx + c[1] * my + c[2] * mz
    for i in range(3):
        v += e[i] * abs(A[i, 0] * mx + A[i, 1] * my + A[i, 2] * mz)
    return v + r * math.sqrt(mx * mx + my * my) + hc * abs(mz)


@njit_inline
def _rim_2d(A, r, j, k, n1, n2, d1, d2):
    """The rim's support point at the direction n1 a_j + n2 a_k, in (a_j, a_k)
    coordinates; (d1, d2) a direction of the same arc, used when that one is +-z (then
    any rim point is a support point, and one of the arc's is exact at its inside)."""
    mx = n1 * A[j, 0] + n2 * A[k, 0]
    my = n1 * A[j, 1] + n2 * A[k, 1]
    s = math.sqrt(mx * mx + my * my)
    if not s > DIV_FLOOR:
        mx = d1 * A[j, 0] + d2 * A[k, 0]
        my = d1 * A[j, 1] + d2 * A[k, 1]
        s = math.sqrt(mx * mx + my * my)
    px, py = r * mx / s, r * my / s
    return px * A[j, 0] + py * A[j, 1], px * A[k, 0] + py * A[k, 1]


@njit_inline
def _in_arc(ux, uy, vx, vy, x, y):
    """Whether the direction (x, y) lies between u and v (counterclockwise, < pi)."""
    return ux * y - uy * x >= 0.0 and x * vy - y * vx >= 0.0


@njit_inline
def _chord_bound(ux, uy, vx, vy, px, py, qx, qy):
    """Least value over the directions d between u and v of max(p . d, q . d)."""
    lb = min(max(px * ux + py * uy, qx * ux + qy * uy),
             max(px * vx + py * vy, qx * vx + qy * vy))
    dx, dy = qx - px, qy - py
    dn = math.sqrt(dx * dx + dy * dy)
    if dn > 0.0:
        x, y = -dy / dn, dx / dn
        if _in_arc(ux, uy, vx, vy, x, y):
            lb = min(lb, px * x + py * y)
        if _in_arc(ux, uy, vx, vy, -x, -y):
            lb = min(lb, -(px * x + py * y))
    pn = math.sqrt(px * px + py * py)
    if pn > 0.0 and _in_arc(ux, uy, vx, vy, -px, -py):
        lb = min(lb, max(-pn, -(qx * px + qy * py) / pn))
    qn = math.sqrt(qx * qx + qy * qy)
    if qn > 0.0 and _in_arc(ux, uy, vx, vy, -qx, -qy):
        lb = min(lb, max(-qn, -(px * qx + py * qy) / qn))
    return lb


@njit_inline
def _candidates(A, c, e, r, hc):
    """The least f over the closed-form candidates (types 1, 2, 3, 5): (value, type,
    mx, my, mz)."""
    best = math.inf
    bt = 0
    bx = by = bz = 0.0
    for i in range(3):
        ax, ay, az = A[i, 0], A[i, 1], A[i, 2]
        ca = c[0] * ax + c[1] * ay + c[2] * az
        dn = math.sqrt(ax * ax + ay * ay)
        # type 1: f(+-a_i) = +-c . a_i + e_i + r |a_i,xy| + hc |a_i,z|
        v = e[i] + r * dn + hc * abs(az) - abs(ca)
        if v < best:
            s = -1.0 if ca > 0.0 else 1.0
            best, bt = v, 1
            bx, by, bz = s * ax, s * ay, s * az
        if dn > NO_DIRECTION:
            # type 2: m = +-(z x a_i) / |.|, horizontal
            mx, my = -ay / dn, ax / dn
            cm = c[0] * mx + c[1] * my
            v = r - abs(cm)
            for j in range(3):
                if j != i:
                    v += e[j] * abs(A[j, 0] * mx + A[j, 1] * my)
            if v < best:
                s = -1.0 if cm > 0.0 else 1.0
                best, bt = v, 2
                bx, by, bz = s * mx, s * my, 0.0
    # type 3: the poles
    v = hc - abs(c[2])
    for i in range(3):
        v += e[i] * abs(A[i, 2])
    if v < best:
        best, bt = v, 3
        bx, by, bz = 0.0, 0.0, (-1.0 if c[2] > 0.0 else 1.0)
    # type 5: along the crease, opposite each box vertex (f >= r - |w_xy| there)
    for q in range(8):
        wx, wy = c[0], c[1]
        for i in range(3):
            s = 1.0 if (q >> i) & 1 else -1.0
            wx += s * e[i] * A[i, 0]
            wy += s * e[i] * A[i, 1]
        wn = math.sqrt(wx * wx + wy * wy)
        if r - wn < best and wn > 0.0:
            mx, my = -wx / wn, -wy / wn
            v = _f(A, c, e, r, hc, mx, my, 0.0)
            if v < best:
                best, bt = v, 5
                bx, by, bz = mx, my, 0.0
    return best, bt, bx, by, bz


@njit_inline
def _ellipse_floor(w1, w2, zj, zk, r, az):
    """On the circle normal to box axis i (2-D coordinates along a_j, a_k), f is over
    each arc the support function of K = (w1, w2) + E, E the projected rim: semi-axes
    r across (zj, zk) and r |az| along it (az = a_i . z).  Returns (inside, depth, x, y):
    whether the origin is inside K, its distance to K's boundary (the least support
    value of K over all directions, a lower bound of f over the arc) and the direction
    (x, y) where that is attained (the nearest boundary point's outward normal).
    Nearest point of an ellipse from an inside point: D. Eberly, "Distance from a
    point to an ellipse, an ellipsoid, or a hyperellipsoid" (2013): the root of a
    convex decreasing function, here by Newton's method from the left of the root
    (monotone, no overshoot)."""
    zn = math.sqrt(zj * zj + zk * zk)
    e0, e1 = r, r * abs(az)
    if not (zn > 0.0 and e1 > SUPPORT_TIE * r):
        return False, 0.0, 0.0, 0.0
    # ellipse frame: u = across (zk, -zj) / zn (semi-axis e0), v = along (semi-axis e1)
    ux, uy, vx, vy = zk / zn, -zj / zn, zj / zn, zk / zn
    y0, y1 = -(w1 * ux + w2 * uy), -(w1 * vx + w2 * vy)    # the origin, from the centre
    if not (y0 / e0) ** 2 + (y1 / e1) ** 2 < 1.0:
        return False, 0.0, 0.0, 0.0
    s0 = -1.0 if y0 < 0.0 else 1.0
    s1 = -1.0 if y1 < 0.0 else 1.0
    y0, y1 = abs(y0), abs(y1)
    if y1 > 0.0:
        if y0 > 0.0:
            z0, z1 = y0 / e0, y1 / e1
            r0 = (e0 / e1) ** 2
            t = -1.0 + z1                   # F(t) >= 0 here
            for _ in range(BC_ROOT_ITERS):
                a0, a1 = r0 * z0 / (t + r0), z1 / (t + 1.0)
                g = a0 * a0 + a1 * a1 - 1.0
                if not g > 0.0:
                    break
                dg = -2.0 * (a0 * a0 / (t + r0) + a1 * a1 / (t + 1.0))
                step = -g / dg
                t += step
                if not step > BC_ROOT_STOP * (1.0 + abs(t)):
                    break
            x0, x1 = r0 * y0 / (t + r0), y1 / (t + 1.0)
        else:
            x0, x1 = 0.0, e1
    else:
        if y0 < (e0 * e0 - e1 * e1) / e0:
            x0 = e0 * e0 * y0 / (e0 * e0 - e1 * e1)
            x1 = e1 * math.sqrt(max(0.0, 1.0 - (x0 / e0) ** 2))
        else:
            x0, x1 = e0, 0.0
    dist = math.sqrt((x0 - y0) ** 2 + (x1 - y1) ** 2)
    n0, n1 = s0 * x0 / (e0 * e0), s1 * x1 / (e1 * e1)
    nn = math.sqrt(n0 * n0 + n1 * n1)
    n0, n1 = n0 / nn, n1 / nn
    return True, dist, n0 * ux + n1 * vx, n0 * uy + n1 * vy


@njit_inline
def _circle_certified(A, c, e, r, hc, i, best, tol, stack, cand):
    """Whether f >= best - tol on the whole great circle normal to box axis i (see
    the module doc), and the least f found: returns (certified, best).  Where a part of
    an arc is not certified after two halvings, the nearest-boundary-point bound of the
    arc's set (_ellipse_floor) is tried once; if its direction lies on the arc, that is
    the arc's minimum (type 4): when below best it becomes the new best and its
    direction is written to ``cand`` (3,).  ``stack`` (>= BC_MAX_LEVEL + 2, 3) is
    scratch for the halving."""
    lim = best - tol
    j, k = (i + 1) % 3, (i + 2) % 3
    zj, zk = A[j, 2], A[k, 2]
    zn = math.sqrt(zj * zj + zk * zk)
    if not zn > NO_DIRECTION:
        return True, best       # the circle is the crease: the candidates cover it
    cj = c[0] * A[j, 0] + c[1] * A[j, 1] + c[2] * A[j, 2]
    ck = c[0] * A[k, 0] + c[1] * A[k, 1] + c[2] * A[k, 2]
    # the crease crosses the circle at +-(ncx, ncy)
    ncx, ncy = zk / zn, -zj / zn
    rmin = r * abs(A[i, 2])     # the ellipse's least support
    ux, uy = 1.0, 0.0
    for q in range(4):
        vx, vy = -uy, ux
        sx, sy = ncx, ncy
        if not (ux * sy - uy * sx > 0.0 and sx * vy - sy * vx > 0.0):
            sx, sy = -ncx, -ncy
        split = ux * sy - uy * sx > 0.0 and sx * vy - sy * vx > 0.0
        for piece in range(2 if split else 1):
            if not split:
                ax, ay, bx, by = ux, uy, vx, vy
            elif piece == 0:
                ax, ay, bx, by = ux, uy, sx, sy
            else:
                ax, ay, bx, by = sx, sy, vx, vy
            # the arc's rectangle vertex and side-line end, from its middle direction
            hx, hy = ax + bx, ay + by
            sg = hc if hx * zj + hy * zk > 0.0 else -hc
            w1 = cj + (e[j] if hx > 0.0 else -e[j]) + sg * zj
            w2 = ck + (e[k] if hy > 0.0 else -e[k]) + sg * zk
            if ax * w2 - ay * w1 <= 0.0 and w1 * by - w2 * bx <= 0.0:
                lw = -math.sqrt(w1 * w1 + w2 * w2)
            else:
                lw = min(w1 * ax + w2 * ay, w1 * bx + w2 * by)
            if lw + rmin >= lim:
                continue                # (the bound below, weaker: no square root)
            # the ellipse's least support over the arc: where |zeta . d| is largest
            ta, tb = zj * ax + zk * ay, zj * bx + zk * by
            if _in_arc(ax, ay, bx, by, zj, zk) or _in_arc(ax, ay, bx, by, -zj, -zk):
                tm = zn
            else:
                tm = max(abs(ta), abs(tb))
            if lw + r * math.sqrt(max(0.0, 1.0 - tm * tm)) >= lim:
                continue
            # halve until every part's chord bound holds (depth-first)
            floor_tried = False
            stack[0, 0], stack[0, 1], stack[0, 2] = ax, ay, 0.0
            stack[1, 0], stack[1, 1] = bx, by
            top = 1                 # stack[0 .. top] are the arc ends, left to right
            while top > 0:
                px_, py_ = stack[top - 1, 0], stack[top - 1, 1]
                qx_, qy_ = stack[top, 0], stack[top, 1]
                lev = stack[top - 1, 2]
                e1x, e1y = _rim_2d(A, r, j, k, px_, py_, hx, hy)
                e2x, e2y = _rim_2d(A, r, j, k, qx_, qy_, hx, hy)
                lb = _chord_bound(px_, py_, qx_, qy_, w1 + e1x, w2 + e1y,
                                  w1 + e2x, w2 + e2y)
                if lb >= lim:
                    top -= 1            # this part holds: on to the next one
                    continue
                if lev >= 2 and not floor_tried:
                    floor_tried = True
                    inside, fl, nx, ny = _ellipse_floor(w1, w2, zj, zk, r, A[i, 2])
                    if inside and _in_arc(ax, ay, bx, by, nx, ny):
                        # the arc's minimum: a box edge against a rim point
                        mx = nx * A[j, 0] + ny * A[k, 0]
                        my = nx * A[j, 1] + ny * A[k, 1]
                        mz = nx * A[j, 2] + ny * A[k, 2]
                        v = _f(A, c, e, r, hc, mx, my, mz)
                        if v < best:
                            best = v
                            lim = best - tol
                            cand[0], cand[1], cand[2] = mx, my, mz
                        break
                    if inside and fl >= lim:
                        break
                if lev >= BC_MAX_LEVEL:
                    return False, best
                mx, my = px_ + qx_, py_ + qy_
                mn = math.sqrt(mx * mx + my * my)
                # insert the middle direction: [mid, q] is tried first
                stack[top + 1, 0], stack[top + 1, 1] = qx_, qy_
                stack[top, 0], stack[top, 1], stack[top, 2] = mx / mn, my / mn, lev + 1.0
                stack[top - 1, 2] = lev + 1.0
                top += 1
        ux, uy = vx, vy
    return True, best


@njit_inline
def _cells_positive(A, c, e, r, hc):
    """Whether f > 0 inside every cell of the arrangement (the origin is not beyond a
    ridge of box - cylinder).  In the cell of box vertex w and cap side s, f is the
    support function g of the flat disc K = w + s hc z + rim, convex and positively
    homogeneous on R^3; where g < 0 somewhere in the cell, its least value over the
    cell's cone (within the unit ball) is either its global minimum, at -x / |x| for x
    the point of K nearest the origin, inside the cell, or on the cell's border (a box
    circle, the crease or a pole, which the candidates and the circles' bounds cover).
    So it suffices that no cell holds its own -x / |x|."""
    for q in range(8):
        wx, wy, wz = c[0], c[1], c[2]
        for i in range(3):
            s = e[i] if (q >> i) & 1 else -e[i]
            wx += s * A[i, 0]
            wy += s * A[i, 1]
            wz += s * A[i, 2]
        rho = math.sqrt(wx * wx + wy * wy)
        if rho > r:
            xx, xy = wx - r * wx / rho, wy - r * wy / rho
        else:
            xx, xy = 0.0, 0.0
        for side in range(2):
            xz = wz + (hc if side == 0 else -hc)
            # -x / |x| must point to the other cap side: m_z = -xz has the sign of s
            if (xz < 0.0) != (side == 0):
                continue
            xn = math.sqrt(xx * xx + xy * xy + xz * xz)
            if not xn > 0.0:
                return False            # the origin on the disc: touching
            inside = True
            for i in range(3):
                am = -(A[i, 0] * xx + A[i, 1] * xy + A[i, 2] * xz)
                if (am > 0.0) != ((q >> i) & 1 == 1):
                    inside = False
                    break
            if inside:
                return False            # f = -|x| < 0 there: apart
    return True


@njit_inline
def _apart_out(res, box_a, r_ab, t_ab, A, c, e, r, hc, gap, mx, my, mz):
    """Cores proved apart along the unit m (the cylinder's frame, from the box to the
    cylinder) by f(m) = -gap < 0: every point of box - cylinder lies at least gap
    below the origin along m, so the cores are at least gap apart.  res = [-gap, n
    (A to B), pa, pb] in A's frame, pa and pb the two cores' support points along n
    and -n (points of the cores, not the closest ones: as GJK's bound, see
    gjk_epa.gjk_epa_ws); returns -gap."""
    bx, by, bz = c[0], c[1], c[2]
    for i in range(3):
        s = e[i] if A[i, 0] * mx + A[i, 1] * my + A[i, 2] * mz >= 0.0 else -e[i]
        bx += s * A[i, 0]
        by += s * A[i, 1]
        bz += s * A[i, 2]
    # the cylinder's support along -m: its rim's point opposite m's horizontal part
    # (the cap's centre when m is the axis), on the cap m points away from
    mn = math.sqrt(mx * mx + my * my)
    cx, cy = (-r * mx / mn, -r * my / mn) if mn > 0.0 else (0.0, 0.0)
    cz = -hc if mz > 0.0 else hc
    res[0] = -gap
    if box_a:
        # to A's (the box's) frame: x_A = r_ab x_B + t_ab
        for q in range(3):
            res[1 + q] = r_ab[q, 0] * mx + r_ab[q, 1] * my + r_ab[q, 2] * mz
            res[4 + q] = r_ab[q, 0] * bx + r_ab[q, 1] * by + r_ab[q, 2] * bz + t_ab[q]
            res[7 + q] = r_ab[q, 0] * cx + r_ab[q, 1] * cy + r_ab[q, 2] * cz + t_ab[q]
    else:
        res[1], res[2], res[3] = -mx, -my, -mz
        res[4], res[5], res[6] = cx, cy, cz
        res[7], res[8], res[9] = bx, by, bz
    return -gap


@njit_separate
def _box_cylinder_bound(sa, sb, r_ab, t_ab, scale, scratch, res):
    """The depth of a box and a cylinder (shape tuples sa, sb, one of each, B's pose
    r_ab, t_ab in A's frame) whose cores overlap, as the module doc says.  ``scratch``
    float64 (>= BC_MAX_LEVEL + 8, 3).  On success writes res[:10] = [depth, n (3),
    pa (3), pb (3)] in A's frame (n from A to B, pa on A's core, pb on B's core,
    pb - pa == -depth * n) as _epa does, and returns the depth (> 0).  Where the line
    of centres or a candidate direction has f < 0, the cores are apart: res = [-gap,
    ...] (_apart_out) and returns -gap, which gjk_epa.gjk_epa_ws takes as GJK's
    distance bound in contacts mode (as cylinder_common's planes).  Returns 0, res untouched,
    when the answer is neither certified nor apart."""
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, r_ab, t_ab = borrow_pose(sa, sb, r_ab, t_ab)
    scratch, res = borrow(scratch), borrow(res)
    box_a = sa[0] == BOX
    pbox = sa[1] if box_a else sb[1]
    pcyl = sb[1] if box_a else sa[1]
    r, hc = pcyl[0], pcyl[1]
    if not (r > 0.0 and hc > 0.0):
        return 0.0
    A = scratch[0:3]            # box axes (rows) in the cylinder's frame
    c = scratch[3]              # box centre there
    e = scratch[4]              # half extents
    for q in range(3):
        e[q] = pbox[q]
    if box_a:
        # x_B = r_ab^T (x_A - t_ab): box axis i is row i of r_ab
        for q in range(3):
            for s in range(3):
                A[q, s] = r_ab[q, s]
            c[q] = -(r_ab[0, q] * t_ab[0] + r_ab[1, q] * t_ab[1] + r_ab[2, q] * t_ab[2])
    else:
        for q in range(3):
            for s in range(3):
                A[q, s] = r_ab[s, q]
            c[q] = t_ab[q]
    tol = EPA_REL_TOL * scale
    # apart along the line of centres (most pairs apart end here)
    cn = math.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
    if cn > 0.0:
        mx, my, mz = -c[0] / cn, -c[1] / cn, -c[2] / cn
        fc = _f(A, c, e, r, hc, mx, my, mz)
        if not fc > tol:
            if fc < 0.0:
                return _apart_out(res, box_a, r_ab, t_ab, A, c, e, r, hc, -fc, mx, my, mz)
            return 0.0
    best, bt, mx, my, mz = _candidates(A, c, e, r, hc)
    if best < 0.0:
        # apart along a candidate (a face normal, a pole, z x a box axis, or the
        # crease opposite a box vertex): as a separating axis test
        return _apart_out(res, box_a, r_ab, t_ab, A, c, e, r, hc, -best, mx, my, mz)
    if not (best > tol and _cells_positive(A, c, e, r, hc)):
        return 0.0
    cand = scratch[5]
    stack = scratch[6:]
    for i in range(3):
        ok, b2 = _circle_certified(A, c, e, r, hc, i, best, tol, stack, cand)
        if not ok:
            return 0.0
        if b2 < best:
            best, bt = b2, 4
            mx, my, mz = cand[0], cand[1], cand[2]
    # witnesses in the cylinder's frame: box point (bpx..) and cylinder point (cpx..)
    d = best
    if bt == 1 or bt == 4:
        # a rim point against a box face, or (type 4) a box edge
        s = math.sqrt(mx * mx + my * my)
        if not (s > BC_FEAT and abs(mz) > BC_FEAT):
            return 0.0                  # a cap or a side line, not a point: EPA
        cpx, cpy, cpz = -r * mx / s, -r * my / s, (-hc if mz > 0.0 else hc)
        bpx, bpy, bpz = cpx + d * mx, cpy + d * my, cpz + d * mz
    else:
        # the box's support along m: a vertex, or for type 2 the edge along axis ii
        vx, vy, vz = c[0], c[1], c[2]
        ii = -1
        for q in range(3):
            am = A[q, 0] * mx + A[q, 1] * my + A[q, 2] * mz
            if abs(am) <= BC_FEAT:
                if ii >= 0:
                    return 0.0
                ii = q
                continue
            s = e[q] if am > 0.0 else -e[q]
            vx += s * A[q, 0]
            vy += s * A[q, 1]
            vz += s * A[q, 2]
        if bt != 2:
            if ii >= 0:
                return 0.0
            bpx, bpy, bpz = vx, vy, vz
            cpx, cpy, cpz = vx - d * mx, vy - d * my, vz - d * mz
        else:
            if ii < 0:
                return 0.0
            ax, ay, az = A[ii, 0], A[ii, 1], A[ii, 2]
            if not abs(az) < 1.0 - BC_FEAT:
                return 0.0
            # edge point v + lam a against side-line point -r m + mu z:
            # lam a - mu z = (d - r) m - v
            qx, qy, qz = (d - r) * mx - vx, (d - r) * my - vy, -vz
            aq = ax * qx + ay * qy + az * qz
            den = 1.0 - az * az
            lam = (aq - az * qz) / den
            mu = (az * aq - qz) / den
            bpx, bpy, bpz = vx + lam * ax, vy + lam * ay, vz + lam * az
            cpx, cpy, cpz = -r * mx, -r * my, mu
    res[0] = d
    if box_a:
        # to A's (the box's) frame: x_A = r_ab x_B + t_ab
        for q in range(3):
            n = r_ab[q, 0] * mx + r_ab[q, 1] * my + r_ab[q, 2] * mz
            pa = r_ab[q, 0] * bpx + r_ab[q, 1] * bpy + r_ab[q, 2] * bpz + t_ab[q]
            pb = r_ab[q, 0] * cpx + r_ab[q, 1] * cpy + r_ab[q, 2] * cpz + t_ab[q]
            res[1 + q] = n
            res[4 + q], res[7 + q] = meet(pa, pb, -(d * n))
    else:
        res[1], res[2], res[3] = -mx, -my, -mz
        res[4], res[7] = meet(cpx, bpx, d * mx)
        res[5], res[8] = meet(cpy, bpy, d * my)
        res[6], res[9] = meet(cpz, bpz, d * mz)
    return d


@njit_inline
def collide_box_cylinder(sa, sb, r_ab, t_ab, scale, scratch, stop, res):
    """What gjk_epa.gjk_epa_ws learns before GJK for a box and a cylinder (constants.PRE_*;
    ``scratch`` as _box_cylinder_bound's): PRE_EXACT with res[:10] the cores' certified
    depth, normal and points (_box_cylinder_bound), PRE_APART when a plane proves the cores
    farther apart than ``stop`` (m; res the bound), else PRE_UNDECIDED."""
    return pre_outcome(_box_cylinder_bound(sa, sb, r_ab, t_ab, scale, scratch, res), stop)
