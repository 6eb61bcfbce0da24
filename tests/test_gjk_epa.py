"""GJK/EPA kernel (mkcollision_ros/kernels/gjk_epa.py): closed forms, invariants, the
peer oracle coal on random pairs of every non-plane type pair, and hard cases.

Agreement targets (the issue): touching flag agrees whenever |signed distance| > 1e-6 *
scale; distances and depths within 1e-6 * scale; normals within 1e-3 rad when |signed
distance| > 1e-3 * scale (scale = sum of the two bounding radii).

coal 3.0.3 is not always right: its EPA returns -DBL_MAX at tight tolerances (the adapter
retries looser ones) and its sphere-cylinder path reports wrong depths (e.g. a sphere of
radius 0.3 at (0.1, 0, 0.5) in a cylinder r=1, h=2 gives -1.2, the true value is -0.8).
A disagreement beyond the target is settled by certificates: for any unit u,
-h_{A-B}(u) is a lower bound of the true signed distance (signed distance = -min over u
of h_{A-B}(u)).  Ours must equal -h(n_ours) (an upper bound on the depth; exact when
apart, with the witness points on the surfaces), and must not be below the bounds from
the slow oracle's direction search (oracles.signed_distance_oracle) or from coal's own
normal.  Disputes must stay rare (< 5 %; < 25 % for sphere-cylinder, coal's bug).  A normal more
than 1e-3 rad from coal's is accepted only when ours is the better one, i.e. its support
value h_{A-B}(n) is not larger than that of coal's normal (+1e-7 * scale): coal's EPA
stops early (its normals are off by ~1e-3 rad on ellipsoids/cones), and near a
cylinder's axis the normal is ill-conditioned (a flat valley of equally deep
directions).

Every run (CI included) uses 10,000 random pairs per type pair and 2,000 near-touching
ones (about 2 minutes); MKC_N=<n> runs fewer while editing.
"""
import math
import os

import numpy as np
import pytest

import oracles as O
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import (OUT_DIST, OUT_NORMAL, OUT_PA, OUT_PB,
                                               ST_FAILED, ST_PENETRATING, ST_SEPARATED,
                                               ST_TOUCHING)
from oracles import ID, gjk, pose

N_PAIRS = int(os.environ.get("MKC_N", 10000))
PAIR_TYPES = [(a, b) for i, a in enumerate(O.TYPES) for b in O.TYPES[i:]]


# --- closed forms -------------------------------------------------------------------------
@pytest.mark.parametrize("x, ra, rb", [(3.0, 1.0, 0.5), (1.2, 1.0, 0.5), (0.0, 1.0, 0.5),
                                       (1.5, 1.0, 0.5), (1e-7, 2.0, 2.0)])
def test_sphere_sphere_closed_form(x, ra, rb):
    r = gjk({"type": "sphere", "radius": ra}, ID, {"type": "sphere", "radius": rb},
            pose([x, 0, 0]))
    assert r.distance == pytest.approx(x - ra - rb, abs=1e-12)
    assert abs(np.linalg.norm(r.normal) - 1.0) < 1e-12
    if x > 0:
        assert r.normal == pytest.approx([1, 0, 0], abs=1e-9)
        assert r.point_a == pytest.approx([ra, 0, 0], abs=1e-9)
        assert r.point_b == pytest.approx([x - rb, 0, 0], abs=1e-9)
    expected = "SEPARATED" if x > ra + rb else ("TOUCHING" if x == ra + rb else "PENETRATING")
    assert r.status.name == expected


@pytest.mark.parametrize("offset, expect", [
    ([2.5, 0.3, -0.2], 0.5),          # apart along x: face gap
    ([1.7, 0.3, -0.2], -0.3),         # overlap 0.3 along x (smallest axis overlap)
    ([0.2, 0.1, 3.9], -0.1),          # overlap 0.1 along z
    ([0.0, 0.0, 0.0], -2.0),          # concentric: shallowest axis x, 1 + 1
    ([2.0, 2.0, 0.0], 0.0),           # edge touching
])
def test_axis_aligned_boxes(offset, expect):
    a = {"type": "box", "size": [2.0, 4.0, 6.0]}
    b = {"type": "box", "size": [2.0, 2.0, 2.0]}
    r = gjk(a, ID, b, pose(offset))
    lo_a, hi_a = -np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, 3.0])
    lo_b, hi_b = np.array(offset) - 1.0, np.array(offset) + 1.0
    overlap = np.minimum(hi_a, hi_b) - np.maximum(lo_a, lo_b)
    if np.all(overlap > 0):
        truth = -float(np.min(np.minimum(hi_a - lo_b, hi_b - lo_a)))
    else:
        truth = float(np.linalg.norm(np.maximum(-overlap, 0.0)))
    assert truth == pytest.approx(expect)
    assert r.distance == pytest.approx(truth, abs=1e-12)
    assert np.all(np.isfinite(r.normal))
    assert r.point_b - r.point_a == pytest.approx(r.distance * r.normal, abs=1e-12)


def test_box_box_face_contact_normal():
    a = {"type": "box", "size": [1.0, 1.0, 1.0]}
    b = {"type": "box", "size": [0.5, 0.5, 0.5]}
    r = gjk(a, ID, b, pose([0.1, 0.05, 0.7]))
    assert r.distance == pytest.approx(-0.05, abs=1e-12)
    assert r.normal == pytest.approx([0, 0, 1], abs=1e-12)
    assert r.status.name == "PENETRATING"


def test_coaxial_cylinders_and_capsules():
    cyl = {"type": "cylinder", "radius": 1.0, "height": 2.0}
    # stacked along z, overlapping by 0.25
    r = gjk(cyl, ID, cyl, pose([0.0, 0.0, 1.75]))
    assert r.distance == pytest.approx(-0.25, abs=1e-10)
    assert r.normal == pytest.approx([0, 0, 1], abs=1e-8)
    # side by side, gap 0.5
    r = gjk(cyl, ID, cyl, pose([2.5, 0.0, 0.3]))
    assert r.distance == pytest.approx(0.5, abs=1e-10)
    cap = {"type": "capsule", "radius": 0.5, "length": 2.0}
    r = gjk(cap, ID, cap, pose([0.0, 0.0, 2.5]))  # tips overlap by 0.5
    assert r.distance == pytest.approx(-0.5, abs=1e-12)
    r = gjk(cap, ID, cap, pose([0.6, 0.0, 0.0]))  # parallel, axes 0.6 apart
    assert r.distance == pytest.approx(-0.4, abs=1e-12)
    assert r.normal == pytest.approx([1, 0, 0], abs=1e-12)


def test_sphere_inside_cylinder_and_cone():
    s = {"type": "sphere", "radius": 0.3}
    cyl = {"type": "cylinder", "radius": 1.0, "height": 2.0}
    cone = {"type": "cone", "radius": 1.0, "height": 2.0}
    # nearest cylinder boundary: top cap at distance 0.5
    r = gjk(s, pose([0.1, 0, 0.5]), cyl, ID)
    assert r.distance == pytest.approx(-0.8, abs=1e-9)
    # centre on the axis: every direction to the side is as deep as the caps (1.0)
    r = gjk(s, ID, cyl, ID)
    assert r.distance == pytest.approx(-1.3, abs=1e-6)
    # on the cone's axis: distance to the slanted side is 1/sqrt(5) (circle of minima)
    r = gjk(s, ID, cone, ID)
    assert r.distance == pytest.approx(-(0.3 + 1 / math.sqrt(5)), abs=1e-9)
    assert r.status == ST_PENETRATING     # EPA's caps are hit, its lower bound decides
    assert np.all(np.isfinite(r.normal))


_REVOLVED = ("sphere", "ellipsoid", "capsule", "cylinder", "cone")


def _revolved_shape(rng, kind):
    """A random body of revolution about z (ellipsoid: radii a, a, c)."""
    r, h = rng.uniform(0.2, 1.5), rng.uniform(0.2, 3.0)
    if kind == "sphere":
        return {"type": "sphere", "radius": r}
    if kind == "ellipsoid":
        return {"type": "ellipsoid", "radii": [r, r, h / 2]}
    if kind == "capsule":
        return {"type": "capsule", "radius": r, "length": h}
    return {"type": kind, "radius": r, "height": h}


def _meridian_min(fun):
    """min over theta in [0, pi] of fun(theta) (vectorised): a dense grid, then golden
    sections inside the best cell's neighbours."""
    th = np.linspace(0.0, math.pi, 20001)
    k = int(np.argmin(fun(th)))
    lo, hi = th[max(k - 1, 0)], th[min(k + 1, len(th) - 1)]
    g = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(80):
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        if fun(np.array([a]))[0] < fun(np.array([b]))[0]:
            hi = b
        else:
            lo = a
    return float(fun(np.array([0.5 * (lo + hi)]))[0])


@pytest.mark.parametrize("method", ["gjk_epa", "auto"])
def test_coaxial_valleys_are_penetrating(method):
    """Two bodies of revolution on one axis (coincident centres or shifted along the
    axis) in a random common pose: a ring of equally deep directions, which EPA's
    polytope cannot enclose to its tolerance (its caps are hit).  A FAILED answer there
    (two coincident cylinders, say) would make the pipeline drop their contact.  The pair
    must come out PENETRATING with the exact depth, from a 1-D search over the
    meridian angle (exact for such pairs), and a normal along which A - B is that
    deep."""
    rng = np.random.default_rng(23)
    for ka in _REVOLVED:
        for kb in _REVOLVED:
            for _ in range(3):
                sa, sb = _revolved_shape(rng, ka), _revolved_shape(rng, kb)
                t = 0.0 if rng.uniform() < 0.5 else rng.uniform(-0.3, 0.3)

                def h(th):
                    u = np.stack([np.sin(th), np.zeros_like(th), np.cos(th)], axis=1)
                    return (O.support_values(sa, u) + O.support_values(sb, -u)
                            - t * np.cos(th))

                depth = _meridian_min(h)
                q = O.random_quats(rng, 1)[0]
                c = rng.uniform(-5.0, 5.0, 3)
                pa = (c, q)
                pb = (c + O.quat_matrix(q) @ np.array([0.0, 0.0, t]), q)
                r = collide(sa, pa, sb, pb, method=method)
                scale = O.bounding_radius(sa) + O.bounding_radius(sb)
                msg = (ka, kb, sa, sb, t, method)
                assert r.status == ST_PENETRATING, msg
                assert abs(r.depth - depth) <= 1e-6 * scale, (r.depth, depth, msg)
                hn = O.cso_support(sa, pa, sb, pb, np.asarray(r.normal)[None, :])[0]
                assert abs(hn - r.depth) <= 1e-6 * scale, (hn, r.depth, msg)


def test_margin_is_exact_offset():
    a = {"type": "box", "size": [1.0, 1.0, 1.0], "margin": 0.1}
    b = {"type": "ellipsoid", "radii": [0.3, 0.2, 0.4], "margin": 0.05}
    r0 = gjk({"type": "box", "size": [1.0, 1.0, 1.0]}, ID,
             {"type": "ellipsoid", "radii": [0.3, 0.2, 0.4]}, pose([0.9, 0.2, 0.1]))
    r1 = gjk(a, ID, b, pose([0.9, 0.2, 0.1]))
    assert r1.distance == pytest.approx(r0.distance - 0.15, abs=1e-9)
    assert r1.normal == pytest.approx(r0.normal, abs=1e-6)


# --- invariants ------------------------------------------------------------------------------
def _random_cases(seed, n, offset=(0.0, 1.2)):
    rng = np.random.default_rng(seed)
    cases = []
    for ka, kb in PAIR_TYPES:
        sa, pa, qa, sb, pb, qb = O.random_pairs(rng, ka, kb, n, offset=offset)
        cases += [(sa[k], (pa[k], qa[k]), sb[k], (pb[k], qb[k])) for k in range(n)]
    return cases


def test_witness_points_on_surfaces_and_consistent():
    n_checked = 0
    for sa, pa, sb, pb in _random_cases(11, 12):
        r = gjk(sa, pa, sb, pb)
        scale = O.bounding_radius(sa) + O.bounding_radius(sb)
        assert r.status in (ST_SEPARATED, ST_TOUCHING, ST_PENETRATING)
        assert abs(np.linalg.norm(r.normal) - 1.0) < 1e-12
        assert r.point_b - r.point_a == pytest.approx(r.distance * r.normal,
                                                      abs=1e-9 * scale)
        # pa is A's extreme point along +n, pb is B's extreme point along -n
        assert abs(O.surface_gap(sa, pa, r.point_a, r.normal)) < 1e-7 * scale
        assert abs(O.surface_gap(sb, pb, r.point_b, -r.normal)) < 1e-7 * scale
        # signed distance = -h_{A-B}(normal): the support gap along the normal
        h = O.cso_support(sa, pa, sb, pb, r.normal[None, :])[0]
        assert r.distance == pytest.approx(-h, abs=1e-7 * scale)
        n_checked += 1
    assert n_checked == 12 * len(PAIR_TYPES)


def test_moving_b_by_depth_flips_state():
    hits = 0
    cases = _random_cases(12, 8)
    for sa, pa, sb, pb in cases:
        r = gjk(sa, pa, sb, pb)
        scale = O.bounding_radius(sa) + O.bounding_radius(sb)
        eps = 1e-5 * scale
        hits += r.touching
        move = -r.distance * r.normal     # brings the pair to touching
        far = (np.asarray(pb[0]) + move + eps * r.normal, pb[1])
        near = (np.asarray(pb[0]) + move - eps * r.normal, pb[1])
        assert gjk(sa, pa, sb, far).status == ST_SEPARATED
        assert gjk(sa, pa, sb, near).status == ST_PENETRATING
        t = gjk(sa, pa, sb, (np.asarray(pb[0]) + move, pb[1]))
        assert abs(t.distance) < 1e-6 * scale
    assert 0.3 < hits / len(cases) < 0.8


def test_swapping_a_and_b_flips_normal():
    for sa, pa, sb, pb in _random_cases(13, 6):
        r1 = gjk(sa, pa, sb, pb)
        r2 = gjk(sb, pb, sa, pa)
        scale = O.bounding_radius(sa) + O.bounding_radius(sb)
        assert r2.distance == pytest.approx(r1.distance, abs=1e-6 * scale)
        if abs(r1.distance) > 1e-3 * scale:
            ang = math.acos(min(1.0, float(-r1.normal @ r2.normal)))
            assert ang < 1e-3


# --- against coal -----------------------------------------------------------------------------
def _compare_with_coal(ka, kb, n, seed, regime):
    rng = np.random.default_rng(seed)
    sa, pa, qa, sb, pb, qb = O.random_pairs(rng, ka, kb, n)
    if regime == "near":
        # put every pair within +-1e-2 .. 1e-7 of touching along our own normal
        out, _ = O.run_batch(sa, pa, qa, sb, pb, qb)
        scale = np.array([O.bounding_radius(a) + O.bounding_radius(b)
                          for a, b in zip(sa, sb)])
        delta = scale * 10.0 ** rng.uniform(-7, -2, n) * rng.choice([-1.0, 1.0], n)
        pb = pb + (delta - out[:, OUT_DIST])[:, None] * out[:, OUT_NORMAL:OUT_NORMAL + 3]
    out, st = O.run_batch(sa, pa, qa, sb, pb, qb)
    assert np.all(np.isfinite(out))
    req = O.coal_request()
    stats = dict(n=n, coal_wrong=0, max_err=0.0, max_ang=0.0, hits=0)
    for k in range(n):
        scale = O.bounding_radius(sa[k]) + O.bounding_radius(sb[k])
        ga, gb = O.coal_shape(sa[k]), O.coal_shape(sb[k])
        d, nrm, _, _ = O.coal_signed_distance(ga, (pa[k], qa[k]), gb, (pb[k], qb[k]), req)
        ours = out[k, OUT_DIST]
        stats["hits"] += ours <= 0
        if not (np.isfinite(d) and abs(d - ours) <= 1e-6 * scale):
            # adjudicate: coal must be certifiably wrong, ours must pass the certificate
            # disputed (coal failed, or coal is off, typically after retrying with a
            # looser EPA tolerance).  Certificates: for every unit u, -h_{A-B}(u) is a
            # lower bound of the true signed distance; ours must equal -h(n_ours) (so
            # it is an upper bound on the depth / a lower bound on the distance, and
            # with pa, pb on the surfaces exact when apart), and must not be below
            # the bound given by the slow oracle's search nor by coal's own normal.
            pose_a, pose_b = (pa[k], qa[k]), (pb[k], qb[k])
            lb, _ = O.signed_distance_oracle(sa[k], pose_a, sb[k], pose_b)
            n_ours = out[k, OUT_NORMAL:OUT_NORMAL + 3]
            h_o = O.cso_support(sa[k], pose_a, sb[k], pose_b, n_ours[None, :])[0]
            assert abs(ours + h_o) <= 1e-7 * scale, (ka, kb, k, ours, -h_o)
            if np.all(np.isfinite(nrm)) and np.linalg.norm(nrm) > 0.5:
                u = nrm / np.linalg.norm(nrm)
                lb = max(lb, -O.cso_support(sa[k], pose_a, sb[k], pose_b, u[None, :])[0])
            assert ours >= lb - 1e-8 * scale, (ka, kb, k, ours, d, lb)
            if ours > 0:
                assert abs(O.surface_gap(sa[k], pose_a, out[k, OUT_PA:OUT_PA + 3],
                                         n_ours)) <= 1e-8 * scale
                assert abs(O.surface_gap(sb[k], pose_b, out[k, OUT_PB:OUT_PB + 3],
                                         -n_ours)) <= 1e-8 * scale
            stats["coal_wrong"] += 1
            continue
        stats["max_err"] = max(stats["max_err"], abs(d - ours) / scale)
        if abs(d) > 1e-6 * scale:
            assert (st[k] in (ST_TOUCHING, ST_PENETRATING)) == (d <= 0), (ka, kb, k, d)
        if abs(d) > 1e-3 * scale:
            n_ours = out[k, OUT_NORMAL:OUT_NORMAL + 3]
            ang = math.acos(min(1.0, float(nrm @ n_ours)))
            if ang >= 1e-3:
                # allowed only when ours is the better normal: the signed distance is
                # -min_n h_{A-B}(n), so the normal with the smaller support value
                # h_{A-B}(n) is the more accurate one.  This happens when coal stops
                # early, and in flat valleys of equally deep directions (a sphere
                # centre near a cylinder's axis) where the normal is ill-conditioned:
                # there ours may be up to ~0.03 rad off with h worse by < 1e-7 * scale.
                pose_a, pose_b = (pa[k], qa[k]), (pb[k], qb[k])
                h_c = O.cso_support(sa[k], pose_a, sb[k], pose_b, nrm[None, :])[0]
                h_o = O.cso_support(sa[k], pose_a, sb[k], pose_b, n_ours[None, :])[0]
                assert h_o <= h_c + 1e-7 * scale, (ka, kb, k, ang, h_c, h_o)
                stats["flat_normals"] = stats.get("flat_normals", 0) + 1
            else:
                stats["max_ang"] = max(stats["max_ang"], ang)
        # witness points: coal-independent check that pb - pa = dist * normal
        dv = out[k, OUT_PB:OUT_PB + 3] - out[k, OUT_PA:OUT_PA + 3]
        assert np.allclose(dv, ours * out[k, OUT_NORMAL:OUT_NORMAL + 3],
                           atol=1e-7 * scale)
    # coal's sphere-cylinder path is wrong for spheres inside the cylinder (see top)
    cap = 0.25 if (ka, kb) == ("sphere", "cylinder") else 0.05
    assert stats["coal_wrong"] <= cap * n, stats
    print(ka, kb, regime, stats)
    return stats


@pytest.mark.parametrize("ka, kb", PAIR_TYPES)
def test_against_coal_random(ka, kb):
    stats = _compare_with_coal(ka, kb, N_PAIRS, 100 + PAIR_TYPES.index((ka, kb)), "mixed")
    # representative: both regimes present in quantity
    assert 0.3 < stats["hits"] / stats["n"] < 0.9, stats


@pytest.mark.parametrize("ka, kb", PAIR_TYPES)
def test_against_coal_near_touching(ka, kb):
    _compare_with_coal(ka, kb, max(200, N_PAIRS // 5),
                       200 + PAIR_TYPES.index((ka, kb)), "near")


# --- hard cases ------------------------------------------------------------------------------
@pytest.mark.parametrize("size", [1e-4, 1.0, 1e4])
@pytest.mark.parametrize("centre", [0.0, 1e5])
def test_scales_and_far_from_origin(size, centre):
    rng = np.random.default_rng(7)
    for ka, kb in PAIR_TYPES:
        sa, pa, qa, sb, pb, qb = O.random_pairs(rng, ka, kb, 20, size=size)
        pa = pa + centre
        pb = pb + centre
        out, st = O.run_batch(sa, pa, qa, sb, pb, qb)
        assert np.all(np.isfinite(out))
        assert np.all(st != ST_FAILED)
        # same geometry at unit size near the origin: distances scale linearly
        s1 = [_rescale(s, 1.0 / size) for s in sa]
        s2 = [_rescale(s, 1.0 / size) for s in sb]
        ref, _ = O.run_batch(s1, (pa - centre) / size, qa, s2, (pb - centre) / size, qb)
        scale = np.array([O.bounding_radius(a) + O.bounding_radius(b)
                          for a, b in zip(s1, s2)])
        # 1e5 m offsets at 1e-4 m sizes lose digits to the pose arithmetic itself
        tol = 1e-6 if centre == 0.0 or size >= 1.0 else 1e-16 * centre / size * 10
        assert np.all(np.abs(out[:, OUT_DIST] / size - ref[:, OUT_DIST]) <= tol * scale)


def _rescale(shape, f):
    s = dict(shape)
    for key in ("radius", "length", "height"):
        if key in s:
            s[key] = s[key] * f
    for key in ("radii", "size", "points"):
        if key in s:
            s[key] = (np.asarray(s[key]) * f).tolist()
    return s


@pytest.mark.parametrize("kb", O.TYPES)
def test_needles_and_plates(kb):
    rng = np.random.default_rng(8)
    needle = {"type": "box", "size": [1e-3, 1e-3, 1.0]}
    plate = {"type": "ellipsoid", "radii": [1.0, 1.0, 1e-3]}
    cyl_disc = {"type": "cylinder", "radius": 1.0, "height": 1e-3}
    for sa in (needle, plate, cyl_disc):
        for _ in range(30):
            sb = O.random_shape(rng, kb, 0.5)
            p = rng.normal(size=3) * 0.5
            q = O.random_quats(rng, 1)[0]
            r = gjk(sa, ID, sb, (p, q))
            assert np.all(np.isfinite(r.normal)) and math.isfinite(r.distance)
            assert r.status != ST_FAILED
            scale = O.bounding_radius(sa) + O.bounding_radius(sb)
            d, _, _, _ = O.coal_signed_distance(O.coal_shape(sa), ID, O.coal_shape(sb),
                                                (p, q))
            if np.isfinite(d) and abs(d - r.distance) > 1e-6 * scale:
                lb, _ = O.signed_distance_oracle(sa, ID, sb, (p, q))
                assert d < lb - 1e-9 * scale and r.distance >= lb - 1e-9 * scale


def test_coincident_centres_all_pairs():
    """Coincident centres, in a random relative orientation and in the same one (then
    bodies of revolution share their axis: rings of equally deep directions)."""
    rng = np.random.default_rng(9)
    for ka, kb in PAIR_TYPES:
        for k in range(6):
            sa = O.random_shape(rng, ka)
            sb = O.random_shape(rng, kb)
            q = O.random_quats(rng, 1)[0] if k % 2 else np.array([0.0, 0.0, 0.0, 1.0])
            r = gjk(sa, ID, sb, ([0.0, 0.0, 0.0], q))
            assert r.status == ST_PENETRATING, (sa, sb, q, r.status)
            assert np.all(np.isfinite(r.normal)) and math.isfinite(r.distance)
            lb, _ = O.signed_distance_oracle(sa, ID, sb, ([0.0, 0.0, 0.0], q))
            scale = O.bounding_radius(sa) + O.bounding_radius(sb)
            assert r.distance >= lb - 1e-9 * scale
            assert r.distance <= lb + 1e-3 * scale   # the oracle is a coarse search


def test_crossing_capsule_axes_flat_core_difference():
    # the two core segments cross: their difference is a flat parallelogram through
    # the origin, so the depth is exactly r_a + r_b along the common perpendicular
    cap = {"type": "capsule", "radius": 0.2, "length": 2.0}
    q = [math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4)]   # axis along -y
    r = gjk(cap, ID, {"type": "capsule", "radius": 0.3, "length": 2.0},
            ([0.0, 0.0, 0.0], q))
    assert r.distance == pytest.approx(-0.5, abs=1e-12)
    assert abs(abs(r.normal[0]) - 1.0) < 1e-12
    assert r.point_b - r.point_a == pytest.approx(r.distance * r.normal, abs=1e-12)
    assert abs(np.linalg.norm(r.point_a) - 0.2) < 1e-12


def test_exact_touching_boxes_and_spheres():
    b = {"type": "box", "size": [1.0, 1.0, 1.0]}
    r = gjk(b, ID, b, pose([1.0, 0.3, 0.2]))
    assert r.status.name == "TOUCHING" and abs(r.distance) < 1e-12
    s = {"type": "sphere", "radius": 0.5}
    r = gjk(s, ID, s, pose([0.6, 0.8, 0.0]))
    assert r.status.name == "TOUCHING"
    r = gjk(s, ID, b, pose([1.0, 0.0, 0.0]))
    assert r.status.name == "TOUCHING"


def test_degenerate_convex_point_and_segment():
    pt = {"type": "convex", "points": [[0.0, 0.0, 0.0]], "margin": 0.2}
    seg = {"type": "convex", "points": [[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]}
    r = gjk(pt, pose([0.1, 0.0, 0.0]), seg, ID)
    assert r.distance == pytest.approx(-0.1, abs=1e-12)
    assert r.normal == pytest.approx([-1, 0, 0], abs=1e-9)
    flat = {"type": "convex", "points": [[1, 1, 0], [1, -1, 0], [-1, 1, 0], [-1, -1, 0]]}
    r = gjk(flat, ID, flat, ID)   # two coincident squares: a flat difference, depth 0
    assert np.all(np.isfinite(r.normal)) and abs(r.distance) < 1e-9
    assert r.status.name == "TOUCHING"
