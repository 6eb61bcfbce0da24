"""ArbiterSet on hand-made contacts: ids, merging, drift, reduction, staleness, events."""
import numpy as np

from mkcollision_ros.arbiters import ArbiterSet, stamp_key
from mkcollision_ros.kernels.persistence import contact_id

IDENT = np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]])
UP = np.array([0.0, 0.0, 1.0])


def touching(points, depth=1e-3):
    """Contacts of pair (0, 1) on the plane z = 0, A below (normal +z)."""
    p = np.atleast_2d(np.asarray(points, float))
    pa = p.copy()
    pb = p.copy()
    pb[:, 2] -= depth
    return {(0, 1): (pa, pb, UP)}


def cid(seq, stamp=0.0, a=0, b=1):
    """The id of pair (a, b)'s new contact number ``seq`` of the step at ``stamp``, with
    the default body hashes (the slot numbers)."""
    return int(contact_id(np.uint64(a), np.uint64(b), stamp_key(stamp), seq))


ID0, ID1 = cid(0), cid(1)


def make(**kw):
    args = dict(merge_distance=0.02, drift_threshold=0.01, max_contacts=4, stale_steps=3)
    args.update(kw)
    return ArbiterSet(**args)


def test_merge_keeps_id_and_new_contacts_get_new_ids():
    s = make()
    pos = np.zeros((2, 3))
    ev = s.update(pos, IDENT, touching([[0, 0, 0]]), set())
    assert ev == [("began", 0, 1, -1), ("began", 0, 1, ID0)] and 0 <= ID0 < 2 ** 63
    ev = s.update(pos, IDENT, touching([[0.015, 0, 0]]), set())      # within 0.02
    c = s.contacts(pos, IDENT)
    assert c["contact_id"].tolist() == [ID0] and c["age"].tolist() == [1]
    assert np.allclose(c["point_a"][0], [0.015, 0, 0])
    assert ev == [("persisted", 0, 1, -1), ("persisted", 0, 1, ID0)]
    # far away: a new id (at the same stamp the mix's first number gives ID0, which the
    # pair holds: it takes the next); the old one stays while it has not drifted
    ev = s.update(pos, IDENT, touching([[0.5, 0, 0]]), set())
    c = s.contacts(pos, IDENT)
    assert c["contact_id"].tolist() == [ID0, ID1] and ID1 != ID0
    assert ("began", 0, 1, ID1) in ev and ("persisted", 0, 1, ID0) in ev


def test_contacts_follow_the_bodies_and_drift_is_dropped():
    s = make()
    pos = np.zeros((2, 3))
    s.update(pos, IDENT, touching([[0.1, 0, 0]]), set())
    # both bodies move together by (1, 2, 3) and A turns 90 deg about z with B about
    # the same axis through the contact: points stay together -> kept, moved
    q = np.array([[0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)]] * 2)
    pos2 = np.array([[1.0, 2, 3], [1.0, 2, 3]])
    ev = s.update(pos2, q, {}, {(0, 1)})                 # unconfirmed: no new contact
    c = s.contacts(pos2, q)
    assert ev[0] == ("persisted", 0, 1, -1)
    assert np.allclose(c["point_a"][0], [1.0, 2.1, 3.0])
    assert np.allclose(c["normal"][0], UP)
    # B lifts by more than drift_threshold along the normal: the contact ends
    pos3 = pos2 + [[0, 0, 0], [0, 0, 0.02]]
    ev = s.update(pos3, q, {}, {(0, 1)})
    assert ("ended", 0, 1, ID0) in ev and len(s.contacts(pos3, q)["contact_id"]) == 0
    # B slides across the normal by more than the threshold: dropped as well
    s = make()
    s.update(pos, IDENT, touching([[0.0, 0, 0]]), set())
    ev = s.update(pos + [[0, 0, 0], [0.011, 0, 0]], IDENT, {}, {(0, 1)})
    assert ("ended", 0, 1, ID0) in ev
    # but within it, kept
    s = make()
    s.update(pos, IDENT, touching([[0.0, 0, 0]]), set())
    ev = s.update(pos + [[0, 0, 0], [0.009, 0, 0.009]], IDENT, {}, {(0, 1)})
    assert ("persisted", 0, 1, ID0) in ev


def test_reduction_keeps_deepest_and_largest_area():
    rng = np.random.default_rng(0)
    s = make()
    grid = np.array([[x, y, 0.0] for x in (-1, 0, 1) for y in (-1, 0, 1)])
    grid = grid[rng.permutation(9)]
    pa = grid.copy()
    pb = grid.copy()
    pb[:, 2] -= 1e-3
    deep = int(np.flatnonzero((grid[:, 0] == 0) & (grid[:, 1] == 1))[0])   # an edge middle
    pb[deep, 2] = -5e-3
    ev = s.update(np.zeros((2, 3)), IDENT, {(0, 1): (pa, pb, UP)}, set())
    c = s.contacts(np.zeros((2, 3)), IDENT)
    assert len(c["contact_id"]) == 4
    kept = c["point_a"]
    assert any(np.allclose(k, grid[deep]) for k in kept)
    assert np.isclose(c["depth"].max(), 5e-3)
    # the other three span the far side: with (0, 1) kept, the best quad uses both far
    # corners (-1, -1), (1, -1) and one of (+-1, 0)/(+-1, 1)
    assert sum(np.allclose(k[:2], [-1, -1]) or np.allclose(k[:2], [1, -1]) for k in kept) == 2
    # pruned new contacts never began
    began = [e for e in ev if e[0] == "began" and e[3] >= 0]
    assert len(began) == 4
    # the kept ones' ids: the step's first four numbers, in manifold order
    assert c["contact_id"].tolist() == [cid(k) for k in range(4)]
    assert sorted(e[3] for e in began) == sorted(cid(k) for k in range(4))


def test_stale_unconfirmed_pair_ends_after_stale_steps():
    s = make(stale_steps=3)
    pos = np.zeros((2, 3))
    s.update(pos, IDENT, touching([[0, 0, 0]]), set())
    kinds = []
    for _ in range(3):
        ev = s.update(pos, IDENT, {}, {(0, 1)})
        kinds.append(ev[0][0])
    assert kinds == ["persisted", "persisted", "ended"]
    assert len(s) == 0 and s.pairs().shape == (0, 2)


def test_separation_ends_immediately_and_a_new_stamp_gives_new_ids():
    s = make()
    pos = np.zeros((2, 3))
    s.update(pos, IDENT, touching([[0, 0, 0]]), set(), stamp=0.0)
    ev = s.update(pos, IDENT, {}, set(), stamp=0.1)
    assert ev == [("ended", 0, 1, -1), ("ended", 0, 1, ID0)]
    assert s.update(pos, IDENT, {}, set(), stamp=0.2) == []
    ev = s.update(pos, IDENT, touching([[0, 0, 0]]), set(), stamp=0.3)
    assert ev == [("began", 0, 1, -1), ("began", 0, 1, cid(0, 0.3))] and cid(0, 0.3) != ID0


def test_ids_depend_on_the_bodies_and_the_stamp_alone():
    """Two arbiter sets, one with another pair alongside, hand the shared pair the same
    ids: a pair's ids do not depend on the other pairs (the shards' premise)."""
    hashes = np.array([11, 22, 33, 44], np.uint64)
    pos = np.zeros((4, 3))
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (4, 1))
    alone, crowded = make(), make()
    for k in range(4):
        pts = [[0.1 * k, 0, 0], [1.0, 0.2 * k, 0]]
        pair = touching(pts)[(0, 1)]
        alone.update(pos, quat, {(0, 1): pair}, set(), stamp=float(k), body_hash=hashes)
        crowded.update(pos, quat, {(0, 1): pair, (2, 3): pair}, set(), stamp=float(k),
                       body_hash=hashes)
        a = alone.contacts(pos, quat)["contact_id"].tolist()
        c = crowded.contacts(pos, quat)
        assert c["contact_id"][c["body_a"] == 0].tolist() == a
    assert len(set(a)) == len(a) >= 2
    assert not set(a) & set(c["contact_id"][c["body_a"] == 2].tolist())


def test_random_sequences_keep_event_invariants():
    """Seeded random pairs, contacts and poses over many steps, one stamp each: every
    contact id begins once, then persists, then ends at most once; the listed contacts are exactly the
    began + persisted ones; at most max_contacts per pair; pair events agree."""
    rng = np.random.default_rng(11)
    n = 6
    s = ArbiterSet(merge_distance=0.05, drift_threshold=0.03, max_contacts=3, stale_steps=2)
    pos = rng.normal(size=(n, 3))
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    state = {}                          # contact id -> "alive" / "dead"
    pair_alive = set()
    n_began = 0
    for step in range(300):
        pos = pos + rng.normal(scale=0.01, size=pos.shape)
        quat = quat + rng.normal(scale=0.01, size=quat.shape)
        quat /= np.linalg.norm(quat, axis=1)[:, None]
        touching, unconfirmed = {}, set()
        for a in range(n):
            for b in range(a + 1, n):
                u = rng.random()
                if u < 0.35:
                    m = int(rng.integers(1, 7))
                    base = 0.5 * (pos[a] + pos[b])
                    pa = base + rng.normal(scale=0.05, size=(m, 3))
                    nrm = rng.normal(size=3)
                    nrm /= np.linalg.norm(nrm)
                    pb = pa - rng.uniform(0, 0.01, size=(m, 1)) * nrm
                    touching[(a, b)] = (pa, pb, nrm)
                elif u < 0.45:
                    unconfirmed.add((a, b))
        ev = s.update(pos, quat, touching, unconfirmed, stamp=0.01 * step)
        c = s.contacts()
        listed = set(c["contact_id"].tolist())
        assert len(listed) == len(c["contact_id"])
        seen_now = set()
        for kind, a, b, cid in ev:
            assert a < b
            if cid < 0:
                if kind == "began":
                    assert (a, b) not in pair_alive
                    pair_alive.add((a, b))
                elif kind == "ended":
                    pair_alive.remove((a, b))
                else:
                    assert (a, b) in pair_alive
                continue
            if kind == "began":
                assert cid not in state
                state[cid] = "alive"
                n_began += 1
            else:
                assert state.get(cid) == "alive", (kind, cid)
                if kind == "ended":
                    state[cid] = "dead"
            if kind != "ended":
                seen_now.add(cid)
        assert seen_now == listed
        assert set(map(tuple, s.pairs().tolist())) == pair_alive
        for key in pair_alive:
            k = (c["body_a"] == key[0]) & (c["body_b"] == key[1])
            assert 1 <= k.sum() <= 3 or key in unconfirmed
        assert set(pair_alive) <= set(touching) | unconfirmed
        assert np.all(c["depth"] >= 0) and np.all(np.isfinite(c["point_a"]))
    assert n_began > 200 and "dead" in state.values()
    assert all(0 <= i < 2 ** 63 for i in state)
