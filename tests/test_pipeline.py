"""The scene pipeline end to end, with the real narrow phase."""
import math

import numba
import numpy as np
import pytest

from mkcollision_ros.arbiters import body_hashes, stamp_key
from mkcollision_ros.kernels.constants import ST_PENETRATING, ST_TOUCHING
from mkcollision_ros.kernels.persistence import contact_id
from mkcollision_ros.pipeline import Pipeline, PipelineConfig, StepResult
from mkcollision_ros.rotations import quat_to_matrix
from oracles import quat_axis, quat_mul

PLANE = {"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0},
         "static": True}
ID = [0.0, 0.0, 0.0, 1.0]


# ---------------------------------------------------------------- validation
@pytest.mark.parametrize("bodies, match", [
    ([], "non-empty"),
    ([{"name": "a", "shape": {"type": "sphere", "radius": 1}, "colour": 1}], "unknown key"),
    ([{"name": "a", "shape": {"type": "sphere", "radius": 1}},
      {"name": "a", "shape": {"type": "sphere", "radius": 1}}], "duplicate name"),
    ([{"name": "a", "shape": {"type": "sphere", "radius": -1}}], "body 'a'.*radius"),
    ([{"name": "a", "shape": {"type": "blob"}}], "unknown shape type"),
    ([{"name": "", "shape": {"type": "sphere", "radius": 1}}], "name"),
    ([{"name": "a", "shape": {"type": "sphere", "radius": 1}, "group": -1}], "group"),
    ([{"name": "a", "shape": {"type": "sphere", "radius": 1}, "static": "yes"}], "static"),
    ([{"name": "a"}], "missing 'shape'"),
])
def test_bad_bodies_raise(bodies, match):
    with pytest.raises(ValueError, match=match):
        Pipeline(bodies)


def test_bad_config_raises():
    bodies = [{"name": "a", "shape": {"type": "sphere", "radius": 1}}]
    with pytest.raises(ValueError, match="unknown setting"):
        PipelineConfig.from_dict({"methd": "auto"})
    for kw, match in [({"method": "sat"}, "method"), ({"proximity": -1.0}, "proximity"),
                      ({"merge_distance": 0.0}, "merge_distance"),
                      ({"drift_threshold": float("nan")}, "drift_threshold"),
                      ({"max_contacts": 0}, "max_contacts"), ({"stale_steps": 1.5}, "stale"),
                      ({"contact_margin": -1e-3}, "contact_margin")]:
        with pytest.raises(ValueError, match=match):
            Pipeline(bodies, PipelineConfig(**kw))
    for allowed, match in [([["a"]], "allowed_pairs"), ([["a", "zz"]], "zz")]:
        with pytest.raises(ValueError, match=match):
            Pipeline(bodies, allowed_pairs=allowed)
    assert PipelineConfig.from_dict({"method": "mpr"}).method == "mpr"


def test_bad_poses_raise_naming_the_body():
    p = Pipeline([{"name": "a", "shape": {"type": "sphere", "radius": 1}},
                  {"name": "b", "shape": {"type": "sphere", "radius": 1}}])
    pos = np.zeros((2, 3))
    quat = np.array([ID, ID])
    bad = pos.copy()
    bad[1, 2] = np.nan
    with pytest.raises(ValueError, match=r"body 1 \('b'\): non-finite position"):
        p.step(bad, quat, 0.0)
    q = quat.copy()
    q[0] = 0.0
    with pytest.raises(ValueError, match=r"body 0 \('a'\): zero quaternion"):
        p.step(pos, q, 0.0)
    q[0] = [np.inf, 0, 0, 1]
    with pytest.raises(ValueError, match="body 0.*non-finite quaternion"):
        p.step(pos, q, 0.0)
    with pytest.raises(ValueError, match=r"\(2, 3\)"):
        p.step(np.zeros((3, 3)), quat, 0.0)
    # unnormalised quaternions are accepted; results are finite
    r = p.step(pos + [[0, 0, 0], [1.5, 0, 0]], quat * 7.0, 0.0)
    assert isinstance(r, StepResult) and len(r.contact_id) == 1
    assert np.all(np.isfinite(r.position)) and np.all(np.isfinite(r.normal))


# ---------------------------------------------------------------- filter rules
def test_filter_rules():
    rng = np.random.default_rng(1)
    n = 24
    bodies = []
    for i in range(n):
        bodies.append({"name": f"b{i}", "shape": {"type": "sphere", "radius": 1.0},
                       "static": bool(i % 5 == 0), "group": int(rng.integers(1, 8)),
                       "mask": int(rng.integers(0, 8))})
    allowed = [["b1", "b2"], ["b7", "b3"], ["b10", "b11"]]
    p = Pipeline(bodies, allowed_pairs=allowed)
    pos = rng.normal(scale=0.2, size=(n, 3))                 # everything overlaps
    r = p.step(pos, np.tile(ID, (n, 1)), 0.0)
    assert r.n_candidate_pairs == n * (n - 1) // 2
    acm = {(1, 2), (3, 7), (10, 11)}
    want = []
    for i in range(n):
        for j in range(i + 1, n):
            bi, bj = bodies[i], bodies[j]
            if bi["static"] and bj["static"]:
                continue
            if not (bi["group"] & bj["mask"] and bj["group"] & bi["mask"]):
                continue
            if (i, j) in acm:
                continue
            want.append((i, j))
    assert 0 < len(want) < n * (n - 1) // 2 - 10       # the rules actually removed pairs
    assert r.n_narrowphase_pairs == len(want)
    assert [tuple(x) for x in r.pairs.tolist()] == want
    assert set(zip(r.body_a.tolist(), r.body_b.tolist())) == set(want)


def test_proximity_makes_candidates_not_contacts():
    bodies = [{"name": "a", "shape": {"type": "sphere", "radius": 0.5}},
              {"name": "b", "shape": {"type": "sphere", "radius": 0.5}}]
    pos = np.array([[0.0, 0, 0], [1.05, 0, 0]])
    quat = np.array([ID, ID])
    assert Pipeline(bodies).step(pos, quat).n_candidate_pairs == 0
    r = Pipeline(bodies, PipelineConfig(proximity=0.1)).step(pos, quat)
    assert r.n_candidate_pairs == 1 and len(r.contact_id) == 0 and len(r.pairs) == 0
    # ... and a proximity pair with its distance and closest points
    assert len(r.proximity) == 1 and (r.proximity.body_a[0], r.proximity.body_b[0]) == (0, 1)
    np.testing.assert_allclose(r.proximity.distance, [0.05], atol=1e-12)
    np.testing.assert_allclose(r.proximity.point_a, [[0.5, 0, 0]], atol=1e-12)
    np.testing.assert_allclose(r.proximity.point_b, [[0.55, 0, 0]], atol=1e-12)
    np.testing.assert_allclose(r.proximity.normal, [[1, 0, 0]], atol=1e-12)


# ---------------------------------------------------------------- manifolds
def box_on_plane(size=(1.0, 0.6, 0.4)):
    return Pipeline([PLANE, {"name": "box", "shape": {"type": "box", "size": list(size)}}])


def test_box_resting_has_four_contacts_from_the_first_step():
    p = box_on_plane()
    pos = np.array([[0, 0, 0], [0.3, -0.2, 0.2 - 1e-4]])
    quat = np.array([ID, quat_axis([0, 0, 1], 0.3)])
    r = p.step(pos, quat, 0.0)
    assert len(r.contact_id) == 4
    assert np.allclose(r.normal, [0, 0, 1])
    assert np.allclose(r.depth, 1e-4, atol=1e-9)
    assert np.allclose(r.point_a[:, 2], 0.0, atol=1e-12)          # on the plane
    corners = np.array([[sx * 0.5, sy * 0.3, -0.2] for sx in (-1, 1) for sy in (-1, 1)])
    corners_w = corners @ quat_to_matrix(quat[1]).T + pos[1]
    for c in corners_w:                                             # on the box corners
        assert np.min(np.linalg.norm(r.point_b - c, axis=1)) < 1e-9
    assert set(r.status.tolist()) == {ST_PENETRATING}


@pytest.mark.parametrize("rock", [0.0, 0.004])
def test_box_still_or_rocking_keeps_stable_four_point_manifold(rock):
    p = box_on_plane()
    ids0 = None
    for k in range(300):
        tilt = rock * math.sin(0.1 * k)                      # radians, ~0.23 deg
        q = quat_axis([1, 0, 0], tilt)
        # lowest corner 1e-4 below the plane
        low = 0.3 * abs(math.sin(tilt)) + 0.2 * math.cos(tilt)
        pos = np.array([[0, 0, 0], [0.0, 0.0, low - 1e-4]])
        r = p.step(pos, np.array([ID, q]), 0.01 * k)
        assert len(r.contact_id) == 4, k
        if ids0 is None:
            ids0 = r.contact_id.copy()
        assert np.array_equal(r.contact_id, ids0), k
        assert np.all(r.age == k)
        assert r.depth.max() == pytest.approx(1e-4, abs=1e-9)
        assert np.all(r.depth >= 0.0)
    assert len(set(ids0.tolist())) == 4 and np.all(ids0 >= 0)


def test_sphere_rolling_keeps_one_contact_with_one_id():
    radius = 0.5
    p = Pipeline([PLANE, {"name": "ball", "shape": {"type": "sphere", "radius": radius}}])
    q = np.array(ID)
    first = None
    for k in range(400):
        x = 0.004 * k
        q = quat_mul(quat_axis([0, 1, 0], 0.004 / radius), q) if k else q
        pos = np.array([[0, 0, 0], [x, 0.1 * math.sin(0.01 * k), radius - 1e-5]])
        r = p.step(pos, np.array([ID, q]), 0.01 * k)
        assert len(r.contact_id) == 1, k
        if first is None:
            first = int(r.contact_id[0])
        assert r.contact_id[0] == first and r.age[0] == k
        assert np.allclose(r.position[0, :2], pos[1, :2], atol=1e-9)
        assert r.depth[0] == pytest.approx(1e-5, abs=1e-10)
    assert x > 1.0                                               # it really travelled


# Bug (demo id churn): in the demo scene bodies slide ~3 cm and spin ~0.05 rad per step.
# Stored contacts dropped by the drift rule before being matched to the new manifold
# would make a body sliding more than drift_threshold per step lose every id, although
# the new points sit exactly on the stored points of the sliding body.  Stored contacts
# are matched first (Bullet's getCacheEntry before refreshContactPoints); only unmatched
# ones may drift out.
def test_sliding_spinning_box_keeps_its_four_ids():
    p = box_on_plane()
    first = None
    for k in range(150):
        q = quat_axis([0, 0, 1], 0.05 * k)                  # spins 0.05 rad per step
        pos = np.array([[0, 0, 0], [0.03 * k, 0.01 * k, 0.2 - 1e-4]])   # slides 3.2 cm
        r = p.step(pos, np.array([ID, q]), k / 30.0)
        assert len(r.contact_id) == 4, k
        if first is None:
            first = r.contact_id.copy()
        assert np.array_equal(r.contact_id, first), k
        assert np.all(r.age == k)
        if k:
            assert all(e[0] == "persisted" for e in r.events), k


def test_sliding_spinning_ball_keeps_one_id():
    radius = 0.3
    p = Pipeline([PLANE, {"name": "ball", "shape": {"type": "sphere", "radius": radius}}])
    ids = set()
    for k in range(150):
        # slides 4 cm per step while spinning about the vertical (the bottom point stays
        # the bottom point) and wobbling 0.02 rad about x (moves it by 6 mm)
        q = quat_mul(quat_axis([0, 0, 1], 0.3 * k), quat_axis([1, 0, 0], 0.02 * math.sin(k)))
        pos = np.array([[0, 0, 0], [0.04 * k, 0.0, radius - 1e-4]])
        r = p.step(pos, np.array([ID, q]), k / 30.0)
        assert len(r.contact_id) == 1, k
        ids.add(int(r.contact_id[0]))
    assert len(ids) == 1                  # one id all along


def test_stacked_boxes_and_lying_shapes():
    bodies = [PLANE,
              {"name": "base", "shape": {"type": "box", "size": [1, 1, 1]}},
              {"name": "top", "shape": {"type": "box", "size": [0.4, 0.4, 0.4]}},
              {"name": "cap", "shape": {"type": "capsule", "radius": 0.1, "length": 0.6}},
              {"name": "can", "shape": {"type": "cylinder", "radius": 0.2, "height": 0.3}}]
    p = Pipeline(bodies)
    pos = np.array([[0, 0, 0], [0, 0, 0.5 - 1e-4], [0.1, 0.2, 1.2 - 2e-4],
                    [3, 0, 0.1 - 1e-4], [-3, 0, 0.15 - 1e-4]])
    quat = np.array([ID, ID, quat_axis([0, 0, 1], 0.7), quat_axis([1, 0, 0], math.pi / 2), ID])
    r = p.step(pos, quat, 0.0)
    count = {tuple(x): int(np.sum((r.body_a == x[0]) & (r.body_b == x[1]))) for x in r.pairs}
    assert count == {(0, 1): 4, (0, 3): 2, (0, 4): 4, (1, 2): 4}
    top = (r.body_a == 1) & (r.body_b == 2)
    assert np.allclose(r.normal[top], [0, 0, 1])
    assert np.allclose(r.depth[top], 1e-4, atol=1e-9)
    assert np.allclose(r.point_a[top][:, 2], 1.0 - 1e-4)
    # contacts lie on the shapes: B moved by depth along the normal touches
    assert np.allclose(r.point_b - r.point_a, -r.depth[:, None] * r.normal, atol=1e-9)


def test_coincident_coaxial_bodies_give_contacts():
    """Bodies of revolution spawned at one pose (a ring of equally deep directions;
    GJK/EPA hits its caps there): each pair still yields its contact, with the exact
    depth (a FAILED answer there would make the pipeline drop them)."""
    bodies = [{"name": "can", "shape": {"type": "cylinder", "radius": 0.2, "height": 0.3}},
              {"name": "peg", "shape": {"type": "cylinder", "radius": 0.1, "height": 0.6}},
              {"name": "ball", "shape": {"type": "sphere", "radius": 0.05}}]
    q = quat_axis([1, 2, 3], 0.4)
    pos = np.array([[1.0, 2.0, 3.0]] * 3)
    r = Pipeline(bodies).step(pos, np.array([q] * 3), 0.0)
    assert sorted(map(tuple, r.pairs)) == [(0, 1), (0, 2), (1, 2)]
    expect = {(0, 1): 0.3, (0, 2): 0.2, (1, 2): 0.15}   # min(r_a + r_b, (h_a + h_b) / 2)
    for (a, b), d in expect.items():
        sel = (r.body_a == a) & (r.body_b == b)
        assert sel.any()
        assert np.allclose(r.depth[sel], d, atol=1e-9), (a, b, r.depth[sel])
        assert np.all(np.isfinite(r.normal[sel]))


# ---------------------------------------------------------------- events
def test_events_two_spheres_approach_touch_separate():
    p = Pipeline([{"name": "a", "shape": {"type": "sphere", "radius": 0.5}},
                  {"name": "b", "shape": {"type": "sphere", "radius": 0.5}}])
    xs = [1.3, 1.1, 0.999, 0.995, 0.99, 0.995, 0.999, 1.05, 1.2]
    log = []
    for k, x in enumerate(xs):
        r = p.step(np.array([[0, 0, 0], [x, 0, 0]]), np.array([ID, ID]), 0.1 * k)
        log.append(r.events)
    # the id: the bodies' name hashes and the stamp of the step it began (arbiters.py)
    h = body_hashes(["a", "b"])
    cid = int(contact_id(h[0], h[1], stamp_key(0.1 * 2), 0))
    assert log[0] == [] and log[1] == []
    assert log[2] == [("began", 0, 1, -1), ("began", 0, 1, cid)]
    for k in range(3, 7):
        assert log[k] == [("persisted", 0, 1, -1), ("persisted", 0, 1, cid)], k
    assert log[7] == [("ended", 0, 1, -1), ("ended", 0, 1, cid)]
    assert log[8] == []


# ---------------------------------------------------------------- determinism
def pile(n, seed):
    rng = np.random.default_rng(seed)
    kinds = [{"type": "sphere", "radius": 0.3}, {"type": "box", "size": [0.5, 0.4, 0.3]},
             {"type": "capsule", "radius": 0.15, "length": 0.4},
             {"type": "cylinder", "radius": 0.2, "height": 0.4},
             {"type": "convex", "points": (rng.normal(size=(8, 3)) * 0.25).tolist()}]
    bodies = [PLANE] + [{"name": f"b{i}", "shape": kinds[i % len(kinds)]} for i in range(n)]
    side = n ** (1 / 3) * 0.6
    pos = np.concatenate([[[0, 0, 0]], rng.uniform([-side, -side, 0], [side, side, side],
                                                   size=(n, 3))])
    quat = rng.normal(size=(n + 1, 4))
    quat[0] = ID
    return bodies, pos, quat


def run_pile(threads, parallel_min, n=150, steps=3):
    bodies, pos, quat = pile(n, 5)
    numba.set_num_threads(threads)
    p = Pipeline(bodies, PipelineConfig(max_contacts=3))
    p.parallel_min_items = parallel_min
    p.parallel_min_cheap_items = parallel_min
    rng = np.random.default_rng(9)
    out = []
    for k in range(steps):
        pos = pos + rng.normal(scale=0.01, size=pos.shape) * (np.arange(len(pos)) > 0)[:, None]
        out.append(p.step(pos, quat, float(k)))
    return out


def test_deterministic_with_one_or_two_threads():
    before = numba.get_num_threads()
    try:
        one = run_pile(1, parallel_min=0)            # force the threaded kernels
        two = run_pile(min(2, numba.config.NUMBA_NUM_THREADS), parallel_min=0)
        ser = run_pile(1, parallel_min=10 ** 9)
    finally:
        numba.set_num_threads(before)
    assert sum(len(r.contact_id) for r in one) > 50          # a real pile
    assert max(r.contact_id.max() for r in one) > 0
    for a, b in zip(one, two):
        for f in ("pairs", "body_a", "body_b", "position", "point_a", "point_b", "normal",
                  "depth", "contact_id", "age", "method", "status"):
            assert np.array_equal(getattr(a, f), getattr(b, f)), f
        assert a.events == b.events
        assert a.n_candidate_pairs == b.n_candidate_pairs
        assert np.all(np.isfinite(a.position)) and np.all(a.depth >= 0)
        assert set(a.status.tolist()) <= {ST_TOUCHING, ST_PENETRATING}
        assert sorted(a.timings) == sorted(["edits", "bounds", "broadphase", "filter",
                                            "narrowphase", "classify", "manifold",
                                            "arbiters"])
    # one thread for short batches runs the same compiled kernels: identical numbers
    for a, b in zip(one, ser):
        for f in ("pairs", "position", "point_a", "point_b", "normal", "depth", "contact_id"):
            assert np.array_equal(getattr(a, f), getattr(b, f)), f
        assert a.events == b.events


def test_warm_up_leaves_state_alone():
    p = box_on_plane()
    p.warm_up()
    pos = np.array([[0, 0, 0], [0, 0, 0.2 - 1e-4]])
    r = p.step(pos, np.array([ID, ID]), 0.0)
    fresh = box_on_plane().step(pos, np.array([ID, ID]), 0.0)
    assert len(r.contact_id) == 4 and r.contact_id.tolist() == fresh.contact_id.tolist()
    assert r.events == fresh.events


def test_clipping_large_face_on_small_face_and_tilted_boxes():
    cube = [[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    bodies = [PLANE,
              {"name": "small", "shape": {"type": "box", "size": [0.4, 0.4, 0.4]}},
              {"name": "large", "shape": {"type": "box", "size": [1.0, 1.0, 0.2]}},
              {"name": "edge", "shape": {"type": "box", "size": [0.5, 0.5, 0.5]}},
              {"name": "corner", "shape": {"type": "box", "size": [0.5, 0.5, 0.5]}},
              {"name": "hull", "shape": {"type": "convex", "points": cube}}]
    p = Pipeline(bodies)
    edge_q = quat_axis([1, 0, 0], 0.5)
    corner_q = quat_mul(quat_axis([1, 0, 0], 0.6), quat_axis([0, 1, 0], 0.5))

    def rest_height(q, half):
        r = quat_to_matrix(q)
        corners = np.array([[x, y, z] for x in (-half, half) for y in (-half, half)
                            for z in (-half, half)]) @ r.T
        return -corners[:, 2].min()

    pos = np.array([[0, 0, 0], [0, 0, 0.2 - 1e-4], [0.02, -0.03, 0.4 + 0.1 - 2e-4],
                    [3, 0, rest_height(edge_q, 0.25) - 1e-4],
                    [6, 0, rest_height(corner_q, 0.25) - 1e-4], [-3, 0, 0.5 - 1e-4]])
    quat = np.array([ID, ID, quat_axis([0, 0, 1], math.pi / 4), edge_q, corner_q, ID])
    r = p.step(pos, quat, 0.0)
    count = {tuple(x): int(np.sum((r.body_a == x[0]) & (r.body_b == x[1]))) for x in r.pairs}
    assert count == {(0, 1): 4, (0, 3): 2, (0, 4): 1, (0, 5): 4, (1, 2): 4}
    # the large rotated face clipped by the small one: the small face's corners
    k = (r.body_a == 1) & (r.body_b == 2)
    want = np.array([[sx * 0.2, sy * 0.2, 0.4 - 1e-4] for sx in (-1, 1) for sy in (-1, 1)])
    for w in want:
        assert np.min(np.linalg.norm(r.point_a[k] - w, axis=1)) < 1e-9
    assert np.allclose(r.depth[k], 1e-4, atol=1e-9)
    # edge and corner contacts sit on the plane, under the lowest box points
    for b in (3, 4):
        k = (r.body_a == 0) & (r.body_b == b)
        assert np.allclose(r.point_a[k][:, 2], 0.0) and np.allclose(r.depth[k], 1e-4)


# ---------------------------------------------------------------- shards
def _shard_scene(n=60, seed=3):
    rng = np.random.default_rng(seed)
    kinds = [{"type": "sphere", "radius": 0.2}, {"type": "box", "size": [0.3, 0.2, 0.4]},
             {"type": "capsule", "radius": 0.1, "length": 0.3},
             {"type": "cylinder", "radius": 0.15, "height": 0.3},
             {"type": "ellipsoid", "radii": [0.2, 0.15, 0.1]}]
    bodies = [{"name": f"b{i}", "shape": kinds[i % len(kinds)]} for i in range(n)]
    bodies.append({"name": "floor", "shape": {"type": "plane", "normal": [0, 0, 1],
                                              "offset": 0.0}, "static": True})
    pos = rng.uniform([0, 0, 0.05], [2.0, 2.0, 0.5], size=(n + 1, 3))
    vel = rng.normal(scale=0.02, size=(n + 1, 3))
    quat = rng.normal(size=(n + 1, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    return bodies, pos, vel, quat


def _rows(r):
    """A step's contacts and events as sets of plain tuples (body names, not slots)."""
    nm = r.names
    con = {(nm[a], nm[b], int(i), tuple(np.round(p, 12)), round(float(d), 12))
           for a, b, i, p, d in zip(r.body_a, r.body_b, r.contact_id, r.position, r.depth)}
    ev = {(k, nm[a], nm[b], i) for k, a, b, i in r.events}
    return con, ev


def test_two_shards_answer_the_whole_scene_with_the_same_ids():
    """Two pipelines with shard_count 2 split the pairs between them, each pair on one
    shard for the whole run, and together give exactly the contacts, ids and events of
    one pipeline on the same poses and stamps."""
    bodies, pos, vel, quat = _shard_scene()
    one = Pipeline(bodies)
    shards = [Pipeline(bodies, PipelineConfig(shard_index=k, shard_count=2))
              for k in range(2)]
    owner = {}
    touching = 0
    for step in range(12):
        p = pos + step * vel
        p[-1] = 0.0
        whole = one.step(p, quat, 0.05 * step)
        parts = [s.step(p, quat, 0.05 * step) for s in shards]
        con, ev = _rows(whole)
        got = [_rows(r) for r in parts]
        assert not got[0][0] & got[1][0]                      # no contact on both
        assert got[0][0] | got[1][0] == con, step
        assert got[0][1] | got[1][1] == ev, step
        for k, r in enumerate(parts):
            for a, b in r.pairs:
                assert owner.setdefault((a, b), k) == k        # a pair stays on its shard
        touching += len(whole.pairs)
    assert touching > 40 and len(set(owner.values())) == 2


def test_shard_settings_are_checked():
    with pytest.raises(ValueError, match="shard_index must be below shard_count"):
        PipelineConfig(shard_index=2, shard_count=2).validate()
    with pytest.raises(ValueError, match="shard_count must be an integer >= 1"):
        PipelineConfig(shard_count=0).validate()


def test_static_grid_gives_the_full_grids_pairs_and_contacts():
    """A static-heavy scene (a plane, a large static slab, static bodies, a few moving
    and some without a pose) stepped with the static grid and with the one grid of
    every body: the same pairs, contacts and ids after moves, a static body moved by a
    pose update (the grid is rebuilt), a static body removed and one added."""
    from bench.common import scene
    bodies, pos, quat, _ = scene(1500, 0.5, seed=3)
    rng = np.random.default_rng(3)
    static = rng.uniform(size=len(bodies)) > 0.1
    bodies = [dict(b, static=bool(s)) for b, s in zip(bodies, static)]
    bodies += [{"name": "floor", "static": True,
                "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 1.0}},
               {"name": "slab", "static": True, "shape": {"type": "box", "size": [30, 30, 0.2]}}]
    pos = np.vstack([pos, [0, 0, 0], [4, 4, 4]])
    quat = np.vstack([quat, [0, 0, 0, 1], [0, 0, 0, 1]])
    grid, full = Pipeline(bodies), Pipeline(bodies)
    full.static_grid_min = 10 ** 9
    moving = np.flatnonzero(~np.r_[static, True, True])
    for k in range(4):
        pos = pos.copy()
        pos[moving] += rng.uniform(-0.02, 0.02, (len(moving), 3))
        if k == 2:
            pos[np.flatnonzero(static)[:50]] += 0.3          # static bodies moved
        ra, rb = grid.step(pos, quat, 0.1 * k), full.step(pos, quat, 0.1 * k)
        assert grid._static is not None and full._static is None
        assert len(ra.pairs) > 50
        assert np.array_equal(ra.pairs, rb.pairs)
        assert ra.n_candidate_pairs < rb.n_candidate_pairs      # no static-static pairs
        ca, cb = grid.arbiters.contacts(), full.arbiters.contacts()
        assert len(ca["contact_id"]) > 50
        assert np.array_equal(ca["contact_id"], cb["contact_id"])
        assert np.array_equal(ca["point_a"], cb["point_a"])
    for p in (grid, full):
        p.scene.remove_body(bodies[int(np.flatnonzero(static)[0])]["name"])
        p.scene.add_body({"name": "crate", "static": True, "pose": [pos[moving[0]].tolist(),
                                                                    [0, 0, 0, 1]],
                          "shape": {"type": "box", "size": [1, 1, 1]}})
    ra, rb = grid.step(), full.step()
    assert np.array_equal(ra.pairs, rb.pairs)
    assert any("crate" in (grid.scene.names[a], grid.scene.names[b]) for a, b in ra.pairs)
