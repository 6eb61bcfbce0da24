"""The face and crease polish steps of EPA (kernels/polish_faces.py): a face normal's
minimum is exact (box, cylinder cap, hull face); an ellipsoid on a hull's ridge lands on
its crease, and the deep cases match exact depths; the face basin proved around a face
normal holds against any shape; two cylinders' crossing face and the crossing basin
(_cylinders_crossing, _crossing_test) against their general forms and the slow oracle."""
import math

import numpy as np
import pytest

import oracles as O
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import ST_PENETRATING
from oracles import ID, pose


def antiprism(radius=1.2, half=0.5):
    """A convex hull whose top face is the triangle of circumradius ``radius`` at
    z = half (the bottom one turned by 60 degrees at -half): every face a triangle."""
    pts = [[radius * math.cos(k * math.pi / 3.0), radius * math.sin(k * math.pi / 3.0),
            half if k % 2 == 0 else -half] for k in range(6)]
    return {"type": "convex", "points": pts}


@pytest.mark.parametrize("kind, cores", [("box", "overlap"), ("box", "apart"),
                                         ("cylinder", "overlap"), ("cylinder", "apart"),
                                         ("convex", "apart")])
def test_face_normal_minimum_is_exact(kind, cores):
    # An ellipsoid pressed into a box's top face, a cylinder's top cap or a convex
    # hull's top face (an antiprism's triangle), its lowest point over the face's
    # interior: the deepest direction is the face normal, and the depth is the face's
    # height less the ellipsoid's lowest point, in closed form.
    # EPA alone stops within its tolerance (depths within 1e-8 * scale); the face test
    # (polish_faces._face_polish) lands on the normal itself, with the witness on the face
    # exactly on its plane: all pairs within EPA's bounds, and nearly all exact (49 or
    # 50 of 50; the others EPA closes before the face test's cap check passes).  A
    # hull's faces are tested by GJK only (polish_faces._hull_polish, on cores apart), so
    # the hull is pressed in shallower than the rolling radius only.
    # Shallower than the ellipsoid's rolling radius its core stays apart from the face's
    # shape and GJK solves the pair: its own face test (in _gjk) takes the normal within
    # a few supports and needs no basin check (h is convex there), so every pair is
    # exact and the median pair takes few iterations (6 on the box, 5 on the cylinder,
    # 8 on the hull; GJK converging on the curved core by itself takes medians of 10, 11
    # and 10).
    rng = np.random.default_rng(16)
    iters = []
    face = ({"type": "box", "size": [2.0, 1.6, 1.0]} if kind == "box"
            else {"type": "cylinder", "radius": 0.9, "height": 1.0} if kind == "cylinder"
            else antiprism())
    exact = 0
    for _ in range(50):
        radii = rng.uniform(0.15, 0.35, 3)
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        r = O.quat_matrix(q)
        sigma = r @ np.diag(radii ** 2) @ r.T
        low = math.sqrt(sigma[2, 2])            # centre height above its lowest point
        # deeper than the ellipsoid's rolling radius, so that its core overlaps the
        # face's shape and EPA runs (shallower pairs are GJK's, on the cores apart)
        roll = radii.min() ** 2 / radii.max()
        if cores == "overlap":
            depth = roll + rng.uniform(0.02, 0.15)
        else:
            depth = roll * rng.uniform(0.2, 0.9)
        xy = rng.uniform(-0.25, 0.25, 2)
        # the lowest point of the ellipsoid of centre c is c - sigma e_z / low
        c = np.array([xy[0], xy[1], 0.5 - depth]) + sigma[:, 2] / low
        pose_e = (c.tolist(), q.tolist())
        r_ = collide(face, ID, {"type": "ellipsoid", "radii": radii.tolist()}, pose_e,
                     method="gjk_epa")
        assert r_.status == ST_PENETRATING
        scale = (O.bounding_radius(face) if kind == "convex"
                 else math.hypot(*face.get("size", [0, 0, 0])) / 2) + radii.max()
        err_d = abs(r_.depth - depth)
        err_n = np.linalg.norm(r_.normal - [0.0, 0.0, 1.0])     # ~ the angle
        assert err_d <= 1e-8 * scale and err_n <= 1e-3
        if err_d <= 1e-12 * scale and err_n <= 1e-9:
            exact += 1
            assert abs(r_.point_a[2] - 0.5) <= 1e-12            # on the face's plane
            assert abs(r_.point_b[2] - (0.5 - depth)) <= 1e-12  # the lowest point
        iters.append(r_.iterations)
    assert exact >= (45 if cores == "overlap" else 50)
    if cores == "apart":
        assert np.median(iters) <= (9 if kind == "convex" else 6)


SLOPE = math.radians(35.0)
WEDGE = {"type": "convex", "points": [[x, y, 0.5 - abs(y) * math.tan(SLOPE)]
                                     for x in (-1.0, 1.0) for y in (-1.0, 0.0, 1.0)]}


def _ellipsoid_pressed_down(rng, radii_range, press_range, x_spread):
    """A random ellipsoid whose lowest point lies at about (x, 0, 0.5), |x| <=
    x_spread (y within +-0.02), moved down by press_range (a uniform range, in units
    of its rolling radius): returns the shape, its centre, its quaternion and sigma =
    R diag(radii^2) R^T (the ellipsoid is {x : (x - c)^T sigma^-1 (x - c) <= 1})."""
    radii = rng.uniform(radii_range[0], radii_range[1], 3)
    q = O.random_quats(rng, 1)[0]
    r = O.quat_matrix(q)
    sigma = r @ np.diag(radii ** 2) @ r.T
    roll = radii.min() ** 2 / radii.max()
    depth = roll * rng.uniform(press_range[0], press_range[1])
    c = np.array([rng.uniform(-x_spread, x_spread), rng.uniform(-0.02, 0.02), 0.5 - depth])
    c += sigma[:, 2] / math.sqrt(sigma[2, 2])
    return {"type": "ellipsoid", "radii": radii.tolist()}, c, q, sigma


@pytest.mark.parametrize("hull_is_a", [True, False])
def test_hull_edge_minimum_is_on_the_crease(hull_is_a):
    # An ellipsoid pressed onto the ridge of a wedge (a convex hull whose top edge runs
    # along x at z = 0.5, its two faces sloping down 35 degrees to either side).  Where
    # the deepest direction lies on the ridge's crease (the arc of directions normal to
    # x strictly between the two faces' normals), the crease search
    # (polish_faces._hull_polish) lands on it: the normal is normal to the ridge to
    # round-off, the depth is h(n) of the pair, and the hull's witness lies on the
    # ridge (within 1e-7 * scale: the search stops short of its minimum by a step
    # below POLISH_STEP_DONE, and the witnesses share the residual).  The ellipsoid
    # is pressed in less than its rolling radius, so the cores stay apart and GJK
    # solves the pair (deeper, EPA: test_deep_hull_ridge_and_apex_against_exact_depths);
    # GJK alone ends within its tolerance, its normal off the crease (without the
    # search no pair's depth is h(n) to 1e-12 * scale with the normal on the crease;
    # with it 50 of 50).
    # A pair whose minimum lies on a side face's normal instead counts as well (the
    # face test, _hull_face_test, finds it exactly).  Depths are checked against the
    # slow oracle's direction search (oracles.signed_distance_oracle), whose pattern
    # search closes slowly along a crease: both are upper bounds of the true depth, so
    # ours must not exceed its.
    rng = np.random.default_rng(19)
    on_crease = on_face = 0
    for _ in range(50):
        # shallower than the rolling radius: the cores stay apart and GJK solves the
        # pair
        ell, c, q, _ = _ellipsoid_pressed_down(rng, (0.15, 0.35), (0.2, 0.9), 0.3)
        scale = O.bounding_radius(WEDGE) + max(ell["radii"])
        res, n, h = O.pressed_in(WEDGE, ell, pose(c, q), hull_is_a, scale)
        assert abs(h + res.distance) <= 1e-8 * scale           # GJK's bound
        if abs(n[0]) <= 1e-12 and abs(abs(n[1]) - math.sin(SLOPE)) <= 1e-12:
            on_face += 1                                # a side face's normal
            assert abs(h + res.distance) <= 1e-12 * scale
        elif abs(n[0]) <= 1e-12 and abs(n[1]) < math.sin(SLOPE) - 1e-6:
            on_crease += 1
            assert abs(h + res.distance) <= 1e-12 * scale      # depth == h(normal)
            ridge = np.asarray(res.point_a if hull_is_a else res.point_b)
            assert abs(ridge[1]) <= 1e-7 * scale and abs(ridge[2] - 0.5) <= 1e-7 * scale
            assert abs(ridge[0]) <= 1.0
    assert on_crease + on_face >= 48 and on_crease >= 40


@pytest.mark.parametrize("hull_is_a", [True, False])
def test_deep_hull_ridge_and_apex_against_exact_depths(hull_is_a):
    # The deep counterparts of test_hull_edge_minimum_is_on_the_crease: an ellipsoid
    # pressed deeper than its rolling radius (the cores overlap: EPA solves the pair)
    # onto the ridge of a wedge and onto the apex (0, 0, 0.5) of a pyramid, against
    # exact depths (O.inner_distance), where the slow oracle's direction search only
    # bounds them.  A point v of the hull inside the ellipsoid E bounds the depth from
    # below by its distance to E's boundary (h_{E-hull}(u) >= h_E(u) - u . v), and
    # that bound is the depth when the hull's support along minus E's normal u at the
    # nearest point is v (then h(u) equals it):
    # * apex: v the apex, its nearest point on E's boundary (3-D);
    # * ridge: the ridge's point (y, z) = (0, 0.5) against the ellipsoid's shadow on
    #   the yz-plane (h_E on directions normal to the ridge is the shadow's support
    #   function), the ridge's two ends tied as the support.
    # Where the feature is the support there (70 of the 120 pairs), the
    # depth must equal the bound, elsewhere be at least it.  EPA searches neither
    # feature (polish_pairs._hull_side: searching them takes fewer steps but more time), so
    # its own tolerance holds: EPA_REL_TOL = 1e-8 * scale.
    rng = np.random.default_rng(25)
    pyramid = {"type": "convex", "points": [[0.0, 0.0, 0.5]] + [
        [x, y, -0.5] for x in (-1.0, 1.0) for y in (-1.0, 1.0)]}
    counts = {"ridge": 0, "apex": 0, "other": 0}
    for k in range(120):
        hull = WEDGE if k % 2 == 0 else pyramid
        ell, c, q, sigma = _ellipsoid_pressed_down(rng, (0.2, 0.4), (1.05, 1.3),
                                                   0.3 if hull is WEDGE else 0.02)
        scale = O.bounding_radius(hull) + max(ell["radii"])
        res, _, _ = O.pressed_in(hull, ell, pose(c, q), hull_is_a, scale)
        pts = np.asarray(hull["points"])
        if hull is WEDGE:
            dist, u2 = O.inner_distance(c[1:], sigma[1:, 1:], [0.0, 0.5])
            u = np.array([0.0, u2[0], u2[1]])
            low_pts = pts @ u
            # the ridge's two ends (points 1 and 4, tied: u is normal to x) lowest
            exact = (low_pts[1] <= low_pts.min() + 1e-12
                     and np.sort(low_pts)[2] > low_pts[1] + 1e-9)
        else:
            dist, u = O.inner_distance(c, sigma, [0.0, 0.0, 0.5])
            low_pts = pts @ u
            exact = np.sort(low_pts)[1] > low_pts[0] + 1e-9         # the apex alone
        assert -res.distance >= dist - 1e-8 * scale
        if exact:
            counts["ridge" if hull is WEDGE else "apex"] += 1
            assert abs(-res.distance - dist) <= 1e-8 * scale
        else:
            counts["other"] += 1
    assert counts["ridge"] >= 40 and counts["apex"] >= 20, counts     # 45 and 25


@pytest.mark.parametrize("face_kind", ["cylinder", "box"])
@pytest.mark.parametrize("other", ["point", "cylinder", "cone", "convex"])
def test_face_basin_is_proved_against_any_shape(face_kind, other):
    # The face test (polish_faces._face_test) finds the normal n of a face of A (a
    # cylinder's top cap, a box's top face) to be a local minimum of h = h_{A-B} when
    # B's support point along -n projects into the face, and claims a cap around n
    # (_face_basin: 2 atan(rin / h(n)), rin the radius of the largest disc about the
    # foot inside the face) in which no direction is deeper: EPA keeps the minimum on
    # that claim, whatever B is.  Checked here with the numpy oracle's h at directions
    # inside the cap (half of them in its outer tenth), B at random poses and depths
    # below the face.  Against a single point the bound is exact along the tilt toward the
    # nearest side of the face, so there a direction 1.2 times farther out must be
    # deeper: the claimed cap is the whole basin, not a fraction of it.
    from mkcollision_ros.kernels import gjk_epa_workspace as W
    from mkcollision_ros.kernels import polish_faces as F
    from mkcollision_ros.kernels.constants import EPA_FACE_CAP_MAX
    from mkcollision_ros.shapes import build_table
    rng = np.random.default_rng(22)
    face = ({"type": "box", "size": [2.0, 1.6, 1.0]} if face_kind == "box"
            else {"type": "cylinder", "radius": 0.9, "height": 1.0})
    top = 0.5
    ws = W.make_gjk_workspace()
    n = np.array([0.0, 0.0, 1.0])
    found, wide, tight = 0, 0, 0
    for _ in range(150):
        if other == "point":
            shape = {"type": "convex", "points": [[0.0, 0.0, 0.0]]}
        elif other == "convex":
            shape = {"type": "convex", "points": (rng.normal(size=(12, 3)) * 0.3).tolist()}
        else:
            shape = {"type": other, "radius": rng.uniform(0.2, 0.5),
                     "height": rng.uniform(0.3, 0.8)}
        q = O.random_quats(rng, 1)[0]
        rb = O.quat_matrix(q)
        low = rb @ O.support_np(shape, rb.T @ -n)           # B's point along -n, B at 0
        foot = rng.uniform(-0.45, 0.45, 2)
        depth = rng.uniform(0.02, 0.4)
        if other == "point":
            # nearer the rim and deeper: caps below 1.2 rad for the tightness check
            a = rng.uniform(0.0, 2.0 * math.pi)
            foot = rng.uniform(0.5, 0.85) * np.array([math.cos(a), math.sin(a)])
            foot = foot if face_kind == "cylinder" else foot * [1.0, 0.8]
            depth = rng.uniform(0.1, 0.9)
        pos_b = np.array([foot[0], foot[1], top - depth]) - low
        table = build_table([face, shape])
        sa = (table.codes[0], table.params[0], table.vrange[0, 0], table.vrange[0, 1])
        sb = (table.codes[1], table.params[1], table.vrange[1, 0], table.vrange[1, 1])
        scale = float(table.params[0, 7] + table.params[1, 7])
        args = (sa, sb, table.verts, np.ascontiguousarray(rb), pos_b, scale, ws)
        if F._face_test(*args, 0, 2, 1.0) <= 0:
            continue
        fs = ws[0]
        assert np.allclose(fs[W._T3 + 15], n, atol=1e-12)
        h0 = float(fs[W._T3 + 15] @ fs[W._T3 + 16])
        assert abs(h0 - depth) <= 1e-12 * scale
        cap = float(fs[W._T3 + 3, 0])
        assert 0.0 < cap <= EPA_FACE_CAP_MAX
        found += 1
        wide += cap >= 0.3
        t = cap * np.concatenate([rng.uniform(0.0, 1.0, 200), rng.uniform(0.9, 1.0, 200)])
        phi = rng.uniform(0.0, 2.0 * math.pi, 400)
        u = np.stack([np.sin(t) * np.cos(phi), np.sin(t) * np.sin(phi), np.cos(t)], 1)
        pb = (pos_b.tolist(), q.tolist())
        h = O.cso_support(face, ID, shape, pb, u)
        assert h.min() >= h0 - 1e-12 * scale
        if other == "point" and face_kind == "cylinder" and cap < 1.2:
            # tilt toward the nearest point of the rim, 1.2 times the cap
            e = np.array([foot[0], foot[1], 0.0]) / np.linalg.norm(foot)
            v = math.cos(1.2 * cap) * n + math.sin(1.2 * cap) * e
            assert O.cso_support(face, ID, shape, pb, v[None])[0] < h0 - 1e-9 * scale
            tight += 1
    assert found >= 40 and wide >= 10
    if other == "point" and face_kind == "cylinder":
        assert tight >= 20


def test_cylinders_crossing_is_the_crossing_test_at_the_lower_normal():
    # EPA tests two cylinders' crossing face once, at its start, along the normal n of
    # both axes with n . t >= 0 (polish_faces._cylinders_crossing): h(+-n) = r_a + r_b -+
    # n . t, and the foot of the origin lies at the same segment parameters on both
    # faces, so where the lower face fails the other fails too.  Checked against
    # _crossing_test along both signs (its general form, from a direction d), on random
    # pairs of cylinders: the same minimum, witnesses and cap where it is taken; the
    # other sign never a lower minimum; refused exactly where _crossing_test refuses
    # both, on pairs not separated along n (EPA's: the origin inside A - B).
    from mkcollision_ros.kernels import gjk_epa_workspace as W
    from mkcollision_ros.kernels import polish_faces as F
    from mkcollision_ros.shapes import build_table
    rng = np.random.default_rng(26)
    ws = W.make_gjk_workspace()
    fs = ws[0]
    taken, refused = 0, 0
    for trial in range(400):
        ra, rb = rng.uniform(0.1, 0.6, 2)
        ha, hb = rng.uniform(0.2, 2.0, 2)
        table = build_table([{"type": "cylinder", "radius": ra, "height": ha},
                             {"type": "cylinder", "radius": rb, "height": hb}])
        sa = (table.codes[0], table.params[0], table.vrange[0, 0], table.vrange[0, 1])
        sb = (table.codes[1], table.params[1], table.vrange[1, 0], table.vrange[1, 1])
        scale = float(table.params[0, 7] + table.params[1, 7])
        q = rng.normal(size=4)
        rot = np.ascontiguousarray(O.quat_matrix(q / np.linalg.norm(q)))
        t_ab = rng.uniform(-0.6, 0.6, 3)
        got = F._cylinders_crossing(sa, sb, rot, t_ab, scale, fs)
        mine = fs[W._T3 + 15:W._T3 + 19].copy(), float(fs[W._T3 + 3, 0])
        n = np.cross([0.0, 0.0, 1.0], rot[:, 2])
        n /= np.linalg.norm(n)
        if n @ t_ab < 0.0:
            n = -n
        ks, hs = [], []
        for sgn in (1.0, -1.0):
            d = sgn * n
            k = F._crossing_test(sa, sb, table.verts, rot, t_ab, scale, ws, 0,
                                 d[0], d[1], d[2])
            ks.append(k)
            hs.append(float(fs[W._T3 + 15] @ fs[W._T3 + 16]) if k == 1 else np.inf)
            if sgn > 0 and k == 1:
                theirs = fs[W._T3 + 15:W._T3 + 19].copy(), float(fs[W._T3 + 3, 0])
        if ra + rb - n @ t_ab <= 0.0:
            # n separates them: EPA never runs on such a pair (h > 0 everywhere there)
            assert not got
            continue
        if not got:
            assert ks[0] != 1 and ks[1] != 1
            refused += 1
            continue
        taken += 1
        assert ks[0] == 1 and hs[1] >= hs[0]
        assert np.allclose(mine[0], theirs[0], rtol=0.0, atol=1e-12 * scale)
        assert abs(mine[1] - theirs[1]) <= 1e-12
        # a - b = h n, a on A's side, b on B's
        nn, w, a, b = mine[0]
        assert np.allclose(a - b, w, rtol=0.0, atol=1e-12 * scale)
        assert abs(math.hypot(a[0], a[1]) - ra) <= 1e-12 * scale and abs(a[2]) <= ha / 2
        bl = rot.T @ (b - t_ab)
        assert abs(math.hypot(bl[0], bl[1]) - rb) <= 1e-12 * scale and abs(bl[2]) <= hb / 2
    assert taken >= 60 and refused >= 60


@pytest.mark.parametrize("other", ["cylinder", "convex", "segment"])
def test_crossing_basin_is_proved(other):
    # Where a cylinder's side (A, along z) crosses B's segment (a cylinder's side, or a
    # convex hull's ridge) at a direction n normal to both, the two supports make a
    # parallelogram face of A - B; polish_faces._crossing_test finds n a local minimum of
    # h = h_{A-B} when the pair of closest points of the two segments lies inside both,
    # and claims a cap around n (_face_basin) in which no direction is deeper.  Checked
    # here with the numpy oracle's h at directions inside the cap (half of them in its
    # outer tenth), for random crossings at random depths, EPA's direction d a little off
    # n; a foot beyond A's segment's end must not be taken for a minimum.  Against a
    # bare segment (a two-point hull) normal to A's axis, the foot nearer A's segment's
    # end than B's, the bound is exact along the tilt toward A's end, so there a
    # direction 1.2 times the cap out must be deeper: the cap is the whole basin.
    from mkcollision_ros.kernels import gjk_epa_workspace as W
    from mkcollision_ros.kernels import polish_faces as F
    from mkcollision_ros.kernels.constants import EPA_FACE_CAP_MAX
    from mkcollision_ros.shapes import build_table
    rng = np.random.default_rng(23)
    cyl = {"type": "cylinder", "radius": 0.5, "height": 1.6}
    ra, ha = 0.5, 0.8
    ws = W.make_gjk_workspace()
    z = np.array([0.0, 0.0, 1.0])
    found, wide, refused, tight = 0, 0, 0, 0
    for trial in range(120):
        phi = rng.uniform(0.0, 2.0 * math.pi)
        n = np.array([math.cos(phi), math.sin(phi), 0.0])
        psi = math.pi / 2.0 if other == "segment" else rng.uniform(0.3, math.pi - 0.3)
        b = math.cos(psi) * z + math.sin(psi) * np.cross(z, n)
        depth = rng.uniform(0.02, 0.5)
        t0 = rng.uniform(-0.3, 0.3)
        outside = trial % 4 == 3
        s0 = rng.uniform(ha + 0.01, ha + 0.2) if outside else rng.uniform(-0.7, 0.7)
        if other == "segment" and not outside:
            t0, s0 = rng.uniform(-0.1, 0.1), rng.uniform(0.55, 0.75)
        pa = ra * n + s0 * z                      # A's point of the crossing
        if other == "cylinder":
            rb = rng.uniform(0.2, 0.5)
            shape = {"type": "cylinder", "radius": rb, "height": 0.8}
            axis = np.cross(z, b)
            half = 0.5 * math.acos(float(np.clip(b @ z, -1.0, 1.0)))
            q = np.append(math.sin(half) * axis / np.linalg.norm(axis), math.cos(half))
            rot = O.quat_matrix(q)
            # B's side along -n: its centre less rb n, t0 along b from its middle
            pos_b = pa - depth * n + rb * n - t0 * b
        elif other == "segment":
            shape = {"type": "convex", "points": [(-0.4 * b).tolist(), (0.4 * b).tolist()]}
            q, rot = np.array([0.0, 0.0, 0.0, 1.0]), np.eye(3)
            pos_b = pa - depth * n - t0 * b
        else:
            # a wedge whose ridge (0.8 long, along b) is its support along -n
            w = np.cross(-n, b)
            shape = {"type": "convex", "points": [
                (sx * 0.4 * b + sy * 0.3 * w + 0.35 * n * (sy != 0)).tolist()
                for sx in (-1.0, 1.0) for sy in (-1.0, 0.0, 1.0)]}
            q, rot = np.array([0.0, 0.0, 0.0, 1.0]), np.eye(3)
            pos_b = pa - depth * n - t0 * b
        table = build_table([cyl, shape])
        sa = (table.codes[0], table.params[0], table.vrange[0, 0], table.vrange[0, 1])
        sb = (table.codes[1], table.params[1], table.vrange[1, 0], table.vrange[1, 1])
        scale = float(table.params[0, 7] + table.params[1, 7])
        if other != "cylinder":
            # EPA's best face: its support points on B, two of them the ridge's ends
            pts = np.asarray(shape["points"]) + pos_b
            ws[2][W._IF] = [0, 1, 2]
            ws[0][W._VB:W._VB + 3] = pts[[1, 4, 0]] if other == "convex" else pts[[0, 1, 0]]
        d = n + rng.normal(size=3) * 0.01
        d /= np.linalg.norm(d)
        k = F._crossing_test(sa, sb, table.verts, np.ascontiguousarray(rot), pos_b,
                             scale, ws, 0, d[0], d[1], d[2])
        if outside:
            assert k == -1
            refused += 1
            continue
        assert k == 1
        fs = ws[0]
        assert np.allclose(fs[W._T3 + 15], n, atol=1e-12)
        h0 = float(fs[W._T3 + 15] @ fs[W._T3 + 16])
        assert abs(h0 - depth) <= 1e-12 * scale
        assert np.allclose(fs[W._T3 + 17], pa, atol=1e-12 * scale)
        cap = float(fs[W._T3 + 3, 0])
        assert 0.0 < cap <= EPA_FACE_CAP_MAX
        found += 1
        wide += cap >= 0.3
        e1 = np.cross(n, z)
        t = cap * np.concatenate([rng.uniform(0.0, 1.0, 200), rng.uniform(0.9, 1.0, 200)])
        ang = rng.uniform(0.0, 2.0 * math.pi, 400)
        u = (np.cos(t)[:, None] * n + (np.sin(t) * np.cos(ang))[:, None] * e1
             + (np.sin(t) * np.sin(ang))[:, None] * z)
        pb = (pos_b.tolist(), q.tolist())
        h = O.cso_support(cyl, ID, shape, pb, u)
        assert h.min() >= h0 - 1e-12 * scale
        if other == "segment" and cap < 1.2:
            v = math.cos(1.2 * cap) * n + math.sin(1.2 * cap) * z
            assert O.cso_support(cyl, ID, shape, pb, v[None])[0] < h0 - 1e-9 * scale
            tight += 1
    assert found >= 60 and wide >= 10 and refused >= 20
    if other == "segment":
        assert tight >= 40
