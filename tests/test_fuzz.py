"""A seeded slice of the narrow-phase fuzzer (mkcollision_ros/fuzzing.py), its saved cases
(tests/fuzz_cases.json) and the two bugs it found, each with a test that names it.

The slice runs every method on random pairs of every shape type (sizes 1 mm - 100 m,
aspect ratios to 1:1000, margins, hulls of 4 to 300 points, far apart to coincident
centres) and asserts the fuzzer's per-call checks: no FAILED, no NaN, a unit normal,
the touching rule, ``point_b - point_a == distance * normal``, B moved by the depth
along the normal no longer penetrating, agreement with auto within the documented
tolerances, the parallel batch equal to one-pair calls, the public API equal to the
batch.  No time bound is asserted (timings belong in the benchmark).
"""
import json
import math
import os

import numpy as np
import pytest

import oracles as O
from mkcollision_ros import fuzzing as F
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import OUT_DIST, P_RADIUS
from mkcollision_ros.results import Status

HERE = os.path.dirname(os.path.abspath(__file__))
with open(os.path.join(HERE, "fuzz_cases.json"), encoding="utf-8") as _f:
    CASES = json.load(_f)["cases"]


def _check(batch, methods=F.METHODS, api_every=0):
    lines = []
    stats = F.check_pairs(batch, methods, time_bound=math.inf, api_every=api_every,
                          report=lines.append)
    return lines, stats


@pytest.fixture(scope="module")
def slice_batch():
    rng = np.random.default_rng(20261202)
    pool = F.make_pool(rng, 80)
    return F.draw_pairs(rng, pool, 20000)


def test_slice_is_representative(slice_batch):
    b = slice_batch
    kinds = [(b.pool.shapes[b.ids[2 * k]]["type"], b.pool.shapes[b.ids[2 * k + 1]]["type"])
             for k in range(b.n)]
    combos = {(x, y) for x in F.KINDS for y in F.KINDS if not x == y == "plane"}
    assert set(kinds) == combos                       # every ordered type pair
    share = np.bincount(b.regime, minlength=len(F.REGIMES)) / b.n
    assert np.all(np.abs(share - np.array(F.REGIME_P)) < 0.04), share
    out, st = b.run(F.METHOD_NAMES.index("auto"))
    hit = np.mean((st == Status.TOUCHING) | (st == Status.PENETRATING))
    assert 0.3 < hit < 0.7, hit
    # the touching regime ends at round-off: |d| within 1e-9 * scale for most pairs
    touch = b.regime == F.REGIMES.index("touching")
    near = np.abs(out[touch, OUT_DIST]) <= 1e-9 * b.scale[touch]
    assert near.mean() > 0.9, near.mean()
    # sizes span the range (bounding radii from about 1 mm to about 100 m)
    r = b.params[:, P_RADIUS]
    assert r.min() < 3e-3 and r.max() > 50.0


def test_slice_passes_every_check(slice_batch):
    lines, stats = _check(slice_batch, api_every=100)
    assert lines == [], "\n".join(lines[:20])
    for s in stats.values():
        assert s.calls == slice_batch.n
        assert s.failed == s.nan == s.other == s.disagree == 0


def test_checks_catch_wrong_answers(monkeypatch):
    """The checks are not vacuous: a row made too shallow, one with a NaN and one
    FAILED are each reported."""
    a = {"type": "sphere", "radius": 1.0}
    b = {"type": "box", "size": [1.0, 2.0, 3.0]}
    poses = [([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]), ([1.2, 0.1, 0.0], [0.0, 0.0, 0.0, 1.0])]
    batch = F.batch_of([(a, poses[0], b, poses[1])] * 3)
    real = F.Batch.run_timed

    def broken(self, method):
        out, st, dt = real(self, method)
        out[0, OUT_DIST] *= 0.5                 # too shallow
        out[1, 1] = np.nan                      # a NaN in the normal
        st[2] = Status.FAILED
        return out, st, dt

    monkeypatch.setattr(F.Batch, "run_timed", broken)
    lines, stats = _check(batch, methods=("gjk_epa",))
    assert len(lines) == 3
    assert "disagrees with auto" in lines[0] and "still penetrates" in lines[0]
    assert "NaN" in lines[1]
    assert "FAILED" in lines[2]
    assert stats["gjk_epa"].failed == 1 and stats["gjk_epa"].nan == 1
    assert all("repro: collide(" in line for line in lines)


def _case_args(case):
    pa = (case["pose_a"]["position"], case["pose_a"]["quat_xyzw"])
    pb = (case["pose_b"]["position"], case["pose_b"]["quat_xyzw"])
    return case["shape_a"], pa, case["shape_b"], pb


@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in CASES])
def test_saved_case(case):
    a, pa, b, pb = _case_args(case)
    lines, _ = _check(F.batch_of([(a, pa, b, pb), (b, pb, a, pa)]), api_every=1)
    assert lines == [], "\n".join(lines)
    # the normal certifies the depth (h along it) and no sampled direction is
    # shallower than the depth reported (tests/oracles.py's slow search)
    d_oracle, _ = O.signed_distance_oracle(a, pa, b, pb)
    scale = O.bounding_radius(a) + O.bounding_radius(b)
    mpr = collide(a, pa, b, pb, method="mpr")
    for method in ("auto", "gjk_epa", case["method"]):
        r = collide(a, pa, b, pb, method=method)
        assert r.status in (Status.TOUCHING, Status.PENETRATING), (method, r)
        h = float(O.cso_support(a, pa, b, pb, r.normal[None])[0])
        assert abs(h + r.distance) <= 1e-6 * scale, (method, h, r.distance)
        if case.get("accuracy") == "upper_bound":
            # GJK stalled: the depth is the smaller of h along MPR's and GJK's normals,
            # an upper bound, no deeper than MPR's
            assert r.distance >= mpr.distance - 1e-6 * scale, (method, r, mpr)
        else:
            assert r.distance >= d_oracle - 1e-6 * scale, (method, r.distance, d_oracle)


def test_tiny_capsule_deep_inside_large_capsule_gjk_epa():
    """The issue's report: a capsule 10^3 - 10^4.5 times smaller at (or near) the centre
    of a larger one.  GJK/EPA hits its caps there; the answer must never be FAILED, and
    its depth is the closed form's."""
    rng = np.random.default_rng(11)
    for k in range(300):
        big_r = 10 ** rng.uniform(-2, 2)
        small_r = big_r / 10 ** rng.uniform(3, 4.5)
        big = {"type": "capsule", "radius": big_r, "length": big_r * 10 ** rng.uniform(-1, 1)}
        small = {"type": "capsule", "radius": small_r,
                 "length": small_r * 10 ** rng.uniform(-1, 1.5)}
        q = O.random_quats(rng, 2)
        c = rng.normal(size=3) * big_r
        pa = (c, q[0])
        pb = (c + (0.0 if k % 3 else 0.1) * big_r * rng.normal(size=3), q[1])
        if k % 2:
            big, small, pa, pb = small, big, pb, pa
        r = collide(big, pa, small, pb, method="gjk_epa")
        ref = collide(big, pa, small, pb, method="analytic")
        assert r.status == Status.PENETRATING, (k, r)
        scale = O.bounding_radius(big) + O.bounding_radius(small)
        assert abs(r.distance - ref.distance) <= 1e-6 * scale, (k, r, ref)


def test_crossing_capsule_axes_take_the_common_perpendicular():
    """Saved case crossing_capsule_axes_noise_normal: capsules at one centre whose axes
    are 1e-6 to 0.5 rad apart.  The closest points of the axes differ by round-off;
    the normal is the common perpendicular (normal to both axes), the depth the sum
    of the radii, h along the normal equal to it."""
    rng = np.random.default_rng(12)
    for k in range(300):
        ra, rb = 10 ** rng.uniform(-2, 2, size=2)
        a = {"type": "capsule", "radius": ra, "length": 10 ** rng.uniform(-2, 2)}
        b = {"type": "capsule", "radius": rb, "length": 10 ** rng.uniform(-2, 2)}
        qa = O.random_quats(rng, 1)[0]
        turn = O.quat_axis(rng.normal(size=3), 10 ** rng.uniform(-6, math.log10(0.5)))
        qb = O.quat_mul(turn, qa)
        c = rng.normal(size=3) * 100.0
        pa, pb = (c, qa), (c, qb)
        ua = O.quat_matrix(qa)[:, 2]
        ub = O.quat_matrix(qb)[:, 2]
        sin = np.linalg.norm(np.cross(ua, ub))
        scale = ra + rb + 0.5 * (a["length"] + b["length"])
        for method in ("auto", "analytic", "gjk_epa"):
            r = collide(a, pa, b, pb, method=method)
            h = float(O.cso_support(a, pa, b, pb, r.normal[None])[0])
            assert abs(h + r.distance) <= 1e-9 * scale, (k, method, h, r.distance)
            assert abs(r.distance + ra + rb) <= 1e-9 * scale, (k, method, r.distance)
            if sin > 1e-3:
                assert abs(r.normal @ ua) < 1e-9 and abs(r.normal @ ub) < 1e-9, (k, method)
