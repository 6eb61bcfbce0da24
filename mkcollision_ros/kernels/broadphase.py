"""Broad phase: exact world AABBs, then a hashed uniform grid; pose and pair filters.

Phases
  1. ``world_aabbs``  - exact world AABB of every body from closed forms of each shape's
     extent along the world axes (box |R| h, ellipsoid sqrt(sum (r_kj a_j)^2), capsule,
     cylinder and cone from their axis and rim; a hull's rotated vertices), grown by the
     margin and ``grow`` (m) on every side.  A plane has no bounded extent: its AABB is
     +-inf on every axis except the one its normal is aligned with (if any), and its
     world half-space ``n_w . x <= d_w`` (grown by margin and ``grow``) is written to
     ``plane_w`` for the pair test.
  2. ``find_pairs``   - a uniform grid, one of two kinds.
     The dense grid, whenever its table is small (at most DENSE_CELLS_PER_BODY cells a
     body): cell edge = the largest AABB extent, so two overlapping boxes have their
     centres in the same or neighbouring cells; each body is entered once, in the cell
     of its centre (a counting sort over a table of every cell, x-major, z fastest), and
     its row reads the 3 x 3 columns around it, each three cells along z one
     contiguous run.  A pair is reported from the lower body's row.  Bodies larger than
     DENSE_BIG_FACTOR x the mean extent are tested against every body instead.
     The hashed grid, for spread or clustered scenes: cell edge GRID_CELL_SCALE x the
     mean largest AABB extent, hashed (Morton code folded onto the table size) into a
     table of counting-sorted entries; every body is entered in each cell its AABB
     touches, and a pair is reported only from the lower body's row and only in the
     cell holding the corner max(lo_i, lo_j), so exactly once.  Bodies spanning more
     than GRID_BIG_CELLS cells are tested against every body instead.  Rows are visited
     in the previous call's space-filling order (passed in and handed back, the broad
     phase keeps no state).  The dense grid costs about a third of the hashed one at
     10,000 bodies (one entry a body instead of about four, and no hashing).  Each plane is paired with every non-plane body whose AABB reaches its
     grown half-space (the AABB corner farthest along -n_w satisfies n_w . x <= d_w).
     Plane-plane pairs are never reported (the narrow phase does not run them).
  3. ``filter_pairs`` (static / group-mask / allowed pairs) and ``normalise_poses``:
     the pipeline's per-pair and per-body checks as one pass each.

The reported set is EXACTLY the pairs whose closed AABB intervals overlap on all three
axes (plus the plane rule above), as int64 (P, 2) rows (i, j), i < j, sorted
lexicographically; every loop writes into fixed slots (each row keeps up to
GRID_ROW_SLOTS sorted keys in its own slots while counting; rows with more run again
into their final offsets), so the output does not depend on the thread count or on
the visiting order.

Why a grid rather than sweep-and-prune (SAP).  SAP tests every body against all the
bodies whose x-interval it overlaps, which in a uniform 3-D scene is ~N^(1/3) times the
true neighbours; the grid only sees the cells around each body, so it grows linearly at
fixed density.  It loses on one-dimensional layouts (where SAP is ideal) and on large
slabs among small parts (randomly turned 8 m slabs span ~1,000 cells each, so they are
"big" and tested against every body).  The cost is dominated by memory latency (random
bucket reads), hence the Morton hash and the space-filling visiting order.  Threads: a
second thread makes these kernels slower whenever the other core is busy, so the
pipeline runs them on one thread below ``PARALLEL_MIN_CHEAP_ITEMS`` (the same compiled
code, the same numbers).
"""
import math

import numpy as np

from .constants import (BOX, CAPSULE, CONE, CYLINDER, ELLIPSOID, NO_DIRECTION, PLANE,
                        PLANE_AXIS_TOL, P_MARGIN, SPHERE)
from .jit import njit_kernel, njit_parallel, prange, run_blocks

# a static_grid of at most this many cells gets a table of each cell's entries (8 bytes
# a cell), larger ones are searched by bisection
STATIC_DENSE_CELLS = 1 << 22
# fewest bodies per block of world_aabbs (jit.n_blocks)
AABB_CHUNK = 1024
# grid cell edge = this x the mean largest AABB extent of the bodies (dimensionless)
GRID_CELL_SCALE = 1.5
# a body spanning more than this many cells is not put in the grid but tested against
# every body (a ground slab of 8 x 8 m among 1 m parts spans ~60 cells: still gridded)
GRID_BIG_CELLS = 256
# keys a row keeps in its fixed slots in the first pass (rows with more run again)
GRID_ROW_SLOTS = 16
# at most this many cells along an axis (the cell grows for very spread scenes; keys
# pack each cell coordinate in 21 bits)
GRID_MAX_CELLS = 1 << 20
# the dense grid (one entry per body): bodies larger than this x the mean largest
# extent are tested against every body; the table has at most this many cells per body
# (+ DENSE_MIN_CELLS), for which the cell may grow to DENSE_MAX_GROW x the largest
# extent; a scene that still needs more cells takes the hashed grid
DENSE_BIG_FACTOR = 4.0
DENSE_CELLS_PER_BODY = 4
DENSE_MIN_CELLS = 4096
DENSE_MAX_GROW = 2.0


def world_aabbs(codes, params, vrange, verts, pos_w, quat_w, grow, lo, hi, plane_w):
    """World AABBs of N bodies, exact (closed forms of each shape's extent along the
    world axes; a hull's rotated vertices), grown by the margin and ``grow``.

    codes int64 (N,), params float64 (N, 8), vrange int64 (N, 2), verts float64 (M, 3):
        the shape table (body frames, metres).
    pos_w float64 (N, 3) world positions (m); quat_w float64 (N, 4) unit quat_xyzw.
    grow float64: distance (m) added on every side of every box (>= 0).
    lo, hi float64 (N, 3) out: world AABB corners (m); planes get +-inf where unbounded.
    plane_w float64 (N, 4) out: for planes (n_w (3,), d_w) of the grown world half-space
        n_w . x <= d_w; zeros for other bodies.
    Bodies run in blocks of at least AABB_CHUNK, one per numba thread (jit.run_blocks).
    """
    run_blocks(_world_aabbs_block, (codes, params, vrange, verts, pos_w, quat_w, grow, lo,
                                    hi, plane_w), codes.shape[0], AABB_CHUNK)


@njit_kernel
def _world_aabbs_block(codes, params, vrange, verts, pos_w, quat_w, grow, lo, hi, plane_w,
                       first, last):
    """world_aabbs of the bodies [first, last).  (One loop body without calls taking
    arrays: those cost ~0.3 us per body of reference counting.)"""
    for i in range(first, last):
        x, y, z, w = quat_w[i, 0], quat_w[i, 1], quat_w[i, 2], quat_w[i, 3]
        # rows of the rotation matrix: row k is world axis e_k in the body frame
        r00 = 1.0 - 2.0 * (y * y + z * z)
        r01 = 2.0 * (x * y - z * w)
        r02 = 2.0 * (x * z + y * w)
        r10 = 2.0 * (x * y + z * w)
        r11 = 1.0 - 2.0 * (x * x + z * z)
        r12 = 2.0 * (y * z - x * w)
        r20 = 2.0 * (x * z - y * w)
        r21 = 2.0 * (y * z + x * w)
        r22 = 1.0 - 2.0 * (x * x + y * y)
        code = codes[i]
        p0, p1, p2 = params[i, 0], params[i, 1], params[i, 2]
        pad = params[i, P_MARGIN] + grow
        if code == PLANE:
            n0 = r00 * p0 + r01 * p1 + r02 * p2
            n1 = r10 * p0 + r11 * p1 + r12 * p2
            n2 = r20 * p0 + r21 * p1 + r22 * p2
            dw = params[i, 3] + n0 * pos_w[i, 0] + n1 * pos_w[i, 1] + n2 * pos_w[i, 2] + pad
            plane_w[i, 0] = n0
            plane_w[i, 1] = n1
            plane_w[i, 2] = n2
            plane_w[i, 3] = dw
            for k in range(3):
                lo[i, k] = -np.inf
                hi[i, k] = np.inf
            for k in range(3):
                nk = n0 if k == 0 else (n1 if k == 1 else n2)
                off = 0.0
                for q in range(3):
                    if q != k:
                        off = max(off, abs(n0 if q == 0 else (n1 if q == 1 else n2)))
                if off <= PLANE_AXIS_TOL:
                    # n_w = +-e_k: the half-space is x_k <= dw or x_k >= -dw
                    if nk > 0.0:
                        hi[i, k] = dw / nk
                    elif nk < 0.0:
                        lo[i, k] = dw / nk
            continue
        for k in range(4):
            plane_w[i, k] = 0.0
        for k in range(3):
            if k == 0:
                a0, a1, a2 = r00, r01, r02
            elif k == 1:
                a0, a1, a2 = r10, r11, r12
            else:
                a0, a1, a2 = r20, r21, r22
            # support values of the core along +a (up) and -a (down), body frame
            if code == SPHERE:
                up = p0
                down = p0
            elif code == ELLIPSOID:
                up = math.sqrt((p0 * a0) ** 2 + (p1 * a1) ** 2 + (p2 * a2) ** 2)
                down = up
            elif code == BOX:
                up = abs(a0) * p0 + abs(a1) * p1 + abs(a2) * p2
                down = up
            elif code == CAPSULE:
                up = abs(a2) * p1 + p0
                down = up
            elif code == CYLINDER:
                up = abs(a2) * p1 + p0 * math.sqrt(a0 * a0 + a1 * a1)
                down = up
            elif code == CONE:
                rim = p0 * math.sqrt(a0 * a0 + a1 * a1)
                up = max(p1 * a2, rim - p1 * a2)
                down = max(-p1 * a2, rim + p1 * a2)
            else:  # CONVEX
                up = -np.inf
                down = -np.inf
                for v in range(vrange[i, 0], vrange[i, 0] + vrange[i, 1]):
                    d = a0 * verts[v, 0] + a1 * verts[v, 1] + a2 * verts[v, 2]
                    up = max(up, d)
                    down = max(down, -d)
            hi[i, k] = pos_w[i, k] + up + pad
            lo[i, k] = pos_w[i, k] - down - pad


@njit_kernel
def _spread3(v):
    """The low 21 bits of v spread to every third bit (Morton interleaving)."""
    v &= 0x1FFFFF
    v = (v | (v << 32)) & 0x1F00000000FFFF
    v = (v | (v << 16)) & 0x1F0000FF0000FF
    v = (v | (v << 8)) & 0x100F00F00F00F00F
    v = (v | (v << 4)) & 0x10C30C30C30C30C3
    v = (v | (v << 2)) & 0x1249249249249249
    return v


@njit_kernel
def _cell_hash(ix, iy, iz, mask, shift):
    """Bucket of the integer cell (ix, iy, iz) in a table of mask + 1 = 2**shift
    buckets: its Morton code folded onto ``shift`` bits, so that nearby cells get nearby
    buckets (the scans stay in cache) while far-spread scenes still use every bucket;
    distinct cells may share a bucket, entries carry their cell."""
    return _fold(_spread3(ix) | (_spread3(iy) << 1) | (_spread3(iz) << 2), mask, shift)


@njit_kernel
def _fold(code, mask, shift):
    """A Morton code folded onto ``shift`` bits (see ``_cell_hash``); the loops over a
    body's cells spread each coordinate once and call this per cell."""
    return (code ^ (code >> shift) ^ (code >> (2 * shift)) ^ (code >> (3 * shift))) & mask


@njit_kernel
def _cell_key(ix, iy, iz):
    """One int64 per cell (each coordinate in [0, 2**21))."""
    return (ix << 42) | (iy << 21) | iz


@njit_kernel
def _row_output(r, write, out, offsets, slots):
    """Where row r writes its keys: (done, base, keys).  The first pass (not ``write``)
    writes into the row's own slots; the second runs only the rows that did not fit
    (done: those that did), straight into ``out`` from offsets[r]."""
    if write:
        return offsets[r + 1] - offsets[r] <= slots.shape[1], offsets[r], out
    return False, r * slots.shape[1], slots.reshape(-1)


@njit_kernel
def _sort_run(keys, base, count):
    """keys[base:base + count] ascending in place (a row's few keys: insertion sort)."""
    for a in range(base + 1, base + count):
        v = keys[a]
        d = a - 1
        while d >= base and keys[d] > v:
            keys[d + 1] = keys[d]
            d -= 1
        keys[d + 1] = v


@njit_parallel
def _grid_par(bodies, order, lo, hi, cmin, cmax, big, is_big, mask, shift, bucket_start,
              e_body, e_key, e_cmin, e_box, n, counts, write, out, offsets, slots):
    """Pairs (i, j), i < j, of each body i = bodies[r] (see ``find_pairs``): its grid
    neighbours through the shared cells, plus every big body; a big body's row tests
    every later body.  Without ``write``: stores each row's count in ``counts[r]`` and
    its first slots.shape[1] keys i * n + j in ``slots[r]`` (ascending when they all
    fit).  With ``write``: runs again only the rows that did not fit, writing their
    keys, ascending, from out[offsets[r]].  The entries of each bucket (e_body rank,
    e_key cell, e_cmin (E, 3) the body's first cell, e_box (E, 6) its AABB lo, hi) are
    copied in bucket order so that a scan reads contiguous memory.  (One loop body, no
    calls taking arrays: a call per row with a dozen array arguments costs ~0.3 us of
    reference counting.)
    """
    m = bodies.shape[0]
    cap = slots.shape[1]
    for q in prange(m):
        r = order[q]      # rows in space-filling order (cache), each in its own slots
        i = bodies[r]
        c = np.int64(0)      # typed int64 at once (jit.py, "Literal")
        done, base, dst = _row_output(r, write, out, offsets, slots)
        if done:
            continue
        if is_big[r]:
            for t in range(r + 1, m):
                j = bodies[t]
                if (lo[i, 0] <= hi[j, 0] and lo[j, 0] <= hi[i, 0] and lo[i, 1] <= hi[j, 1]
                        and lo[j, 1] <= hi[i, 1] and lo[i, 2] <= hi[j, 2]
                        and lo[j, 2] <= hi[i, 2]):
                    if write or c < cap:
                        dst[base + c] = i * n + j
                    c += 1
        else:
            for b in range(big.shape[0]):
                t = big[b]
                if t <= r:
                    continue
                j = bodies[t]
                if (lo[i, 0] <= hi[j, 0] and lo[j, 0] <= hi[i, 0] and lo[i, 1] <= hi[j, 1]
                        and lo[j, 1] <= hi[i, 1] and lo[i, 2] <= hi[j, 2]
                        and lo[j, 2] <= hi[i, 2]):
                    if write or c < cap:
                        dst[base + c] = i * n + j
                    c += 1
            x0, y0, z0 = cmin[r, 0], cmin[r, 1], cmin[r, 2]
            lo0, lo1, lo2 = lo[i, 0], lo[i, 1], lo[i, 2]
            hi0, hi1, hi2 = hi[i, 0], hi[i, 1], hi[i, 2]
            for ix in range(x0, cmax[r, 0] + 1):
                sx = _spread3(ix)
                for iy in range(y0, cmax[r, 1] + 1):
                    sxy = sx | (_spread3(iy) << 1)
                    for iz in range(z0, cmax[r, 2] + 1):
                        key = (ix << 42) | (iy << 21) | iz
                        hb = _fold(sxy | (_spread3(iz) << 2), mask, shift)
                        for e in range(bucket_start[hb], bucket_start[hb + 1]):
                            t = e_body[e]
                            if t <= r or e_key[e] != key:
                                continue
                            # report the pair only in the cell of max(lo_i, lo_j)
                            if ix != max(x0, e_cmin[e, 0]) or iy != max(y0, e_cmin[e, 1]) or (
                                    iz != max(z0, e_cmin[e, 2])):
                                continue
                            if (lo0 <= e_box[e, 3] and e_box[e, 0] <= hi0
                                    and lo1 <= e_box[e, 4] and e_box[e, 1] <= hi1
                                    and lo2 <= e_box[e, 5] and e_box[e, 2] <= hi2):
                                if write or c < cap:
                                    dst[base + c] = i * n + bodies[t]
                                c += 1
        if write or c <= cap:
            _sort_run(dst, base, c)
        counts[r] = c


@njit_kernel
def _dense_grid(lo, hi, bodies):
    """The dense grid of the non-plane ``bodies`` (see ``find_pairs``), or ok False when
    its table would be too large.  Returns (ok, cell (m, 3) int64 each row's cell,
    ncell (3,), start (cells + 1,) each cell's first entry, e_body (E,) and e_box (E, 6)
    the entries' body and AABB lo, hi in cell order, rows (m,) the rows in cell order
    then the big ones, big (B,) the big rows, is_big (m,))."""
    m = bodies.shape[0]
    ext = np.empty(m)
    total = 0.0
    for r in range(m):
        i = bodies[r]
        e = 0.0
        for k in range(3):
            e = max(e, hi[i, k] - lo[i, k])
        ext[r] = e
        total += e
    mean = total / max(m, 1)
    is_big = np.zeros(m, np.bool_)
    n_big = 0
    h = 0.0
    for r in range(m):
        if ext[r] > DENSE_BIG_FACTOR * mean:
            is_big[r] = True
            n_big += 1
        else:
            h = max(h, ext[r])
    # a little over the largest extent: centres at most h apart stay within one cell
    # of each other after rounding
    h = h * (1.0 + 1e-6) if h > 0.0 else 1.0
    origin = np.full(3, np.inf)
    top = np.full(3, -np.inf)
    for r in range(m):
        if not is_big[r]:
            i = bodies[r]
            for k in range(3):
                c = 0.5 * (lo[i, k] + hi[i, k])
                origin[k] = min(origin[k], c)
                top[k] = max(top[k], c)
    span = np.zeros(3)
    for k in range(3):
        if top[k] > origin[k]:
            span[k] = top[k] - origin[k]
        else:
            origin[k] = 0.0
    limit = float(DENSE_CELLS_PER_BODY * m + DENSE_MIN_CELLS)
    cells = (span[0] / h + 1.0) * (span[1] / h + 1.0) * (span[2] / h + 1.0)
    if cells > limit:                  # grow the cell, within DENSE_MAX_GROW
        lo_h = h
        hi_h = DENSE_MAX_GROW * h
        if (span[0] / hi_h + 1.0) * (span[1] / hi_h + 1.0) * (span[2] / hi_h + 1.0) > limit:
            return (False, np.empty((0, 3), np.int64), np.ones(3, np.int64),
                    np.zeros(1, np.int64), np.empty(0, np.int64), np.empty((0, 6)),
                    np.empty(0, np.int64), np.empty(0, np.int64), is_big)
        for _ in range(30):            # bisection on the edge
            mid = 0.5 * (lo_h + hi_h)
            if (span[0] / mid + 1.0) * (span[1] / mid + 1.0) * (span[2] / mid + 1.0) > limit:
                lo_h = mid
            else:
                hi_h = mid
        h = hi_h
    ncell = np.ones(3, np.int64)
    for k in range(3):
        ncell[k] = np.int64(math.floor(span[k] / h)) + 1
    n_cells = ncell[0] * ncell[1] * ncell[2]
    cell = np.zeros((m, 3), np.int64)
    flat = np.empty(m, np.int64)
    start = np.zeros(n_cells + 1, np.int64)
    for r in range(m):
        if is_big[r]:
            continue
        i = bodies[r]
        for k in range(3):
            v = np.int64(math.floor((0.5 * (lo[i, k] + hi[i, k]) - origin[k]) / h))
            cell[r, k] = min(max(v, 0), ncell[k] - 1)
        flat[r] = (cell[r, 0] * ncell[1] + cell[r, 1]) * ncell[2] + cell[r, 2]
        start[flat[r] + 1] += 1
    for c in range(n_cells):
        start[c + 1] += start[c]
    fill = start[:n_cells].copy()
    n_entries = m - n_big
    e_body = np.empty(n_entries, np.int64)
    e_box = np.empty((n_entries, 6))
    rows = np.empty(m, np.int64)
    big = np.empty(n_big, np.int64)
    b = 0
    for r in range(m):
        if is_big[r]:
            big[b] = r
            rows[n_entries + b] = r
            b += 1
            continue
        e = fill[flat[r]]
        fill[flat[r]] += 1
        i = bodies[r]
        e_body[e] = i
        rows[e] = r
        for k in range(3):
            e_box[e, k] = lo[i, k]
            e_box[e, 3 + k] = hi[i, k]
    return True, cell, ncell, start, e_body, e_box, rows, big, is_big


@njit_parallel
def _dense_par(bodies, rows, lo, hi, cell, ncell, start, e_body, e_box, big, is_big, n,
               counts, write, out, offsets, slots):
    """The dense grid's pairs (i, j), i < j, of each body i = bodies[r] (see
    ``find_pairs``): the entries of the 3 x 3 x 3 cells around its own, plus every big
    body; a big body's row tests every body.  ``write``, ``counts``, ``out``,
    ``offsets`` and ``slots`` as in ``_grid_par``.  (One loop body, as there.)"""
    m = bodies.shape[0]
    cap = slots.shape[1]
    ny = ncell[1]
    nz = ncell[2]
    for q in prange(m):
        r = rows[q]       # rows in cell order (cache), each in its own slots
        i = bodies[r]
        c = np.int64(0)      # typed int64 at once (jit.py, "Literal")
        done, base, dst = _row_output(r, write, out, offsets, slots)
        if done:
            continue
        lo0, lo1, lo2 = lo[i, 0], lo[i, 1], lo[i, 2]
        hi0, hi1, hi2 = hi[i, 0], hi[i, 1], hi[i, 2]
        if is_big[r]:
            for t in range(m):
                j = bodies[t]
                if (j > i and lo0 <= hi[j, 0] and lo[j, 0] <= hi0 and lo1 <= hi[j, 1]
                        and lo[j, 1] <= hi1 and lo2 <= hi[j, 2] and lo[j, 2] <= hi2):
                    if write or c < cap:
                        dst[base + c] = i * n + j
                    c += 1
        else:
            for t in range(big.shape[0]):
                j = bodies[big[t]]
                if (j > i and lo0 <= hi[j, 0] and lo[j, 0] <= hi0 and lo1 <= hi[j, 1]
                        and lo[j, 1] <= hi1 and lo2 <= hi[j, 2] and lo[j, 2] <= hi2):
                    if write or c < cap:
                        dst[base + c] = i * n + j
                    c += 1
            z0 = max(cell[r, 2] - 1, 0)
            z1 = min(cell[r, 2] + 1, nz - 1)
            for ix in range(max(cell[r, 0] - 1, 0), min(cell[r, 0] + 1, ncell[0] - 1) + 1):
                for iy in range(max(cell[r, 1] - 1, 0), min(cell[r, 1] + 1, ny - 1) + 1):
                    column = (ix * ny + iy) * nz
                    for e in range(start[column + z0], start[column + z1 + 1]):
                        j = e_body[e]
                        if (j > i and lo0 <= e_box[e, 3] and e_box[e, 0] <= hi0
                                and lo1 <= e_box[e, 4] and e_box[e, 1] <= hi1
                                and lo2 <= e_box[e, 5] and e_box[e, 2] <= hi2):
                            if write or c < cap:
                                dst[base + c] = i * n + j
                            c += 1
        if write or c <= cap:
            _sort_run(dst, base, c)
        counts[r] = c


@njit_kernel
def _plane_row(b, planes, bodies, lo, hi, plane_w, hit):
    i = bodies[b]
    for q in range(planes.shape[0]):
        p = planes[q]
        s = 0.0
        for k in range(3):
            nk = plane_w[p, k]
            s += nk * (lo[i, k] if nk > 0.0 else hi[i, k])
        hit[q, b] = s <= plane_w[p, 3]


@njit_parallel
def _plane_par(planes, bodies, lo, hi, plane_w, hit):
    for b in prange(bodies.shape[0]):
        _plane_row(b, planes, bodies, lo, hi, plane_w, hit)


@njit_kernel
def _grid_extent(lo, hi, rows):
    """The frame of a grid over the boxes ``rows`` int64 of lo, hi (N, 3): their lowest
    and highest corners (zeros without rows), a cell edge of GRID_CELL_SCALE x their
    mean largest extent (1 for points) and the largest side of their union.  Returns
    (origin (3,), top (3,), edge, span)."""
    origin = np.full(3, np.inf)
    top = np.full(3, -np.inf)
    ext = 0.0
    for r in range(rows.shape[0]):
        i = rows[r]
        e = 0.0
        for k in range(3):
            origin[k] = min(origin[k], lo[i, k])
            top[k] = max(top[k], hi[i, k])
            e = max(e, hi[i, k] - lo[i, k])
        ext += e
    h = GRID_CELL_SCALE * ext / max(rows.shape[0], 1)
    span = 0.0
    for k in range(3):
        if rows.shape[0] == 0:
            origin[k] = 0.0
            top[k] = 0.0
        span = max(span, top[k] - origin[k])
    if not h > 0.0:
        h = 1.0
    return origin, top, h, span


@njit_kernel
def _hashed_grid(lo, hi, bodies, order_prev):
    """The hashed grid of the non-plane ``bodies`` (see ``find_pairs``).  Returns (cmin,
    cmax (m, 3) each row's cell range, big (B,) the big rows, is_big (m,), mask, shift
    of the bucket table, bucket_start, the entries e_body, e_key, e_cmin, e_box in
    bucket order, order (m,) the rows to visit, new_order (m,) the next call's)."""
    m = bodies.shape[0]
    # cell size from the mean largest extent, origin at the lowest corner
    origin, top, h, span = _grid_extent(lo, hi, bodies)
    if span / h > GRID_MAX_CELLS:
        h = span / GRID_MAX_CELLS
    cmin = np.empty((m, 3), np.int64)
    cmax = np.empty((m, 3), np.int64)
    is_big = np.zeros(m, np.bool_)
    n_big = 0
    n_entries = 0
    for r in range(m):
        i = bodies[r]
        cells = 1.0
        for k in range(3):
            cmin[r, k] = np.int64(math.floor((lo[i, k] - origin[k]) / h))
            cmax[r, k] = np.int64(math.floor((hi[i, k] - origin[k]) / h))
            cells *= float(cmax[r, k] - cmin[r, k] + 1)
        if cells > GRID_BIG_CELLS:
            is_big[r] = True
        if is_big[r]:
            n_big += 1
        else:
            n_entries += np.int64(cells)
    big = np.empty(n_big, np.int64)
    n_big = 0
    for r in range(m):
        if is_big[r]:
            big[n_big] = r
            n_big += 1
    size = 1
    shift = 0
    while size < n_entries:
        size *= 2
        shift += 1
    shift = max(shift, 1)
    mask = size - 1
    # rows in the previous call's order if it is one (bodies barely move between steps,
    # so it is still nearly space-filling), else in index order
    order = np.empty(m, np.int64)
    ok = order_prev.shape[0] == m
    if ok:
        seen = np.zeros(m, np.bool_)
        for q in range(m):
            r = order_prev[q]
            if r < 0 or r >= m or seen[r]:
                ok = False
                break
            seen[r] = True
            order[q] = r
    if not ok:
        for q in range(m):
            order[q] = q
    bucket_start = np.zeros(size + 1, np.int64)
    for q in range(m):
        r = order[q]
        if is_big[r]:
            continue
        for ix in range(cmin[r, 0], cmax[r, 0] + 1):
            sx = _spread3(ix)
            for iy in range(cmin[r, 1], cmax[r, 1] + 1):
                sxy = sx | (_spread3(iy) << 1)
                for iz in range(cmin[r, 2], cmax[r, 2] + 1):
                    bucket_start[_fold(sxy | (_spread3(iz) << 2), mask, shift) + 1] += 1
    for c in range(size):
        bucket_start[c + 1] += bucket_start[c]
    fill = bucket_start[:size].copy()
    e_body = np.empty(n_entries, np.int64)
    e_key = np.empty(n_entries, np.int64)
    e_cmin = np.empty((n_entries, 3), np.int64)
    e_box = np.empty((n_entries, 6))
    for q in range(m):
        r = order[q]
        if is_big[r]:
            continue
        i = bodies[r]
        for ix in range(cmin[r, 0], cmax[r, 0] + 1):
            sx = _spread3(ix)
            for iy in range(cmin[r, 1], cmax[r, 1] + 1):
                sxy = sx | (_spread3(iy) << 1)
                for iz in range(cmin[r, 2], cmax[r, 2] + 1):
                    hb = _fold(sxy | (_spread3(iz) << 2), mask, shift)
                    e = fill[hb]
                    e_body[e] = r
                    e_key[e] = _cell_key(ix, iy, iz)
                    for k in range(3):
                        e_cmin[e, k] = cmin[r, k]
                        e_box[e, k] = lo[i, k]
                        e_box[e, 3 + k] = hi[i, k]
                    fill[hb] += 1
    # the next call's row order: small bodies by the bucket of their first cell (Morton
    # order), then the big ones
    new_order = np.empty(m, np.int64)
    q = 0
    for e in range(n_entries):
        r = e_body[e]
        if e_key[e] == _cell_key(cmin[r, 0], cmin[r, 1], cmin[r, 2]):
            new_order[q] = r
            q += 1
    for b in range(n_big):
        new_order[q] = big[b]
        q += 1
    return (cmin, cmax, big, is_big, mask, shift, bucket_start, e_body, e_key, e_cmin, e_box,
            order, new_order)


@njit_kernel
def find_pairs(lo, hi, is_plane, plane_w, order_prev, axis_prev):
    """Overlapping AABB pairs.

    lo, hi float64 (N, 3): world AABBs (m) from ``world_aabbs``.
    is_plane bool (N,); plane_w float64 (N, 4): grown world half-spaces of the planes.
    order_prev int64 (m,): the order returned by the previous call (or empty): the
        bodies are visited in it, which keeps memory accesses local; any permutation of
        the m non-plane bodies' ranks is valid, anything else is ignored.  The result
        does not depend on it (the dense grid does not use it).  axis_prev: unused.
    Returns (pairs int64 (P, 2) with i < j sorted lexicographically,
             order int64 (m,) to pass back as ``order_prev``,
             kind: 1 the dense grid ran, 0 the hashed grid).
    """
    n = lo.shape[0]
    n_planes = 0
    for i in range(n):
        if is_plane[i]:
            n_planes += 1
    bodies = np.empty(n - n_planes, np.int64)
    planes = np.empty(n_planes, np.int64)
    a = 0
    b = 0
    for i in range(n):
        if is_plane[i]:
            planes[b] = i
            b += 1
        else:
            bodies[a] = i
            a += 1
    m = bodies.shape[0]
    # --- body pairs: count per row, then write each row's keys sorted in its slot
    # (one pass writes up to GRID_ROW_SLOTS keys per row into fixed slots and counts;
    # only rows with more are run again, straight into the output)
    counts = np.zeros(m, np.int64)
    offsets = np.zeros(m + 1, np.int64)
    slots = np.empty((m, GRID_ROW_SLOTS), np.int64)
    dummy = np.empty(0, np.int64)
    dense, cell, ncell, start, d_body, d_box, d_rows, d_big, d_is_big = _dense_grid(
        lo, hi, bodies)
    if dense:
        new_order = d_rows
        _dense_par(bodies, d_rows, lo, hi, cell, ncell, start, d_body, d_box, d_big,
                   d_is_big, n, counts, np.bool_(False), dummy, offsets, slots)
    else:
        (cmin, cmax, big, is_big, mask, shift, bucket_start, e_body, e_key, e_cmin, e_box,
         order, new_order) = _hashed_grid(lo, hi, bodies, order_prev)
        _grid_par(bodies, order, lo, hi, cmin, cmax, big, is_big, mask, shift, bucket_start,
                  e_body, e_key, e_cmin, e_box, n, counts, np.bool_(False), dummy, offsets,
                  slots)
    n_over = 0
    for r in range(m):
        offsets[r + 1] = offsets[r] + counts[r]
        if counts[r] > GRID_ROW_SLOTS:
            n_over += 1
    n_body_pairs = offsets[m]
    body_keys = np.empty(n_body_pairs, np.int64)
    for r in range(m):
        if counts[r] <= GRID_ROW_SLOTS:
            for c in range(counts[r]):
                body_keys[offsets[r] + c] = slots[r, c]
    if n_over > 0 and dense:
        _dense_par(bodies, d_rows, lo, hi, cell, ncell, start, d_body, d_box, d_big,
                   d_is_big, n, counts, np.bool_(True), body_keys, offsets, slots)
    elif n_over > 0:
        _grid_par(bodies, order, lo, hi, cmin, cmax, big, is_big, mask, shift,
                  bucket_start, e_body, e_key, e_cmin, e_box, n, counts, np.bool_(True),
                  body_keys, offsets, slots)
    # --- planes against every body reaching their half-space
    hit = np.zeros((n_planes, m), np.bool_)
    if n_planes > 0 and m > 0:
        _plane_par(planes, bodies, lo, hi, plane_w, hit)
    n_plane_pairs = 0
    for q in range(n_planes):
        for r in range(m):
            if hit[q, r]:
                n_plane_pairs += 1
    plane_keys = np.empty(n_plane_pairs, np.int64)
    t = 0
    for q in range(n_planes):
        p = planes[q]
        for r in range(m):
            if hit[q, r]:
                i = bodies[r]
                plane_keys[t] = min(i, p) * n + max(i, p)
                t += 1
    if n_planes > 1 or (n_planes == 1 and planes[0] < n - 1):
        plane_keys.sort()
    # --- merge the two sorted key lists
    keys = np.empty(n_body_pairs + n_plane_pairs, np.int64)
    x = 0
    y = 0
    for t in range(keys.shape[0]):
        if y >= n_plane_pairs or (x < n_body_pairs and body_keys[x] < plane_keys[y]):
            keys[t] = body_keys[x]
            x += 1
        else:
            keys[t] = plane_keys[y]
            y += 1
    pairs = np.empty((keys.shape[0], 2), np.int64)
    for t in range(keys.shape[0]):
        pairs[t, 0] = keys[t] // n
        pairs[t, 1] = keys[t] % n
    return pairs, new_order, np.int64(1 if dense else 0)


@njit_kernel
def static_grid(lo, hi):
    """A grid of static bodies, built once and queried every step (static_pairs).

    lo, hi float64 (S, 3): the static bodies' world AABBs (m; no planes: find_pairs
    pairs a plane with every body).  Cell edge GRID_CELL_SCALE x their mean largest
    extent (grown so that no axis has more than GRID_MAX_CELLS cells), origin at their
    lowest corner; a body spanning more than GRID_BIG_CELLS cells is left out of the
    cells and listed in ``big``.
    Returns (frame float64 (7,) = origin (3), cell edge, cells per axis (3),
             keys int64 (E,) the sorted cell numbers ((x ny + y) nz + z) of every
             (cell, body) entry, members int64 (E,) the entries' body rows,
             start int64 (C + 1,): the entries of cell c are [start[c], start[c + 1]),
             when the grid has C <= STATIC_DENSE_CELLS cells, else empty (a cell's
             entries are then found by bisection in ``keys``), big int64 (B,) rows)."""
    n = lo.shape[0]
    frame = np.zeros(7)
    origin, top, h, span = _grid_extent(lo, hi, np.arange(n))
    if span / h > GRID_MAX_CELLS - 1:
        h = span / (GRID_MAX_CELLS - 1)
    for k in range(3):
        frame[k] = origin[k]
        frame[4 + k] = math.floor((top[k] - origin[k]) / h) + 1
    frame[3] = h
    count = np.zeros(n, np.int64)
    n_big = 0
    for i in range(n):
        c = 1
        for k in range(3):
            c *= (int(math.floor((hi[i, k] - origin[k]) / h))
                  - int(math.floor((lo[i, k] - origin[k]) / h)) + 1)
        if c > GRID_BIG_CELLS:
            n_big += 1
        else:
            count[i] = c
    keys = np.empty(count.sum(), np.int64)
    members = np.empty(keys.shape[0], np.int64)
    big = np.empty(n_big, np.int64)
    e = 0
    b = 0
    for i in range(n):
        if count[i] == 0:
            big[b] = i
            b += 1
            continue
        x0 = int(math.floor((lo[i, 0] - origin[0]) / h))
        y0 = int(math.floor((lo[i, 1] - origin[1]) / h))
        z0 = int(math.floor((lo[i, 2] - origin[2]) / h))
        x1 = int(math.floor((hi[i, 0] - origin[0]) / h))
        y1 = int(math.floor((hi[i, 1] - origin[1]) / h))
        z1 = int(math.floor((hi[i, 2] - origin[2]) / h))
        for x in range(x0, x1 + 1):
            for y in range(y0, y1 + 1):
                for z in range(z0, z1 + 1):
                    keys[e] = _cell_number(x, y, z, frame)
                    members[e] = i
                    e += 1
    order = np.argsort(keys, kind="mergesort")
    keys, members = keys[order], members[order]
    cells = 1.0
    for k in range(3):
        cells *= frame[4 + k]
    start = np.zeros(0, np.int64)
    if cells <= STATIC_DENSE_CELLS:
        start = np.searchsorted(keys, np.arange(int(cells) + 1))
    return frame, keys, members, start, big


@njit_kernel
def _cell_number(x, y, z, frame):
    """The number (x ny + y) nz + z of the cell (x, y, z) of a static_grid."""
    return (x * np.int64(frame[5]) + y) * np.int64(frame[6]) + z


@njit_kernel
def _cell_of(x, origin, h, top):
    """The cell coordinate of x along one axis of a static_grid, clamped to [0, top]."""
    c = int(math.floor((x - origin) / h))
    return min(max(c, 0), top)


@njit_kernel
def static_pairs(lo_m, hi_m, lo_s, hi_s, frame, keys, members, start, big):
    """The overlapping pairs of moving and static bodies: row (m, s) for every moving
    body m (AABBs lo_m, hi_m (M, 3)) and static body s (lo_s, hi_s (S, 3), indexed by the
    static_grid ``frame, keys, members, big``) whose closed AABBs overlap on all three
    axes, each pair once (found in the cell holding max(lo_m, lo_s), as find_pairs),
    sorted by m then s.  Costs O(M) grid cells and their entries, not O(S); a moving
    body over more than GRID_BIG_CELLS cells is tested against every static body."""
    h = frame[3]
    tx, ty, tz = int(frame[4]) - 1, int(frame[5]) - 1, int(frame[6]) - 1
    count = np.zeros(lo_m.shape[0] + 1, np.int64)
    for sweep in range(2):
        if sweep == 1:
            for m in range(lo_m.shape[0]):
                count[m + 1] += count[m]
            out = np.empty((count[-1], 2), np.int64)
        else:
            out = np.empty((0, 2), np.int64)
        for m in range(lo_m.shape[0]):
            w = count[m]
            outside = False
            for k in range(3):
                if hi_m[m, k] < frame[k] or lo_m[m, k] > frame[k] + (frame[4 + k]) * h:
                    outside = True
            found = 0
            x0 = _cell_of(lo_m[m, 0], frame[0], h, tx)
            y0 = _cell_of(lo_m[m, 1], frame[1], h, ty)
            z0 = _cell_of(lo_m[m, 2], frame[2], h, tz)
            x1 = _cell_of(hi_m[m, 0], frame[0], h, tx)
            y1 = _cell_of(hi_m[m, 1], frame[1], h, ty)
            z1 = _cell_of(hi_m[m, 2], frame[2], h, tz)
            # a body over many cells is tested against every static body instead
            brute = (x1 - x0 + 1) * (y1 - y0 + 1) * (z1 - z0 + 1) > GRID_BIG_CELLS
            if not outside and not brute:
                for x in range(x0, x1 + 1):
                    for y in range(y0, y1 + 1):
                        for z in range(z0, z1 + 1):
                            key = _cell_number(x, y, z, frame)
                            if start.shape[0]:
                                e, last = start[key], start[key + 1]
                            else:
                                e = np.searchsorted(keys, key)
                                last = e
                                while last < keys.shape[0] and keys[last] == key:
                                    last += 1
                            while e < last:
                                s = members[e]
                                e += 1
                                if (lo_m[m, 0] > hi_s[s, 0] or lo_s[s, 0] > hi_m[m, 0]
                                        or lo_m[m, 1] > hi_s[s, 1] or lo_s[s, 1] > hi_m[m, 1]
                                        or lo_m[m, 2] > hi_s[s, 2] or lo_s[s, 2] > hi_m[m, 2]):
                                    continue
                                # the one cell of the pair: that of the corner max(lo)
                                if (_cell_of(max(lo_m[m, 0], lo_s[s, 0]), frame[0], h, tx) != x
                                        or _cell_of(max(lo_m[m, 1], lo_s[s, 1]), frame[1], h,
                                                    ty) != y
                                        or _cell_of(max(lo_m[m, 2], lo_s[s, 2]), frame[2], h,
                                                    tz) != z):
                                    continue
                                if sweep == 1:
                                    out[w + found, 0] = m
                                    out[w + found, 1] = s
                                found += 1
            for q in range(lo_s.shape[0] if brute else big.shape[0]):
                s = q if brute else big[q]
                if outside:
                    break
                if (lo_m[m, 0] > hi_s[s, 0] or lo_s[s, 0] > hi_m[m, 0]
                        or lo_m[m, 1] > hi_s[s, 1] or lo_s[s, 1] > hi_m[m, 1]
                        or lo_m[m, 2] > hi_s[s, 2] or lo_s[s, 2] > hi_m[m, 2]):
                    continue
                if sweep == 1:
                    out[w + found, 0] = m
                    out[w + found, 1] = s
                found += 1
            if sweep == 0:
                count[m + 1] = found
            else:
                # the statics of m in increasing order
                rows = out[w:w + found, 1]
                rows.sort()
    return out


@njit_kernel
def poses_unchanged(slots, pos_w, quat_w, old_pos, old_quat):
    """Whether the rows ``slots`` int64 (K,) of pos_w (S, 3) and quat_w (S, 4) equal
    old_pos (K, 3) and old_quat (K, 4) exactly (the static grid's check that its bodies
    kept their poses: no copy of the rows, and it stops at the first change)."""
    for r in range(slots.shape[0]):
        i = slots[r]
        for k in range(3):
            if pos_w[i, k] != old_pos[r, k]:
                return False
        for k in range(4):
            if quat_w[i, k] != old_quat[r, k]:
                return False
    return True


@njit_kernel
def normalise_poses(pos_w, quat_w, quat_out):
    """Check and normalise N poses in one pass.

    pos_w float64 (N, 3) m; quat_w float64 (N, 4) xyzw of any non-zero norm;
    quat_out float64 (N, 4) out: the unit quaternions.
    Returns (body, why): the first bad body and 1 non-finite position, 2 non-finite
    quaternion, 3 zero quaternion (norm <= 1e-12); (-1, 0) when all are good.
    """
    for i in range(pos_w.shape[0]):
        for k in range(3):
            if not math.isfinite(pos_w[i, k]):
                return i, 1
        s = 0.0
        for k in range(4):
            v = quat_w[i, k]
            if not math.isfinite(v):
                return i, 2
            s += v * v
        nrm = math.sqrt(s)
        if not nrm > NO_DIRECTION:
            return i, 3
        for k in range(4):
            quat_out[i, k] = quat_w[i, k] / nrm
    return -1, 0


@njit_kernel
def filter_pairs(pairs, static, group, mask, allowed, n_bodies):
    """The pairs int64 (P, 2) that may collide: not both ``static`` (bool (N,)),
    ``(group[i] & mask[j]) != 0 and (group[j] & mask[i]) != 0`` (int64 (N,)), and
    key ``i * n_bodies + j`` not in ``allowed`` (int64 (K,), sorted).  Returns int64
    (Q, 2), in the input's order."""
    keep = np.empty(pairs.shape[0], np.bool_)
    q = 0
    na = allowed.shape[0]
    for r in range(pairs.shape[0]):
        i = pairs[r, 0]
        j = pairs[r, 1]
        ok = (not (static[i] and static[j])) and (group[i] & mask[j]) != 0 and (
            group[j] & mask[i]) != 0
        if ok and na > 0:
            key = i * n_bodies + j
            t = np.searchsorted(allowed, key)
            if t < na and allowed[t] == key:
                ok = False
        keep[r] = ok
        q += ok
    out = np.empty((q, 2), np.int64)
    q = 0
    for r in range(pairs.shape[0]):
        if keep[r]:
            out[q, 0] = pairs[r, 0]
            out[q, 1] = pairs[r, 1]
            q += 1
    return out
