"""Ellipsoid tests (kernels/ellipsoid.py): the exact test against coal's signed distance
and the project's GJK/EPA on ellipsoid supports, over seeded random pairs in near,
shallow, deep and separated regimes, with needle/flat ellipsoids (axis ratio 1e3),
sizes 1e-4..1e4 and poses 1e5 from the world origin; the sampled test's guarantees (no
false positives, nested levels, containment).  Seeded; no timings.

Run as a script to print the miss-rate table of docs/narrowphase-notes.md:
    PYTHONPATH=. python tests/test_ellipsoid.py
"""
import sys

import coal
import numpy as np
import pytest

import oracles as O

from mkcollision_ros.kernels import constants as C
from mkcollision_ros.kernels.ellipsoid import ellipsoid_exact, ellipsoid_sampled
from mkcollision_ros.kernels.gjk_epa import gjk_epa

VERTS0 = np.zeros((0, 3))


def ell(radii, margin=0.0):
    prm = np.zeros(C.N_PARAMS)
    prm[:3] = radii
    prm[C.P_MARGIN] = margin
    prm[C.P_RADIUS] = max(radii) + margin
    return (np.int64(C.ELLIPSOID), prm, np.int64(0), np.int64(0))


def sph(r):
    prm = np.zeros(C.N_PARAMS)
    prm[0] = r
    prm[C.P_RADIUS] = r
    return (np.int64(C.SPHERE), prm, np.int64(0), np.int64(0))


def radii_of(s):
    return np.full(3, s[1][0]) if s[0] == C.SPHERE else s[1][:3].copy()


def coal_dist(sa, sb, r, t):
    ga = coal.Ellipsoid(*radii_of(sa))
    gb = coal.Ellipsoid(*radii_of(sb))
    tf = coal.Transform3s()
    tf.setRotation(r)
    tf.setTranslation(t)
    req = coal.DistanceRequest()
    req.gjk_tolerance = 1e-12
    req.gjk_max_iterations = 1000
    res = coal.DistanceResult()
    return coal.distance(ga, coal.Transform3s(), gb, tf, req, res)


def exact(sa, sb, r, t):
    out = np.full(C.OUT_SIZE, np.nan)
    st = ellipsoid_exact(sa, sb, r, t, out)
    return st, out


def touching_offset(sa, sb, r, u):
    """Offset s* along the unit u at which B touches A (bisection on the exact kernel's
    T-frame gap; used only to place test pairs, never as the oracle)."""
    lo = 0.0
    hi = 1.01 * (radii_of(sa).max() + radii_of(sb).max())
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if exact(sa, sb, r, u * mid)[1][0] <= 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


REGIMES = {"near": (1 - 1e-3, 1 + 1e-3), "shallow": (0.95, 1.05), "deep": (0.0, 0.6),
           "separated": (1.02, 2.0)}


def random_radii(rng, family, size):
    if family == "needle":          # one long axis, ratio 1e3
        r = np.array([1.0, 1e-3, 1e-3]) * rng.uniform(0.8, 1.2, 3)
    elif family == "flat":          # one short axis, ratio 1e3
        r = np.array([1.0, 1.0, 1e-3]) * rng.uniform(0.8, 1.2, 3)
    else:
        r = rng.uniform(0.2, 1.5, 3)
    return rng.permutation(r) * size


def random_pair(rng, regime, family="plain", size=1.0, far=False):
    fa = family if rng.random() < 0.7 else "plain"
    sa = ell(random_radii(rng, fa, size))
    sb = ell(random_radii(rng, family, size * 10 ** rng.uniform(-0.5, 0.5)))
    r = O.random_rotation(rng)
    u = rng.normal(size=3)
    u /= np.linalg.norm(u)
    lo, hi = REGIMES[regime]
    t = u * rng.uniform(lo, hi) * touching_offset(sa, sb, r, u)
    if far:
        # both bodies 1e5 m from the world origin: recompute the relative pose from
        # world poses as the pipeline does (it loses the low bits of t)
        r_a = O.random_rotation(rng)
        p_a = rng.normal(size=3) / np.sqrt(3) * 1e5
        r_b = r_a @ r
        p_b = p_a + r_a @ t
        r, t = r_a.T @ r_b, r_a.T @ (p_b - p_a)   # geometry.relative_pose's formula
    return sa, sb, r, t


def scale_of(sa, sb):
    return sa[1][7] + sb[1][7]


@pytest.mark.parametrize("family,size,far", [
    ("plain", 1.0, False), ("needle", 1.0, False), ("flat", 1.0, False),
    ("plain", 1e-4, False), ("plain", 1e4, False), ("needle", 1e4, True),
    ("plain", 1.0, True)])
def test_exact_agrees_with_coal_and_gjk(family, size, far):
    rng = np.random.default_rng(int(1000 * np.log10(size) + 7 * len(family) + far) % 2 ** 31)
    n_each = 110
    totals = {}
    for regime in REGIMES:
        hits = 0
        counted = 0
        for _ in range(n_each):
            sa, sb, r, t = random_pair(rng, regime, family, size, far)
            st, out = exact(sa, sb, r, t)
            assert np.all(np.isfinite(out))
            assert out[C.OUT_METHOD] == C.M_ELLIPSOID_EXACT
            assert abs(np.linalg.norm(out[1:4]) - 1) < 1e-12
            hit = st != C.ST_SEPARATED
            scale = scale_of(sa, sb)
            cd = coal_dist(sa, sb, r, t)
            ref = np.empty(C.OUT_SIZE)
            st_g = gjk_epa(sa, sb, VERTS0, r, t, ref)
            if abs(cd) > 1e-6 * scale:
                counted += 1
                hits += cd < 0
                assert hit == (cd < 0), (regime, sa, sb, r, t, cd, out[0])
            if abs(ref[0]) > 1e-6 * scale and st_g != C.ST_FAILED:
                assert hit == (st_g != C.ST_SEPARATED), (regime, sa, sb, r, t, ref[0], out[0])
            if out[0] > -1.0:
                # nearest points on the surfaces (A's at pa, B's at pb)
                ra, rb = radii_of(sa), radii_of(sb)
                assert np.sum((out[4:7] / ra) ** 2) == pytest.approx(1.0, abs=1e-9)
                pb_b = r.T @ (out[7:10] - t)
                assert np.sum((pb_b / rb) ** 2) == pytest.approx(1.0, abs=1e-6)
        totals[regime] = (hits, counted)
    h, c = totals["near"]
    assert 0.3 * c <= h <= 0.7 * c, totals
    h, c = totals["shallow"]
    assert 0.3 * c <= h <= 0.7 * c, totals
    assert totals["deep"][0] == totals["deep"][1] and totals["separated"][0] == 0
    h = sum(v[0] for v in totals.values())
    c = sum(v[1] for v in totals.values())
    assert 0.3 * c <= h <= 0.7 * c


def test_sphere_pair_gap_closed_form():
    rng = np.random.default_rng(4)
    for _ in range(200):
        ra, rb = rng.uniform(0.1, 2.0, 2)
        d = rng.uniform(0.0, 2.0) * (ra + rb)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        st, out = exact(sph(ra), sph(rb), O.random_rotation(rng), u * d)
        if d > rb:     # origin outside E (B's ball of radius rb / ra in the T frame)
            assert out[0] == pytest.approx((d - ra - rb) / ra, abs=1e-12 * (1 + rb / ra))
            np.testing.assert_allclose(out[1:4], u, atol=1e-9)
        else:
            assert out[0] == -1.0
        assert (st == C.ST_SEPARATED) == (d > ra + rb * (1 + 1e-12))


def test_not_run_for_margins_and_other_shapes():
    out = np.full(C.OUT_SIZE, 3.0)
    box = (np.int64(C.BOX), np.array([1, 1, 1, 0, 0, 0, 0, 1.8]), np.int64(0), np.int64(0))
    eye, z = np.eye(3), np.zeros(3)
    assert ellipsoid_exact(ell([1, 2, 3], 0.1), ell([1, 1, 1]), eye, z, out) == C.ST_NOT_RUN
    assert ellipsoid_exact(box, ell([1, 1, 1]), eye, z, out) == C.ST_NOT_RUN
    assert ellipsoid_sampled(ell([1, 1, 1]), ell([1, 2, 3], 0.1), eye, z, 2, out) == C.ST_NOT_RUN
    assert np.all(out == 3.0)


def test_containment_both_ways():
    eye = np.eye(3)
    small, big = ell([0.1, 0.2, 0.15]), ell([3.0, 2.0, 4.0])
    off = np.array([0.3, -0.2, 0.1])
    for n in range(3):
        out = np.empty(C.OUT_SIZE)
        # A inside B: no sample of B's surface is within A, only the point-in test sees it
        assert ellipsoid_sampled(small, big, eye, off, n, out) == C.ST_PENETRATING
        assert out[0] == -1.0 and out[C.OUT_ITERS] == 0
        # B inside A: every sample of B is inside A
        assert ellipsoid_sampled(big, small, eye, off, n, out) == C.ST_PENETRATING
    assert exact(small, big, eye, off)[0] == C.ST_PENETRATING
    assert exact(big, small, eye, off)[0] == C.ST_PENETRATING


def test_sampled_never_false_positive_and_levels_are_nested():
    rng = np.random.default_rng(8)
    misses = np.zeros(5, int)
    hits = 0
    for i in range(300):
        family = ("plain", "needle", "flat")[i % 3]
        sa, sb, r, t = random_pair(rng, "shallow", family)
        st, out = exact(sa, sb, r, t)
        hits += st != C.ST_SEPARATED
        prev = False
        for n in range(5):
            o = np.empty(C.OUT_SIZE)
            sts = ellipsoid_sampled(sa, sb, r, t, n, o)
            assert o[C.OUT_METHOD] == C.M_ELLIPSOID_SAMPLED and np.all(np.isfinite(o))
            # samples are points of B: their gap bounds the exact gap from above
            assert o[0] >= out[0] - 1e-9
            # level n+1 contains level n's points: a detection is never lost (the gap
            # values are not nested, the scan stops at the first face with a hit)
            assert sts != C.ST_SEPARATED or not prev
            prev = sts != C.ST_SEPARATED
            if sts == C.ST_SEPARATED and st != C.ST_SEPARATED:
                misses[n] += 1
    assert 0.3 * 300 <= hits <= 0.7 * 300
    assert misses[0] > misses[4]


def measure(n_pairs=2000, seed=99):
    """Miss rate of ellipsoid_sampled vs ellipsoid_exact on colliding near-contact
    pairs, per subdivision level and shape family; prints a markdown table."""
    rng = np.random.default_rng(seed)
    print("| regime | family | colliding pairs | " +
          " | ".join(f"miss n={n} ({10 * 4 ** n + 2} pts)" for n in range(5)) + " |")
    print("|---|---|---|" + "---|" * 5)
    REGIMES["moderate"] = (0.8, 0.99)
    for regime in ("near", "shallow", "moderate"):
        for family in ("plain", "needle", "flat"):
            miss = np.zeros(5, int)
            hits = 0
            for _ in range(n_pairs):
                sa, sb, r, t = random_pair(rng, regime, family)
                st, _ = exact(sa, sb, r, t)
                if st == C.ST_SEPARATED:
                    continue
                hits += 1
                for n in range(5):
                    o = np.empty(C.OUT_SIZE)
                    if ellipsoid_sampled(sa, sb, r, t, n, o) == C.ST_SEPARATED:
                        miss[n] += 1
            print(f"| {regime} | {family} | {hits} | " +
                  " | ".join(f"{100 * m / max(hits, 1):.1f}%" for m in miss) + " |")


if __name__ == "__main__":
    measure(int(sys.argv[1]) if len(sys.argv) > 1 else 2000)
