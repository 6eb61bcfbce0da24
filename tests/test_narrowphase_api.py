"""Public narrow-phase API (mkcollision_ros.collide / distance / warm_up) and the
dispatcher/batch kernel (mkcollision_ros/kernels/narrowphase.py)."""
import math
import subprocess
import sys

import numba
import numpy as np
import pytest

import oracles as O
from mkcollision_ros import CollisionResult, Status, collide, distance, warm_up
from mkcollision_ros.kernels.constants import OUT_DIST, OUT_NORMAL, OUT_PA, OUT_PB

ID = ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
SPHERE = {"type": "sphere", "radius": 0.5}
BOX = {"type": "box", "size": [1.0, 2.0, 3.0]}


def test_import_does_not_pull_ros_or_rerun():
    code = ("import sys, mkcollision_ros; "
            "bad = [m for m in ('rclpy', 'rerun') if m in sys.modules]; "
            "print(','.join(bad)); sys.exit(1 if bad else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_warm_up_runs():
    assert warm_up() is None


def test_result_fields_and_sign_convention():
    r = collide(SPHERE, ID, SPHERE, ([0.8, 0.0, 0.0], [0, 0, 0, 1]))
    assert isinstance(r, CollisionResult)
    assert r.status == Status.PENETRATING and r.touching
    assert r.distance == pytest.approx(-0.2) and r.depth == pytest.approx(0.2)
    assert r.normal == pytest.approx([1, 0, 0])
    assert r.point_b - r.point_a == pytest.approx(r.distance * r.normal)
    assert r.method == "analytic"   # auto picks the closed form
    d = distance(SPHERE, ID, SPHERE, ([3.0, 0.0, 0.0], [0, 0, 0, 1]))
    assert d.status == Status.SEPARATED and not d.touching and d.depth == 0.0
    assert d.point_a == pytest.approx([0.5, 0, 0]) and d.point_b == pytest.approx([2.5, 0, 0])


def test_auto_falls_back_to_gjk_epa():
    e = {"type": "ellipsoid", "radii": [0.5, 0.4, 0.3]}
    r = collide(e, ID, BOX, ([1.5, 0.0, 0.0], [0, 0, 0, 1]))
    assert r.method == "gjk_epa"
    assert r.distance == pytest.approx(0.5, abs=1e-10)


@pytest.mark.parametrize("method", ["auto", "gjk_epa", "mpr", "analytic",
                                    "ellipsoid_exact", "ellipsoid_sampled"])
def test_every_method_name_runs(method):
    e = {"type": "ellipsoid", "radii": [0.5, 0.4, 0.3]}
    r = collide(e, ID, e, ([0.7, 0.1, 0.0], [0, 0, 0, 1]), method=method)
    assert np.all(np.isfinite(r.normal)) and math.isfinite(r.distance)
    assert abs(np.linalg.norm(r.normal) - 1.0) < 1e-9
    if method == "analytic":
        assert r.status == Status.NOT_RUN   # no closed form for ellipsoids
    else:
        assert r.status in (Status.PENETRATING, Status.TOUCHING)


def test_unknown_method_raises():
    with pytest.raises(ValueError):
        collide(SPHERE, ID, SPHERE, ID, method="bullet")


@pytest.mark.parametrize("shape", [
    {"type": "sphere", "radius": float("nan")},
    {"type": "sphere", "radius": float("inf")},
    {"type": "sphere", "radius": -1.0},
    {"type": "box", "size": [1.0, -2.0, 1.0]},
    {"type": "box", "size": [1.0, float("nan"), 1.0]},
    {"type": "ellipsoid", "radii": [1.0, 2.0]},
    {"type": "capsule", "radius": 0.1, "length": -1.0},
    {"type": "convex", "points": [[0.0, 0.0, float("inf")]]},
    {"type": "sphere", "radius": 1.0, "margin": -0.1},
    {"type": "torus", "radius": 1.0},
])
def test_invalid_shapes_raise(shape):
    with pytest.raises(ValueError):
        collide(shape, ID, SPHERE, ID)
    with pytest.raises(ValueError):
        distance(SPHERE, ID, shape, ID)


@pytest.mark.parametrize("pose", [
    ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]),
    ([0.0, 0.0, float("nan")], [0.0, 0.0, 0.0, 1.0]),
    ([0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
    ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ([0.0, 0.0, 0.0], [0.0, float("inf"), 0.0, 1.0]),
    "not a pose",
])
def test_invalid_poses_raise(pose):
    with pytest.raises(ValueError):
        collide(SPHERE, pose, SPHERE, ID)


def test_quaternion_is_normalised():
    q = np.array([0.1, 0.2, 0.3, 0.9])
    r1 = collide(BOX, ([0, 0, 0], q * 7.0), BOX, ([1.2, 0.3, 0.1], [0, 0, 0, 1]), "gjk_epa")
    r2 = collide(BOX, ([0, 0, 0], q / np.linalg.norm(q)), BOX,
                 ([1.2, 0.3, 0.1], [0, 0, 0, 1]), "gjk_epa")
    assert r1.distance == pytest.approx(r2.distance, abs=1e-12)
    assert r1.normal == pytest.approx(r2.normal, abs=1e-12)


def test_swap_to_canonical_order_flips_back():
    # box (code 2) as A and sphere (code 0) as B: the dispatcher solves (sphere, box)
    rng = np.random.default_rng(3)
    for _ in range(50):
        q = O.random_quats(rng, 1)[0]
        p = rng.normal(size=3)
        for method in ("auto", "gjk_epa", "mpr"):
            r1 = collide(BOX, ID, SPHERE, (p, q), method)
            r2 = collide(SPHERE, (p, q), BOX, ID, method)
            assert r1.status == r2.status
            assert r1.distance == pytest.approx(r2.distance, abs=1e-6)
            if abs(r1.distance) > 1e-3:
                assert r1.normal == pytest.approx(-r2.normal, abs=1e-3)
                assert r1.point_a == pytest.approx(r2.point_b, abs=1e-3)
            assert r1.point_b - r1.point_a == pytest.approx(r1.distance * r1.normal,
                                                            abs=1e-6)


def test_plane_pairs():
    plane = {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": 0.0}
    pose_b = ([0.0, 0.0, 0.3], [0, 0, 0, 1])
    # gjk_epa does not handle half-spaces
    r = collide(BOX, pose_b, plane, ID, "gjk_epa")
    assert r.status == Status.NOT_RUN and not r.touching
    assert np.all(np.isfinite(r.normal))
    # auto: the closed form; box bottom at z = -1.2, half-space z <= 0 -> depth 1.2
    r1 = collide(BOX, pose_b, plane, ID, "auto")
    r2 = collide(plane, ID, BOX, pose_b, "auto")
    assert r1.status == Status.PENETRATING and r2.status == Status.PENETRATING
    assert r1.distance == pytest.approx(-1.2) and r2.distance == pytest.approx(-1.2)
    assert r1.normal == pytest.approx(-r2.normal)
    assert r1.normal == pytest.approx([0, 0, -1])   # from the box towards the half-space


def test_plane_margin_grows_the_half_space():
    """A plane's margin m grows its half-space n.x <= d to n.x <= d + m, in the world
    frame path of collide and in the body-frame closed form alike, as the broad phase
    grows the plane by it."""
    from mkcollision_ros.kernels.analytic import collide_analytic
    from mkcollision_ros.shapes import shape_row
    sphere = {"type": "sphere", "radius": 0.5}
    # tilted, offset plane body: the half-space z' <= 0.2 (+ 0.1 margin) of its frame
    s2 = math.sqrt(0.5)
    pose_p = ([1.0, -2.0, 0.5], [s2, 0.0, 0.0, s2])      # 90 degrees about x: z' = -y
    for margin, want in ((0.0, 0.3), (0.1, 0.2), (0.4, -0.1)):
        plane = {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": 0.2,
                 "margin": margin}
        # sphere centre 1.0 out along the plane's world normal (-y) from its origin
        pose_s = ([1.0, -3.0, 0.5], [0.0, 0.0, 0.0, 1.0])
        r1 = collide(sphere, pose_s, plane, pose_p)
        r2 = collide(plane, pose_p, sphere, pose_s)
        assert r1.distance == pytest.approx(want, abs=1e-12)
        assert r2.distance == pytest.approx(want, abs=1e-12)
        assert r1.normal == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)
        assert r2.normal == pytest.approx([0.0, -1.0, 0.0], abs=1e-12)
        assert r1.point_b == pytest.approx([1.0, -2.2 - margin, 0.5], abs=1e-12)
        assert r1.touching == (want <= 0.0)
        # the body-frame closed form, B's pose in A's frame
        ca, pa, _ = shape_row(sphere)
        cb, pb, _ = shape_row(plane)
        r_ab = O.quat_matrix(np.array(pose_p[1]))
        t_ab = np.array(pose_p[0]) - np.array(pose_s[0])
        out = np.empty(12)
        collide_analytic((ca, pa, 0, 0), (cb, pb, 0, 0), np.zeros((0, 3)), r_ab, t_ab, out)
        assert out[OUT_DIST] == pytest.approx(want, abs=1e-12)


def _scene(rng, n_shapes=40, n_pairs=300, types=O.TYPES):
    shapes = [O.random_shape(rng, types[i % len(types)]) for i in range(n_shapes)]
    from mkcollision_ros.shapes import build_table
    table = build_table(shapes)
    pos = rng.uniform(-1.0, 1.0, size=(n_shapes, 3))
    quat = O.random_quats(rng, n_shapes)
    pairs = rng.integers(0, n_shapes, size=(n_pairs, 2)).astype(np.int64)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    return shapes, table, pos, quat, pairs


def _batch(table, pos, quat, pairs, method=0):
    from mkcollision_ros.kernels.narrowphase import collide_batch
    out = np.full((len(pairs), 12), np.nan)
    status = np.full(len(pairs), -1, dtype=np.int64)
    collide_batch(table.codes, table.params, table.vrange, table.verts, pairs, pos, quat,
                  np.int64(method), np.inf, out, status)
    return out, status


def test_batch_matches_single_calls_and_is_thread_count_independent():
    rng = np.random.default_rng(4)
    shapes, table, pos, quat, pairs = _scene(rng)
    old = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        out1, st1 = _batch(table, pos, quat, pairs)
        numba.set_num_threads(max(2, old))
        out2, st2 = _batch(table, pos, quat, pairs)
    finally:
        numba.set_num_threads(old)
    assert np.array_equal(out1, out2) and np.array_equal(st1, st2)
    assert np.all(np.isfinite(out1)) and np.all(st1 >= 0)
    hits = np.isin(st1, (Status.TOUCHING, Status.PENETRATING)).mean()
    assert 0.2 < hits < 0.8
    # single calls renormalise the quaternion, so agreement is to round-off
    for k in range(0, len(pairs), 7):
        i, j = pairs[k]
        r = collide(shapes[i], (pos[i], quat[i]), shapes[j], (pos[j], quat[j]))
        scale = O.bounding_radius(shapes[i]) + O.bounding_radius(shapes[j])
        assert r.status == st1[k]
        assert abs(r.distance - out1[k, OUT_DIST]) < 1e-9 * scale
        assert np.allclose(r.normal, out1[k, OUT_NORMAL:OUT_NORMAL + 3], atol=1e-6)
        assert np.allclose(r.point_a, out1[k, OUT_PA:OUT_PA + 3], atol=1e-6 * scale)
        assert np.allclose(r.point_b, out1[k, OUT_PB:OUT_PB + 3], atol=1e-6 * scale)


def _cutoff_zero_early_stops(shapes, table, pos, quat, pairs, method):
    """Check the contacts-only mode (cutoff 0) against exact distances: the same
    touching pairs with the same rows, and for pairs apart a certified lower bound with
    its separating direction.  Returns how many pairs stopped at a bound below the
    exact distance."""
    from mkcollision_ros.kernels.narrowphase import collide_batch
    exact, st = _batch(table, pos, quat, pairs, method)
    cut = np.full_like(exact, np.nan)
    st_cut = np.full_like(st, -1)
    collide_batch(table.codes, table.params, table.vrange, table.verts, pairs, pos,
                  quat, np.int64(method), 0.0, cut, st_cut)
    assert np.array_equal(st, st_cut) and np.all(np.isfinite(cut))
    apart = st == Status.SEPARATED
    assert 0.2 < apart.mean() < 0.8
    assert np.array_equal(exact[~apart], cut[~apart])
    early = 0
    for k in np.flatnonzero(apart):
        i, j = pairs[k]
        scale = O.bounding_radius(shapes[i]) + O.bounding_radius(shapes[j])
        d, n = cut[k, OUT_DIST], cut[k, OUT_NORMAL:OUT_NORMAL + 3]
        assert 0.0 < d <= exact[k, OUT_DIST] + 1e-12 * scale
        assert abs(np.linalg.norm(n) - 1.0) < 1e-12
        h = O.cso_support(shapes[i], (pos[i], quat[i]), shapes[j], (pos[j], quat[j]),
                          n[None, :])[0]
        assert h <= -d + 1e-9 * scale   # the plane normal to n separates them by d
        early += d < exact[k, OUT_DIST] - 1e-9 * scale
    return early


def test_cutoff_zero_keeps_every_contact_and_bounds_the_distance_of_the_rest():
    rng = np.random.default_rng(11)
    shapes, table, pos, quat, pairs = _scene(rng, n_shapes=60, n_pairs=600)
    early = sum(_cutoff_zero_early_stops(shapes, table, pos, quat, pairs, method)
                for method in (0, 1, 2))
    assert early > 50    # GJK did stop early on many pairs


def test_cutoff_zero_box_pairs_apart_keep_the_separating_axis_bound():
    # auto on two boxes: a separating axis of the cores ends the pair at once when its
    # gap exceeds the cutoff (kernels/narrowphase._box_box)
    rng = np.random.default_rng(12)
    shapes, table, pos, quat, pairs = _scene(rng, n_shapes=40, n_pairs=800,
                                             types=["box"])
    assert _cutoff_zero_early_stops(shapes, table, pos, quat, pairs, 0) > 50


def test_batch_world_frame_witnesses():
    rng = np.random.default_rng(5)
    shapes, table, pos, quat, pairs = _scene(rng, n_pairs=200)
    out, st = _batch(table, pos, quat, pairs, method=1)
    for k, (i, j) in enumerate(pairs):
        scale = O.bounding_radius(shapes[i]) + O.bounding_radius(shapes[j])
        n = out[k, OUT_NORMAL:OUT_NORMAL + 3]
        assert abs(O.surface_gap(shapes[i], (pos[i], quat[i]), out[k, OUT_PA:OUT_PA + 3],
                                 n)) < 1e-7 * scale
        assert abs(O.surface_gap(shapes[j], (pos[j], quat[j]), out[k, OUT_PB:OUT_PB + 3],
                                 -n)) < 1e-7 * scale


def test_never_nan_on_hard_inputs():
    rng = np.random.default_rng(6)
    for _ in range(200):
        ka, kb = rng.choice(O.TYPES, 2)
        size_a, size_b = 10.0 ** rng.uniform(-4, 4, 2)
        sa = O.random_shape(rng, ka, size_a, ratio=1e3)
        sb = O.random_shape(rng, kb, size_b, ratio=1e3)
        centre = rng.choice([0.0, 1e5])
        pa = (centre + rng.normal(size=3) * size_a, O.random_quats(rng, 1)[0])
        pb = (pa[0] + rng.normal(size=3) * (size_a + size_b) * 0.5,
              O.random_quats(rng, 1)[0])
        for method in ("auto", "gjk_epa"):
            r = collide(sa, pa, sb, pb, method)
            assert math.isfinite(r.distance)
            assert np.all(np.isfinite(r.normal)) and np.all(np.isfinite(r.point_a))
            assert abs(np.linalg.norm(r.normal) - 1.0) < 1e-9


def test_ellipsoid_methods_decide_status_and_report_metric_geometry():
    """The ellipsoid tests say whether the pair touches; distance, normal and points are
    GJK/EPA's, in metres (the kernels' own gap is in A's unit-sphere frame)."""
    e = {"type": "ellipsoid", "radii": [2.0, 0.5, 0.5]}
    s = {"type": "sphere", "radius": 0.5}
    for x, touching in ((2.4, True), (2.6, False)):
        ref = collide(e, ID, s, ([x, 0.0, 0.0], [0, 0, 0, 1]), method="gjk_epa")
        for method in ("ellipsoid_exact", "ellipsoid_sampled"):
            r = collide(e, ID, s, ([x, 0.0, 0.0], [0, 0, 0, 1]), method=method)
            assert r.method == method and r.touching == touching
            assert r.distance == pytest.approx(x - 2.5, abs=1e-9)
            assert r.distance == pytest.approx(ref.distance, abs=1e-12)
            np.testing.assert_allclose(r.normal, [1.0, 0.0, 0.0], atol=1e-9)


def test_mpr_touching_rule_at_an_exact_kiss():
    """MPR alone reports SEPARATED with a ~0 lower bound for exactly touching boxes
    (found by the regression corpus, fcl#398 scene); the same touching rule as every
    other path must hold."""
    box = {"type": "box", "size": [1.0, 1.0, 1.0]}
    r = collide(box, ID, box, ([1.0, 0.3, 0.2], [0, 0, 0, 1]), method="mpr")
    assert r.status == Status.TOUCHING and r.touching
    assert abs(r.distance) <= 1e-9
    apart = collide(box, ID, box, ([1.01, 0.3, 0.2], [0, 0, 0, 1]), method="mpr")
    assert apart.status == Status.SEPARATED
