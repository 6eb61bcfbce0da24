"""Closed-form pair kernels (kernels/analytic.py) against hand-derived values, coal (peer
oracle, whose sphere/box/capsule/half-space pairs are themselves closed forms) and the
sign-convention invariants.  Seeded; no timings."""

import math

import numpy as np
import pytest

import oracles as O
from mkcollision_ros import rotations
from mkcollision_ros.kernels import constants as C
from mkcollision_ros.kernels.analytic import collide_analytic
from mkcollision_ros.kernels.geometry import support_full
from mkcollision_ros.shapes import point_count, shape_row

VERTS0 = np.zeros((0, 3))


def tup(shape, voff=0):
    code, prm, v = shape_row(shape)
    return (np.int64(code), prm, np.int64(voff), np.int64(point_count(code, prm, v))), v


def sdf(shape, p):
    """Signed distance (m) of the body-frame point p to the shape (exact)."""
    t = shape["type"]
    m = shape.get("margin", 0.0)
    if t == "sphere":
        return np.linalg.norm(p) - shape["radius"] - m
    if t == "box":
        h = 0.5 * np.asarray(shape["size"])
        q = np.abs(p) - h
        return np.linalg.norm(np.maximum(q, 0.0)) + min(q.max(), 0.0) - m
    if t == "capsule":
        hl = 0.5 * shape["length"]
        z = min(hl, max(-hl, p[2]))
        return np.linalg.norm(p - np.array([0, 0, z])) - shape["radius"] - m
    if t == "plane":
        n = np.asarray(shape["normal"], float)
        return n @ p - shape["offset"]
    raise ValueError(t)


def run(sa_d, sb_d, r, t):
    sa, _ = tup(sa_d)
    sb, _ = tup(sb_d)
    out = np.full(C.OUT_SIZE, np.nan)
    st = collide_analytic(sa, sb, VERTS0, r, t, out)
    return st, out


def rand_shape(rng, kind, margin_p=0.3):
    if kind == "sphere":
        s = {"type": "sphere", "radius": rng.uniform(0.1, 1.0)}
    elif kind == "box":
        s = {"type": "box", "size": list(rng.uniform(0.1, 2.0, 3))}
    elif kind == "capsule":
        s = {"type": "capsule", "radius": rng.uniform(0.1, 1.0),
             "length": rng.uniform(0.0, 2.0)}
    elif kind == "ellipsoid":
        s = {"type": "ellipsoid", "radii": list(rng.uniform(0.1, 1.5, 3))}
    elif kind == "cylinder":
        s = {"type": "cylinder", "radius": rng.uniform(0.1, 1.0), "height": rng.uniform(0.1, 2)}
    elif kind == "cone":
        s = {"type": "cone", "radius": rng.uniform(0.1, 1.0), "height": rng.uniform(0.1, 2)}
    else:
        raise ValueError(kind)
    if rng.random() < margin_p:
        s["margin"] = rng.uniform(0.0, 0.3)
    return s


def contact_offset(sa, sb, r, u):
    """h_A(u) + h_B(-u): beyond this offset along the unit u the pair is apart."""
    pa = np.empty(3)
    pb = np.empty(3)
    support_full(sa[0], sa[1], VERTS0, sa[2], sa[3], u, pa)
    support_full(sb[0], sb[1], VERTS0, sb[2], sb[3], -(r.T @ u), pb)
    return pa @ u + pb @ (r.T @ u) * -1.0


def check_invariants(sa_d, sb_d, r, t, st, out, scale):
    d = out[C.OUT_DIST]
    n = out[C.OUT_NORMAL:C.OUT_NORMAL + 3]
    pa = out[C.OUT_PA:C.OUT_PA + 3]
    pb = out[C.OUT_PB:C.OUT_PB + 3]
    assert np.all(np.isfinite(out))
    assert out[C.OUT_METHOD] == C.M_ANALYTIC
    assert abs(np.linalg.norm(n) - 1.0) < 1e-12
    np.testing.assert_allclose(pb - pa, d * n, atol=1e-12 * scale)
    # witness points on the surfaces (B's point taken into B's frame)
    assert abs(sdf(sa_d, pa)) < 1e-9 * scale
    assert abs(sdf(sb_d, r.T @ (pb - t))) < 1e-9 * scale
    # moving B by -distance along the normal brings the pair to touching
    st2, out2 = run(sa_d, sb_d, r, t - d * n)
    assert abs(out2[C.OUT_DIST]) < 1e-9 * scale
    st3, _ = run(sa_d, sb_d, r, t - d * n + 1e-6 * scale * n)
    assert st3 == C.ST_SEPARATED
    # swapping A and B flips the normal and swaps the points
    st_s, out_s = run(sb_d, sa_d, r.T, -r.T @ t)
    assert st_s == st
    assert abs(out_s[C.OUT_DIST] - d) < 1e-9 * scale
    np.testing.assert_allclose(r @ out_s[C.OUT_NORMAL:C.OUT_NORMAL + 3], -n, atol=1e-7)


def test_sphere_sphere_closed_form():
    st, out = run({"type": "sphere", "radius": 1.0},
                  {"type": "sphere", "radius": 0.5, "margin": 0.25}, np.eye(3),
                  np.array([2.0, 0.0, 0.0]))
    assert st == C.ST_SEPARATED
    assert out[C.OUT_DIST] == pytest.approx(0.25, abs=1e-15)
    np.testing.assert_allclose(out[1:4], [1, 0, 0])
    np.testing.assert_allclose(out[4:7], [1, 0, 0])
    np.testing.assert_allclose(out[7:10], [1.25, 0, 0])


def test_sphere_sphere_coincident_centres_is_finite():
    st, out = run({"type": "sphere", "radius": 1.0}, {"type": "sphere", "radius": 2.0},
                  np.eye(3), np.zeros(3))
    assert st == C.ST_PENETRATING
    assert out[C.OUT_DIST] == pytest.approx(-3.0)
    assert np.all(np.isfinite(out))


def test_sphere_centre_inside_box_uses_nearest_face():
    # box 2 x 4 x 6 (half 1, 2, 3) with margin 0.1; sphere r = 0.5 at (0.7, 0.2, -0.5)
    # in the box frame: nearest face +x at gap 0.3, depth = 0.3 + 0.5 + 0.1
    box = {"type": "box", "size": [2.0, 4.0, 6.0], "margin": 0.1}
    sph = {"type": "sphere", "radius": 0.5}
    t = -np.array([0.7, 0.2, -0.5])   # box origin seen from the sphere (r = I)
    st, out = run(sph, box, np.eye(3), t)
    assert st == C.ST_PENETRATING
    assert out[C.OUT_DIST] == pytest.approx(-0.9, abs=1e-14)
    # B must move along -x (its +x face is nearest to the sphere centre)
    np.testing.assert_allclose(out[1:4], [-1, 0, 0], atol=1e-15)
    check_invariants(sph, box, np.eye(3), t, st, out, 1.0)


def test_capsule_capsule_parallel_and_crossing():
    cap = {"type": "capsule", "radius": 0.2, "length": 2.0}
    # parallel, overlapping along z, 0.5 apart in x: distance 0.1 exactly
    st, out = run(cap, cap, np.eye(3), np.array([0.5, 0.0, 0.7]))
    assert st == C.ST_SEPARATED
    assert out[C.OUT_DIST] == pytest.approx(0.1, abs=1e-14)
    np.testing.assert_allclose(out[1:4], [1, 0, 0], atol=1e-14)
    # witness in the middle of the overlap (z in [-0.3, 1]), not jumping to an end
    assert out[C.OUT_PA + 2] == pytest.approx(0.35)
    # exactly collinear axes, end caps overlapping by 0.1
    st, out = run(cap, cap, np.eye(3), np.array([0.0, 0.0, 2.3]))
    assert st == C.ST_PENETRATING
    assert out[C.OUT_DIST] == pytest.approx(-0.1, abs=1e-14)
    # crossing axes (B rotated 90 deg about x, centres coincide): depth r_a + r_b
    rx = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    st, out = run(cap, cap, rx, np.zeros(3))
    assert st == C.ST_PENETRATING
    assert out[C.OUT_DIST] == pytest.approx(-0.4, abs=1e-14)
    assert abs(out[C.OUT_NORMAL + 0]) == pytest.approx(1.0)


def test_unsupported_pairs_do_not_run():
    plane = {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}
    out = np.full(C.OUT_SIZE, 7.0)
    sa, _ = tup(plane)
    assert collide_analytic(sa, sa, VERTS0, np.eye(3), np.zeros(3), out) == C.ST_NOT_RUN
    sb, _ = tup({"type": "box", "size": [1, 1, 1]})
    assert collide_analytic(sb, sb, VERTS0, np.eye(3), np.zeros(3), out) == C.ST_NOT_RUN
    se, _ = tup({"type": "ellipsoid", "radii": [1, 2, 3]})
    assert collide_analytic(se, sb, VERTS0, np.eye(3), np.zeros(3), out) == C.ST_NOT_RUN
    assert np.all(out == 7.0)


PAIRS = [("sphere", "sphere"), ("sphere", "box"), ("sphere", "capsule"),
         ("capsule", "capsule"), ("box", "sphere"), ("capsule", "sphere"),
         ("box", "capsule"), ("capsule", "box")]


@pytest.mark.parametrize("ka,kb", PAIRS)
def test_random_pairs_against_coal_and_invariants(ka, kb):
    rng = np.random.default_rng(PAIRS.index((ka, kb)) + 11)
    hits = 0
    n = 150
    for _ in range(n):
        sa_d = rand_shape(rng, ka)
        sb_d = rand_shape(rng, kb)
        sa, _ = tup(sa_d)
        sb, _ = tup(sb_d)
        scale = sa[1][7] + sb[1][7]
        r = O.random_rotation(rng)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        t = u * rng.uniform(0.5, 1.5) * contact_offset(sa, sb, r, u)
        st, out = run(sa_d, sb_d, r, t)
        cd = O.coal_dist(sa_d, sb_d, r, t)
        assert out[C.OUT_DIST] == pytest.approx(cd, abs=1e-8 * scale), (sa_d, sb_d, r, t)
        hits += st != C.ST_SEPARATED
        check_invariants(sa_d, sb_d, r, t, st, out, scale)
    assert 0.3 * n <= hits <= 0.7 * n


@pytest.mark.parametrize("kind", ["sphere", "box", "capsule", "ellipsoid", "cylinder",
                                  "cone", "convex"])
def test_plane_against_every_shape(kind):
    rng = np.random.default_rng(["sphere", "box", "capsule", "ellipsoid", "cylinder",
                                 "cone", "convex"].index(kind) + 101)
    n = 120
    hits = 0
    for _ in range(n):
        nrm = rng.normal(size=3)
        nrm /= np.linalg.norm(nrm)
        plane = {"type": "plane", "normal": list(nrm), "offset": float(rng.uniform(-1, 1))}
        if kind == "convex":
            pts = rng.normal(size=(12, 3))
            shape = {"type": "convex", "points": pts.tolist()}
            if rng.random() < 0.3:
                shape["margin"] = rng.uniform(0, 0.2)
        else:
            shape = rand_shape(rng, kind)
        sa, verts = tup(shape)
        r = O.random_rotation(rng)
        t = rng.normal(size=3) * 1.5
        # choose the offset so the signed distance is uniform in +-0.5 * A's radius
        x = np.empty(3)
        support_full(sa[0], sa[1], verts, sa[2], sa[3], -(r @ nrm), x)
        plane["offset"] = float(nrm @ (r.T @ (x - t)) - rng.uniform(-0.5, 0.5) * sa[1][7])
        sb, _ = tup(plane)
        out = np.full(C.OUT_SIZE, np.nan)
        st = collide_analytic(sa, sb, verts, r, t, out)
        scale = sa[1][7]
        # oracle: min over A of (n_b . x_b - d), exact by the support function
        n_a = r @ nrm
        if kind == "convex":
            x_b = (verts[:sa[3]] - t) @ r    # rows: r^T (v - t), the points only
            ref = (x_b @ nrm).min() - shape.get("margin", 0.0) - plane["offset"]
        else:
            ref = O.coal_dist(shape, plane, r, t)
        assert out[C.OUT_DIST] == pytest.approx(ref, abs=1e-9 * max(scale, 1.0))
        d = out[C.OUT_DIST]
        nv = out[1:4]
        np.testing.assert_allclose(nv, -n_a, atol=1e-14)
        np.testing.assert_allclose(out[7:10] - out[4:7], d * nv, atol=1e-12 * scale)
        # pb on the plane
        assert abs(sdf(plane, r.T @ (out[7:10] - t))) < 1e-12 * max(scale, 1.0)
        hits += st != C.ST_SEPARATED
        # move B (the plane) by depth along the normal: touching; a bit more: apart
        out2 = np.empty(C.OUT_SIZE)
        collide_analytic(sa, sb, verts, r, t - d * nv, out2)
        assert abs(out2[C.OUT_DIST]) < 1e-12 * max(scale, 1.0) + 1e-14
        st3 = collide_analytic(sa, sb, verts, r, t - d * nv + 1e-6 * nv, out2)
        assert st3 == C.ST_SEPARATED
        # plane first: normal flips
        out_s = np.empty(C.OUT_SIZE)
        st_s = collide_analytic(sb, sa, verts, r.T.copy(), -r.T @ t, out_s)
        assert st_s == st
        np.testing.assert_allclose(r @ out_s[1:4], -nv, atol=1e-12)
        assert out_s[C.OUT_DIST] == pytest.approx(d, abs=1e-12)
    assert 0.3 * n <= hits <= 0.7 * n


def test_box_capsule_flat_on_a_face_edge_on_and_apart():
    box = {"type": "box", "size": [2.0, 2.0, 2.0]}
    # lying flat on the top face, 0.1 deep: the witness is the middle of the segment's
    # part over the face (x in [-0.2, 0.8]), not one of its ends
    cap = {"type": "capsule", "radius": 0.2, "length": 1.0}
    ry = np.array([[0.0, 0, 1.0], [0, 1.0, 0], [-1.0, 0, 0]])    # capsule axis along x
    t = np.array([0.3, 0.0, 1.1])
    st, out = run(box, cap, ry, t)
    assert st == C.ST_PENETRATING
    assert out[C.OUT_DIST] == pytest.approx(-0.1, abs=1e-14)
    np.testing.assert_allclose(out[1:4], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(out[C.OUT_PA:C.OUT_PA + 3], [0.3, 0.0, 1.0], atol=1e-14)
    check_invariants(box, cap, ry, t, st, out, 3.0)
    # axis inside the box, across the edge along y at x = z = 1: the edge axis
    # (1, 0, 1)/sqrt(2) is the shortest way out, core depth 0.1/sqrt(2)
    cap = {"type": "capsule", "radius": 0.1, "length": 2.0}
    c = math.sqrt(0.5)
    r = np.array([[-c, 0, c], [0, 1.0, 0], [-c, 0, -c]])           # axis (1, 0, -1)/sqrt(2)
    t = np.array([0.95, 0.0, 0.95])
    st, out = run(box, cap, r, t)
    assert st == C.ST_PENETRATING
    assert out[C.OUT_DIST] == pytest.approx(-0.1 / math.sqrt(2) - 0.1, abs=1e-14)
    np.testing.assert_allclose(out[1:4], [c, 0, c], atol=1e-14)
    np.testing.assert_allclose(out[C.OUT_PA:C.OUT_PA + 3], [1.0, 0.0, 1.0], atol=1e-14)
    check_invariants(box, cap, r, t, st, out, 4.0)
    # the same axis along y, just outside that edge: the cores are apart, the nearest
    # box point is on the edge
    rx = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])       # axis along y
    t = np.array([1.05, 0.0, 1.05])
    st, out = run(box, cap, rx, t)
    assert out[C.OUT_DIST] == pytest.approx(0.05 * math.sqrt(2) - 0.1, abs=1e-14)
    np.testing.assert_allclose(out[1:4], [c, 0, c], atol=1e-14)
    check_invariants(box, cap, rx, t, st, out, 4.0)


def test_box_capsule_closed_form_matches_gjk_epa_when_deep():
    from mkcollision_ros import collide
    from mkcollision_ros.results import Status
    rng = np.random.default_rng(91)
    for k in range(200):
        box = rand_shape(rng, "box")
        cap = rand_shape(rng, "capsule")
        q = rng.normal(size=4)
        pose_a = ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
        # centres within a tenth of the box's size: deep, often both cores crossing
        pose_b = (list(rng.uniform(-0.1, 0.1, 3) * np.asarray(box["size"])), list(q))
        ra = collide(box, pose_a, cap, pose_b)
        rg = collide(box, pose_a, cap, pose_b, method="gjk_epa")
        assert ra.method == "analytic" and ra.status == Status.PENETRATING
        scale = np.linalg.norm(box["size"]) + cap["radius"] + cap["length"]
        assert ra.distance == pytest.approx(rg.distance, abs=1e-6 * scale)
        assert np.dot(ra.normal, rg.normal) > math.cos(1e-3), (box, cap, pose_b)


# --- sphere-cylinder closed form: against GJK/EPA and the exact sdf -----------------------
def _sdf_cylinder(shape, p):
    """Exact signed distance of a body-frame point to a (rounded) cylinder."""
    rr, h = shape["radius"], 0.5 * shape["height"]
    d0 = math.hypot(p[0], p[1]) - rr
    d1 = abs(p[2]) - h
    core = min(max(d0, d1), 0.0) + math.hypot(max(d0, 0.0), max(d1, 0.0))
    return core - shape.get("margin", 0.0)


def test_sphere_cylinder_closed_form_against_sdf_and_gjk_epa():
    from mkcollision_ros import collide
    rng = np.random.default_rng(77)
    n, hits = 300, 0
    for k in range(n):
        sa_d = rand_shape(rng, "sphere")
        sb_d = rand_shape(rng, "cylinder")
        sa, _ = tup(sa_d)
        sb, _ = tup(sb_d)
        scale = sa[1][7] + sb[1][7]
        r = O.random_rotation(rng)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        # mixture: some centres deep inside the cylinder, some near touching, some apart
        t = u * rng.uniform(0.0, 1.5) * contact_offset(sa, sb, r, u)
        if k % 10 == 0:
            t = u * 1e-3 * scale     # centre near B's centre (deep; near the axis)
        st, out = run(sa_d, sb_d, r, t)
        assert st != C.ST_NOT_RUN and out[C.OUT_METHOD] == C.M_ANALYTIC
        # exact: sphere distance = sdf_B(sphere centre) - sphere radius (incl. margins)
        c_b = r.T @ (np.zeros(3) - t)
        truth = _sdf_cylinder(sb_d, c_b) - sa_d["radius"] - sa_d.get("margin", 0.0)
        d = out[C.OUT_DIST]
        assert d == pytest.approx(truth, abs=1e-12 * scale)
        hits += st != C.ST_SEPARATED
        n_ = out[C.OUT_NORMAL:C.OUT_NORMAL + 3]
        pa = out[C.OUT_PA:C.OUT_PA + 3]
        pb = out[C.OUT_PB:C.OUT_PB + 3]
        assert abs(np.linalg.norm(n_) - 1.0) < 1e-12
        np.testing.assert_allclose(pb - pa, d * n_, atol=1e-12 * scale)
        assert abs(np.linalg.norm(pa) - sa_d["radius"] - sa_d.get("margin", 0.0)) < 1e-9 * scale
        assert abs(_sdf_cylinder(sb_d, r.T @ (pb - t))) < 1e-9 * scale
        # swapped order flips the normal
        st_s, out_s = run(sb_d, sa_d, r.T, -r.T @ t)
        assert st_s == st and abs(out_s[C.OUT_DIST] - d) < 1e-12 * scale
        # agreement with GJK/EPA (issue targets: 1e-6 scale; 1e-3 rad when well posed)
        q = [0.0, 0.0, 0.0, 1.0]
        w = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
        qw = 0.5 * math.sqrt(max(0.0, 1.0 + np.trace(r)))
        if qw > 1e-3:
            q = list(np.append(w / (4.0 * qw), qw))
            g = collide(sa_d, ([0.0, 0.0, 0.0], [0, 0, 0, 1]), sb_d, (list(t), q),
                        method="gjk_epa")
            assert g.distance == pytest.approx(d, abs=1e-6 * scale)
            rho = math.hypot(c_b[0], c_b[1])
            if abs(d) > 1e-3 * scale and rho > 1e-2 * scale:
                ang = math.acos(min(1.0, float(g.normal @ n_)))
                assert ang < 1e-3
    assert 0.3 * n <= hits <= 0.8 * n


def test_sphere_inside_cylinder_nearest_face():
    s = {"type": "sphere", "radius": 0.3}
    cyl = {"type": "cylinder", "radius": 1.0, "height": 2.0}
    # nearest boundary of the centre (0.1, 0, 0.5): the top cap, 0.5 away
    st, out = run(s, cyl, np.eye(3), -np.array([0.1, 0.0, 0.5]))
    assert st == C.ST_PENETRATING
    assert out[C.OUT_DIST] == pytest.approx(-0.8, abs=1e-14)
    # B must move down (-z) to push its top cap past the centre: normal A -> B is -z
    assert out[C.OUT_NORMAL:C.OUT_NORMAL + 3] == pytest.approx([0, 0, -1], abs=1e-14)
    # nearest boundary: the side, 0.2 away along +x
    st, out = run(s, cyl, np.eye(3), -np.array([0.8, 0.0, 0.1]))
    assert out[C.OUT_DIST] == pytest.approx(-0.5, abs=1e-14)
    assert out[C.OUT_NORMAL:C.OUT_NORMAL + 3] == pytest.approx([-1, 0, 0], abs=1e-14)


def _check_closed_form(sa_d, sb_d, r, t):
    """Run the closed form on A at the origin and B at (r, t), check it against GJK/EPA
    and the invariants (witness points on the surfaces, pb - pa = distance * normal, the
    distance certified by the support function along the normal, swapping A and B), and
    return its status."""
    from mkcollision_ros import collide
    sa, _ = tup(sa_d)
    sb, _ = tup(sb_d)
    scale = sa[1][7] + sb[1][7]
    st, out = run(sa_d, sb_d, r, t)
    assert st != C.ST_NOT_RUN and out[C.OUT_METHOD] == C.M_ANALYTIC
    assert np.all(np.isfinite(out))
    d = out[C.OUT_DIST]
    nrm = out[C.OUT_NORMAL:C.OUT_NORMAL + 3]
    pa = out[C.OUT_PA:C.OUT_PA + 3]
    pb = out[C.OUT_PB:C.OUT_PB + 3]
    assert abs(np.linalg.norm(nrm) - 1.0) < 1e-12
    np.testing.assert_allclose(pb - pa, d * nrm, atol=1e-12 * scale)
    # the same pair in world poses: A at the origin (identity), B at (t, r)
    pose_a = ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
    pose_b = (list(t), list(rotations.matrix_to_quat(r)))
    assert abs(O.surface_gap(sa_d, pose_a, pa, nrm)) < 1e-9 * scale
    assert abs(O.surface_gap(sb_d, pose_b, pb, -nrm)) < 1e-9 * scale
    h = O.cso_support(sa_d, pose_a, sb_d, pose_b, nrm[None, :])[0]
    assert d == pytest.approx(-h, abs=1e-9 * scale)
    g = collide(sa_d, pose_a, sb_d, pose_b, method="gjk_epa")
    assert g.distance == pytest.approx(d, abs=1e-6 * scale), (sa_d, sb_d, r, t)
    st_s, out_s = run(sb_d, sa_d, r.T, -r.T @ t)
    assert st_s == st and abs(out_s[C.OUT_DIST] - d) < 1e-12 * scale
    return st


def test_sphere_cone_closed_form_against_gjk_epa():
    """sphere-cone closed form (meridian-plane triangle) against GJK/EPA and the
    invariants: witness points on the surfaces, pb - pa = distance * normal, the depth
    certified by the support function along the normal."""
    rng = np.random.default_rng(78)
    n, hits = 300, 0
    for k in range(n):
        sa_d = rand_shape(rng, "sphere")
        sb_d = rand_shape(rng, "cone")
        sa, _ = tup(sa_d)
        sb, _ = tup(sb_d)
        scale = sa[1][7] + sb[1][7]
        qb = O.random_quats(rng, 1)[0]
        r = O.quat_matrix(qb).T          # B's frame is A's, A is rotated: pose of B in A
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        t = u * rng.uniform(0.0, 1.5) * contact_offset(sa, sb, r, u)
        if k % 10 == 0:
            t = u * 1e-3 * scale
        hits += _check_closed_form(sa_d, sb_d, r, t) != C.ST_SEPARATED
    assert 0.3 * n <= hits <= 0.8 * n


def test_sphere_ellipsoid_closed_form_against_gjk_epa():
    """sphere-ellipsoid closed form (Newton on the Lagrange multiplier) against GJK/EPA and
    the invariants, including the special points: the centre inside on the plane of the
    shortest axis (the flat case), coincident centres, spheroids with tied shortest
    axes, flat and needle ellipsoids; an ellipsoid with a margin is not an ellipsoid
    and is left to GJK/EPA."""
    rng = np.random.default_rng(79)
    n, hits, flat_cases = 400, 0, 0
    for k in range(n):
        sa_d = rand_shape(rng, "sphere")
        radii = rng.uniform(0.1, 1.5, 3)
        if k % 5 == 1:
            radii[rng.integers(3)] = radii[rng.integers(3)]      # ties
        if k % 17 == 2:
            radii = radii * np.array([1.0, 1e-2, 1.0])[rng.permutation(3)]   # flat
        sb_d = {"type": "ellipsoid", "radii": list(radii)}
        sa, _ = tup(sa_d)
        sb, _ = tup(sb_d)
        r = O.quat_matrix(O.random_quats(rng, 1)[0]).T
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        t = u * rng.uniform(0.0, 1.5) * contact_offset(sa, sb, r, u)
        p_b = rng.uniform(-1, 1, 3) * radii * 0.4            # a point inside B ...
        if k % 7 == 3:
            p_b[np.argmin(radii)] = 0.0                         # ... on the shortest-axis plane
            t = -r @ p_b
            flat_cases += 1
        elif k % 31 == 4:
            t = np.zeros(3)                                     # coincident centres
        hits += _check_closed_form(sa_d, sb_d, r, t) != C.ST_SEPARATED
    assert 0.3 * n <= hits <= 0.8 * n and flat_cases > 40
    # with a margin the pair goes to GJK/EPA
    sb_m, _ = tup({"type": "ellipsoid", "radii": [1.0, 2.0, 3.0], "margin": 0.1})
    sa, _ = tup({"type": "sphere", "radius": 0.5})
    out = np.zeros(C.OUT_SIZE)
    assert collide_analytic(sa, sb_m, VERTS0, np.eye(3), np.array([0, 0, 4.0]), out) == C.ST_NOT_RUN


def _world_against_body_frame(shapes, pos, quat, normal_atol, point_tol):
    """collide_batch (method auto) on the pairs (2k, 2k + 1) against collide_analytic
    fed each pair's relative pose: the same status and method, the distance within
    1e-12 * scale, the world normal within ``normal_atol`` and the world witness points
    within ``point_tol`` * (scale + |A's position|).  Returns the statuses."""
    from mkcollision_ros.kernels.narrowphase import collide_batch
    from mkcollision_ros.shapes import build_table
    table = build_table(shapes)
    n = len(shapes) // 2
    pairs = np.arange(2 * n, dtype=np.int64).reshape(n, 2)
    out = np.full((n, C.OUT_SIZE), np.nan)
    st = np.full(n, -1, dtype=np.int64)
    collide_batch(table.codes, table.params, table.vrange, table.verts, pairs, pos, quat,
                  np.int64(C.M_AUTO), np.inf, out, st)
    for k in range(n):
        i, j = pairs[k]
        ra, rb = O.quat_matrix(quat[i]), O.quat_matrix(quat[j])
        st_b, ref = run(shapes[i], shapes[j], ra.T @ rb, ra.T @ (pos[j] - pos[i]))
        scale = table.params[i, 7] + table.params[j, 7]
        assert st[k] == st_b
        assert out[k, C.OUT_DIST] == pytest.approx(ref[C.OUT_DIST], abs=1e-12 * scale)
        np.testing.assert_allclose(out[k, C.OUT_NORMAL:C.OUT_NORMAL + 3],
                                   ra @ ref[C.OUT_NORMAL:C.OUT_NORMAL + 3], atol=normal_atol)
        for c in (C.OUT_PA, C.OUT_PB):
            np.testing.assert_allclose(out[k, c:c + 3], pos[i] + ra @ ref[c:c + 3],
                                       atol=point_tol * (scale + np.abs(pos[i]).max()))
        assert out[k, C.OUT_METHOD] == C.M_ANALYTIC
    return st


def _paired_poses(rng, n, spread):
    """World poses of n pairs (2k, 2k + 1): random orientations, the first body near the
    origin or 1e3 m from it, the second ``spread`` * a normal draw away from it."""
    quat = O.random_quats(rng, 2 * n)
    pos = np.zeros((2 * n, 3))
    pos[0::2] = rng.choice([0.0, 1e3], size=(n, 1)) + rng.normal(size=(n, 3))
    pos[1::2] = pos[0::2] + spread * rng.normal(size=(n, 3))
    return quat, pos


SPHERE_WORLD = ["sphere", "box", "capsule", "cylinder", "cone", "ellipsoid"]


@pytest.mark.parametrize("kind", SPHERE_WORLD)
def test_batch_sphere_pairs_solved_in_the_world_match_the_body_frame_closed_forms(kind):
    """The batch kernel (and the API) solves a sphere against a shape with a sphere-*
    closed form in the other body's frame, straight from the world poses, for either
    order of the pair (kernels/sphere_shape.sphere_world); the body-frame kernels of
    collide_analytic, fed the relative pose, are the reference: the same status, the
    distance, normal and world witness points to round-off, the pair placed near the
    origin or 1e3 m from it."""
    rng = np.random.default_rng(SPHERE_WORLD.index(kind) + 41)
    n = 400
    shapes = []
    for k in range(n):
        sphere = rand_shape(rng, "sphere")
        other = rand_shape(rng, kind, 0.0 if kind == "ellipsoid" else 0.3)
        shapes += [sphere, other] if k % 2 == 0 else [other, sphere]
    quat, pos = _paired_poses(rng, n, 0.9)
    st = _world_against_body_frame(shapes, pos, quat, 1e-12, 1e-12)
    hits = np.isin(st, (C.ST_TOUCHING, C.ST_PENETRATING)).mean()
    assert 0.2 < hits < 0.9


def test_sphere_centred_on_a_capsule_axis_pushes_across_the_axis():
    """A sphere centred on a capsule's segment: every direction normal to the segment is
    as deep; the answer is the capsule's x axis, whichever shape is A and in the world
    path as in the body frame."""
    from mkcollision_ros import collide
    sphere = {"type": "sphere", "radius": 0.3}
    capsule = {"type": "capsule", "radius": 0.2, "length": 1.0}
    s2 = math.sqrt(0.5)
    q = [0.0, 0.0, s2, s2]                       # 90 degrees about z: x axis -> world +y
    pose_c = ([1.0, 2.0, 3.0], q)
    pose_s = ([1.0, 2.0, 3.25], [0.0, 0.0, 0.0, 1.0])   # on the segment, 0.25 up
    r1 = collide(sphere, pose_s, capsule, pose_c)
    r2 = collide(capsule, pose_c, sphere, pose_s)
    for r, sign in ((r1, 1.0), (r2, -1.0)):
        assert r.distance == pytest.approx(-0.5, abs=1e-12)
        np.testing.assert_allclose(r.normal, [0.0, sign, 0.0], atol=1e-12)
    st, out = run(sphere, capsule, np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0],
                                             [0.0, 0.0, 1.0]]), np.array([0.0, 0.0, -0.25]))
    assert out[C.OUT_DIST] == pytest.approx(-0.5, abs=1e-12)
    np.testing.assert_allclose(out[C.OUT_NORMAL:C.OUT_NORMAL + 3], [0.0, 1.0, 0.0],
                               atol=1e-12)


HALF_SPACE_WORLD = ["sphere", "ellipsoid", "box", "capsule", "cylinder", "cone"]


@pytest.mark.parametrize("kind", HALF_SPACE_WORLD)
def test_batch_half_space_pairs_solved_in_the_world_match_the_body_frame_closed_form(kind):
    """A shape against a half-space is solved straight from the world poses
    (narrowphase._half_space_world, one call site for both orders); collide_analytic on
    the relative pose is the reference, to round-off, with the plane as A and as B, near
    the origin and 1e3 m from it."""
    rng = np.random.default_rng(HALF_SPACE_WORLD.index(kind) + 61)
    n = 200
    shapes = []
    for k in range(n):
        nrm = rng.normal(size=3)
        plane = {"type": "plane", "normal": list(nrm / np.linalg.norm(nrm)),
                 "offset": float(rng.uniform(-0.5, 0.5)), "margin": float(rng.uniform(0, 0.1))}
        other = rand_shape(rng, kind, 0.3)
        shapes += [plane, other] if k % 2 == 0 else [other, plane]
    quat, pos = _paired_poses(rng, n, 0.9)
    st = _world_against_body_frame(shapes, pos, quat, 1e-12, 1e-9)
    hits = np.isin(st, (C.ST_TOUCHING, C.ST_PENETRATING)).mean()
    assert 0.2 < hits < 0.9


def test_batch_capsule_pairs_solved_in_the_world_match_the_body_frame_closed_form():
    """Two capsules are solved straight from their world poses
    (capsule_capsule.capsule_capsule_world, the same segment kernel as the body-frame path);
    collide_analytic on the relative pose is the reference, to round-off, on random
    pairs, parallel axes (the overlap's middle) and axes crossing at the centres (the
    common perpendicular)."""
    rng = np.random.default_rng(53)
    n = 600
    shapes = [rand_shape(rng, "capsule") for _ in range(2 * n)]
    quat, pos = _paired_poses(rng, n, 1.2)
    quat[3:200:4] = quat[2:200:4]                                   # parallel axes
    pos[201:400:4] = pos[200:400:4]                                 # coincident centres
    st = _world_against_body_frame(shapes, pos, quat, 1e-9, 1e-9)
    hits = np.isin(st, (C.ST_TOUCHING, C.ST_PENETRATING)).mean()
    assert 0.2 < hits < 0.9


@pytest.mark.parametrize("la,lb", [(0.8, 0.5), (0.0, 0.5), (0.8, 0.0)])
def test_capsules_whose_axes_meet_in_a_line_or_a_point_separate_across_them(la, lb):
    """Coaxial capsules with coincident centres (the common perpendicular of parallel
    axes is round-off, so it must not be used) and a zero-length capsule centred on the
    other's segment: every direction normal to the segment is as deep, so the normal
    is normal to it and the depth is the sum of the radii, in either order, for both
    the world-frame path and the body frame."""
    from mkcollision_ros import collide
    rng = np.random.default_rng(61)
    a = {"type": "capsule", "radius": 0.3, "length": la}
    b = {"type": "capsule", "radius": 0.2, "length": lb}
    for _ in range(20):
        q = O.random_quats(rng, 1)[0]
        qa = q if la > 0.0 and lb > 0.0 else O.random_quats(rng, 1)[0]
        axis = O.quat_matrix(q if lb > 0.0 else qa)[:, 2]
        c = rng.uniform(-5.0, 5.0, 3)
        for r in (collide(a, (c, qa), b, (c, q)), collide(b, (c, q), a, (c, qa))):
            assert r.depth == pytest.approx(0.5, abs=1e-12)
            assert abs(np.dot(r.normal, axis)) < 1e-12
        ra = O.quat_matrix(qa)
        st, out = run(a, b, ra.T @ O.quat_matrix(q), np.zeros(3))
        assert out[C.OUT_DIST] == pytest.approx(-0.5, abs=1e-12)
        assert abs(np.dot(ra @ out[C.OUT_NORMAL:C.OUT_NORMAL + 3], axis)) < 1e-12
