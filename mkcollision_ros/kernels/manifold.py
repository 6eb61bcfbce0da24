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

Output per pair of ``manifold_batch`` (fixed slots, thread-count independent): up to MAX_MANIFOLD contacts
``cpts[k, c] = (point_a (3,), point_b (3,), distance)`` in the world frame (m), with
``point_b - point_a = distance * normal`` and distance < 0 penetrating, the normal
``cnormal[k]`` (unit, A to B) and the count ``ccount[k]`` (0 when the pair does not
touch).  ``split_pairs`` sorts the narrow phase's rows into touching and undecided ones
first; what becomes of the contacts from step to step: persistence.py.
"""
import math

import numpy as np

from .constants import (BOX, CAPSULE, CONE, CONTACT_SAME_SQ, CONVEX, CYLINDER, ELLIPSOID, FACE_SIN,
                        FACE_SLACK, OUT_DIST, OUT_METHOD, OUT_NORMAL, OUT_PA, OUT_PB, PLANE,
                        P_MARGIN, P_RADIUS, REF_COS, REF_TIE, ST_PENETRATING, ST_SEPARATED,
                        ST_TOUCHING)
from .geometry import inflation, quat_to_matrix_into
from .jit import borrow, keep_alive, njit_kernel, run_blocks

MAX_FEATURE = 8          # points of a supporting feature (cylinder cap as an 8-gon)
MAX_MANIFOLD = 16        # clipped points of one pair (<= 2 * MAX_FEATURE)
CAP_SIDES = 8            # polygon approximating a cylinder / cone cap
MANIFOLD_CHUNK = 32      # fewest rows of manifold_batch per block (jit.n_blocks)


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
def _feature(code, prm, verts, v0, vn, d, poly, fn):
    """Supporting feature of a shape along the unit direction ``d`` (3,) (body frame).

    Writes up to MAX_FEATURE points into ``poly`` (MAX_FEATURE, 3) and the feature's
    outward normal into ``fn`` (3,), both body frame.  Returns the point count: 0 for a
    curved feature (use the narrow phase point), 2 for a segment, >= 3 for a polygon
    (ordered around its centre).
    """
    dx, dy, dz = d[0], d[1], d[2]
    count = np.int64(0)   # typed int64 at once (jit.py, "Literal")
    if code == BOX:
        ax0, ax1, ax2 = abs(dx), abs(dy), abs(dz)
        k = 0
        best = ax0
        if ax1 > best:
            k = 1
            best = ax1
        if ax2 > best:
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
    """Sort ``poly[:count]`` by angle about their centroid, around the axis ``d``
    (stable insertion sort, count <= MAX_FEATURE; scalar code, one small temporary)."""
    cx = 0.0
    cy = 0.0
    cz = 0.0
    for c in range(count):
        cx += poly[c, 0]
        cy += poly[c, 1]
        cz += poly[c, 2]
    cx /= count
    cy /= count
    cz /= count
    # a basis (u, v) of the plane perpendicular to d
    ux = 0.0
    uy = 0.0
    uz = 0.0
    if abs(d[0]) < 0.57:
        ux = 1.0
    elif abs(d[1]) < 0.57:
        uy = 1.0
    else:
        uz = 1.0
    du = ux * d[0] + uy * d[1] + uz * d[2]
    ux -= du * d[0]
    uy -= du * d[1]
    uz -= du * d[2]
    nu = math.sqrt(ux ** 2 + uy ** 2 + uz ** 2)
    ux /= nu
    uy /= nu
    uz /= nu
    vx = d[1] * uz - d[2] * uy
    vy = d[2] * ux - d[0] * uz
    vz = d[0] * uy - d[1] * ux
    ang = np.empty(count)
    for c in range(count):
        wx = poly[c, 0] - cx
        wy = poly[c, 1] - cy
        wz = poly[c, 2] - cz
        ang[c] = math.atan2(wx * vx + wy * vy + wz * vz, wx * ux + wy * uy + wz * uz)
    for c in range(1, count):
        a = ang[c]
        p0, p1, p2 = poly[c, 0], poly[c, 1], poly[c, 2]
        q = c - 1
        while q >= 0 and ang[q] > a:
            ang[q + 1] = ang[q]
            poly[q + 1, 0] = poly[q, 0]
            poly[q + 1, 1] = poly[q, 1]
            poly[q + 1, 2] = poly[q, 2]
            q -= 1
        ang[q + 1] = a
        poly[q + 1, 0] = p0
        poly[q + 1, 1] = p1
        poly[q + 1, 2] = p2


@njit_kernel
def _to_world(poly, count, r, p, out):
    for c in range(count):
        for i in range(3):
            out[c, i] = p[i] + r[i, 0] * poly[c, 0] + r[i, 1] * poly[c, 1] + r[i, 2] * poly[c, 2]


@njit_kernel
def _clip(subject, ns, px, py, pz, nx, ny, nz, out):
    """Clip polygon ``subject[:ns]`` (world) by the half-space (x - p) . n >= 0, with
    p = (px, py, pz), n = (nx, ny, nz); write the result in ``out`` and return its count
    (Sutherland-Hodgman, one plane; scalar code, no temporaries)."""
    no = 0
    if ns == 0:
        return 0
    cap = out.shape[0]
    for c in range(ns):
        c2 = (c + 1) % ns
        da = (subject[c, 0] - px) * nx + (subject[c, 1] - py) * ny + (subject[c, 2] - pz) * nz
        db = ((subject[c2, 0] - px) * nx + (subject[c2, 1] - py) * ny
              + (subject[c2, 2] - pz) * nz)
        if da >= 0.0:
            if no < cap:
                for i in range(3):
                    out[no, i] = subject[c, i]
                no += 1
        if (da >= 0.0) != (db >= 0.0) and ns > 1:
            t = da / (da - db)
            if no < cap:
                for i in range(3):
                    out[no, i] = subject[c, i] + t * (subject[c2, i] - subject[c, i])
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
                   cpts_k, cn_k, ws):
    ca, cb = codes[ia], codes[ib]
    if ca <= ELLIPSOID or cb <= ELLIPSOID:
        # a sphere or an ellipsoid only ever presents one point
        return _single(row, cpts_k, cn_k)
    ra, rb, fa, fb, fna, fnb, ref_pts, inc_pts, buf0, buf1, da, db = ws
    n = row[OUT_NORMAL:OUT_NORMAL + 3].copy()
    quat_to_matrix_into(quat_w[ia], ra)
    quat_to_matrix_into(quat_w[ib], rb)
    for i in range(3):      # n in A's frame, -n in B's frame
        da[i] = ra[0, i] * n[0] + ra[1, i] * n[1] + ra[2, i] * n[2]
        db[i] = -(rb[0, i] * n[0] + rb[1, i] * n[1] + rb[2, i] * n[2])
    na = 0
    nb = 0
    if ca != PLANE:
        na = _feature(ca, params[ia], verts, vrange[ia, 0], vrange[ia, 1], da, fa, fna)
    if cb != PLANE:
        nb = _feature(cb, params[ib], verts, vrange[ib, 0], vrange[ib, 1], db, fb, fnb)
    # reference face: point, outward normal (world); which side is the reference
    ref_is_a = True
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
        for i in range(3):
            ref_pts[0, i] = d * n_ref[i]
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
            ref_is_a = al_a >= al_b - REF_TIE
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
    # clip the incident polygon by the reference face's side planes (scalar code)
    for c in range(ni):
        for i in range(3):
            buf0[c, i] = inc_pts[c, i]
    cnt = ni
    nx, ny, nz = n_ref[0], n_ref[1], n_ref[2]
    if nr == 2:
        ex = ref_pts[1, 0] - ref_pts[0, 0]
        ey = ref_pts[1, 1] - ref_pts[0, 1]
        ez = ref_pts[1, 2] - ref_pts[0, 2]
        cnt = _clip(buf0, cnt, ref_pts[0, 0], ref_pts[0, 1], ref_pts[0, 2], ex, ey, ez, buf1)
        cnt = _clip(buf1, cnt, ref_pts[1, 0], ref_pts[1, 1], ref_pts[1, 2], -ex, -ey, -ez,
                    buf0)
    elif nr >= 3:
        cx = 0.0
        cy = 0.0
        cz = 0.0
        for c in range(nr):
            cx += ref_pts[c, 0]
            cy += ref_pts[c, 1]
            cz += ref_pts[c, 2]
        cx /= nr
        cy /= nr
        cz /= nr
        for c in range(nr):
            c2 = (c + 1) % nr
            ax, ay, az = ref_pts[c, 0], ref_pts[c, 1], ref_pts[c, 2]
            ex = ref_pts[c2, 0] - ax
            ey = ref_pts[c2, 1] - ay
            ez = ref_pts[c2, 2] - az
            sx = ny * ez - nz * ey
            sy = nz * ex - nx * ez
            sz = nx * ey - ny * ex
            if sx * (cx - ax) + sy * (cy - ay) + sz * (cz - az) < 0.0:
                sx = -sx
                sy = -sy
                sz = -sz
            cnt = _clip(buf0, cnt, ax, ay, az, sx, sy, sz, buf1)
            for q in range(cnt):
                for i in range(3):
                    buf0[q, i] = buf1[q, i]
    # keep the points below the reference plane (+ keep_dist)
    out = 0
    for c in range(cnt):
        sep = (nx * (buf0[c, 0] - ref_pts[0, 0]) + ny * (buf0[c, 1] - ref_pts[0, 1])
               + nz * (buf0[c, 2] - ref_pts[0, 2]))
        if not (sep <= keep_dist):
            continue
        for i in range(3):
            p = buf0[c, i]
            q = p - sep * n_ref[i]
            if ref_is_a:
                cpts_k[out, i] = q
                cpts_k[out, 3 + i] = p
            else:
                cpts_k[out, i] = p
                cpts_k[out, 3 + i] = q
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
            if dd <= CONTACT_SAME_SQ:
                dup = True
                break
        if not dup:
            for i in range(7):
                cpts_k[m, i] = cpts_k[c, i]
            m += 1
    return m


@njit_kernel
def _manifold_row(k, codes, params, vrange, verts, pairs, rows, pos_w, quat_w, out,
                  keep_dist, cpts, cnormal, ccount, ws):
    r = rows[k]
    c = _pair_manifold(codes, params, vrange, verts, pairs[r, 0], pairs[r, 1], pos_w,
                       quat_w, out[r], keep_dist, cpts[k], cnormal[k], ws)
    # never hand on non-finite numbers: fall back to the narrow phase's point
    ok = True
    for q in range(c):
        for i in range(7):
            if not math.isfinite(cpts[k, q, i]):
                ok = False
    if not ok:
        c = _single(out[r], cpts[k], cnormal[k])
    ccount[k] = c


@njit_kernel
def _workspace():
    return (np.empty((3, 3)), np.empty((3, 3)), np.zeros((MAX_FEATURE, 3)),
            np.zeros((MAX_FEATURE, 3)), np.zeros(3), np.zeros(3),
            np.zeros((MAX_FEATURE, 3)), np.zeros((MAX_FEATURE, 3)),
            np.zeros((MAX_MANIFOLD, 3)), np.zeros((MAX_MANIFOLD, 3)), np.zeros(3),
            np.zeros(3))


@njit_kernel
def _borrowed(ws):
    """The workspace's arrays as owner-less views (the caller keeps ``ws`` alive)."""
    return (borrow(ws[0]), borrow(ws[1]), borrow(ws[2]), borrow(ws[3]), borrow(ws[4]),
            borrow(ws[5]), borrow(ws[6]), borrow(ws[7]), borrow(ws[8]), borrow(ws[9]),
            borrow(ws[10]), borrow(ws[11]))


@njit_kernel
def _manifold_block(codes, params, vrange, verts, pairs, rows, pos_w, quat_w, out,
                    keep_dist, cpts, cnormal, ccount, lo, hi):
    """Rows [lo, hi) of ``manifold_batch`` with one scratch workspace, in a plain loop
    (faster than a loop inside numba's parallel region; see narrowphase._collide_block)."""
    # owner-less views: no atomic reference counting per row (jit.borrow)
    codes, params, vrange, verts = borrow(codes), borrow(params), borrow(vrange), borrow(verts)
    pairs, rows, pos_w, quat_w, out = (borrow(pairs), borrow(rows), borrow(pos_w),
                                       borrow(quat_w), borrow(out))
    cpts, cnormal, ccount = borrow(cpts), borrow(cnormal), borrow(ccount)
    own = _workspace()
    ws = _borrowed(own)
    for k in range(lo, hi):
        r = rows[k]
        if codes[pairs[r, 0]] <= ELLIPSOID or codes[pairs[r, 1]] <= ELLIPSOID:
            # a sphere or an ellipsoid presents one point: the narrow phase's (inline,
            # as a call with array arguments costs more than the copy)
            for i in range(3):
                cpts[k, 0, i] = out[r, OUT_PA + i]
                cpts[k, 0, 3 + i] = out[r, OUT_PB + i]
                cnormal[k, i] = out[r, OUT_NORMAL + i]
            cpts[k, 0, 6] = out[r, OUT_DIST]
            ccount[k] = 1
            continue
        _manifold_row(k, codes, params, vrange, verts, pairs, rows, pos_w, quat_w, out,
                      keep_dist, cpts, cnormal, ccount, ws)
    keep_alive(own)


def manifold_batch(codes, params, vrange, verts, pairs, rows, pos_w, quat_w, out,
                   keep_dist, cpts, cnormal, ccount):
    """Contact manifolds of the touching pairs ``pairs[rows]``.

    codes, params, vrange, verts: the shape table (body frames, m).
    pairs int64 (P, 2); rows int64 (T,): the rows of ``pairs`` / ``out`` to run, each a
        touching or penetrating pair; pos_w float64 (N, 3) m; quat_w float64 (N, 4)
        unit xyzw.
    out float64 (P, OUT_SIZE): the narrow phase's world rows.
    keep_dist float64 (m): clipped points up to this far outside the reference face
        are kept (speculative contacts, distance > 0).
    cpts float64 (>= T, MAX_MANIFOLD, 7) out: world point_a (3), point_b (3), distance.
    cnormal float64 (>= T, 3) out: unit normal A -> B, world.
    ccount int64 (>= T,) out: contacts of the pair (>= 1).
    Row k of the outputs is pair ``rows[k]``; rows run in contiguous blocks, one per
    thread (none smaller than MANIFOLD_CHUNK), with one scratch workspace each; every row
    writes only its own slots: deterministic for any thread count (jit.run_blocks, as
    narrowphase.collide_batch).
    """
    run_blocks(_manifold_block, (codes, params, vrange, verts, pairs, rows, pos_w, quat_w,
                                 out, keep_dist, cpts, cnormal, ccount),
               rows.shape[0], MANIFOLD_CHUNK)


@njit_kernel
def split_pairs(pairs, out, status, n_bodies, st_failed, t_rows, t_keys, t_status,
                t_method, u_rows, u_keys, u_status, u_method):
    """Sort the narrow phase's pairs (P rows, ``pairs`` int64 (P, 2) sorted, ``out``
    float64 (P, OUT_SIZE), ``status`` int64 (P,)) into touching and undecided ones.

    A row with a non-finite number is a failure whatever its status says: its status
    is set to ``st_failed`` in place.  Touching / penetrating rows go to ``t_*``, failed
    / not-run rows to ``u_*`` (each int64 (>= P,)): the row index, the key
    ``a * n_bodies + b`` (sorted, as the pairs are), the status and the method code.
    Returns (T, U).
    """
    nt = 0
    nu = 0
    for r in range(pairs.shape[0]):
        st = status[r]
        for c in range(out.shape[1]):
            if not math.isfinite(out[r, c]):
                st = st_failed
                status[r] = st
                break
        key = pairs[r, 0] * n_bodies + pairs[r, 1]
        if st == ST_TOUCHING or st == ST_PENETRATING:
            t_rows[nt] = r
            t_keys[nt] = key
            t_status[nt] = st
            t_method[nt] = np.int64(out[r, OUT_METHOD])
            nt += 1
        elif st != ST_SEPARATED:
            u_rows[nu] = r
            u_keys[nu] = key
            u_status[nu] = st
            u_method[nu] = np.int64(out[r, OUT_METHOD])
            nu += 1
    return nt, nu
