"""Persistent contacts: one arbiter per touching pair (box2d-lite's Arbiter, Bullet's
persistent manifold, Jolt's contact listener for the events).

An arbiter is keyed by the canonical pair ``(a, b)``, ``a < b`` (body slots, key
``a * KEY_BASE + b``, scene.KEY_BASE, so keys do not change as a scene grows).  Each
step it receives the pair's new contacts (world frame, from the manifold) and:

  1. refreshes its stored contacts: each is kept in the two bodies' local frames
     (``local_a`` in A's frame, ``local_b`` in B's frame, ``normal_a`` in A's frame), so
     it follows the bodies;
  2. matches every new contact to the closest stored one (greedy by distance, closest
     first, deterministic ties): within ``merge_distance`` (m, distance between the new
     and stored points on either body) it updates it and keeps its ``contact_id``;
     otherwise it is added (``began``) and, if it survives step 4, gets a new id: a
     63-bit mix of the two bodies' name hashes (``body_hashes``), the step's stamp
     (``stamp_key``) and its number among the pair's new contacts of the step, never
     one the pair holds (kernels/persistence.py); so any process that runs the pair on
     the same poses and stamps gives it the same ids, whatever else it runs (shards).
     Matching comes before the drift rule (as Bullet's getCacheEntry comes before
     refreshContactPoints): a body sliding or spinning faster than ``drift_threshold``
     per step moves the stored point on the other body away, but the new point is
     still where the stored one is on its own body, so the id survives (the demo's id
     churn; tests/test_pipeline.py);
  3. stored contacts not matched survive (``persisted``) while their points, re-expressed
     in the world, are within ``drift_threshold`` (m) of each other along the normal
     (separating) and across it; otherwise they end (``ended``);
  4. reduces to ``max_contacts``: the deepest, then the farthest from it, then the
     point spanning the largest triangle, then the largest quadrilateral, and so on by
     greedy area (Bullet's ``sortCachedPoints``, Jolt's ``PruneContactPoints``);
     ties go to the older contact so the manifold stays stable.

The arbiter of a pair is created when the pair starts touching (``began`` pair event)
and removed when it separates (``ended``) or was not confirmed (narrow phase failed or
did not run) for ``stale_steps`` steps.  ``end_bodies`` ends every arbiter of given
bodies at once (a body removed from the scene, or given a new shape).

Events are an ``Events`` object: arrays ``kind`` (EV_BEGAN 0 / EV_PERSISTED 1 /
EV_ENDED 2), ``body_a``, ``body_b``, ``contact_id`` (-1 for pair events), ordered by
pair, the pair's event first, then its contacts' by id.  Iterating it (or ``tolist()``)
gives tuples ``(kind, body_a, body_b, contact_id)`` with ``kind`` one of ``"began"``,
``"persisted"``, ``"ended"``, and it compares equal to a list of such tuples.  All
vectors are float64 in metres; depth >= 0 (m), distance = -depth when penetrating.

The whole step - merging the previous arbiters with this step's touching and undecided
pairs (a sorted-key merge), matching, drift, reduction, ids, events and the compacted
new state - is one serial numba kernel (``kernels.persistence.arbiter_step``), so a step
costs microseconds for a few pairs and ~1 us per touching pair, with no Python loop.
"""
import hashlib

import numpy as np

from .kernels.constants import ST_NOT_RUN
from .kernels.manifold import MAX_MANIFOLD
from .kernels.persistence import EV_BEGAN, EV_ENDED, EV_PERSISTED, arbiter_step
from .rotations import quat_to_matrix
from .scene import KEY_BASE

def body_hashes(names):
    """uint64 (N,): each body name's hash (BLAKE2b, the same in every process), 0 for a
    free slot (None); the bodies' part of their contacts' ids."""
    return np.array([0 if n is None else
                     int.from_bytes(hashlib.blake2b(n.encode(), digest_size=8).digest(),
                                    "little") for n in names], np.uint64)


def stamp_key(stamp):
    """The step's part of its new contacts' ids: the bits of the float64 ``stamp``."""
    return np.float64(stamp).view(np.uint64)


BEGAN = "began"
PERSISTED = "persisted"
ENDED = "ended"
KIND_NAMES = np.array([BEGAN, PERSISTED, ENDED], dtype=object)
assert (EV_BEGAN, EV_PERSISTED, EV_ENDED) == (0, 1, 2)


class Events:
    """Events of one step, as arrays (E,): ``kind`` int64 (EV_BEGAN / EV_PERSISTED /
    EV_ENDED; ``KIND_NAMES[kind]`` are the names), ``body_a``, ``body_b`` int64 (a < b),
    ``contact_id`` int64 (-1 for the pair's own event).  Ordered by pair, the pair's
    event first, then its contacts' by id.  ``tolist()``, iteration and indexing give
    tuples ``(kind name, body_a, body_b, contact_id)`` of Python values; ``==`` compares
    with another Events or a list of such tuples."""

    __slots__ = ("kind", "body_a", "body_b", "contact_id")
    __hash__ = None

    def __init__(self, kind, body_a, body_b, contact_id):
        self.kind = kind
        self.body_a = body_a
        self.body_b = body_b
        self.contact_id = contact_id

    @classmethod
    def empty(cls):
        z = np.zeros(0, np.int64)
        return cls(z, z, z, z)

    def tolist(self):
        return list(zip(KIND_NAMES[self.kind].tolist(), self.body_a.tolist(),
                        self.body_b.tolist(), self.contact_id.tolist()))

    def __len__(self):
        return len(self.kind)

    def __iter__(self):
        return iter(self.tolist())

    def __getitem__(self, i):
        return self.tolist()[i]

    def __contains__(self, item):
        return item in self.tolist()

    def __eq__(self, other):
        if isinstance(other, Events):
            return all(np.array_equal(getattr(self, f), getattr(other, f))
                       for f in self.__slots__)
        if isinstance(other, (list, tuple)):
            return self.tolist() == list(other)
        return NotImplemented

    def __repr__(self):
        return f"Events({self.tolist()!r})"

    @classmethod
    def concat(cls, *parts):
        """The events of ``parts`` one after the other."""
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in cls.__slots__))


class ArbiterSet:
    """All arbiters of a scene, as sorted arrays.

    merge_distance (m) > 0, drift_threshold (m) > 0, max_contacts >= 1,
    stale_steps >= 1 (attributes, may change between steps).

    State (read-only outside this class), arbiters sorted by key = a * KEY_BASE + b:
      keys int64 (A,), unconfirmed int64 (A,): steps in a row without confirmation,
      start int64 (A + 1,): arbiter k's contacts are rows [start[k], start[k + 1]);
      contacts by key, each arbiter's oldest first: c_id, c_age int64 (C,), c_la, c_lb
      float64 (C, 3)
      points in A's / B's body frame (m), c_na float64 (C, 3) normal in A's frame.
    """

    def __init__(self, merge_distance, drift_threshold, max_contacts, stale_steps):
        self.merge_distance = float(merge_distance)
        self.drift_threshold = float(drift_threshold)
        self.max_contacts = int(max_contacts)
        self.stale_steps = int(stale_steps)
        z = np.zeros(0, np.int64)
        self.keys = z
        self.unconfirmed = z
        self.start = np.zeros(1, np.int64)
        self._pairs = np.zeros((0, 2), np.int64)
        self.c_id = z
        self.c_age = z
        self.c_la = self.c_lb = self.c_na = np.zeros((0, 3))
        self._con = {"body_a": z, "body_b": z, "contact_id": z, "age": z,
                     "point_a": np.zeros((0, 3)), "point_b": np.zeros((0, 3)),
                     "normal": np.zeros((0, 3)), "depth": np.zeros(0),
                     "status": z, "method": z}

    def __len__(self):
        return len(self.keys)

    def pairs(self):
        """Pairs with an arbiter, int64 (A, 2), a < b, sorted."""
        return self._pairs

    # ------------------------------------------------------------------------------
    def update(self, pos_w, quat_w, touching, unconfirmed, stamp=0.0, body_hash=None):
        """Advance one step (dict form; the pipeline uses ``update_arrays``).

        pos_w float64 (N, 3), quat_w float64 (N, 4) unit xyzw: this step's poses.
        touching: dict {(a, b): (point_a (m, 3), point_b (m, 3), normal (3,))} of the pairs
            the narrow phase found touching, world frame, a < b, 1 <= m <= MAX_MANIFOLD.
        unconfirmed: set of pairs (a, b) the narrow phase could not decide (failed or not
            run); their arbiters are kept for ``stale_steps`` steps.
        Every other existing arbiter has separated and ends.  ``stamp`` (s) and
        ``body_hash``: see ``update_arrays``.
        Returns the Events.
        """
        n = KEY_BASE
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
        return self.update_arrays(np.ascontiguousarray(pos_w, np.float64),
                                  np.ascontiguousarray(quat_w, np.float64),
                                  tkeys, cpts, cnormal, ccount, ukeys, stamp=stamp,
                                  body_hash=body_hash)

    def update_arrays(self, pos_w, quat_w, tkeys, cpts, cnormal, ccount, ukeys,
                      t_status=None, t_method=None, u_status=None, u_method=None,
                      stamp=0.0, body_hash=None):
        """Advance one step (array form).

        pos_w float64 (N, 3), quat_w float64 (N, 4) unit xyzw, both C-contiguous.
        tkeys int64 (T,) sorted keys a * KEY_BASE + b of the touching pairs, with their
        manifolds in the first T rows of cpts float64 (>= T, MAX_MANIFOLD, 7), cnormal
        (>= T, 3), ccount int64 (>= T,) (see kernels.manifold.manifold_batch); ukeys
        int64 (U,) sorted keys of the pairs the narrow phase could not decide.
        t_status, t_method int64 (T,), u_status, u_method int64 (U,): the pairs' status
        and method codes, reported with their contacts (default ST_NOT_RUN / 0).
        stamp (s): the step's time; body_hash uint64 (N,): ``body_hashes`` of the
        bodies' names (default: of their slot numbers); the new contacts' ids come from
        both (module docstring).
        Returns the Events.
        """
        n = KEY_BASE
        t, u = len(tkeys), len(ukeys)
        if body_hash is None:
            body_hash = np.arange(len(pos_w), dtype=np.uint64)
        if t_status is None:
            t_status = np.full(t, ST_NOT_RUN, np.int64)
        if t_method is None:
            t_method = np.zeros(t, np.int64)
        if u_status is None:
            u_status = np.full(u, ST_NOT_RUN, np.int64)
        if u_method is None:
            u_method = np.zeros(u, np.int64)
        k = self.max_contacts
        a_cap = len(self.keys) + t
        c_cap = a_cap * k
        e_cap = a_cap * (1 + k) + len(self.c_id)
        out_arb = (np.empty(a_cap, np.int64), np.empty(a_cap, np.int64),
                   np.empty(a_cap + 1, np.int64), np.empty((a_cap, 2), np.int64))
        i64 = [np.empty(c_cap, np.int64) for _ in range(4)]
        f3 = [np.empty((c_cap, 3)) for _ in range(6)]
        out_con = (*i64, *f3, np.empty(c_cap), np.empty(c_cap, np.int64),
                   np.empty(c_cap, np.int64))
        out_ev = tuple(np.empty(e_cap, np.int64) for _ in range(4))
        old = (self.keys, self.unconfirmed, self.start, self.c_id, self.c_age, self.c_la,
               self.c_lb, self.c_na)
        new = (tkeys, t_status, t_method, cpts, cnormal, ccount)
        settings = (self.merge_distance, self.drift_threshold, k, self.stale_steps)
        na, nc, ne = arbiter_step(
            n, old, new, (ukeys, u_status, u_method), pos_w, quat_w, settings,
            stamp_key(stamp), body_hash, out_arb, out_con, out_ev)
        self.keys = out_arb[0][:na]
        self.unconfirmed = out_arb[1][:na]
        self.start = out_arb[2][:na + 1]
        self._pairs = out_arb[3][:na]
        c = [x[:nc] for x in out_con]
        self.c_id, self.c_age, self.c_la, self.c_lb, self.c_na = c[2], c[3], c[4], c[5], c[6]
        self._con = {"body_a": c[0], "body_b": c[1], "contact_id": c[2], "age": c[3],
                     "point_a": c[7], "point_b": c[8], "normal": c[9], "depth": c[10],
                     "status": c[11], "method": c[12]}
        return Events(*(x[:ne] for x in out_ev))

    def end_bodies(self, slots):
        """End every arbiter with a body in ``slots`` (int64 (K,)): they are removed and
        their events returned (Events: each pair's ``ended``, then its contacts' by id)."""
        slots = np.asarray(slots, np.int64)
        if not len(self.keys) or not len(slots):
            return Events.empty()
        hit = np.isin(self._pairs[:, 0], slots) | np.isin(self._pairs[:, 1], slots)
        if not hit.any():
            return Events.empty()
        counts = np.diff(self.start)
        c_hit = np.repeat(hit, counts)
        # events: one row per ended pair plus one per contact, pair rows first
        ends = np.flatnonzero(hit)
        n_ev = counts[ends] + 1
        at = np.concatenate([[0], np.cumsum(n_ev)[:-1]])
        total = int(n_ev.sum())
        ev_a = np.repeat(self._pairs[ends, 0], n_ev)
        ev_b = np.repeat(self._pairs[ends, 1], n_ev)
        ev_id = np.full(total, -1, np.int64)
        is_contact = np.ones(total, bool)
        is_contact[at] = False
        ids = self.c_id[c_hit]                     # by pair, each pair's oldest first
        group = np.repeat(np.arange(len(ends)), counts[ends])
        ev_id[is_contact] = ids[np.lexsort((ids, group))]      # each pair's by id
        ended = Events(np.full(total, EV_ENDED, np.int64), ev_a, ev_b, ev_id)
        keep = ~hit
        self.keys = self.keys[keep]
        self.unconfirmed = self.unconfirmed[keep]
        self._pairs = self._pairs[keep]
        self.start = np.concatenate([[0], np.cumsum(counts[keep])]).astype(np.int64)
        c_keep = ~c_hit
        self.c_id, self.c_age = self.c_id[c_keep], self.c_age[c_keep]
        self.c_la, self.c_lb, self.c_na = self.c_la[c_keep], self.c_lb[c_keep], self.c_na[c_keep]
        self._con = {k: v[c_keep] for k, v in self._con.items()}
        return ended

    def end_all(self):
        """End every arbiter (a time reset): the Events, as ``end_bodies``."""
        return self.end_bodies(np.unique(self._pairs))

    def contacts(self, pos_w=None, quat_w=None):
        """Every stored contact in the world, ordered by pair then id: dict of arrays
        body_a, body_b, contact_id, age (int64 (C,)), point_a, point_b, normal
        (float64 (C, 3)), depth (float64 (C,), >= 0); without poses also status and
        method (int64 (C,), the pair's this step).  Without poses: as of the last
        update (the arrays are shared, do not modify them); with poses: the stored
        local points moved to those poses."""
        if pos_w is None:
            return dict(self._con)
        a, b = self._con["body_a"], self._con["body_b"]
        rot = quat_to_matrix(np.asarray(quat_w, np.float64))
        pos_w = np.asarray(pos_w, np.float64)
        pa = np.einsum("cij,cj->ci", rot[a], self.c_la) + pos_w[a]
        pb = np.einsum("cij,cj->ci", rot[b], self.c_lb) + pos_w[b]
        nrm = np.einsum("cij,cj->ci", rot[a], self.c_na)
        depth = np.maximum(0.0, -np.sum((pb - pa) * nrm, axis=1))
        return {"body_a": a.copy(), "body_b": b.copy(), "contact_id": self.c_id.copy(),
                "age": self.c_age.copy(), "point_a": pa, "point_b": pb, "normal": nrm,
                "depth": depth}
