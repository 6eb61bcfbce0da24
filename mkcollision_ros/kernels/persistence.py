"""Contact persistence: the arbiters' kernel, ``arbiter_step``, and the reduction of a
pair's contacts to ``max_contacts`` (``_reduce``).

Persistence (``arbiter_step``, the arbiters' kernel, one serial pass so ids are
deterministic): the previous step's arbiters are merged with this step's touching and
undecided pairs by sorted key; each arbiter's stored contacts are refreshed from the
bodies' frames, matched to the new manifold by distance, the unmatched ones dropped past
the drift threshold, the set reduced to ``max_contacts`` (deepest, farthest, then
largest hull area: Bullet's ``sortCachedPoints``, Jolt's ``PruneContactPoints``), and
the surviving new ones get ids; events and the compacted new state are written to
preallocated arrays.  See arbiters.py.  Events: EV_BEGAN, EV_PERSISTED, EV_ENDED (below).

Contact ids are a function of the pair and the step, not of a counter: a new contact's
id is a 64-bit mix (splitmix64's finalizer) of its two bodies' hashes (``body_hash``,
from their names), the step's ``id_key`` (the bits of its stamp) and its sequence
number among the pair's new contacts of the step, masked to 63 bits (>= 0); the
sequence number is passed over when the mix equals an id the pair holds, so a pair's
ids are distinct at any time.  So every process that runs a pair on the same poses and
stamps hands out the same ids, whichever other pairs it runs (the shards of a scene,
pipeline.py).  Two pairs share an id with probability about (contacts alive)^2 / 2^64.
"""
import math

import numpy as np

from .constants import DEPTH_TIE, REDUCE_TIE
from .geometry import quat_to_matrix_into
from .jit import njit_kernel
from .manifold import MAX_MANIFOLD, _cross, _dot

# --- persistence: matching new contacts to stored ones (the arbiters' kernel) ----------
EV_BEGAN = 0
EV_PERSISTED = 1
EV_ENDED = 2
_FRESH_RANK = 1 << 62      # tie rank of contacts without an id yet (after every stored one)
# splitmix64's constants (the contact ids' mix, module docstring)
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX_1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX_2 = np.uint64(0x94D049BB133111EB)
_ID_MASK = np.uint64(0x7FFFFFFFFFFFFFFF)
# added to B's mixed hash in a pair's shard (pair_shards), a constant of its own so that
# a pair's shard and its contacts' ids are not the same draw
_SHARD_SALT = np.uint64(0x632BE59BD9B4E019)


@njit_kernel
def _mix64(x):
    """splitmix64's finalizer of the uint64 ``x``: a bijection that spreads every bit."""
    x = (x ^ (x >> np.uint64(30))) * _MIX_1
    x = (x ^ (x >> np.uint64(27))) * _MIX_2
    return x ^ (x >> np.uint64(31))


@njit_kernel
def pair_shards(body_hash, pairs, shard_count, out):
    """Write into ``out`` int64 (P,) the shard (0 <= s < shard_count) of each pair of
    ``pairs`` int64 (P, 2) (slots, A the lower), from the bodies' name hashes
    ``body_hash`` uint64 (S,) (arbiters.body_hashes): a mix of the pair's two hashes,
    modulo the count.  A pair's shard depends on its two names alone, so it never moves
    while the scene runs and its arbiter stays on one shard; and the mix spreads the
    pairs over the shards as a random draw would, so each shard gets an equal share of
    every kind of pair, and of the cost, in expectation (a cost-weighted split would
    have to move pairs as the scene changes)."""
    count = np.uint64(shard_count)
    for k in range(pairs.shape[0]):
        ha = body_hash[pairs[k, 0]]
        hb = body_hash[pairs[k, 1]]
        out[k] = np.int64(_mix64(ha ^ _mix64(hb + _SHARD_SALT)) % count)


@njit_kernel
def contact_id(hash_a, hash_b, id_key, seq):
    """The id (int64 >= 0) of a pair's new contact: bodies' hashes ``hash_a``,
    ``hash_b`` (uint64, A the lower slot), the step's ``id_key`` (uint64) and the
    sequence number ``seq`` (int64 >= 0) among the pair's new contacts of the step."""
    pair = _mix64(hash_a ^ _mix64(hash_b + _GOLDEN))
    step = _mix64(id_key + np.uint64(seq) * _GOLDEN)
    return np.int64(_mix64(pair ^ step) & _ID_MASK)


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
def _pick(score, rank, chosen, m, tol):
    """The unchosen candidate of largest ``score`` (m,), where every score within
    ``tol`` of the largest counts as equal and the smallest ``rank`` (the oldest
    contact) wins among them; -1 when all are chosen."""
    top = -np.inf
    for c in range(m):
        if not chosen[c] and score[c] > top:
            top = score[c]
    best = -1
    for c in range(m):
        if chosen[c] or not score[c] >= top - tol:
            continue
        if best < 0 or rank[c] < rank[best]:
            best = c
    return best


@njit_kernel
def _reduce(mid, depth, rank, n, m, k, keep, depth_tie):
    """Choose ``k`` of ``m`` contacts (midpoints ``mid`` (m, 3), ``depth`` (m,), tie
    ``rank`` (m,), smaller = older): the deepest, the farthest from it, then greedily
    the one giving the largest hull area in the plane normal to ``n``.  Writes the
    chosen indices into ``keep[:k]``.

    Scores that differ by less than a tie band count as equal and go to the older
    contact, so a flat rest, whose candidates tie up to the pose noise (a cylinder
    cap's 8-gon on a face: eight equal depths, pairs of equal areas), keeps the
    contacts it chose first: depths within ``depth_tie`` (m), squared distances and
    areas within REDUCE_TIE of the largest (relative)."""
    chosen = np.zeros(m, np.bool_)
    score = np.empty(m)
    best = _pick(depth, rank, chosen, m, depth_tie)
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
        top = 0.0
        for c in range(m):
            if chosen[c]:
                continue
            for q in range(t):
                sel[q] = keep[q]
            sel[t] = c
            if t == 1:
                dx = mid[c] - mid[keep[0]]
                score[c] = _dot(dx, dx)
            else:
                score[c] = _hull_area(px, py, sel, t + 1)
            top = max(top, score[c])
        best = _pick(score, rank, chosen, m, REDUCE_TIE * top)
        keep[t] = best
        chosen[best] = True


@njit_kernel
def arbiter_step(n_bodies, old, new, unconf, pos_w, quat_w, settings, id_key, body_hash,
                 out_arb, out_con, out_ev):
    """All arbiters of a scene for one step, in one serial pass.  Keys are ``a *
    n_bodies + b`` with a < b.

    old: the state of the previous step, a tuple
        (keys int64 (A,) sorted, unconfirmed int64 (A,) steps without confirmation,
         start int64 (A + 1,) arbiter k's stored contacts are rows [start[k], start[k+1])
         of: id int64 (S,), age int64 (S,), la, lb float64 (S, 3) points in A's / B's
         body frame (m), na float64 (S, 3) normal in A's frame).
    new: the touching pairs of this step, a tuple
        (tkeys int64 (T,) sorted, t_status int64 (T,), t_method int64 (T,),
         cpts float64 (>= T, MAX_MANIFOLD, 7), cnormal float64 (>= T, 3),
         ccount int64 (>= T,): manifolds, see ``manifold_batch``).
    unconf: pairs the narrow phase could not decide, a tuple
        (ukeys int64 (U,) sorted, u_status int64 (U,), u_method int64 (U,)).
    pos_w (N, 3) m, quat_w (N, 4) unit xyzw: this step's poses.
    settings: (merge_distance m, drift_threshold m, max_contacts int, stale_steps int).
    id_key uint64, body_hash uint64 (N,): the step's key and the bodies' hashes, of
        which new contacts' ids are made (module docstring).
    out_arb: (keys, unconfirmed int64 (>= A + T,), start int64 (>= A + T + 1,),
        pairs int64 (>= A + T, 2)) - the new state, arbiter rows.
    out_con: (body_a, body_b, id, age int64, la, lb, na, point_a, point_b, normal
        float64 (., 3), depth float64, status, method int64), at least
        (A + T) * max_contacts rows: the new contacts, by pair, then stored ones
        oldest first, then new ones in manifold order; point_a, point_b,
        normal in the world (m), depth >= 0 (m), status / method the pair's this step.
    out_ev: (kind int64 (EV_*), body_a, body_b, id int64), at least
        (A + T) * (1 + max_contacts) + S + T * MAX_MANIFOLD rows: events by pair, the
        pair's event (id -1) first, then its contacts' by id.
    Returns (arbiters, contacts, events).
    """
    o_keys, o_unc, o_start, o_id, o_age, o_la, o_lb, o_na = old
    tkeys, t_status, t_method, cpts, cnormal, ccount = new
    ukeys, u_status, u_method = unconf
    merge_distance, drift_threshold, max_contacts, stale_steps = settings
    a_keys, a_unc, a_start, a_pairs = out_arb
    (c_a, c_b, c_id, c_age, c_la, c_lb, c_na, c_pa, c_pb, c_n, c_depth, c_status,
     c_method) = out_con
    ev_kind, ev_a, ev_b, ev_id = out_ev
    # scratch of one arbiter (plain locals: tuples of arrays unpacked in the loop would
    # cost ~1 us of reference counting per arbiter)
    cap = MAX_MANIFOLD + 2 * max_contacts + 8
    ra = np.empty((3, 3))
    rb = np.empty((3, 3))
    spa = np.empty((cap, 3))
    spb = np.empty((cap, 3))
    sn = np.empty((cap, 3))
    sid = np.empty(cap, np.int64)
    sage = np.empty(cap, np.int64)
    pa = np.empty((cap, 3))
    pb = np.empty((cap, 3))
    nn = np.empty((cap, 3))
    ids = np.empty(cap, np.int64)
    age = np.empty(cap, np.int64)
    rank = np.empty(cap, np.int64)
    depth = np.empty(cap)
    mid = np.empty((cap, 3))
    keep = np.empty(cap, np.int64)
    match_new = np.empty(cap, np.int64)
    used_old = np.empty(cap, np.bool_)
    t_id = np.empty(2 * cap, np.int64)
    t_kind = np.empty(2 * cap, np.int64)
    n_old = o_keys.shape[0]
    n_t = tkeys.shape[0]
    n_u = ukeys.shape[0]
    io = 0
    it = 0
    iu = 0
    na = 0
    nc = 0
    ne = 0
    a_start[0] = 0
    while io < n_old or it < n_t:
        # the next key of the union of the old and the touching keys
        if it >= n_t or (io < n_old and o_keys[io] < tkeys[it]):
            key = o_keys[io]
        else:
            key = tkeys[it]
        has_old = io < n_old and o_keys[io] == key
        has_t = it < n_t and tkeys[it] == key
        ia = key // n_bodies
        ib = key % n_bodies
        s0 = o_start[io] if has_old else 0
        s1 = o_start[io + 1] if has_old else 0
        row = -1
        status = 0
        method = 0
        alive = True
        kind = EV_PERSISTED
        if has_t:
            row = it
            unc = 0
            status = t_status[it]
            method = t_method[it]
            if not has_old:
                kind = EV_BEGAN
        else:
            while iu < n_u and ukeys[iu] < key:
                iu += 1
            unc = o_unc[io] + 1
            if iu < n_u and ukeys[iu] == key and unc < stale_steps:
                status = u_status[iu]
                method = u_method[iu]
            else:
                alive = False
        ev_a[ne] = ia
        ev_b[ne] = ib
        ev_id[ne] = -1
        if alive:
            ev_kind[ne] = kind
            ne += 1
            quat_to_matrix_into(quat_w[ia], ra)
            quat_to_matrix_into(quat_w[ib], rb)
            te = 0
            # 1. stored contacts in the world
            m_old = 0
            for s in range(s0, s1):
                for i in range(3):
                    spa[m_old, i] = (pos_w[ia, i] + ra[i, 0] * o_la[s, 0] + ra[i, 1] * o_la[s, 1]
                                     + ra[i, 2] * o_la[s, 2])
                    spb[m_old, i] = (pos_w[ib, i] + rb[i, 0] * o_lb[s, 0] + rb[i, 1] * o_lb[s, 1]
                                     + rb[i, 2] * o_lb[s, 2])
                    sn[m_old, i] = ra[i, 0] * o_na[s, 0] + ra[i, 1] * o_na[s, 1] + ra[i, 2] * o_na[s, 2]
                sid[m_old] = o_id[s]
                sage[m_old] = o_age[s] + 1
                used_old[m_old] = False
                m_old += 1
            # 2. match this step's contacts to the stored ones, closest pairs first (before the
            #    drift rule: a sliding or spinning body moves its stored point on one body, but
            #    the new point is still where the stored one is on the other body)
            m_new = ccount[row] if row >= 0 else 0
            for i in range(m_new):
                match_new[i] = -1
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
            # 3. the merged set: this step's contacts, then the unmatched stored ones that did
            #    not drift (points apart along the normal, or across it, by > drift_threshold)
            m = np.int64(0)   # typed int64 at once (jit.py, "Literal")
            for i in range(m_new):
                for q in range(3):
                    pa[m, q] = cpts[row, i, q]
                    pb[m, q] = cpts[row, i, 3 + q]
                    nn[m, q] = cnormal[row, q]
                j = match_new[i]
                if j >= 0:
                    ids[m] = sid[j]
                    age[m] = sage[j]
                    rank[m] = j          # the stored order: oldest first
                else:
                    ids[m] = -1
                    age[m] = 0
                    rank[m] = _FRESH_RANK + i
                m += 1
            for j in range(m_old):
                if used_old[j]:
                    continue
                along = 0.0
                for q in range(3):
                    along += (spb[j, q] - spa[j, q]) * sn[j, q]
                side2 = 0.0
                for q in range(3):
                    g = spb[j, q] - spa[j, q] - along * sn[j, q]
                    side2 += g * g
                if along <= drift_threshold and math.sqrt(side2) <= drift_threshold:
                    for q in range(3):
                        pa[m, q] = spa[j, q]
                        pb[m, q] = spb[j, q]
                        nn[m, q] = sn[j, q]
                    ids[m] = sid[j]
                    age[m] = sage[j]
                    rank[m] = j
                    m += 1
                else:
                    t_id[te] = sid[j]
                    t_kind[te] = EV_ENDED
                    te += 1
            for c in range(m):
                dd = 0.0
                for q in range(3):
                    dd += (pb[c, q] - pa[c, q]) * nn[c, q]
                    mid[c, q] = 0.5 * (pa[c, q] + pb[c, q])
                depth[c] = max(0.0, -dd)
            # 4. reduce to max_contacts
            if m > max_contacts:
                nrm = cnormal[row].copy() if m_new > 0 else nn[0].copy()
                _reduce(mid, depth, rank, nrm, m, max_contacts, keep,
                        DEPTH_TIE * merge_distance)
                k = max_contacts
                for c in range(m):
                    if ids[c] < 0:
                        continue
                    kept = False
                    for q in range(k):
                        if keep[q] == c:
                            kept = True
                    if not kept:
                        t_id[te] = ids[c]
                        t_kind[te] = EV_ENDED
                        te += 1
            else:
                k = m
                for c in range(m):
                    keep[c] = c
            # order the survivors: stored ones as stored (oldest first), then fresh ones
            # in manifold order
            for c in range(1, k):
                v = keep[c]
                d = c - 1
                while d >= 0 and rank[keep[d]] > rank[v]:
                    keep[d + 1] = keep[d]
                    d -= 1
                keep[d + 1] = v
            seq = np.int64(0)
            for c in range(k):
                src = keep[c]
                if ids[src] < 0:
                    while True:          # an id the pair does not hold (module docstring)
                        cid = contact_id(body_hash[ia], body_hash[ib], id_key, seq)
                        seq += 1
                        held = False
                        for q in range(k):
                            if ids[keep[q]] == cid:
                                held = True
                        for q in range(m_old):       # ending ones too: no id ends and
                            if sid[q] == cid:        # begins in one step
                                held = True
                        if not held:
                            break
                    ids[src] = cid
                    t_kind[te] = EV_BEGAN
                else:
                    t_kind[te] = EV_PERSISTED
                t_id[te] = ids[src]
                te += 1
                o = nc + c
                c_a[o] = ia
                c_b[o] = ib
                c_id[o] = ids[src]
                c_age[o] = age[src]
                c_depth[o] = depth[src]
                for i in range(3):
                    c_pa[o, i] = pa[src, i]
                    c_pb[o, i] = pb[src, i]
                    c_n[o, i] = nn[src, i]
                for i in range(3):       # local frames: R^T (p - x)
                    c_la[o, i] = (ra[0, i] * (pa[src, 0] - pos_w[ia, 0]) + ra[1, i] * (pa[src, 1] - pos_w[ia, 1])
                                  + ra[2, i] * (pa[src, 2] - pos_w[ia, 2]))
                    c_lb[o, i] = (rb[0, i] * (pb[src, 0] - pos_w[ib, 0]) + rb[1, i] * (pb[src, 1] - pos_w[ib, 1])
                                  + rb[2, i] * (pb[src, 2] - pos_w[ib, 2]))
                    c_na[o, i] = ra[0, i] * nn[src, 0] + ra[1, i] * nn[src, 1] + ra[2, i] * nn[src, 2]
            # this arbiter's contact events, by id
            for c in range(1, te):
                vi = t_id[c]
                vk = t_kind[c]
                d = c - 1
                while d >= 0 and t_id[d] > vi:
                    t_id[d + 1] = t_id[d]
                    t_kind[d + 1] = t_kind[d]
                    d -= 1
                t_id[d + 1] = vi
                t_kind[d + 1] = vk
            for c in range(te):
                ev_kind[ne + c] = t_kind[c]
                ev_id[ne + c] = t_id[c]
            e = te
            for c in range(nc, nc + k):
                c_status[c] = status
                c_method[c] = method
            for c in range(ne, ne + e):
                ev_a[c] = ia
                ev_b[c] = ib
            a_keys[na] = key
            a_unc[na] = unc
            a_pairs[na, 0] = ia
            a_pairs[na, 1] = ib
            nc += k
            ne += e
            na += 1
            a_start[na] = nc
        else:
            ev_kind[ne] = EV_ENDED
            ne += 1
            for s in range(s0, s1):
                ev_kind[ne] = EV_ENDED
                ev_a[ne] = ia
                ev_b[ne] = ib
                ev_id[ne] = o_id[s]
                ne += 1
        if has_old:
            io += 1
        if has_t:
            it += 1
    return na, nc, ne
