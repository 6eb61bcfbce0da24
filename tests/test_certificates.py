"""The certificates that end EPA at a polished minimum (kernels/certificates.py): the
ball certificate and an ellipsoid's rolling ball are lower bounds on the depth (the
rolling ball lies in the core and touches it), and a box vertex's minimum against an
ellipsoid (_vertex_cap) is the depth."""
import math

import numpy as np
import pytest

import oracles as O
from mkcollision_ros.kernels.constants import OUT_DIST, OUT_NORMAL, OUT_PA, OUT_PB, ST_PENETRATING


@pytest.mark.parametrize("kind", ["cylinder", "box"])
def test_ball_certificate_is_a_lower_bound_on_the_depth(kind):
    # certificates._ball_certified ends EPA at a polished minimum h(n) when a ball of radius
    # >= h(n) - tol about one shape's witness fits inside the other's core
    # (_core_inradius): A - B then holds that ball about the origin, so no direction
    # is shallower.  Checked here: the ball fits (its radius is at most h_A(u) - u . p
    # along 4,000 random directions u and the shape's face and side normals, the
    # numpy oracle's support function), it is the largest that fits (that minimum
    # equals it), a point outside the core gets -inf, and the certificate accepts
    # h(n) up to the radius + tol and refuses it just beyond.
    from mkcollision_ros.kernels import certificates as K
    from mkcollision_ros.kernels import gjk_epa_workspace as W
    from mkcollision_ros.shapes import build_table
    rng = np.random.default_rng(24)
    shape = ({"type": "cylinder", "radius": 0.4, "height": 1.5} if kind == "cylinder"
             else {"type": "box", "size": [0.6, 1.0, 1.8]})
    table = build_table([shape, {"type": "sphere", "radius": 0.1}])
    sa = (table.codes[0], table.params[0], table.vrange[0, 0], table.vrange[0, 1])
    sb = (table.codes[1], table.params[1], table.vrange[1, 0], table.vrange[1, 1])
    ws = W.make_gjk_workspace()
    fs = ws[0]
    u = rng.normal(size=(4000, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    tol = 1e-8
    inside = outside = 0
    for trial in range(60):
        p = rng.uniform(-1.0, 1.0, 3) * (0.45, 0.55, 0.95)
        rot = np.ascontiguousarray(O.quat_matrix(O.random_quats(rng, 1)[0]))
        t_ab = rng.normal(size=3)
        # B's point p of its own frame, in A's: the test converts it back
        x = rot @ p + t_ab
        rho = K._core_inradius(1, sb, sa, rot, t_ab, x[0], x[1], x[2])
        if kind == "cylinder":
            k = np.array([p[0], p[1], 0.0]) / max(math.hypot(p[0], p[1]), 1e-300)
            normals = np.array([k, (0, 0, 1.0), (0, 0, -1.0)])
        else:
            normals = np.vstack([np.eye(3), -np.eye(3)])
        gaps = [O.support_value(shape, v) - float(v @ p) for v in np.vstack([u, normals])]
        if min(gaps) < 0.0:
            assert rho == -np.inf
            outside += 1
            continue
        inside += 1
        assert rho <= min(gaps) + 1e-12
        assert rho >= min(gaps) - 1e-12
        # the certificate on a stored minimum (n, w = a - b = h n, a, b): A's witness a
        # is the point inside B, the shape
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        for h, expect in ((rho + 0.99 * tol, True), (rho + 1.01 * tol, False)):
            fs[W._T3 + 15] = n
            fs[W._T3 + 16] = h * n
            fs[W._T3 + 17] = x
            fs[W._T3 + 18] = x - h * n
            bound = K._pending_bound(sb, sa, rot, t_ab, fs, tol)
            if expect:
                assert bound == -np.inf
            else:     # h(n) - tol, to rounding (the kernel's dot may fuse multiply-adds)
                assert abs(bound - (float(n @ fs[W._T3 + 16]) - tol)) <= 1e-15
    assert inside >= 15 and outside >= 15


def test_rolling_ball_lies_in_the_ellipsoid_core_and_touches_it():
    # certificates._rolling_ball: at an ellipsoid core's point x with outward normal n, the
    # ball of radius rho about q = x - rho n, rho = c^2 / |D n| - P_ROLL.  Checked on
    # random ellipsoids (axis ratios up to 20) and normals, on either side of the pair:
    # the ball lies in the core (q . u + rho <= h_core(u) along 200,000 random u and the
    # core's normal at x, the numpy oracle's support less P_ROLL), it touches the core
    # at x (equality along n), its radius is exactly c - P_ROLL at the ends of the
    # shortest axis and 0 at those of the longest (P_ROLL itself rolls there), and a
    # ball 1% larger about x - 1.01 rho n sticks out along one of the 200,000
    # directions wherever rho is at least a tenth of c - P_ROLL (it is the largest ball
    # touching at x; measured here: all 73 such cases; smaller balls stick out by less
    # than the directions resolve).
    from mkcollision_ros.kernels import certificates as K
    from mkcollision_ros.kernels.constants import P_ROLL
    from mkcollision_ros.kernels.geometry import support_core_xyz
    from mkcollision_ros.shapes import build_table
    rng = np.random.default_rng(36)
    u = rng.normal(size=(200_000, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    larger_out = trials = 0
    for trial in range(200):
        radii = rng.uniform(0.05, 1.0, 3)
        radii[rng.integers(3)] *= rng.choice([1.0, 0.05])
        shape = {"type": "ellipsoid", "radii": radii.tolist()}
        other = {"type": "box", "size": [0.3, 0.4, 0.5]}
        side = trial % 2
        table = build_table([shape, other] if side == 0 else [other, shape])
        sa, sb = ((table.codes[i], table.params[i], table.vrange[i, 0], table.vrange[i, 1])
                  for i in range(2))
        prm = table.params[side]
        rot = np.ascontiguousarray(O.quat_matrix(O.random_quats(rng, 1)[0]))
        t_ab = rng.normal(size=3)
        m = rng.normal(size=3)                  # the core's normal in its own frame
        if trial % 10 == 0:
            m = np.eye(3)[int(np.argmin(radii)) if trial % 20 == 0 else int(np.argmax(radii))]
        m /= np.linalg.norm(m)
        xl = np.array(support_core_xyz(table.codes[side], prm, table.verts, 0, 0, *m))
        # in A's frame (the shape is B on side 1)
        x, n = (xl, m) if side == 0 else (rot @ xl + t_ab, rot @ m)
        qx, qy, qz, rho = K._rolling_ball(side, sa, sb, rot, *x, *n)
        q = np.array([qx, qy, qz])
        ql = q if side == 0 else rot.T @ (q - t_ab)
        dirs = np.vstack([u, m])
        h_core = O.support_values(shape, dirs) - prm[P_ROLL]
        room = h_core - dirs @ ql - rho
        assert room.min() >= -1e-12
        assert abs(room[-1]) <= 1e-12
        if trial % 10 == 0:
            expect = radii.min() - prm[P_ROLL] if trial % 20 == 0 else 0.0
            assert abs(rho - expect) <= 1e-9
            continue
        if rho < 0.1 * (radii.min() - prm[P_ROLL]):
            continue                    # too small a ball to see 1% of it stick out
        trials += 1
        big = 1.01 * rho
        larger_out += (h_core - dirs @ (xl - big * m) - big).min() < 0.0
    assert larger_out == trials >= 60


@pytest.mark.parametrize("kind", ["box", "cylinder", "ellipsoid", "convex", "capsule"])
def test_rolling_ball_certificate_is_a_lower_bound_on_the_depth(kind):
    # certificates._ball_certified with an ellipsoid: A' - B' lies in A - B for the
    # ellipsoid's rolling ball (_rolling_ball) as A' and the other shape's witness
    # point, its own ball, or (box, cylinder) its whole core as B', so a direction
    # whose h is at most such a pair's depth plus tol is the depth.  Checked on the
    # deep pairs of 300 random ellipsoid-kind pairs: the certificate is asked about the
    # reported minimum (core witnesses, hmin = core depth - tol); where it accepts, h of
    # A - B along 20,000 random directions and 2,000 within 0.05 rad of the normal is
    # never below the depth - tol (a ball sticking out of the core, or a wrong bound,
    # would accept shallower directions), and it accepts at least a quarter of the
    # deep pairs, at least 10 of them where the witnesses' balls alone (_core_inradius)
    # do not (measured: box 135 of 269, 84 beyond those balls; cylinder 148 of 277, 82;
    # ellipsoid 204 of 275; convex 100 of 245; capsule 207 of 258, all beyond).
    from mkcollision_ros.kernels import certificates as K
    from mkcollision_ros.kernels.geometry import inflation, quat_to_matrix, relative_pose
    from mkcollision_ros.shapes import build_table
    rng = np.random.default_rng(361)
    sa, pa, qa, sb, pb, qb = O.random_pairs(rng, "ellipsoid", kind, 300, offset=(0.0, 0.8))
    out, st = O.run_batch(sa, pa, qa, sb, pb, qb)
    dirs = rng.normal(size=(20_000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    deep = accepted = beyond_points = 0
    for k in np.flatnonzero(st == ST_PENETRATING):
        table = build_table([sa[k], sb[k]])
        scale = table.params[0, 7] + table.params[1, 7]
        depth = -out[k, OUT_DIST]
        if not depth > 1e-3 * scale:
            continue
        deep += 1
        shapes = [(table.codes[i], table.params[i], table.vrange[i, 0], table.vrange[i, 1])
                  for i in range(2)]
        ra, rb = (inflation(table.codes[i], table.params[i]) for i in range(2))
        qa_k, qb_k = (q / np.linalg.norm(q) for q in (qa[k], qb[k]))
        ma, mb = quat_to_matrix(qa_k), quat_to_matrix(qb_k)
        r_ab, t_ab = relative_pose(pa[k], ma, pb[k], mb)
        nw = out[k, OUT_NORMAL:OUT_NORMAL + 3]
        n = ma.T @ nw                                       # A's frame
        a = ma.T @ (out[k, OUT_PA:OUT_PA + 3] - pa[k]) - ra * n      # core witnesses
        b = ma.T @ (out[k, OUT_PB:OUT_PB + 3] - pa[k]) + rb * n
        tol = 1e-9 * scale
        hmin = depth - ra - rb - tol
        if not K._ball_certified(shapes[0], shapes[1], r_ab, t_ab, hmin, *n, *a, *b):
            continue
        accepted += 1
        beyond_points += max(K._core_inradius(0, *shapes, r_ab, t_ab, *b),
                             K._core_inradius(1, *shapes, r_ab, t_ab, *a)) < hmin
        near = nw + 0.05 * rng.uniform(-1.0, 1.0, (2000, 3))
        w = np.vstack([dirs, near / np.linalg.norm(near, axis=1, keepdims=True)])
        h = O.cso_support(sa[k], (pa[k], qa_k), sb[k], (pb[k], qb_k), w)
        assert h.min() >= depth - 2 * tol
    assert deep >= 150
    assert accepted >= 0.25 * deep
    assert beyond_points >= 10


def test_box_vertex_minimum_against_an_ellipsoid_is_the_depth():
    # EPA's Newton minimum in a box vertex's region against an ellipsoid
    # (certificates._vertex_cap): kept under the plane test in the cap no box crease
    # crosses, where the box's support is that one vertex.  Checked on the deep pairs
    # of 2,000 random ellipsoid-box pairs (box as A or B) whose normal lies in a
    # vertex's region (more than 0.05 rad from every crease of the box): the depth is
    # never deeper than the slow oracle's minimum of h over directions by more than
    # 1e-8 * scale (a minimum kept while a deeper one lies elsewhere would be), and at
    # least 25 such pairs are found (measured: 54 of 1,766 deep pairs).
    rng = np.random.default_rng(362)
    found = 0
    for order in (("ellipsoid", "box"), ("box", "ellipsoid")):
        sa, pa, qa, sb, pb, qb = O.random_pairs(rng, *order, 1000, offset=(0.0, 0.8))
        out, st = O.run_batch(sa, pa, qa, sb, pb, qb)
        for k in np.flatnonzero(st == ST_PENETRATING):
            scale = O.bounding_radius(sa[k]) + O.bounding_radius(sb[k])
            depth = -out[k, OUT_DIST]
            if not depth > 1e-3 * scale:
                continue
            qbox = qa[k] if order[0] == "box" else qb[k]
            axes = O.quat_matrix(qbox / np.linalg.norm(qbox))
            n = out[k, OUT_NORMAL:OUT_NORMAL + 3]
            if np.abs(axes.T @ n).min() <= math.sin(0.05):
                continue
            found += 1
            pose_a = (pa[k], qa[k] / np.linalg.norm(qa[k]))
            pose_b = (pb[k], qb[k] / np.linalg.norm(qb[k]))
            sd, _ = O.signed_distance_oracle(sa[k], pose_a, sb[k], pose_b, n_start=2000,
                                             n_keep=6, n_iter=200)
            assert depth <= -sd + 1e-8 * scale
    assert found >= 25
