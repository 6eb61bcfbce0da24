"""An ellipsoid and a box before GJK (kernels/pairs/ellipsoid_box.py): the depth at a
face certified by the rolling ball is global, the cores' exact distance over a face, an
edge or a vertex matches the batch kernel in both modes and the numpy support, and
hand-placed scenes match their closed forms."""
import numpy as np
import pytest

import oracles as O
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import (OUT_DIST, OUT_ITERS, OUT_NORMAL, OUT_PA,
                                               OUT_PB, ST_PENETRATING, ST_SEPARATED)
from oracles import ID, pose


@pytest.mark.parametrize("order", ["ellipsoid-box", "box-ellipsoid"])
def test_ellipsoid_box_shortcut_certified_depth_is_global(order):
    # An ellipsoid whose core overlaps a box is first tried without GJK or EPA
    # (kernels/pairs/ellipsoid_box.py): the core's lowest point under the face of least h, whose
    # rolling ball lies as deep in the box as that h.  Checked on random pairs in both
    # orders as O.check_certified_shortcut says (the depth reported is h itself).  At
    # least 15% of the penetrating pairs are certified (measured here: 156 of 707 and
    # 167 of 709; these overlaps are deeper than the benchmark's).
    from mkcollision_ros.kernels.constants import EPA_REL_TOL
    seed = {"ellipsoid-box": 67, "box-ellipsoid": 71}[order]
    certified, pen, _ = O.check_certified_shortcut(seed, order.split("-"), 40, EPA_REL_TOL)
    assert pen >= 250
    assert certified >= 0.15 * pen


@pytest.mark.parametrize("order", ["ellipsoid-box", "box-ellipsoid"])
def test_ellipsoid_box_shortcut_exact_distance_of_cores_apart(order):
    # Where the ellipsoid's core lies apart from the box over a face (its lowest point's
    # foot in the face), an edge or a vertex (ellipsoid_box._beyond_rim: Newton's method on
    # the edge's normal angle, or on a vertex's nearest point on the ellipsoid),
    # collide_ellipsoid_box reports the cores' distance as exact, and the batch kernel takes it
    # whether the shapes (grown by the rolling radius) then touch or not.  On random
    # pairs, each pair so decided: the exact row (cutoff inf) holds that distance less
    # the radii, in one iteration, and so does the contacts row (cutoff 0) where they
    # touch (apart, it may hold a face plane's gap below it); h_{A-B} along the normal
    # is minus it (numpy oracle: a lower bound on the distance) and the witnesses lie
    # on the surfaces that far apart along it (an upper bound); on the first 40 it is
    # no less than the slow oracle's signed distance (whose direction search stops
    # short on some, by up to 5e-7 * scale).  At least a quarter of the pairs are so
    # decided, at least 50 of them penetrating (measured here: 226 and 248 of 600, 89
    # and 80 penetrating).
    from mkcollision_ros.kernels.pairs.ellipsoid_box import collide_ellipsoid_box
    from mkcollision_ros.kernels.constants import METHOD_NAMES, PRE_EXACT, TOUCH_TOL
    from mkcollision_ros.kernels.geometry import inflation
    from mkcollision_ros.kernels.narrowphase import collide_batch
    kinds = order.split("-")
    rng = np.random.default_rng({"ellipsoid-box": 73, "box-ellipsoid": 79}[order])
    sa, pa, qa, sb, pb, qb = O.random_pairs(rng, *kinds, 600, offset=(0.0, 1.0))
    table, pairs, pos, quat, n = O.paired_table(sa, pa, qa, sb, pb, qb)
    rows = {}
    for cutoff in (np.inf, 0.0):
        out = np.zeros((n, 12))
        st = np.zeros(n, np.int64)
        collide_batch(table.codes, table.params, table.vrange, table.verts, pairs, pos, quat,
                      np.int64(METHOD_NAMES.index("gjk_epa")), cutoff, out, st)
        rows[cutoff] = (out, st)
    decided = penetrating = 0
    for k in range(n):
        shapes, scale, r_ab, t_ab = O.table_pair(table, pos, quat, k, n)
        res = np.zeros(10)
        got = collide_ellipsoid_box(shapes[0], shapes[1], r_ab, t_ab, scale, np.inf, res)
        d = res[0]
        if not (got == PRE_EXACT and d <= 0.0):
            continue
        decided += 1
        grown = sum(inflation(table.codes[i], table.params[i]) for i in (k, k + n))
        dist = -d - grown
        penetrating += dist < 0.0
        for cutoff, (out, st) in rows.items():
            if cutoff == 0.0 and dist > TOUCH_TOL * scale:
                # contacts mode may stop at a face plane's gap, a bound below it
                assert st[k] == ST_SEPARATED
                assert 0.0 < out[k, OUT_DIST] <= dist + 1e-12 * scale
            else:
                assert abs(out[k, OUT_DIST] - dist) <= 1e-12 * scale
            assert out[k, OUT_ITERS] == 1
        out = rows[np.inf][0]
        nrm = out[k, OUT_NORMAL:OUT_NORMAL + 3]
        pose_a, pose_b = (pos[k], quat[k]), (pos[k + n], quat[k + n])
        h = O.cso_support(sa[k], pose_a, sb[k], pose_b, nrm[None])[0]
        assert abs(h + dist) <= 1e-9 * scale
        assert abs(O.surface_gap(sa[k], pose_a, out[k, OUT_PA:OUT_PA + 3], nrm)) <= 1e-9 * scale
        assert abs(O.surface_gap(sb[k], pose_b, out[k, OUT_PB:OUT_PB + 3], -nrm)) <= 1e-9 * scale
        # the witnesses dist apart along the normal: with -h(n) = dist, that is exact
        gap = out[k, OUT_PB:OUT_PB + 3] - out[k, OUT_PA:OUT_PA + 3]
        assert np.linalg.norm(gap - dist * nrm) <= 1e-12 * scale
        if decided <= 40:
            sd, _ = O.signed_distance_oracle(sa[k], pose_a, sb[k], pose_b, n_start=2000,
                                             n_keep=6, n_iter=200)
            assert dist >= sd - 1e-8 * scale
    assert decided >= 0.25 * n
    assert penetrating >= 50


BOX_UNIT = {"type": "box", "size": [1.0, 1.0, 1.0]}


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("scene, ellipsoid, z, depth", [
    # radii 0.4, 0.3, 0.2, 0.05 into the top face: the core (rolling radius 0.1) is
    # 0.05 deep too, and its lowest point's rolling ball (radius 0.1) certifies it
    ("shallow into the top", {"type": "ellipsoid", "radii": [0.4, 0.3, 0.2]}, 0.65, 0.05),
    # a wide, flat one 0.15 into the top, with a margin of 0.01 (depth 0.16): the ball
    # is cut to the core's depth and still certifies it
    ("deep into the top", {"type": "ellipsoid", "radii": [0.6, 0.6, 0.2], "margin": 0.01},
     0.55, 0.16),
    # radii 0.3, 0.3, 0.1, 0.02 into the top: the core (shrunk by 0.1^2 / 0.3) stays
    # above the face's plane, its distance to the box is exact, and so is the depth
    ("cores apart, shapes 0.02 deep", {"type": "ellipsoid", "radii": [0.3, 0.3, 0.1]},
     0.58, 0.02),
])
def test_ellipsoid_box_shortcut_closed_form_scenes(scene, ellipsoid, z, depth, swap):
    # An ellipsoid over the middle of a unit box's top face, pressed into it: the depth,
    # the normal along z and the witnesses (the ellipsoid's lowest point and its foot
    # on the face) in closed form, from collide_ellipsoid_box in one iteration (no GJK or EPA step),
    # by both methods and with A and B swapped (normal flipped).
    for method in ("gjk_epa", "auto"):
        a, pose_a, b, pose_b = BOX_UNIT, ID, ellipsoid, pose([0.0, 0.0, z])
        if swap:
            a, pose_a, b, pose_b = b, pose_b, a, pose_a
        r = collide(a, pose_a, b, pose_b, method=method)
        assert r.status == ST_PENETRATING
        assert r.iterations == 1
        assert r.distance == pytest.approx(-depth, abs=1e-12)
        up = np.array([0.0, 0.0, -1.0 if swap else 1.0])
        assert r.normal == pytest.approx(up, abs=1e-12)
        low = [0.0, 0.0, z - ellipsoid["radii"][2] - ellipsoid.get("margin", 0.0)]
        top = [0.0, 0.0, 0.5]
        assert (r.point_b if swap else r.point_a) == pytest.approx(top, abs=1e-12)
        assert (r.point_a if swap else r.point_b) == pytest.approx(low, abs=1e-12)
