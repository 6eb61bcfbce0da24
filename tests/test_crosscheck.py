"""MPR against GJK/EPA on a scene's pairs, and one-line repros."""
import math

import numpy as np

from mkcollision_ros import collide
from mkcollision_ros.crosscheck import cross_check, describe, repro
from mkcollision_ros.scene import Scene
from oracles import random_quats, random_shape

KINDS = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex")


def _scene(seed, n=40):
    rng = np.random.default_rng(seed)
    sc = Scene([{"name": f"b{i}", "shape": random_shape(rng, KINDS[i % 7], 0.4)}
                for i in range(n)])
    sc.set_poses_at(np.arange(n), rng.uniform(0, 1.6, (n, 3)), random_quats(rng, n))
    return sc


def test_repro_reproduces_the_pair_exactly():
    sc = _scene(1, 10)
    for a, b in [(0, 1), (2, 9), (6, 3)]:
        line = repro(sc, min(a, b), max(a, b), "gjk_epa")
        got = eval(line, {"collide": collide})              # noqa: S307 - our own line
        sa, sb = (sc.body(sc.names[s]).shape for s in (min(a, b), max(a, b)))
        want = collide(sa, (sc.positions[min(a, b)], sc.orientations[min(a, b)]),
                       sb, (sc.positions[max(a, b)], sc.orientations[max(a, b)]), "gjk_epa")
        assert got.distance == want.distance and np.array_equal(got.normal, want.normal)


def test_cross_check_finds_exactly_the_pairs_where_the_methods_differ():
    sc = _scene(2)
    n = len(sc)
    pairs = np.array([(i, j) for i in range(n) for j in range(i + 1, n)], np.int64)
    checked, found = cross_check(sc, pairs, depth_tol=1e-4, angle_tol=math.radians(1.0))
    assert checked == len(pairs)
    want, touching = set(), 0
    for i, j in pairs:
        args = (sc.body(f"b{i}").shape, (sc.positions[i], sc.orientations[i]),
                sc.body(f"b{j}").shape, (sc.positions[j], sc.orientations[j]))
        m, g = collide(*args, method="mpr"), collide(*args, method="gjk_epa")
        touching += g.touching
        if m.touching != g.touching:
            want.add((i, j))
        elif m.touching and (abs(m.depth - g.depth) > 1e-4 or np.degrees(np.arccos(
                np.clip(np.dot(m.normal, g.normal), -1, 1))) > 1.0):
            want.add((i, j))
    assert touching > 20
    assert {(d.a, d.b) for d in found} == want
    for d in found:
        assert "repro: collide(" in describe(d, sc)
    # a loose tolerance leaves only touching disagreements
    _, loose = cross_check(sc, pairs, depth_tol=10.0, angle_tol=math.pi)
    assert all(d.status_mpr != d.status_gjk_epa for d in loose)
