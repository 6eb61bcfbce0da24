"""The cylinder pair kernels run before GJK (kernels/pairs/cylinder_cylinder.py,
capsule_cylinder.py, ellipsoid_cylinder.py, cylinder_convex.py's ball kernel and their
cylinder_common.py), called directly and through the batch kernel: a certified depth is
global (never deeper than the slow oracle), the crossing's and the cover bound's
certificates hold on every direction, an apart bound is a separating plane (every
kernel run before GJK, box-cylinder and ellipsoid-box included), and hand-placed scenes
match their closed forms."""
import math

import numpy as np
import pytest

import oracles as O
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import (OUT_DIST, OUT_ITERS, OUT_NORMAL, OUT_PA,
                                               OUT_PB, ST_PENETRATING, ST_SEPARATED)
from oracles import ID


def test_cylinder_pair_ball_certified_depth_is_global():
    # Two cylinders whose cores overlap are first tried without GJK or EPA
    # (kernels/pairs/cylinder_cylinder.py): a rim's point nearest the other's axis, or
    # the lowest point under the other's cap, whose ball inside the other is as deep as
    # h_{A-B} along
    # the other's normal there, certifies that h as the depth (within EPA_REL_TOL *
    # scale; it reports that h itself); so does the crossing of the two sides, h along
    # the normal to both axes against a witness's ball or, near a cylinder's end,
    # against cylinder_cylinder._crossing_global's bound.  Checked on random pairs as
    # O.check_certified_shortcut says.  At least 20% of the penetrating pairs are
    # certified (measured here 316 of 750, 42%: these overlaps are deep, up to the
    # centres' coinciding), at least 100 of them by the crossing (measured here: 200;
    # 44 with the witnesses' balls alone), whose normal is
    # square to both axes.
    certified, pen, found = O.check_certified_shortcut(31, ("cylinder", "cylinder"), 60,
                                                      0.0)
    assert pen >= 250
    assert certified >= 0.2 * pen
    crossing = sum(abs(n[2]) < 1e-12 and abs(n @ r_ab[:, 2]) < 1e-12 for n, r_ab in found)
    assert crossing >= 100


def test_crossing_global_certificate_holds_on_every_direction():
    # Where two cylinders' sides cross near an end, neither witness's ball is as deep
    # as h(n) and cylinder_cylinder._crossing_global certifies h(n) instead: a bound on h(w) - h
    # over the plane of the axes (an inner disc from the witnesses' room to the ends,
    # then rings from the concavity of h along rays and the shadow's eight edge
    # normals).  Checked on random crossings (A on the z axis at the origin, B anywhere):
    # wherever it certifies, h_{A-B} over 200,000 random unit directions plus 2,000
    # within 0.05 rad of n is never below h - tol; and it certifies at least 40% of
    # the crossings whose witnesses are both on their segments (measured: 386 of 603),
    # at least 100 of them where neither ball does (measured: 224).
    from mkcollision_ros.kernels.pairs.cylinder_cylinder import _crossing_global
    from mkcollision_ros.kernels.geometry import quat_to_matrix
    rng = np.random.default_rng(83)
    dirs = rng.normal(size=(200_000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    tol = 1e-8
    tried = certified = beyond_ball = 0
    for _ in range(2500):
        ra, rb = rng.uniform(0.05, 1.0, 2)
        la, lb = rng.uniform(0.05, 1.5, 2)
        q = rng.normal(size=4)
        b = quat_to_matrix(q / np.linalg.norm(q))[:, 2]
        t = rng.uniform(-1.0, 1.0, 3) * (ra + rb + la + lb) * rng.uniform(0.1, 1.0)
        sn = math.hypot(b[0], b[1])
        n = np.array([-b[1], b[0], 0.0]) / sn
        if n @ t < 0.0:
            n = -n
        g = t - (n @ t) * n                       # t's part in the axes' plane: s a - u b
        s = (g[2] - b[2] * (g @ b)) / sn ** 2
        u = (b[2] * g[2] - g @ b) / sn ** 2
        h = ra + rb - n @ t
        if not (h > 0.0 and abs(s) <= la and abs(u) <= lb):
            continue
        tried += 1
        if not _crossing_global(ra, la, rb, lb, h, s, u, sn, b[2], tol):
            continue
        certified += 1
        ball = max(min(rb - abs(rb - h), lb - abs(u)), min(ra - abs(ra - h), la - abs(s)))
        beyond_ball += ball < h - tol
        near = n + 0.05 * rng.uniform(-1.0, 1.0, (2000, 3))
        w = np.vstack([dirs, near / np.linalg.norm(near, axis=1, keepdims=True)])
        hw = (ra * np.sqrt(np.maximum(0.0, 1.0 - w[:, 2] ** 2)) + la * np.abs(w[:, 2])
              + rb * np.sqrt(np.maximum(0.0, 1.0 - (w @ b) ** 2)) + lb * np.abs(w @ b)
              - w @ t)
        assert hw.min() >= h - tol
    assert certified >= 0.4 * tried
    assert beyond_ball >= 100


def test_cover_bound_holds_on_every_direction():
    # Where a cap or the side cuts the ball of a point p of one cylinder inside the
    # other short, cylinder_common._cover may still bound the depth by p's gap delta to the
    # other's side or cap: every translate by |t| < delta meets the other cylinder at
    # p or at a point of three segments from p (its side line, its cap's diameter,
    # the diagonal).  Checked on random rim points p of a cylinder Y inside X (on the
    # z axis at the origin), both kinds: wherever it returns delta > 0, h_{X-Y} over
    # 200,000 random unit directions is never below delta, and the ball about p is
    # shorter than delta (the cover, not the ball, gave it).  At least 150 points of
    # each kind are covered (measured: 206 under a side, 215 under a cap).
    from mkcollision_ros.kernels.pairs.cylinder_common import _cover
    from mkcollision_ros.kernels.geometry import quat_to_matrix
    rng = np.random.default_rng(89)
    dirs = rng.normal(size=(200_000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    covered = {True: 0, False: 0}
    for _ in range(6000):
        big_r, big_h, rho, eta = rng.uniform(0.05, 1.0, 4)
        q = rng.normal(size=4)
        rot = quat_to_matrix(q / np.linalg.norm(q))
        u, v, k = rot[:, 0], rot[:, 1], rot[:, 2]
        c = rng.uniform(-1.0, 1.0, 3) * np.array([big_r, big_r, big_h])
        th = rng.uniform(0.0, 2.0 * np.pi)
        tau = rng.choice([-1.0, 1.0])
        p = c + tau * eta * k + rho * (np.cos(th) * u + np.sin(th) * v)
        d1 = -2.0 * tau * eta * k
        d2 = 2.0 * (c + tau * eta * k - p)
        ball = min(big_r - math.hypot(p[0], p[1]), big_h - abs(p[2]))
        for radial, s in ((True, 0.0), (False, 1.0), (False, -1.0)):
            delta = _cover(radial, s, *p, big_r, big_h, *d1, *d2, *(d1 + d2))
            if not delta > 0.0:
                continue
            covered[radial] += 1
            assert ball < delta
            hw = (big_r * np.sqrt(np.maximum(0.0, 1.0 - dirs[:, 2] ** 2))
                  + big_h * np.abs(dirs[:, 2])
                  + rho * np.sqrt(np.maximum(0.0, 1.0 - (dirs @ k) ** 2))
                  + eta * np.abs(dirs @ k) - dirs @ c)
            assert hw.min() >= delta - 1e-12
    assert covered[True] >= 150 and covered[False] >= 150


@pytest.mark.parametrize("order", ["capsule-cylinder", "cylinder-capsule",
                                   "ellipsoid-cylinder", "cylinder-ellipsoid",
                                   "convex-cylinder", "cylinder-convex"])
def test_cylinder_shortcut_certified_depth_is_global(order):
    # A capsule, an ellipsoid or a convex hull whose core overlaps a cylinder is first
    # tried without GJK or EPA (collide_capsule_cylinder, collide_ellipsoid_cylinder,
    # collide_cylinder_convex_ball): the core's point nearest the cylinder's axis against the
    # side, or its lowest point under a cap against that cap, whose ball inside the
    # cylinder is as deep as h_{A-B} along the normal there.  Checked on random pairs in
    # both orders as O.check_certified_shortcut says; the depth reported is the
    # witness's gap to the cylinder's side or cap, within EPA_REL_TOL * scale of h.  At
    # least a fifth of the penetrating pairs are certified, a tenth for hulls (measured
    # here, in the orders listed: 210 of 723, 204 of 715, 188 of 734, 179 of 738, 157
    # of 699, 157 of 703).
    from mkcollision_ros.kernels.constants import EPA_REL_TOL
    seed = {"capsule-cylinder": 37, "cylinder-capsule": 41, "ellipsoid-cylinder": 43,
            "cylinder-ellipsoid": 47, "convex-cylinder": 59, "cylinder-convex": 61}[order]
    certified, pen, _ = O.check_certified_shortcut(seed, order.split("-"), 40, EPA_REL_TOL)
    assert pen >= 250
    assert certified >= (0.1 if "convex" in order else 0.2) * pen


@pytest.mark.parametrize("order", ["cylinder-cylinder", "capsule-cylinder",
                                   "cylinder-capsule", "ellipsoid-cylinder",
                                   "cylinder-ellipsoid", "convex-cylinder",
                                   "cylinder-convex", "box-cylinder", "cylinder-box",
                                   "ellipsoid-box", "box-ellipsoid"])
def test_cylinder_shortcut_apart_bound_is_a_separating_plane(order):
    # Where the cylinder pair kernels find the cores apart (one past a cap's plane, beyond the
    # side's tangent plane (for two cylinders, either's, facing the other's centre),
    # or, for two cylinders, across the plane of their sides' crossing, or a hull's
    # shadow missing the side's disc; for a box, box_cylinder's line of centres or one of its
    # candidate directions) they return minus that plane's gap, with its normal and a
    # point of each core; in contacts mode (cutoff 0) gjk_epa_ws then ends the pair with
    # that bound, without GJK, when it clears the touching band.  On random pairs, each
    # pair the shortcut so decides: the contacts-mode row is SEPARATED as the exact one (cutoff
    # inf), in one iteration, at the plane's gap less the radii, which is positive and
    # at most the exact distance; the plane normal to its normal separates the shapes
    # by that much (h_{A-B}(n) by the numpy oracle); and both witnesses lie in their
    # shapes (the slow oracle's inside test).  At least 5% of the pairs are so decided
    # (measured here, in the orders listed: 116, 124, 116, 109, 87, 168, 155, 151 and 142
    # of 600).  An ellipsoid and a box (collide_ellipsoid_box: a box face's plane) likewise, in both
    # orders.
    from mkcollision_ros.kernels.constants import METHOD_NAMES, TOUCH_TOL
    from mkcollision_ros.kernels.geometry import inflation
    from mkcollision_ros.kernels.narrowphase import collide_batch
    kinds = order.split("-")
    shortcut = O.pre_kernel(kinds)
    rng = np.random.default_rng(["cylinder-cylinder", "capsule-cylinder", "cylinder-capsule",
                                 "ellipsoid-cylinder", "cylinder-ellipsoid", "convex-cylinder",
                                 "cylinder-convex", "box-cylinder", "cylinder-box",
                                 "ellipsoid-box", "box-ellipsoid"].index(order) + 53)
    sa, pa, qa, sb, pb, qb = O.random_pairs(rng, *kinds, 600, offset=(0.0, 1.0))
    exact, st = O.run_batch(sa, pa, qa, sb, pb, qb)
    table, pairs, pos, quat, n = O.paired_table(sa, pa, qa, sb, pb, qb)
    cut = np.zeros_like(exact)
    st_cut = np.zeros_like(st)
    collide_batch(table.codes, table.params, table.vrange, table.verts, pairs, pos, quat,
                  np.int64(METHOD_NAMES.index("gjk_epa")), 0.0, cut, st_cut)
    decided = 0
    for k in range(n):
        shapes, scale, r_ab, t_ab = O.table_pair(table, pos, quat, k, n)
        res = np.zeros(10)
        h_core = shortcut(shapes[0], shapes[1], table.verts, r_ab, t_ab, scale, res)
        grown = sum(inflation(table.codes[i], table.params[i]) for i in (k, k + n))
        if not (h_core < 0.0 and -h_core - grown > TOUCH_TOL * scale):
            continue
        decided += 1
        d, nrm = cut[k, OUT_DIST], cut[k, OUT_NORMAL:OUT_NORMAL + 3]
        assert st[k] == st_cut[k] == ST_SEPARATED
        assert cut[k, OUT_ITERS] == 1
        assert abs(d - (-h_core - grown)) <= 1e-12 * scale
        assert 0.0 < d <= exact[k, OUT_DIST] + 1e-12 * scale
        pose_a, pose_b = (pos[k], quat[k]), (pos[k + n], quat[k + n])
        h = O.cso_support(sa[k], pose_a, sb[k], pose_b, nrm[None])[0]
        assert h <= -d + 1e-9 * scale
        assert O.inside_value(sa[k], pose_a, cut[k, OUT_PA:OUT_PA + 3]) <= 1e-9 * scale
        assert O.inside_value(sb[k], pose_b, cut[k, OUT_PB:OUT_PB + 3]) <= 1e-9 * scale
    assert decided >= 0.05 * n


CYL = {"type": "cylinder", "radius": 0.5, "height": 0.6}
ACROSS_X = [0.0, math.sqrt(0.5), 0.0, math.sqrt(0.5)]   # a body's axis along x
OCTAHEDRON = {"type": "convex", "points": [[0.1, 0.0, 0.0], [-0.1, 0.0, 0.0], [0.0, 0.1, 0.0],
                                           [0.0, -0.1, 0.0], [0.0, 0.0, 0.1], [0.0, 0.0, -0.1]]}


@pytest.mark.parametrize("method", ["gjk_epa", "auto"])
@pytest.mark.parametrize("scene, other, pose_other, swap, depth, normal, point_a", [
    # a capsule lying across the top, both ends past the rim: the segment's point over
    # the axis stands in for its ends (whose balls the side cuts short)
    ("capsule across the top", {"type": "capsule", "radius": 0.05, "length": 2.0},
     ([0.1, 0.2, 0.28], ACROSS_X), False, 0.07, [0.0, 0.0, 1.0], [0.0, 0.2, 0.3]),
    # a capsule upright against the side, its segment 0.02 inside
    ("capsule against the side", {"type": "capsule", "radius": 0.05, "length": 0.2},
     ([0.48, 0.0, 0.05], [0.0, 0.0, 0.0, 1.0]), False, 0.07, [1.0, 0.0, 0.0],
     [0.5, 0.0, 0.05]),
    # a capsule upright, pressing down into the top, the capsule as A
    ("capsule into the top",
     {"type": "capsule", "radius": 0.05, "length": 0.2, "margin": 0.01},
     ([0.1, 0.0, 0.39], [0.0, 0.0, 0.0, 1.0]), True, 0.07, [0.0, 0.0, -1.0],
     [0.1, 0.0, 0.23]),
    # an ellipsoid against the side (its core, shrunk by the rolling radius 0.05, 0.05
    # deep): Newton's method on the side normal's angle starts at its answer
    ("ellipsoid against the side", {"type": "ellipsoid", "radii": [0.2, 0.1, 0.15]},
     ([0.6, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]), False, 0.1, [1.0, 0.0, 0.0],
     [0.5, 0.0, 0.0]),
    # an ellipsoid tilted about z against the side, off the axis's plane: Newton's
    # method turns the side normal to the ellipsoid's deepest point
    ("tilted ellipsoid against the side", {"type": "ellipsoid", "radii": [0.2, 0.1, 0.15]},
     ([0.6 * math.cos(0.3), 0.6 * math.sin(0.3), 0.0],
      [0.0, 0.0, math.sin(0.35), math.cos(0.35)]), False, None, None, None),
    # an ellipsoid pressing down into the top, the ellipsoid as A
    ("ellipsoid into the top",
     {"type": "ellipsoid", "radii": [0.2, 0.1, 0.15], "margin": 0.01},
     ([0.1, 0.1, 0.38], [0.0, 0.0, 0.0, 1.0]), True, 0.08, [0.0, 0.0, -1.0],
     [0.1, 0.1, 0.22]),
    # a thin cylinder along x crossing the side, 0.1 deep: the crossing of the sides
    # (no cap or rim is certified here; GJK and EPA would take three steps)
    ("cylinder crossing the side", {"type": "cylinder", "radius": 0.2, "height": 2.0},
     ([0.0, 0.6, 0.0], ACROSS_X), False, 0.1, [0.0, 1.0, 0.0], [0.0, 0.5, 0.0]),
    # the same, its axis tilted 30 degrees up, off the centre, with a margin
    ("tilted cylinder crossing the side",
     {"type": "cylinder", "radius": 0.15, "height": 2.0, "margin": 0.05},
     ([0.1, 0.6, 0.05], [0.0, 0.5, 0.0, math.sqrt(0.75)]), False, None, None, None),
    # an octahedron's vertex pressed 0.05 into the side (the hull's point nearest the
    # axis: GJK on its shadow), and one 0.02 into the top, the hull as A
    ("hull's vertex against the side", OCTAHEDRON, ([0.55, 0.0, 0.05], [0.0, 0.0, 0.0, 1.0]),
     False, 0.05, [1.0, 0.0, 0.0], [0.5, 0.0, 0.05]),
    ("hull's vertex into the top", OCTAHEDRON, ([0.1, 0.1, 0.38], [0.0, 0.0, 0.0, 1.0]),
     True, 0.02, [0.0, 0.0, -1.0], [0.1, 0.1, 0.28]),
])
def test_cylinder_shortcut_closed_form_scenes(scene, other, pose_other, swap, depth, normal,
                                              point_a, method):
    # Closed-form depths of a capsule, an ellipsoid or a hull pressed into a cylinder's
    # side or cap, or a cylinder crossing its side, taken by the cylinder pair kernels
    # (kernels/pairs/; one iteration: no GJK or EPA step), with the exact normal and
    # witnesses; the same with A and B
    # swapped (normal flipped).  The tilted ellipsoid and cylinder are checked without
    # a closed form: there the shortcut's depth is h(n) by the numpy oracle and no
    # deeper than the slow oracle's.
    a, pose_a, b, pose_b = CYL, ID, other, pose_other
    if swap:
        a, pose_a, b, pose_b = b, pose_b, a, pose_a
    for flip in (False, True):
        if flip:
            a, pose_a, b, pose_b = b, pose_b, a, pose_a
        r = collide(a, pose_a, b, pose_b, method=method)
        assert r.status == ST_PENETRATING, scene
        assert r.iterations == 1, scene
        assert np.allclose(r.point_b - r.point_a, -r.depth * r.normal, atol=1e-12), scene
        if depth is None:
            h = O.cso_support(a, pose_a, b, pose_b, r.normal[None])[0]
            assert abs(h - r.depth) <= 1e-12, scene
            sd, _ = O.signed_distance_oracle(a, pose_a, b, pose_b, n_start=2000, n_keep=6,
                                             n_iter=200)
            assert r.depth <= -sd + 1e-9, scene
            assert r.depth >= -sd - 1e-6, scene
            continue
        sign = -1.0 if flip else 1.0
        assert r.depth == pytest.approx(depth, abs=1e-12), scene
        assert np.allclose(r.normal, sign * np.array(normal), atol=1e-12), scene
        assert np.allclose(r.point_b if flip else r.point_a, point_a, atol=1e-12), scene
