"""Persistent contacts: one arbiter per touching pair (box2d-lite's Arbiter, Bullet's
persistent manifold, Jolt's contact listener for the events).

An arbiter is keyed by the canonical pair ``(a, b)``, ``a < b`` (body indices).  Each
step it receives the pair's new contacts (world frame, from the manifold) and:

  1. refreshes its stored contacts: each is kept in the two bodies' local frames
     (``local_a`` in A's frame, ``local_b`` in B's frame, ``normal_a`` in A's frame), so
     it follows the bodies; re-expressed in the world, a contact whose points drifted
     apart along the normal by more than ``drift_threshold`` (m, separating) or across
     it by more than ``drift_threshold`` is dropped (``ended``);
  2. matches every new contact to the closest stored one (greedy by distance, closest
     first, deterministic ties): within ``merge_distance`` (m, distance between the new
     and stored points on either body) it updates it and keeps its ``contact_id``;
     otherwise it is added (``began``) and, if it survives step 4, gets a new id from a
     monotonic counter (ids are never reused);
  3. stored contacts not matched survive (``persisted``) while within the drift rule;
  4. reduces to ``max_contacts``: the deepest, then the farthest from it, then the
     point spanning the largest triangle, then the largest quadrilateral, and so on by
     greedy area (Bullet's ``sortCachedPoints``, Jolt's ``PruneContactPoints``);
     ties go to the older contact (smaller id) so the manifold stays stable.

The arbiter of a pair is created when the pair starts touching (``began`` pair event)
and removed when it separates (``ended``) or was not confirmed (narrow phase failed or
did not run) for ``stale_steps`` steps.

Events are tuples ``(kind, body_a, body_b, contact_id)`` with ``kind`` one of
``"began"``, ``"persisted"``, ``"ended"``; ``contact_id`` is -1 for pair events.  They
are ordered by pair, the pair's event first, then its contacts' by id.  All vectors are
float64 in metres; depth >= 0 (m), distance = -depth when penetrating.

The pair bookkeeping is numpy over sorted pair keys ``a * n_bodies + b``; the contact
work runs in one serial numba kernel (``kernels.manifold.persist_batch``), so a step
with thousands of touching pairs costs milliseconds, not a Python loop per pair.
"""
import numpy as np

from .kernels.manifold import (EV_BEGAN, EV_ENDED, EV_PERSISTED, MAX_MANIFOLD,
                               persist_batch)

BEGAN = "began"
PERSISTED = "persisted"
ENDED = "ended"
_KIND_NAMES = np.array([BEGAN, PERSISTED, ENDED], dtype=object)
assert (EV_BEGAN, EV_PERSISTED, EV_ENDED) == (0, 1, 2)


def quat_matrices(quat_xyzw):
    """Rotation matrices float64 (N, 3, 3) of unit quaternions (N, 4) xyzw."""
    x, y, z, w = (quat_xyzw[:, i] for i in range(4))
    r = np.empty((len(quat_xyzw), 3, 3))
    r[:, 0, 0] = 1 - 2 * (y * y + z * z)
    r[:, 0, 1] = 2 * (x * y - z * w)
    r[:, 0, 2] = 2 * (x * z + y * w)
    r[:, 1, 0] = 2 * (x * y + z * w)
    r[:, 1, 1] = 1 - 2 * (x * x + z * z)
    r[:, 1, 2] = 2 * (y * z - x * w)
    r[:, 2, 0] = 2 * (x * z - y * w)
    r[:, 2, 1] = 2 * (y * z + x * w)
    r[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return r


class ArbiterSet:
    """All arbiters of a scene, as sorted arrays, and the contact id counter.

    n_bodies; merge_distance (m) > 0, drift_threshold (m) > 0, max_contacts >= 1,
    stale_steps >= 1.

    State (read-only outside this class), arbiters sorted by key = a * n_bodies + b:
      keys int64 (A,), unconfirmed int64 (A,): steps in a row without confirmation;
      contacts sorted by (key, id): c_key, c_id, c_age int64 (C,), c_la, c_lb float64
      (C, 3) points in A's / B's body frame (m), c_na float64 (C, 3) normal in A's frame.
    """

    def __init__(self, merge_distance, drift_threshold, max_contacts, stale_steps,
                 n_bodies=None):
        self.merge_distance = float(merge_distance)
        self.drift_threshold = float(drift_threshold)
        self.max_contacts = int(max_contacts)
        self.stale_steps = int(stale_steps)
        self.n_bodies = n_bodies
        self.next_id = 0
        self.keys = np.zeros(0, np.int64)
        self.unconfirmed = np.zeros(0, np.int64)
        self.c_key = np.zeros(0, np.int64)
        self.c_id = np.zeros(0, np.int64)
        self.c_age = np.zeros(0, np.int64)
        self.c_la = np.zeros((0, 3))
        self.c_lb = np.zeros((0, 3))
        self.c_na = np.zeros((0, 3))

    def __len__(self):
        return len(self.keys)

    def pairs(self):
        """Pairs with an arbiter, int64 (A, 2), a < b, sorted."""
        n = self._n()
        return np.stack([self.keys // n, self.keys % n], axis=1).astype(np.int64)

    def _n(self):
        if self.n_bodies is None:
            raise ValueError("ArbiterSet needs n_bodies (or a first update)")
        return self.n_bodies

    # ------------------------------------------------------------------------------
    def update(self, pos_w, quat_w, touching, unconfirmed):
        """Advance one step (dict form; the pipeline uses ``update_arrays``).

        pos_w float64 (N, 3), quat_w float64 (N, 4) unit xyzw: this step's poses.
        touching: dict {(a, b): (point_a (m, 3), point_b (m, 3), normal (3,))} of the pairs
            the narrow phase found touching, world frame, a < b, 1 <= m <= MAX_MANIFOLD.
        unconfirmed: set of pairs (a, b) the narrow phase could not decide (failed or not
            run); their arbiters are kept for ``stale_steps`` steps.
        Every other existing arbiter has separated and ends.
        Returns the events, a list of (kind, a, b, contact_id).
        """
        if self.n_bodies is None:
            self.n_bodies = len(pos_w)
        n = self.n_bodies
        tk = sorted(touching)
        cpts = np.zeros((len(tk), MAX_MANIFOLD, 7))
        cnormal = np.zeros((len(tk), 3))
        ccount = np.zeros(len(tk), np.int64)
        for r, key in enumerate(tk):
            pa, pb, nrm = touching[key]
            m = len(pa)
            cpts[r, :m, 0:3] = pa
            cpts[r, :m, 3:6] = pb
            cpts[r, :m, 6] = np.sum((np.asarray(pb) - pa) * nrm, axis=1)
            cnormal[r] = nrm
            ccount[r] = m
        tkeys = np.array([a * n + b for a, b in tk], np.int64)
        ukeys = np.array(sorted(a * n + b for a, b in unconfirmed), np.int64)
        return self.update_arrays(pos_w, quat_w, tkeys, cpts, cnormal, ccount, ukeys)

    def update_arrays(self, pos_w, quat_w, tkeys, cpts, cnormal, ccount, ukeys):
        """Advance one step (array form).

        tkeys int64 (T,) sorted keys a * n_bodies + b of the touching pairs, with their
        manifolds cpts float64 (T, MAX_MANIFOLD, 7), cnormal (T, 3), ccount int64 (T,)
        (see kernels.manifold.manifold_batch); ukeys int64 (U,) sorted keys of the pairs
        the narrow phase could not decide.  Returns the events (see ``update``).
        """
        n = self._n() if self.n_bodies is not None else len(pos_w)
        self.n_bodies = n
        old = self.keys
        in_t = np.isin(old, tkeys)
        in_u = np.isin(old, ukeys) & ~in_t
        unconf = np.where(in_t, 0, self.unconfirmed + 1)
        survive_u = in_u & (unconf < self.stale_steps)
        kept = in_t | survive_u
        fresh = tkeys[~np.isin(tkeys, old)]
        keys = np.concatenate([old[kept], fresh])
        order = np.argsort(keys, kind="stable")
        keys = keys[order]
        unconf = np.concatenate([unconf[kept], np.zeros(len(fresh), np.int64)])[order]
        is_fresh = np.concatenate([np.zeros(int(kept.sum()), bool),
                                   np.ones(len(fresh), bool)])[order]
        ended = old[~kept]
        # where each arbiter's stored contacts and new manifold are
        src = np.zeros((len(keys), 2), np.int64)
        src[:, 0] = np.searchsorted(self.c_key, keys, side="left")
        src[:, 1] = np.searchsorted(self.c_key, keys, side="right")
        src[is_fresh] = 0
        if len(tkeys):
            r = np.minimum(np.searchsorted(tkeys, keys), len(tkeys) - 1)
            row = np.where(tkeys[r] == keys, r, -1).astype(np.int64)
        else:
            row = np.full(len(keys), -1, np.int64)
        k = self.max_contacts
        a_cap = len(keys) * k
        n_id = np.zeros(a_cap, np.int64)
        n_age = np.zeros(a_cap, np.int64)
        n_la = np.zeros((a_cap, 3))
        n_lb = np.zeros((a_cap, 3))
        n_na = np.zeros((a_cap, 3))
        n_pa = np.zeros((a_cap, 3))
        n_pb = np.zeros((a_cap, 3))
        n_n = np.zeros((a_cap, 3))
        n_count = np.zeros(len(keys), np.int64)
        ev_cap = len(self.c_id) + a_cap + 1
        ev_arb = np.zeros(ev_cap, np.int64)
        ev_kind = np.zeros(ev_cap, np.int64)
        ev_id = np.zeros(ev_cap, np.int64)
        if len(keys):
            self.next_id, n_ev = persist_batch(
                keys // n, keys % n, src, row, self.c_id, self.c_age, self.c_la, self.c_lb,
                self.c_na, np.ascontiguousarray(cpts, dtype=np.float64),
                np.ascontiguousarray(cnormal, dtype=np.float64),
                np.ascontiguousarray(ccount, dtype=np.int64), pos_w, quat_w,
                self.merge_distance, self.drift_threshold, k, self.next_id, n_id, n_age,
                n_la, n_lb, n_na, n_pa, n_pb, n_n, n_count, ev_arb, ev_kind, ev_id)
        else:
            n_ev = 0
        # events: pair events (id -1) and contact events, sorted by key then id
        ended_rows = np.isin(self.c_key, ended)
        e_key = np.concatenate([keys, ended, keys[ev_arb[:n_ev]], self.c_key[ended_rows]])
        e_id = np.concatenate([np.full(len(keys) + len(ended), -1, np.int64), ev_id[:n_ev],
                               self.c_id[ended_rows]])
        e_kind = np.concatenate([np.where(is_fresh, 0, 1), np.full(len(ended), 2),
                                 ev_kind[:n_ev], np.full(int(ended_rows.sum()), 2)])
        o = np.lexsort((e_id, e_key))
        e_key, e_id, e_kind = e_key[o], e_id[o], e_kind[o]
        events = list(zip(_KIND_NAMES[e_kind].tolist(), (e_key // n).tolist(),
                          (e_key % n).tolist(), e_id.tolist()))
        # compact the new state
        valid = (np.arange(a_cap) % k) < np.repeat(n_count, k)
        self.keys = keys
        self.unconfirmed = unconf.astype(np.int64)
        self.c_key = np.repeat(keys, n_count)
        self.c_id = n_id[valid]
        self.c_age = n_age[valid]
        self.c_la = n_la[valid]
        self.c_lb = n_lb[valid]
        self.c_na = n_na[valid]
        self._world = (n_pa[valid], n_pb[valid], n_n[valid])
        return events

    def contacts(self, pos_w=None, quat_w=None):
        """Every stored contact in the world, ordered by pair then id: dict of arrays
        body_a, body_b, contact_id, age (int64 (C,)), point_a, point_b, normal
        (float64 (C, 3)), depth (float64 (C,), >= 0).  Without poses: as of the last
        update; with poses: the stored local points moved to those poses."""
        n = self.n_bodies or 1
        a = self.c_key // n
        b = self.c_key % n
        if pos_w is None:
            pa, pb, nrm = self._world if hasattr(self, "_world") else (
                np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
        else:
            rot = quat_matrices(np.asarray(quat_w, np.float64))
            pa = np.einsum("cij,cj->ci", rot[a], self.c_la) + pos_w[a]
            pb = np.einsum("cij,cj->ci", rot[b], self.c_lb) + pos_w[b]
            nrm = np.einsum("cij,cj->ci", rot[a], self.c_na)
        depth = np.maximum(0.0, -np.sum((pb - pa) * nrm, axis=1))
        return {"body_a": a.astype(np.int64), "body_b": b.astype(np.int64),
                "contact_id": self.c_id.copy(), "age": self.c_age.copy(),
                "point_a": pa, "point_b": pb, "normal": nrm, "depth": depth}
