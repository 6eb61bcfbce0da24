"""The scene (one owner of bodies, slots, filters and poses), edits between steps,
settings between steps, the contact margin and proximity pairs."""
import math

import numpy as np
import pytest

import mkcollision_ros.scene as scene_mod
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import ST_TOUCHING
from mkcollision_ros.pipeline import Pipeline, PipelineConfig
from mkcollision_ros.scene import Scene, validate_body
from oracles import quat_axis, quat_mul, random_quats, random_shape

ID = [0.0, 0.0, 0.0, 1.0]


def ball(name, r=0.5, **kw):
    return {"name": name, "shape": {"type": "sphere", "radius": r}, **kw}


def cube(name, side=1.0, **kw):
    return {"name": name, "shape": {"type": "box", "size": [side] * 3}, **kw}


def at(x, y=0.0, z=0.0):
    return ([x, y, z], ID)


# ---------------------------------------------------------------- the scene itself
def test_validator_is_the_one_and_masks_are_32_bits():
    assert validate_body(ball("a", mask=0xFFFFFFFF)).mask == 0xFFFFFFFF
    for bad, match in [(ball("a", mask=1 << 32), "mask"), (ball("a", group=-1), "group"),
                       (ball("a", group=True), "group"), (ball("a", static="yes"), "static"),
                       (ball("", ), "name"), ({"name": "a"}, "missing 'shape'"),
                       (ball("a", colour=1), "unknown key"),
                       (ball("a", pose=([0, 0], ID)), "initial pose"),
                       ({"name": "a", "shape": {"type": "sphere", "radius": -1}}, "radius")]:
        with pytest.raises(ValueError, match=match):
            validate_body(bad)
    # the params file goes through the same validator
    from mkcollision_ros.config import bodies_from_flat
    with pytest.raises(ValueError, match=r"'mask' must be an integer bitmask in \[0, 0xFFFFFFFF\]"):
        bodies_from_flat({"names": ["a"], "a.type": "sphere", "a.radius": 1.0,
                          "a.mask": 1 << 40})


def test_slots_are_stable_and_reused():
    sc = Scene([ball("a"), ball("b"), ball("c")])
    assert sc.names == ["a", "b", "c"] and len(sc) == 3
    assert sc.remove_body("b") == 1
    assert sc.names == ["a", None, "c"] and "b" not in sc and len(sc) == 2
    assert sc.add_body(cube("x")) == 3                    # not before the step
    ended, retired = sc.take_ended()                      # what a step does
    assert ended.tolist() == [1] and retired == {1: "b"}
    sc.remove_body("x")
    sc.take_ended()
    assert sc.add_body(cube("d")) == 1                    # the freed slot, lowest first
    assert sc.add_body(cube("e")) == 3
    assert sc.index == {"a": 0, "d": 1, "c": 2, "e": 3}
    with pytest.raises(ValueError, match="unknown body 'zz'"):
        sc.remove_body("zz")
    with pytest.raises(ValueError, match="duplicate name 'a'"):
        sc.add_body(ball("a"))
    # all or none
    version = sc.version
    with pytest.raises(ValueError, match="body 'g'.*radius"):
        sc.add_bodies([ball("f"), {"name": "g", "shape": {"type": "sphere", "radius": 0}}])
    assert "f" not in sc and sc.version == version and sc.n_slots == 4


def test_batched_edits_apply_all_or_none():
    sc = Scene([ball("a"), ball("b"), ball("c")], allowed_pairs=[["a", "b"], ["b", "c"]])
    version = sc.version
    for kw, match in [({"remove": ["zz"]}, "unknown body 'zz'"),
                      ({"remove": ["a", "a"]}, "twice"),
                      ({"remove": ["a"], "bodies": [ball("d"), ball("d")]}, "duplicate"),
                      ({"bodies": [ball("d", r=-1)]}, "radius"),
                      ({"remove": ["a"], "allowed_pairs": [["a", "c"]]}, "unknown body 'a'")]:
        with pytest.raises(ValueError, match=match):
            sc.edit(**kw)
        assert sc.names == ["a", "b", "c"] and sc.version == version
    slots = sc.edit(remove=["a"], bodies=[cube("b"), ball("d")])
    assert slots == [1, 3] and sc.body("b").shape["type"] == "box"
    assert sc.allowed_pairs() == [["b", "c"]]             # the pair naming a went with it
    sc.edit(allowed_pairs=[["c", "d"]])
    assert sc.allowed_pairs() == [["c", "d"]]


def test_set_poses_drops_bad_entries_only_and_stamps_each_body():
    sc = Scene([ball("a"), ball("b"), ball("c")])
    applied, problems = sc.set_poses(
        ["a", "b", "zzz", "c"],
        [[1, 2, 3], [np.inf, 0, 0], [0, 0, 0], [4, 5, 6]],
        [[0, 0, 0, 2], [0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 0]], stamp=4.5)
    assert applied == 1
    assert sorted(problems) == ["b: non-finite value", "c: zero quaternion", "zzz: unknown body"]
    np.testing.assert_allclose(sc.orientations[0], [0, 0, 0, 1])
    assert sc.posed.tolist() == [True, False, False]
    assert np.isfinite(sc.positions).all()
    assert sc.stamps[0] == 4.5 and np.isnan(sc.stamps[1:]).all()
    with pytest.raises(ValueError, match="lengths must agree"):
        sc.set_poses_at([0, 1], [[0, 0, 0]], [ID])


def test_an_added_body_touches_only_its_own_rows(monkeypatch):
    """One body added to a 10,000-body scene builds one shape row, and every other
    body's rows stay as they were."""
    rng = np.random.default_rng(3)
    kinds = ("sphere", "box", "convex", "capsule")
    sc = Scene([{"name": f"b{i}", "shape": random_shape(rng, kinds[i % 4], 0.3)}
                for i in range(10_000)])
    before = sc.table
    before = [a.copy() for a in before]
    calls = []
    real = scene_mod.shape_row
    monkeypatch.setattr(scene_mod, "shape_row", lambda s, *a: calls.append(s) or real(s, *a))
    sc.add_body({"name": "new", "shape": random_shape(rng, "convex", 0.3)})
    sc.remove_body("b17")
    sc.replace_body({"name": "b18", "shape": {"type": "sphere", "radius": 0.2}})
    assert len(calls) == 2                      # the added body and the replaced one
    after = sc.table
    keep = np.ones(10_000, bool)
    keep[[17, 18]] = False
    for old, new in zip(before[:3], after[:3]):
        np.testing.assert_array_equal(old[:10_000][keep], new[:10_000][keep])
    first, count = after.vrange[5]
    np.testing.assert_array_equal(after.verts[first:first + count],
                                  before[3][before[2][5, 0]:before[2][5, 0] + count])


def test_removed_shapes_vertices_are_compacted():
    rng = np.random.default_rng(4)
    hulls = [{"name": f"h{i}", "shape": random_shape(rng, "convex", 0.3)} for i in range(300)]
    sc = Scene(hulls)
    pts = {f"h{i}": _points(sc, f"h{i}") for i in range(300)}
    for i in range(0, 300, 3):
        sc.remove_body(f"h{i}")
        sc.replace_body({"name": f"h{i + 1}", "shape": random_shape(rng, "convex", 0.3)})
    live = int(sc._vlen[sc.used].sum())
    assert sc._garbage <= max(1024, sc._n_verts // 2)               # garbage reclaimed
    assert sc._n_verts <= 2 * live + 1024
    for i in range(2, 300, 3):
        np.testing.assert_array_equal(_points(sc, f"h{i}"), pts[f"h{i}"])


def _points(sc, name):
    first, count = sc.table.vrange[sc.index[name]]
    return sc.table.verts[first:first + count].copy()


# ---------------------------------------------------------------- edits between steps
def _touching_row():
    """Five balls in a row, each touching the next (4 touching pairs)."""
    return [ball(f"b{i}", pose=at(0.99 * i)) for i in range(5)]


def test_edits_keep_the_other_pairs_ids_and_end_the_removed_bodys_pairs():
    p = Pipeline(Scene(_touching_row()))
    r0 = p.step(stamp=0.0)
    assert [tuple(x) for x in r0.pairs] == [(0, 1), (1, 2), (2, 3), (3, 4)]
    ids = dict(zip(zip(r0.body_a.tolist(), r0.body_b.tolist()), r0.contact_id.tolist()))
    p.scene.remove_body("b2")
    p.scene.add_body(ball("b5", pose=at(0.99 * 5)))         # touches b4
    r1 = p.step(stamp=1.0)
    assert [tuple(x) for x in r1.pairs] == [(0, 1), (3, 4), (4, 5)]
    assert r1.names[2] == "b2" and p.scene.names[2] is None  # named for its events
    # the removed body's pairs end first, with their contacts, before the step's events
    assert r1.events.tolist()[:4] == [("ended", 1, 2, -1), ("ended", 1, 2, ids[(1, 2)]),
                                      ("ended", 2, 3, -1), ("ended", 2, 3, ids[(2, 3)])]
    got = dict(zip(zip(r1.body_a.tolist(), r1.body_b.tolist()), r1.contact_id.tolist()))
    assert got[(0, 1)] == ids[(0, 1)] and got[(3, 4)] == ids[(3, 4)]
    assert ("began", 4, 5, -1) in r1.events
    assert p.scene.add_body(ball("far", pose=at(50.0))) == 2   # reused after the step
    # a replaced shape ends its pairs and begins them anew; a filter change ends a pair
    p.scene.replace_body(cube("b0", side=1.2, pose=at(-0.1)))
    p.scene.replace_body(ball("b4", group=2, mask=2, pose=at(0.99 * 4)))
    r2 = p.step(stamp=2.0)
    assert ("ended", 0, 1, -1) in r2.events and ("began", 0, 1, -1) in r2.events
    assert ("ended", 3, 4, -1) in r2.events and ("ended", 4, 5, -1) in r2.events
    assert [tuple(x) for x in r2.pairs] == [(0, 1)]
    assert r2.contact_id[0] != ids[(0, 1)]
    # allowed pairs change between steps
    p.scene.set_allowed_pairs([["b0", "b1"]])
    r3 = p.step(stamp=3.0)
    assert len(r3.pairs) == 0 and r3.events.tolist() == [
        ("ended", 0, 1, -1), ("ended", 0, 1, int(r2.contact_id[0]))]
    with pytest.raises(ValueError, match="unknown body 'b2'"):
        p.scene.set_allowed_pairs([["b0", "b2"]])


def test_a_body_without_a_pose_does_not_collide():
    sc = Scene([ball("a", pose=at(0.0)), ball("b")])            # b sits at the origin
    p = Pipeline(sc)
    assert len(p.step().pairs) == 0
    sc.set_poses(["b"], [[0.9, 0, 0]], [ID], stamp=1.0)
    assert [tuple(x) for x in p.step().pairs] == [(0, 1)]


def test_step_with_arrays_ignores_free_slots_rows():
    p = Pipeline([ball("a"), ball("b"), ball("c")])
    p.scene.remove_body("b")
    pos = np.array([[0.0, 0, 0], [np.nan, 0, 0], [0.9, 0, 0]])
    quat = np.array([ID, [0.0, 0, 0, 0], ID])
    r = p.step(pos, quat, 1.0)
    assert [tuple(x) for x in r.pairs] == [(0, 2)]
    assert np.isnan(p.scene.stamps[1]) and p.scene.stamps[2] == 1.0
    with pytest.raises(ValueError, match=r"body 2 \('c'\): zero quaternion"):
        p.step(pos, np.array([ID, ID, [0.0, 0, 0, 0]]), 2.0)


def test_settings_change_between_steps_or_are_refused():
    p = Pipeline(Scene(_touching_row()))
    ids = p.step().contact_id.copy()
    for bad, match in [({"max_contacts": -1}, "max_contacts"), ({"method": "foo"}, "method"),
                       ({"contact_margin": float("nan")}, "contact_margin"),
                       ({"proximity": -0.1}, "proximity"), ({"merge_distance": 0}, "merge"),
                       ({"drift_threshold": "1"}, "drift"), ({"stale_steps": 0}, "stale"),
                       ({"rate": 1.0}, "unknown setting")]:
        before = p.config
        with pytest.raises(ValueError, match=match):
            p.configure(**{"method": "mpr", **bad})     # all or none
        assert p.config is before
    p.configure(method="mpr", proximity=1.0, max_contacts=2, merge_distance=0.03)
    assert p.arbiters.max_contacts == 2 and p.arbiters.merge_distance == 0.03
    r = p.step()
    np.testing.assert_array_equal(r.contact_id, ids)          # arbiters survive
    assert set(r.method.tolist()) == {2}                        # M_MPR
    assert len(r.proximity) == 3                                # (0, 2), (1, 3), (2, 4)


# ---------------------------------------------------------------- the contact margin
@pytest.mark.parametrize("gap", [1e-9, 1e-5])
def test_cubes_at_an_alternating_gap_keep_their_ids(gap):
    p = Pipeline([cube("a"), cube("b")])
    quat = np.array([ID, ID])
    seen = set()
    for k in range(100):
        g = gap if k % 2 else -gap
        r = p.step(np.array([[0.0, 0, 0], [1.0 + g, 0, 0]]), quat, float(k))
        assert len(r.contact_id) == 4
        seen.update(r.contact_id.tolist())
        if g > 0:
            assert np.all(r.depth == 0.0) and np.all(r.status == ST_TOUCHING)
    assert len(seen) == 4


def test_margin_hysteresis_makes_at_touch_and_breaks_beyond_the_margin():
    p = Pipeline([ball("a"), ball("b")], PipelineConfig(contact_margin=1e-3))
    quat = np.array([ID, ID])

    def step(gap):
        return p.step(np.array([[0.0, 0, 0], [1.0 + gap, 0, 0]]), quat)
    assert len(step(5e-4).pairs) == 0          # within the margin, never touched: apart
    assert len(step(-1e-4).pairs) == 1         # touching
    held = step(9e-4)                          # held within the margin
    assert len(held.pairs) == 1 and held.depth[0] == 0.0
    np.testing.assert_allclose(held.point_b - held.point_a, [[9e-4, 0, 0]], atol=1e-12)
    assert step(1.1e-3).events.tolist()[0] == ("ended", 0, 1, -1)
    assert len(step(5e-4).pairs) == 0
    p.configure(contact_margin=0.0)            # no margin: breaks as soon as apart
    step(-1e-4)
    assert len(step(1e-6).pairs) == 0


def test_fresh_pairs_touch_in_the_pipeline_iff_collide_says_so():
    """Random pairs of every bounded type placed within a few 1e-9 of touching (along a
    random direction, by bisection on collide's distance): a fresh pipeline step reports
    the pair touching exactly when ``collide`` does."""
    rng = np.random.default_rng(11)
    kinds = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex")
    agree = touching = 0
    for case in range(120):
        sa = random_shape(rng, kinds[case % 7], 0.5)
        sb = random_shape(rng, kinds[(case // 7) % 7], 0.5)
        qa, qb = random_quats(rng, 2)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        lo, hi = 0.0, 4.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            d = collide(sa, ([0, 0, 0], qa), sb, (mid * u, qb)).distance
            lo, hi = (mid, hi) if d < 0 else (lo, mid)
        for off in (-3e-9, -1e-9, 0.0, 1e-9, 3e-9):
            pos_b = (hi + off) * u
            c = collide(sa, ([0, 0, 0], qa), sb, (pos_b, qb))
            want = c.touching
            p = Pipeline([{"name": "a", "shape": sa}, {"name": "b", "shape": sb}])
            r = p.step(np.array([[0.0, 0, 0], pos_b]), np.array([qa, qb]))
            same = (len(r.pairs) == 1) == want
            agree += same
            touching += want
            if not same:
                # GJK's distance this close to zero is accurate to its termination
                # tolerance (~1e-9 m here), so at the band's very edge the pipeline's
                # batch loop and collide's call, two compiled copies fed poses normalised
                # apart, may fall either side of it
                assert abs(c.distance) < 1e-8, (case, off, c)
    assert agree >= 598
    assert 0.3 < touching / 600 < 0.9          # the cases straddle the touching band


# ---------------------------------------------------------------- proximity pairs
def test_proximity_pairs_match_collide_and_stay_out_of_the_arbiters():
    rng = np.random.default_rng(5)
    kinds = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex")
    bodies = [{"name": f"b{i}", "shape": random_shape(rng, kinds[i % 7], 0.3)}
              for i in range(60)]
    pos = rng.uniform(0, 2.5, size=(60, 3))
    quat = random_quats(rng, 60)
    p = Pipeline(bodies, PipelineConfig(proximity=0.1))
    r = p.step(pos, quat)
    prox = r.proximity
    assert len(prox) > 10 and len(r.pairs) > 5
    pairs = list(zip(prox.body_a.tolist(), prox.body_b.tolist()))
    assert pairs == sorted(pairs) and not set(pairs) & {tuple(x) for x in r.pairs.tolist()}
    assert len(p.arbiters) == len(r.pairs)
    want = set()
    for i in range(60):
        for j in range(i + 1, 60):
            c = collide(bodies[i]["shape"], (pos[i], quat[i]), bodies[j]["shape"],
                        (pos[j], quat[j]))
            if not c.touching and c.distance <= 0.1:
                want.add((i, j))
                k = pairs.index((i, j))
                assert abs(prox.distance[k] - c.distance) <= 1e-9
                np.testing.assert_allclose(prox.point_b[k] - prox.point_a[k],
                                           prox.distance[k] * prox.normal[k], atol=1e-9)
                assert np.linalg.norm(prox.point_a[k] - c.point_a) <= 1e-6
    assert set(pairs) == want
    assert np.all(prox.distance > 0) and np.all(prox.distance <= 0.1)
    np.testing.assert_allclose(np.linalg.norm(prox.normal, axis=1), 1.0, atol=1e-12)
    assert len(Pipeline(bodies).step(pos, quat).proximity) == 0


# ---------------------------------------------------------------- contacts that hold still
LYING = quat_axis([1, 0, 0], math.pi / 2)      # z axis turned onto -y: lying on its side
PRISM = [[0.3 * math.cos(a), 0.3 * math.sin(a), z] for a in np.arange(6) * math.pi / 3
         for z in (-0.15, 0.15)]
SLAB = {"type": "box", "size": [3.0, 3.0, 0.2]}          # top face at z = 0 when at -0.1
FLOOR = {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}
# (name, support shape, support centre z, resting shape, its centre z, its orientation);
# the resting body sits off the support's axis, except in the aligned case
RESTS = [
    ("cylinder cap on a box", SLAB, -0.1, {"type": "cylinder", "radius": 0.3, "height": 0.4},
     0.2, ID),
    ("cylinder cap on a plane", FLOOR, 0.0, {"type": "cylinder", "radius": 0.3, "height": 0.4},
     0.2, ID),
    ("cylinder side on a box", SLAB, -0.1, {"type": "cylinder", "radius": 0.2, "height": 0.8},
     0.2, LYING),
    ("cylinder side on a plane", FLOOR, 0.0, {"type": "cylinder", "radius": 0.2, "height": 0.8},
     0.2, LYING),
    ("capsule side on a box", SLAB, -0.1, {"type": "capsule", "radius": 0.1, "length": 0.6},
     0.1, LYING),
    ("capsule side on a plane", FLOOR, 0.0, {"type": "capsule", "radius": 0.1, "length": 0.6},
     0.1, LYING),
    ("box on a box", SLAB, -0.1, {"type": "box", "size": [0.5, 0.4, 0.3]}, 0.15, ID),
    ("box on an equal box", {"type": "box", "size": [0.5, 0.4, 0.3]}, -0.15,
     {"type": "box", "size": [0.5, 0.4, 0.3]}, 0.15, ID),
    ("box on an equal box, aligned", {"type": "box", "size": [0.5, 0.4, 0.3]}, -0.15,
     {"type": "box", "size": [0.5, 0.4, 0.3]}, 0.15, ID),
    ("box on a plane", FLOOR, 0.0, {"type": "box", "size": [0.5, 0.4, 0.3]}, 0.15, ID),
    ("hull face on a box", SLAB, -0.1, {"type": "convex", "points": PRISM}, 0.15, ID),
    ("hull face on a plane", FLOOR, 0.0, {"type": "convex", "points": PRISM}, 0.15, ID),
    ("cone base on a box", SLAB, -0.1, {"type": "cone", "radius": 0.3, "height": 0.5},
     0.25, ID),
    ("cylinder cap on a cylinder cap", {"type": "cylinder", "radius": 0.3, "height": 0.4},
     -0.2, {"type": "cylinder", "radius": 0.3, "height": 0.4}, 0.2, ID),
    ("box on a hull face", {"type": "convex", "points": PRISM}, -0.15,
     {"type": "box", "size": [0.2, 0.2, 0.2]}, 0.1, ID),
]


@pytest.mark.parametrize("rest", RESTS, ids=[r[0] for r in RESTS])
def test_flat_rests_keep_their_contacts_under_pose_noise(rest):
    """300 frames of 1e-9 m and 1e-9 rad noise on both bodies at zero gap: the same ids
    throughout, and every point within ten times the noise of where it began (a
    side line follows the normal, which the noise turns by a few 1e-8 rad)."""
    _, support, z_support, shape, z_rest, q_rest = rest
    rng = np.random.default_rng(7)
    bodies = [{"name": "support", "shape": support, "static": support is FLOOR},
              {"name": "rest", "shape": shape}]
    p = Pipeline(bodies)
    x, y = (0.0, 0.0) if "aligned" in rest[0] else (0.05, -0.03)
    base_pos = np.array([[0.0, 0.0, z_support], [x, y, z_rest]])
    base_quat = np.array([ID, q_rest])
    first = None
    for k in range(300):
        pos = base_pos + rng.uniform(-1e-9, 1e-9, size=(2, 3))
        quat = np.array([quat_mul(quat_axis(rng.normal(size=3), rng.uniform(-1e-9, 1e-9)),
                                   q) for q in base_quat])
        r = p.step(pos, quat, float(k))
        order = np.argsort(r.contact_id)
        if first is None:
            first = (r.contact_id[order].copy(), r.point_a[order].copy())
            assert len(first[0]) >= 2                    # a manifold, not one point
            continue
        np.testing.assert_array_equal(r.contact_id[order], first[0])
        assert np.abs(r.point_a[order] - first[1]).max() <= 1e-8


def test_max_pairs_truncates_a_step_and_keeps_the_arbiters_a_while():
    bodies = [ball(f"b{i}") for i in range(6)]
    pos = np.zeros((6, 3))
    pos[:, 0] = 0.1 * np.arange(6)                 # every pair overlaps: 15 pairs
    quat = np.tile(ID, (6, 1))
    p = Pipeline(bodies, PipelineConfig(stale_steps=2))
    full = p.step(pos, quat)
    assert len(full.pairs) == 15 and full.n_truncated_pairs == 0
    p.configure(max_pairs=4)
    r = p.step(pos, quat)
    assert r.n_truncated_pairs == 11 and r.n_narrowphase_pairs == 15
    assert len(r.pairs) == 15                      # the rest kept, unconfirmed
    run = {tuple(x) for x in full.pairs[:4].tolist()}
    assert set(r.status[[tuple(x) in run for x in zip(r.body_a, r.body_b)]]) <= {1, 2}
    r = p.step(pos, quat)
    assert [tuple(x) for x in r.pairs] == [tuple(x) for x in full.pairs[:4]]
    with pytest.raises(ValueError, match="max_pairs"):
        p.configure(max_pairs=-1)
