"""Contact manifolds by face clipping, in one step (Sutherland-Hodgman, as Box2D and
Jolt do it).

For each touching pair the narrow phase gives one contact (normal ``n`` from A to B,
world frame).  This module turns face-on-face contacts into the full manifold:

  1. Features.  Each shape reports the feature it presents along a direction (its
     *supporting feature*, body frame): a box its most aligned face (4 points); a convex
     hull the vertices whose support value is within FACE_SLACK * 2 * radius of the
     maximum (ordered by angle, up to MAX_FEATURE, normal by Newell's method; hulls have
     no face table, so this stands in for Jolt's GetSupportingFace); a cylinder its
     cap (an 8-gon) when the direction is within FACE_SIN of its axis or its side line
     (2 points) when within FACE_SIN of perpendicular; a cone its base cap; a capsule
     its segment (2 points) when nearly perpendicular to the axis.  Every other case (spheres,
     ellipsoids, rims, tips) is curved: one point, the narrow phase's.  Feature points
     are grown by the shape's inflation (margin, capsule radius) along the direction.
  2. Reference and incident.  A plane is always the reference face.  Otherwise the
     polygon (>= 3 points) whose face normal is better aligned with ``n`` is the
     reference (ties to A), the other is incident; a segment is only a reference when
     both are segments (the side planes are then the segment's end planes).  The
     reference must be aligned with ``n`` within REF_COS, else the single point is kept
     (edge-edge contacts).
  3. Clipping.  The incident polygon is clipped by the side planes of the reference
     face (Sutherland-Hodgman); clipped points whose separation from the reference
     plane is <= ``keep_dist`` (m) are contacts: the point on the incident body and its
     projection on the reference face.  No point left: the narrow phase's one point.

Persistence (``persist_batch``, the arbiters' kernel, serial so ids are deterministic):
stored contacts are refreshed from the bodies' frames and dropped past the drift
threshold, matched to the new manifold by distance, reduced to ``max_contacts``
(deepest, farthest, then largest hull area: Bullet's ``sortCachedPoints``, Jolt's
``PruneContactPoints``), and the surviving new ones get ids; see arbiters.py.

Output per pair of ``manifold_batch`` (fixed slots, thread-count independent): up to MAX_MANIFOLD contacts
``cpts[k, c] = (point_a (3,), point_b (3,), distance)`` in the world frame (m), with
``point_b - point_a = distance * normal`` and distance < 0 penetrating, the normal
``cnormal[k]`` (unit, A to B) and the count ``ccount[k]`` (0 when the pair does not
touch).
"""
import math

import numpy as np

from .constants import (BOX, CAPSULE, CONE, CONVEX, CYLINDER, OUT_DIST, OUT_NORMAL,
                        OUT_PA, OUT_PB, P_MARGIN, P_RADIUS, PLANE, ST_PENETRATING,
                        ST_TOUCHING)
from .geometry import inflation, quat_to_matrix
from .jit import njit_kernel, njit_parallel, prange

MAX_FEATURE = 8          # points of a supporting feature (cylinder cap as an 8-gon)
MAX_MANIFOLD = 16        # clipped points of one pair (<= 2 * MAX_FEATURE)
CAP_SIDES = 8            # polygon approximating a cylinder / cone cap
FACE_SIN = 0.05          # sin of the angle (~2.9 deg) within which a cap / side is a face
FACE_SLACK = 0.05        # convex hull face tolerance, relative to the hull's diameter
REF_COS = 0.9            # the reference face normal must be within ~26 deg of n


@njit_kernel
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit_kernel
def _cross(a, b):
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit_kernel
def _mv(r, v):
    """r (3, 3) times v (3,) (numba's ``@`` needs BLAS, which is not installed)."""
    out = np.empty(3)
    for i in range(3):
        out[i] = r[i, 0] * v[0] + r[i, 1] * v[1] + r[i, 2] * v[2]
    return out


@njit_kernel
def _mtv(r, v):
    """r^T (3, 3) times v (3,)."""
    out = np.empty(3)
    for i in range(3):
        out[i] = r[0, i] * v[0] + r[1, i] * v[1] + r[2, i] * v[2]
    return out


@njit_kernel
def _feature(code, prm, verts, v0, vn, d, poly, fn):
    """Supporting feature of a shape along the unit direction ``d`` (3,) (body frame).

    Writes up to MAX_FEATURE points into ``poly`` (MAX_FEATURE, 3) and the feature's
    outward normal into ``fn`` (3,), both body frame.  Returns the point count: 0 for a
    curved feature (use the narrow phase point), 2 for a segment, >= 3 for a polygon
    (ordered around its centre).
    """
    dx, dy, dz = d[0], d[1], d[2]
    count = 0
    if code == BOX:
        ax = np.abs(d)
        k = 0
        if ax[1] > ax[k]:
            k = 1
        if ax[2] > ax[k]:
            k = 2
        s = 1.0 if d[k] >= 0.0 else -1.0
        u = (k + 1) % 3
        v = (k + 2) % 3
        su = (1.0, -1.0, -1.0, 1.0)
        sv = (1.0, 1.0, -1.0, -1.0)
        for c in range(4):
            poly[c, k] = s * prm[k]
            poly[c, u] = su[c] * prm[u]
            poly[c, v] = sv[c] * prm[v]
        fn[0] = 0.0
        fn[1] = 0.0
        fn[2] = 0.0
        fn[k] = s
        count = 4
    elif code == CYLINDER or code == CONE:
        r, h = prm[0], prm[1]
        cap_cos = 1.0 - FACE_SIN * FACE_SIN
        if (code == CYLINDER and dz >= cap_cos) or dz <= -cap_cos:
            z = h if dz > 0.0 else -h
            for c in range(CAP_SIDES):
                a = 2.0 * math.pi * c / CAP_SIDES
                poly[c, 0] = r * math.cos(a)
                poly[c, 1] = r * math.sin(a)
                poly[c, 2] = z
            fn[0] = 0.0
            fn[1] = 0.0
            fn[2] = 1.0 if dz > 0.0 else -1.0
            count = CAP_SIDES
        elif code == CYLINDER and abs(dz) <= FACE_SIN:
            s = math.sqrt(dx * dx + dy * dy)
            for c in range(2):
                poly[c, 0] = r * dx / s
                poly[c, 1] = r * dy / s
                poly[c, 2] = h if c == 0 else -h
            fn[0] = dx / s
            fn[1] = dy / s
            fn[2] = 0.0
            count = 2
    elif code == CAPSULE:
        if abs(dz) <= FACE_SIN:
            for c in range(2):
                poly[c, 0] = 0.0
                poly[c, 1] = 0.0
                poly[c, 2] = prm[1] if c == 0 else -prm[1]
            fn[0] = dx
            fn[1] = dy
            fn[2] = dz
            count = 2
    elif code == CONVEX and vn >= 3:
        best = -np.inf
        for i in range(v0, v0 + vn):
            best = max(best, verts[i, 0] * dx + verts[i, 1] * dy + verts[i, 2] * dz)
        tol = FACE_SLACK * 2.0 * (prm[P_RADIUS] - prm[P_MARGIN])
        for i in range(v0, v0 + vn):
            if verts[i, 0] * dx + verts[i, 1] * dy + verts[i, 2] * dz >= best - tol:
                if count < MAX_FEATURE:
                    for j in range(3):
                        poly[count, j] = verts[i, j]
                    count += 1
        fn[0] = dx
        fn[1] = dy
        fn[2] = dz
        if count >= 3:
            _order_by_angle(poly, count, d)
            # the face's own normal (Newell's method), oriented along d
            nx = 0.0
            ny = 0.0
            nz = 0.0
            for c in range(count):
                p = poly[c]
                q = poly[(c + 1) % count]
                nx += (p[1] - q[1]) * (p[2] + q[2])
                ny += (p[2] - q[2]) * (p[0] + q[0])
                nz += (p[0] - q[0]) * (p[1] + q[1])
            nn = math.sqrt(nx * nx + ny * ny + nz * nz)
            if nn > 0.0:
                sgn = 1.0 if nx * dx + ny * dy + nz * dz >= 0.0 else -1.0
                fn[0] = sgn * nx / nn
                fn[1] = sgn * ny / nn
                fn[2] = sgn * nz / nn
        elif count == 1:
            count = 0
    rad = inflation(code, prm)
    for c in range(count):
        for j in range(3):
            poly[c, j] += rad * d[j]
    return count


@njit_kernel
def _order_by_angle(poly, count, d):
    """Sort ``poly[:count]`` by angle about their centroid, around the axis ``d``."""
    cx = np.zeros(3)
    for c in range(count):
        cx += poly[c]
    cx /= count
    # a basis (u, v) of the plane perpendicular to d
    u = np.zeros(3)
    if abs(d[0]) < 0.57:
        u[0] = 1.0
    elif abs(d[1]) < 0.57:
        u[1] = 1.0
    else:
        u[2] = 1.0
    u -= _dot(u, d) * d
    u /= math.sqrt(u[0] ** 2 + u[1] ** 2 + u[2] ** 2)
    v = _cross(d, u)
    ang = np.empty(count)
    for c in range(count):
        w = poly[c] - cx
        ang[c] = math.atan2(_dot(w, v), _dot(w, u))
    idx = np.argsort(ang, kind="mergesort")
    tmp = poly[:count].copy()
    for c in range(count):
        poly[c] = tmp[idx[c]]


@njit_kernel
def _to_world(poly, count, r, p, out):
    for c in range(count):
        for i in range(3):
            out[c, i] = p[i] + r[i, 0] * poly[c, 0] + r[i, 1] * poly[c, 1] + r[i, 2] * poly[c, 2]


@njit_kernel
def _clip(subject, ns, pnt, nrm, out):
    """Clip polygon ``subject[:ns]`` (world) by the half-space (x - pnt) . nrm >= 0;
    write the result in ``out`` and return its count (Sutherland-Hodgman, one plane)."""
    no = 0
    if ns == 0:
        return 0
    for c in range(ns):
        a = subject[c]
        b = subject[(c + 1) % ns]
        da = (a[0] - pnt[0]) * nrm[0] + (a[1] - pnt[1]) * nrm[1] + (a[2] - pnt[2]) * nrm[2]
        db = (b[0] - pnt[0]) * nrm[0] + (b[1] - pnt[1]) * nrm[1] + (b[2] - pnt[2]) * nrm[2]
        if da >= 0.0:
            if no < out.shape[0]:
                out[no] = a
                no += 1
        if (da >= 0.0) != (db >= 0.0) and ns > 1:
            t = da / (da - db)
            if no < out.shape[0]:
                out[no] = a + t * (b - a)
                no += 1
    return no


@njit_kernel
def _single(row, cpts_k, cn_k):
    for i in range(3):
        cpts_k[0, i] = row[OUT_PA + i]
        cpts_k[0, 3 + i] = row[OUT_PB + i]
        cn_k[i] = row[OUT_NORMAL + i]
    cpts_k[0, 6] = row[OUT_DIST]
    return 1


@njit_kernel
def _pair_manifold(codes, params, vrange, verts, ia, ib, pos_w, quat_w, row, keep_dist,
                   cpts_k, cn_k):
    n = row[OUT_NORMAL:OUT_NORMAL + 3].copy()
    ca, cb = codes[ia], codes[ib]
    ra = quat_to_matrix(quat_w[ia])
    rb = quat_to_matrix(quat_w[ib])
    fa = np.zeros((MAX_FEATURE, 3))
    fb = np.zeros((MAX_FEATURE, 3))
    fna = np.zeros(3)
    fnb = np.zeros(3)
    na = 0
    nb = 0
    if ca != PLANE:
        na = _feature(ca, params[ia], verts, vrange[ia, 0], vrange[ia, 1], _mtv(ra, n), fa, fna)
    if cb != PLANE:
        nb = _feature(cb, params[ib], verts, vrange[ib, 0], vrange[ib, 1], -_mtv(rb, n), fb, fnb)
    # reference face: point, outward normal (world); which side is the reference
    ref_is_a = True
    ref_pts = np.zeros((MAX_FEATURE, 3))
    inc_pts = np.zeros((MAX_FEATURE, 3))
    n_ref = np.zeros(3)
    nr = 0
    ni = 0
    if ca == PLANE or cb == PLANE:
        if ca == PLANE and cb == PLANE:
            return _single(row, cpts_k, cn_k)
        ref_is_a = ca == PLANE
        ip = ia if ref_is_a else ib
        rp = ra if ref_is_a else rb
        n_ref = _mv(rp, params[ip, :3])
        d = params[ip, 3] + params[ip, P_MARGIN] + _dot(n_ref, pos_w[ip])
        ref_pts[0] = d * n_ref
        nr = -1  # unbounded: no side planes
        if ref_is_a:
            ni = nb
            _to_world(fb, nb, rb, pos_w[ib], inc_pts)
        else:
            ni = na
            _to_world(fa, na, ra, pos_w[ia], inc_pts)
    else:
        fa_w = _mv(ra, fna)
        fb_w = _mv(rb, fnb)
        al_a = _dot(fa_w, n) if na >= 3 else -2.0
        al_b = -_dot(fb_w, n) if nb >= 3 else -2.0
        if na >= 3 or nb >= 3:
            ref_is_a = al_a >= al_b - 1e-3
        else:
            ref_is_a = True
        if ref_is_a:
            nr, ni = na, nb
            _to_world(fa, na, ra, pos_w[ia], ref_pts)
            _to_world(fb, nb, rb, pos_w[ib], inc_pts)
            n_ref = fa_w if na >= 3 else n.copy()
        else:
            nr, ni = nb, na
            _to_world(fb, nb, rb, pos_w[ib], ref_pts)
            _to_world(fa, na, ra, pos_w[ia], inc_pts)
            n_ref = fb_w if nb >= 3 else -n
        if nr >= 2 and _dot(n_ref, n) * (1.0 if ref_is_a else -1.0) < REF_COS:
            return _single(row, cpts_k, cn_k)
    if ni < 2 or nr == 0 or nr == 1:
        return _single(row, cpts_k, cn_k)
    # clip the incident polygon by the reference face's side planes
    buf0 = np.zeros((MAX_MANIFOLD, 3))
    buf1 = np.zeros((MAX_MANIFOLD, 3))
    for c in range(ni):
        buf0[c] = inc_pts[c]
    cnt = ni
    if nr == 2:
        e = ref_pts[1] - ref_pts[0]
        cnt = _clip(buf0, cnt, ref_pts[0], e, buf1)
        cnt = _clip(buf1, cnt, ref_pts[1], -e, buf0)
    elif nr >= 3:
        cen = np.zeros(3)
        for c in range(nr):
            cen += ref_pts[c]
        cen /= nr
        for c in range(nr):
            a = ref_pts[c]
            b = ref_pts[(c + 1) % nr]
            side = _cross(n_ref, b - a)
            if _dot(side, cen - a) < 0.0:
                side = -side
            cnt = _clip(buf0, cnt, a, side, buf1)
            for q in range(cnt):
                buf0[q] = buf1[q]
    # keep the points below the reference plane (+ keep_dist)
    out = 0
    for c in range(cnt):
        p = buf0[c]
        sep = _dot(n_ref, p - ref_pts[0])
        if not (sep <= keep_dist):
            continue
        q = p - sep * n_ref
        for i in range(3):
            if ref_is_a:
                cpts_k[out, i] = q[i]
                cpts_k[out, 3 + i] = p[i]
            else:
                cpts_k[out, i] = p[i]
                cpts_k[out, 3 + i] = q[i]
        cpts_k[out, 6] = sep
        out += 1
    if out == 0:
        return _single(row, cpts_k, cn_k)
    for i in range(3):
        cn_k[i] = n_ref[i] if ref_is_a else -n_ref[i]
    # drop duplicates left by degenerate clips (segments clipped as 2-gons)
    m = 0
    for c in range(out):
        dup = False
        for q in range(m):
            dd = 0.0
            for i in range(6):
                dd += (cpts_k[c, i] - cpts_k[q, i]) ** 2
            if dd <= 1e-24:
                dup = True
                break
        if not dup:
            for i in range(7):
                cpts_k[m, i] = cpts_k[c, i]
            m += 1
    return m


@njit_kernel
def _manifold_row(k, codes, params, vrange, verts, pairs, pos_w, quat_w, out, status,
                  keep_dist, cpts, cnormal, ccount):
    st = status[k]
    if st != ST_TOUCHING and st != ST_PENETRATING:
        ccount[k] = 0
        return
    c = _pair_manifold(codes, params, vrange, verts, pairs[k, 0], pairs[k, 1], pos_w,
                       quat_w, out[k], keep_dist, cpts[k], cnormal[k])
    # never hand on non-finite numbers: fall back to the narrow phase's point
    ok = True
    for q in range(c):
        for i in range(7):
            if not math.isfinite(cpts[k, q, i]):
                ok = False
    if not ok:
        c = _single(out[k], cpts[k], cnormal[k])
    ccount[k] = c


@njit_parallel
def manifold_batch(codes, params, vrange, verts, pairs, pos_w, quat_w, out, status,
                   keep_dist, cpts, cnormal, ccount):
    """Contact manifolds of P pairs.

    codes, params, vrange, verts: the shape table (body frames, m).
    pairs int64 (P, 2); pos_w float64 (N, 3) m; quat_w float64 (N, 4) unit xyzw.
    out float64 (P, OUT_SIZE), status int64 (P,): the narrow phase's world rows.
    keep_dist float64 (m): clipped points up to this far outside the reference face
        are kept (speculative contacts, distance > 0).
    cpts float64 (P, MAX_MANIFOLD, 7) out: world point_a (3), point_b (3), distance.
    cnormal float64 (P, 3) out: unit normal A -> B, world.
    ccount int64 (P,) out: contacts of the pair (0 when not touching).
    """
    for k in prange(pairs.shape[0]):
        _manifold_row(k, codes, params, vrange, verts, pairs, pos_w, quat_w, out, status,
                      keep_dist, cpts, cnormal, ccount)


# --- persistence: matching new contacts to stored ones (the arbiters' kernel) ----------
EV_BEGAN = 0
EV_PERSISTED = 1
EV_ENDED = 2
_FRESH_RANK = 1 << 62      # tie rank of contacts without an id yet (after every stored one)


@njit_kernel
def _hull_area(px, py, idx, m):
    """Area of the 2D convex hull of the points ``(px[idx[:m]], py[idx[:m]])`` (monotone
    chain; m <= MAX_MANIFOLD + a few).  Fewer than 3 points: the squared spread, a proxy
    that grows with the distance of 2 points."""
    if m < 3:
        if m == 2:
            dx = px[idx[0]] - px[idx[1]]
            dy = py[idx[0]] - py[idx[1]]
            return dx * dx + dy * dy
        return 0.0
    order = np.empty(m, np.int64)
    for c in range(m):
        order[c] = idx[c]
    for c in range(1, m):                 # insertion sort by (x, y)
        v = order[c]
        d = c - 1
        while d >= 0 and (px[order[d]] > px[v] or (px[order[d]] == px[v] and py[order[d]] > py[v])):
            order[d + 1] = order[d]
            d -= 1
        order[d + 1] = v
    hull = np.empty(2 * m + 1, np.int64)
    h = 0
    for c in range(m):
        p = order[c]
        while h >= 2 and ((px[hull[h - 1]] - px[hull[h - 2]]) * (py[p] - py[hull[h - 2]])
                          - (py[hull[h - 1]] - py[hull[h - 2]]) * (px[p] - px[hull[h - 2]])) <= 0.0:
            h -= 1
        hull[h] = p
        h += 1
    lower = h + 1
    for c in range(m - 2, -1, -1):
        p = order[c]
        while h >= lower and ((px[hull[h - 1]] - px[hull[h - 2]]) * (py[p] - py[hull[h - 2]])
                              - (py[hull[h - 1]] - py[hull[h - 2]]) * (px[p] - px[hull[h - 2]])) <= 0.0:
            h -= 1
        hull[h] = p
        h += 1
    h -= 1
    area = 0.0
    for c in range(h):
        p = hull[c]
        q = hull[(c + 1) % h]
        area += px[p] * py[q] - px[q] * py[p]
    return 0.5 * abs(area)


@njit_kernel
def _reduce(mid, depth, rank, n, m, k, keep):
    """Choose ``k`` of ``m`` contacts (midpoints ``mid`` (m, 3), ``depth`` (m,), tie
    ``rank`` (m,), smaller = older): the deepest, the farthest from it, then greedily
    the one giving the largest hull area in the plane normal to ``n``.  Writes the
    chosen indices into ``keep[:k]``."""
    chosen = np.zeros(m, np.bool_)
    best = 0
    for c in range(1, m):
        if depth[c] > depth[best] or (depth[c] == depth[best] and rank[c] < rank[best]):
            best = c
    keep[0] = best
    chosen[best] = True
    # basis of the contact plane
    u = np.zeros(3)
    if abs(n[0]) < 0.57:
        u[0] = 1.0
    elif abs(n[1]) < 0.57:
        u[1] = 1.0
    else:
        u[2] = 1.0
    u -= _dot(u, n) * n
    u /= math.sqrt(_dot(u, u))
    v = _cross(n, u)
    px = np.empty(m)
    py = np.empty(m)
    for c in range(m):
        px[c] = _dot(mid[c], u)
        py[c] = _dot(mid[c], v)
    sel = np.empty(m, np.int64)
    for t in range(1, k):
        best = -1
        best_score = -1.0
        for c in range(m):
            if chosen[c]:
                continue
            for q in range(t):
                sel[q] = keep[q]
            sel[t] = c
            if t == 1:
                dx = mid[c] - mid[keep[0]]
                score = _dot(dx, dx)
            else:
                score = _hull_area(px, py, sel, t + 1)
            tol = 1e-12 * max(1.0, abs(best_score))
            if best < 0 or score > best_score + tol or (
                    abs(score - best_score) <= tol and rank[c] < rank[best]):
                best = c
                best_score = score
        keep[t] = best
        chosen[best] = True


@njit_kernel
def persist_batch(arb_a, arb_b, arb_src, arb_row, o_id, o_age, o_la, o_lb, o_na,
                  cpts, cnormal, ccount, pos_w, quat_w, merge_distance, drift_threshold,
                  max_contacts, next_id, n_id, n_age, n_la, n_lb, n_na, n_pa, n_pb, n_n,
                  n_count, ev_arb, ev_kind, ev_id):
    """Persistent contacts of A arbiters for one step (serial: ids are handed out in
    arbiter order, so they are deterministic).

    arb_a, arb_b int64 (A,): bodies (a < b); arb_src int64 (A, 2): [start, end) of the
        arbiter's stored contacts in the ``o_*`` arrays; arb_row int64 (A,): its row in
        ``cpts``/``cnormal``/``ccount`` (the manifold of this step), -1 if the narrow
        phase did not confirm it this step (stored contacts are then only refreshed).
    o_id, o_age int64 (S,); o_la, o_lb, o_na float64 (S, 3): stored contacts, points in
        A's / B's body frame (m), normal in A's frame.
    cpts float64 (T, MAX_MANIFOLD, 7), cnormal (T, 3), ccount int64 (T,): manifolds
        (world point_a, point_b, distance), see ``manifold_batch``.
    pos_w (N, 3), quat_w (N, 4) unit xyzw; merge_distance, drift_threshold (m);
    max_contacts >= 1; next_id: the first id to hand out.
    Outputs, A * max_contacts rows laid out per arbiter at a * max_contacts:
        n_id, n_age, n_la, n_lb, n_na (as o_*), n_pa, n_pb, n_n (world, m) and
        n_count int64 (A,) contacts kept per arbiter;
    events, at most S + T * MAX_MANIFOLD rows: ev_arb (arbiter index), ev_kind
        (EV_BEGAN / EV_PERSISTED / EV_ENDED), ev_id (contact id), per arbiter by id.
    Returns (next_id, number of events).
    """
    n_ev = 0
    cap = MAX_MANIFOLD + 2 * max_contacts + 8
    pa = np.empty((cap, 3))
    pb = np.empty((cap, 3))
    nn = np.empty((cap, 3))
    ids = np.empty(cap, np.int64)
    age = np.empty(cap, np.int64)
    rank = np.empty(cap, np.int64)
    depth = np.empty(cap)
    mid = np.empty((cap, 3))
    keep = np.empty(cap, np.int64)
    ev_tmp_id = np.empty(2 * cap, np.int64)
    ev_tmp_kind = np.empty(2 * cap, np.int64)
    for a in range(arb_a.shape[0]):
        ia = arb_a[a]
        ib = arb_b[a]
        ra = quat_to_matrix(quat_w[ia])
        rb = quat_to_matrix(quat_w[ib])
        ne = 0
        # 1. stored contacts in the world; drop the drifted ones
        s0 = arb_src[a, 0]
        s1 = arb_src[a, 1]
        m_old = 0
        spa = np.empty((max(s1 - s0, 1), 3))
        spb = np.empty((max(s1 - s0, 1), 3))
        sn = np.empty((max(s1 - s0, 1), 3))
        sid = np.empty(max(s1 - s0, 1), np.int64)
        sage = np.empty(max(s1 - s0, 1), np.int64)
        for s in range(s0, s1):
            wa = _mv(ra, o_la[s]) + pos_w[ia]
            wb = _mv(rb, o_lb[s]) + pos_w[ib]
            wn = _mv(ra, o_na[s])
            gap = wb - wa
            along = _dot(gap, wn)
            side = gap - along * wn
            if along <= drift_threshold and math.sqrt(_dot(side, side)) <= drift_threshold:
                spa[m_old] = wa
                spb[m_old] = wb
                sn[m_old] = wn
                sid[m_old] = o_id[s]
                sage[m_old] = o_age[s] + 1
                m_old += 1
            else:
                ev_tmp_id[ne] = o_id[s]
                ev_tmp_kind[ne] = EV_ENDED
                ne += 1
        # 2. match this step's contacts to the stored ones, closest pairs first
        row = arb_row[a]
        m_new = ccount[row] if row >= 0 else 0
        match_new = np.full(max(m_new, 1), -1, np.int64)
        used_old = np.zeros(max(m_old, 1), np.bool_)
        while True:
            bi = -1
            bj = -1
            bd = np.inf
            for i in range(m_new):
                if match_new[i] >= 0:
                    continue
                for j in range(m_old):
                    if used_old[j]:
                        continue
                    d1 = 0.0
                    d2 = 0.0
                    for q in range(3):
                        d1 += (cpts[row, i, q] - spa[j, q]) ** 2
                        d2 += (cpts[row, i, 3 + q] - spb[j, q]) ** 2
                    d = math.sqrt(min(d1, d2))
                    if d <= merge_distance and d < bd:
                        bd = d
                        bi = i
                        bj = j
            if bi < 0:
                break
            match_new[bi] = bj
            used_old[bj] = True
        # 3. the merged set: this step's contacts, then the unmatched stored ones
        m = 0
        for i in range(m_new):
            for q in range(3):
                pa[m, q] = cpts[row, i, q]
                pb[m, q] = cpts[row, i, 3 + q]
                nn[m, q] = cnormal[row, q]
            j = match_new[i]
            if j >= 0:
                ids[m] = sid[j]
                age[m] = sage[j]
                rank[m] = sid[j]
            else:
                ids[m] = -1
                age[m] = 0
                rank[m] = _FRESH_RANK + i
            m += 1
        for j in range(m_old):
            if used_old[j]:
                continue
            pa[m] = spa[j]
            pb[m] = spb[j]
            nn[m] = sn[j]
            ids[m] = sid[j]
            age[m] = sage[j]
            rank[m] = sid[j]
            m += 1
        for c in range(m):
            depth[c] = max(0.0, -_dot(pb[c] - pa[c], nn[c]))
            mid[c] = 0.5 * (pa[c] + pb[c])
        # 4. reduce to max_contacts
        if m > max_contacts:
            nrm = cnormal[row].copy() if m_new > 0 else nn[0].copy()
            _reduce(mid, depth, rank, nrm, m, max_contacts, keep)
            k = max_contacts
            kept = np.zeros(m, np.bool_)
            for c in range(k):
                kept[keep[c]] = True
            for c in range(m):
                if not kept[c] and ids[c] >= 0:
                    ev_tmp_id[ne] = ids[c]
                    ev_tmp_kind[ne] = EV_ENDED
                    ne += 1
        else:
            k = m
            for c in range(m):
                keep[c] = c
        # order the survivors: stored ones by id, then fresh ones in manifold order
        for c in range(1, k):
            v = keep[c]
            d = c - 1
            while d >= 0 and rank[keep[d]] > rank[v]:
                keep[d + 1] = keep[d]
                d -= 1
            keep[d + 1] = v
        base = a * max_contacts
        for c in range(k):
            src = keep[c]
            if ids[src] < 0:
                ids[src] = next_id
                next_id += 1
                ev_tmp_kind[ne] = EV_BEGAN
            else:
                ev_tmp_kind[ne] = EV_PERSISTED
            ev_tmp_id[ne] = ids[src]
            ne += 1
            o = base + c
            n_id[o] = ids[src]
            n_age[o] = age[src]
            n_la[o] = _mtv(ra, pa[src] - pos_w[ia])
            n_lb[o] = _mtv(rb, pb[src] - pos_w[ib])
            n_na[o] = _mtv(ra, nn[src])
            n_pa[o] = pa[src]
            n_pb[o] = pb[src]
            n_n[o] = nn[src]
        n_count[a] = k
        # this arbiter's contact events, by id
        for c in range(1, ne):
            vi = ev_tmp_id[c]
            vk = ev_tmp_kind[c]
            d = c - 1
            while d >= 0 and ev_tmp_id[d] > vi:
                ev_tmp_id[d + 1] = ev_tmp_id[d]
                ev_tmp_kind[d + 1] = ev_tmp_kind[d]
                d -= 1
            ev_tmp_id[d + 1] = vi
            ev_tmp_kind[d + 1] = vk
        for c in range(ne):
            ev_arb[n_ev] = a
            ev_kind[n_ev] = ev_tmp_kind[c]
            ev_id[n_ev] = ev_tmp_id[c]
            n_ev += 1
    return next_id, n_ev
