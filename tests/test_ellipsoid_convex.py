"""The normal fan of a small hull (hull.fan_rows) and the exact ellipsoid-hull depth over
it (kernels/pairs/ellipsoid_convex.py), against GJK/EPA on the same points without the
fan (a table built with prune=False stores none) on seeded random pairs, both orders,
with margins.  coal checks the same path in test_gjk_epa.py (test_against_coal_random:
its ellipsoid-convex pairs go through collide_ellipsoid_convex whenever the cores
overlap)."""
import numpy as np
import pytest

from mkcollision_ros.cases import pair_cases, relative_poses
from mkcollision_ros.hull import FAN_MAX_POINTS, fan_rows
from mkcollision_ros.kernels import constants as C
from mkcollision_ros.kernels.constants import PRE_APART, PRE_EXACT, PRE_UNPROVED
from mkcollision_ros.kernels.gjk_epa import gjk_epa
from mkcollision_ros.kernels.pairs.ellipsoid_convex import collide_ellipsoid_convex
from mkcollision_ros.kernels.pairs.normal_fan import HE_ROWS
from mkcollision_ros.kernels.narrowphase import collide_batch
from mkcollision_ros.shapes import build_table, point_count, shape_row

CUBE = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)


def _fan(points):
    """(faces, edges, vertices, normals, offsets, vertex ids, edges (E, 4)) unpacked."""
    nf, ne, nv, rows = fan_rows(points)
    flat = rows[nf:].ravel()
    return (nf, ne, nv, rows[:nf], flat[:nf], flat[nf:nf + nv].astype(int),
            flat[nf + nv:nf + nv + 4 * ne].astype(int).reshape(-1, 4))


def test_fan_counts_of_polytopes_and_degenerate_sets():
    assert _fan(CUBE)[:3] == (6, 12, 8)                      # coplanar corners: 6 faces
    assert _fan(np.concatenate([CUBE, CUBE[:3], [[0.0, 0.0, 0.0]]]))[:3] == (6, 12, 8)
    assert _fan(np.eye(3).tolist() + [[0.0, 0.0, 0.0]])[:3] == (4, 6, 4)
    flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]
    line = [[float(k), 0.0, 0.0] for k in range(5)]
    rng = np.random.default_rng(3)
    many = rng.normal(size=(FAN_MAX_POINTS + 1, 3))
    for pts in (flat, line, many, CUBE[:3]):
        assert fan_rows(pts)[0] == 0
    # the table stores it after the points; point_count still finds the points
    code, prm, rows = shape_row({"type": "convex", "points": CUBE.tolist()})
    assert prm[C.P_FAN_FACES] == 6 and point_count(code, prm, rows) == 8
    assert np.array_equal(rows[:8], CUBE)
    code, prm, rows = shape_row({"type": "convex", "points": flat})
    assert prm[C.P_FAN_FACES] == 0 and point_count(code, prm, rows) == 4


@pytest.mark.parametrize("seed", range(4))
def test_fan_is_the_hulls_boundary(seed):
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(int(rng.integers(5, FAN_MAX_POINTS + 1)), 3)) * rng.uniform(
        0.1, 3.0, 3)
    nf, ne, nv, FN, FO, VX, E = _fan(P)
    assert nf > 0 and nv - ne + nf == 2
    assert np.allclose(np.linalg.norm(FN, axis=1), 1.0)
    size = np.linalg.norm(P.max(0) - P.min(0))
    assert np.allclose((P @ FN.T).max(0), FO, rtol=0, atol=1e-12 * size)
    # every point attaining a support maximum is a listed vertex, and every vertex is
    # the only maximum along the sum of its faces' normals (inside its normal cone)
    d = rng.normal(size=(20000, 3))
    assert set(np.argmax(P @ d.T, axis=0)) <= set(VX)
    on = np.abs(P @ FN.T - FO) < 1e-9 * size
    for u in VX:
        s = P @ FN[on[u]].sum(0)
        assert np.argmax(s) == u and np.sum(s >= s[u] - 1e-9 * size) == 1
    for a, b, f, g in E:
        for u in (a, b):
            assert abs(P[u] @ FN[f] - FO[f]) < 1e-9 * size
            assert abs(P[u] @ FN[g] - FO[g]) < 1e-9 * size


def _pair_runs(n, seed, margin, swap):
    """Per case: (GJK/EPA's depth, the ellipsoid's rolling radius, outcome of the first
    call (no overlap known, ``stop`` 0), decided (again with the overlap known where
    GJK/EPA finds the cores overlapping, as gjk_epa_ws does), fan depth, fan normal, GJK
    normal, witness residual (pb - pa + h n), scale, res), the kernel called directly."""
    shapes, _, _, pos, quat = pair_cases("ellipsoid", "convex", n, seed=seed)
    for s in shapes:
        s["margin"] = margin
    fan, plain = build_table(shapes), build_table(shapes, prune=False)
    assert np.all(fan.params[1::2, C.P_FAN_FACES] > 0)
    assert np.all(plain.params[1::2, C.P_FAN_FACES] == 0)
    rows, roots, res, out = np.zeros((HE_ROWS, 3)), np.zeros(8), np.zeros(10), np.zeros(
        C.OUT_SIZE)
    runs = []
    for k in range(n):
        ia, ib = (2 * k + 1, 2 * k) if swap else (2 * k, 2 * k + 1)
        R, T = relative_poses(pos[[ia, ib]], quat[[ia, ib]])
        sa, sb, qa, qb = [(t.codes[i], t.params[i], t.vrange[i, 0], t.vrange[i, 1])
                          for t in (fan, plain) for i in (ia, ib)]
        scale = fan.params[ia, C.P_RADIUS] + fan.params[ib, C.P_RADIUS]
        gjk_epa(qa, qb, plain.verts, R[0], T[0], out)
        roll = fan.params[ib if swap else ia, C.P_ROLL]
        depth = -out[C.OUT_DIST]
        res[:] = np.nan
        args = (sa, sb, fan.verts, R[0], T[0], scale)
        first = collide_ellipsoid_convex(*args, False, 0.0, rows, roots, res)
        got = first
        if first == PRE_UNPROVED and depth > roll + 2 * margin + 1e-9 * scale:
            got = collide_ellipsoid_convex(*args, True, 0.0, rows, roots, res)
        full = res[0] + roll + 2 * margin           # both margins
        runs.append((depth, roll, first, got == PRE_EXACT, full, res[1:4].copy(),
                     out[C.OUT_NORMAL:C.OUT_NORMAL + 3].copy(),
                     np.linalg.norm(res[7:10] - res[4:7] + res[0] * res[1:4]), scale,
                     res.copy()))
    return runs


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("margin", [0.0, 0.04])
def test_exact_depth_matches_gjk_epa(swap, margin):
    runs = _pair_runs(400, 11 + swap + int(100 * margin), margin, swap)
    # the kernel is for the ellipsoid and the hull without their margins; GJK's proof
    # of overlap for their cores (the ellipsoid less its rolling radius)
    cores = [r for r in runs if r[0] > r[1] + 2 * margin + 1e-9 * r[8]]
    assert len(cores) > 60
    # its own proof holds only for overlapping pairs, and (with GJK in E's unit-ball
    # frame where no vertex or centre proves it) proves nearly all of them
    proved = [r for r in runs if r[2] == PRE_EXACT]
    assert all(r[0] > 2 * margin for r in proved)
    assert sum(r[2] == PRE_EXACT for r in cores) >= 0.98 * len(cores)
    # with GJK's proof, it decides nearly all of them (the rest go on to EPA)
    assert sum(r[3] for r in cores) >= 0.95 * len(cores)
    for depth, _, _, dec, h, n, n_ref, resid, scale, _ in runs:
        if dec:
            assert abs(h - depth) <= 2e-8 * scale
            assert np.arccos(np.clip(n @ n_ref, -1.0, 1.0)) < 1e-3
            assert resid <= 1e-12 * scale


@pytest.mark.parametrize("swap", [False, True])
def test_planes_prove_pairs_apart(swap):
    margin = 0.02
    runs = _pair_runs(400, 31 + 2 * swap, margin, swap)
    # cores apart by GJK/EPA (the distance of the cores: the ellipsoid less its
    # rolling radius, both margins off)
    apart = [r for r in runs if r[0] < r[1] + 2 * margin - 1e-9 * r[8]]
    out = [r for r in runs if r[2] == PRE_APART]
    assert len(apart) > 60 and len(out) >= 0.95 * len(apart)
    for depth, roll, _, _, h, n, _, _, scale, res in out:
        gap = -(h - roll - 2 * margin)           # res[0] = -gap, for the cores
        assert gap > 0.0                         # beyond ``stop`` (0 here)
        assert gap <= -depth + roll + 2 * margin + 1e-9 * scale   # a lower bound
        assert abs(np.linalg.norm(n) - 1.0) < 1e-12
        # pa and pb on either side of the plane, gap apart along its normal
        assert abs(n @ (res[7:10] - res[4:7]) - gap) <= 1e-9 * scale


def test_batch_kernel_takes_the_fan_and_agrees_with_gjk_epa():
    shapes, fan, pairs, pos, quat = pair_cases("ellipsoid", "convex", 400, seed=21)
    plain = build_table(shapes, prune=False)
    outs, sts = [], []
    for t in (fan, plain):
        out, st = np.zeros((len(pairs), C.OUT_SIZE)), np.zeros(len(pairs), np.int64)
        collide_batch(t.codes, t.params, t.vrange, t.verts, pairs, pos, quat, C.M_AUTO,
                      np.inf, out, st)
        outs.append(out)
        sts.append(st)
    scale = fan.params[0::2, C.P_RADIUS] + fan.params[1::2, C.P_RADIUS]
    assert np.all(np.isfinite(outs[0]))
    deep = outs[1][:, C.OUT_DIST] < -1e-3 * scale
    assert deep.sum() > 100
    assert np.array_equal(sts[0][deep], sts[1][deep])
    assert np.all(np.abs(outs[0][deep, 0] - outs[1][deep, 0]) <= 2e-8 * scale[deep])
    # the fan answers before GJK (one step) or after it in place of EPA, where GJK/EPA
    # take many steps
    steps = outs[0][deep, C.OUT_ITERS], outs[1][deep, C.OUT_ITERS]
    assert np.mean(steps[0] == 1) > 0.7 and np.all(steps[1] > 1)
    assert steps[0].mean() < 0.5 * steps[1].mean()


def test_contacts_mode_ends_pairs_apart_at_a_face_plane():
    # cutoff 0 (the pipeline's): a face plane (or the plane of GJK in E's unit-ball
    # frame) proving a pair farther apart than the touching band ends it without GJK on
    # the cores (test_planes_prove_pairs_apart), with the gap as a lower bound on the
    # distance; the statuses are those of exact distances
    shapes, fan, pairs, pos, quat = pair_cases("ellipsoid", "convex", 400, seed=22)
    plain = build_table(shapes, prune=False)
    outs, sts = [], []
    for t, cutoff in ((fan, 0.0), (plain, np.inf)):
        out, st = np.zeros((len(pairs), C.OUT_SIZE)), np.zeros(len(pairs), np.int64)
        collide_batch(t.codes, t.params, t.vrange, t.verts, pairs, pos, quat, C.M_AUTO,
                      cutoff, out, st)
        outs.append(out)
        sts.append(st)
    assert np.array_equal(sts[0], sts[1]) and np.all(np.isfinite(outs[0]))
    radius = fan.params[:, C.P_RADIUS]
    scale = radius[0::2] + radius[1::2]
    near = np.linalg.norm(pos[1::2] - pos[0::2], axis=1) <= scale
    sep = (sts[0] == C.ST_SEPARATED) & near
    assert sep.sum() > 50
    got, exact = outs[0][sep, C.OUT_DIST], outs[1][sep, C.OUT_DIST]
    assert np.all(got > 0.0) and np.all(got <= exact + 1e-9 * scale[sep])
    n = outs[0][sep, C.OUT_NORMAL:C.OUT_NORMAL + 3]
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)


def _first_call(box_lo, box_hi, swap, stop):
    """An ellipsoid (radii 1, 0.8, 0.6) at the origin and the box [box_lo, box_hi] as a
    hull, the kernel's first call (no overlap known) and GJK/EPA on the same pair:
    (outcome, res, GJK/EPA's out, scale, E's rolling radius)."""
    corners = [[x, y, z] for x in (box_lo[0], box_hi[0]) for y in (box_lo[1], box_hi[1])
               for z in (box_lo[2], box_hi[2])]
    shapes = [{"type": "ellipsoid", "radii": [1.0, 0.8, 0.6]},
              {"type": "convex", "points": corners}]
    pos = np.zeros((2, 3))
    quat = np.array([[0.0, 0.0, 0.0, 1.0]] * 2)
    if swap:
        shapes, pos = shapes[::-1], pos[::-1].copy()
    fan, plain = build_table(shapes), build_table(shapes, prune=False)
    R, T = relative_poses(pos, quat)
    sa, sb, qa, qb = [(t.codes[i], t.params[i], t.vrange[i, 0], t.vrange[i, 1])
                      for t in (fan, plain) for i in (0, 1)]
    scale = fan.params[0, C.P_RADIUS] + fan.params[1, C.P_RADIUS]
    out, res = np.zeros(C.OUT_SIZE), np.zeros(10)
    gjk_epa(qa, qb, plain.verts, R[0], T[0], out)
    got = collide_ellipsoid_convex(sa, sb, fan.verts, R[0], T[0], scale, False, stop,
                                   np.zeros((HE_ROWS, 3)), np.zeros(8), res)
    return got, res, out, scale, fan.params[1 if swap else 0, C.P_ROLL]


@pytest.mark.parametrize("swap", [False, True])
def test_unit_ball_gjk_decides_pairs_no_vertex_or_centre_proves(swap):
    # a long bar (y in [-3, 3]) whose edge along y passes through the ellipsoid: no
    # corner inside E, E's centre outside the bar, so only GJK in E's unit-ball frame
    # proves the overlap on the first call (``stop`` inf: no plane ends it; the cores,
    # E less its rolling radius, are apart here); the depth is then exact
    for lo, hi in (([0.5, -3.0, 0.3], [1.5, 3.0, 1.3]), ([-0.2, -3.0, 0.4], [0.2, 3.0, 1.4])):
        got, res, out, scale, roll = _first_call(lo, hi, swap, np.inf)
        assert got == PRE_EXACT
        assert abs(res[0] + roll + out[C.OUT_DIST]) <= 1e-9 * scale
        assert np.arccos(np.clip(res[1:4] @ out[C.OUT_NORMAL:C.OUT_NORMAL + 3], -1, 1)) < 1e-6
    # the bar's edge at x = 0.8, z = 0.5: E reaches beyond both its faces' planes (x up
    # to 1, z up to 0.6) yet misses the edge (0.8^2 + 0.5^2 / 0.36 > 1), so no face plane
    # separates them; the plane from that GJK does, its gap a lower bound on the
    # distance.  ``stop`` is E's rolling radius a_min^2 / a_max, so only a plane with E
    # itself (not only its core) apart from the bar ends the call
    got, res, out, scale, roll = _first_call([0.8, -3.0, 0.5], [1.8, 3.0, 1.5], swap, 0.36)
    gap = -res[0]                                     # the cores' (E less its roll)
    assert got == PRE_APART and out[C.OUT_DIST] > 0.0 and roll == pytest.approx(0.36)
    assert roll < gap <= out[C.OUT_DIST] + roll + 1e-9 * scale
    n = res[1:4]
    assert abs(np.linalg.norm(n) - 1.0) < 1e-12
    assert abs(n @ (res[7:10] - res[4:7]) - gap) <= 1e-9 * scale
