"""The exact cylinder-hull depth over the hull's normal fan (kernels/pairs/cylinder_convex.py,
collide_cylinder_convex): against closed forms on hand-placed pairs, and against GJK/EPA
on the same points without the fan (a table built with prune=False stores none) on
seeded random pairs, both orders, with margins.  coal checks the same path in
test_gjk_epa.py (test_against_coal_random: its cylinder-convex pairs go through
collide_cylinder_convex whenever the cores overlap)."""
import numpy as np
import pytest

from mkcollision_ros.cases import pair_cases, relative_poses
from mkcollision_ros.kernels import constants as C
from mkcollision_ros.kernels.constants import PRE_APART, PRE_EXACT, PRE_UNPROVED
from mkcollision_ros.kernels.gjk_epa import gjk_epa
from mkcollision_ros.kernels.pairs.cylinder_convex import collide_cylinder_convex
from mkcollision_ros.kernels.pairs.normal_fan import HE_ROWS
from mkcollision_ros.kernels.narrowphase import collide_batch
from mkcollision_ros.shapes import build_table

OCTA = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                float)


def _rot(axis, angle):
    """The rotation matrix about a unit axis."""
    x, y, z = axis
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _hand(points, rot, tr, swap=False, stop=0.0, overlap=False):
    """The kernel on a cylinder (radius 1, height 4) and the hull of ``points`` at
    (rot, tr) in the cylinder's frame: (outcome, res), res in A's frame."""
    t = build_table([{"type": "cylinder", "radius": 1.0, "height": 4.0},
                     {"type": "convex", "points": np.asarray(points).tolist()}])
    assert t.params[1, C.P_FAN_FACES] > 0
    sc, sh = [(t.codes[i], t.params[i], t.vrange[i, 0], t.vrange[i, 1]) for i in (0, 1)]
    rot, tr = np.asarray(rot, float), np.asarray(tr, float)
    if swap:
        sc, sh, rot, tr = sh, sc, rot.T, -rot.T @ tr
    res = np.full(10, np.nan)
    got = collide_cylinder_convex(sc, sh, t.verts, rot, tr, 3.0, overlap, stop,
                                  np.zeros((HE_ROWS, 3)), np.zeros(8), res)
    return got, res


@pytest.mark.parametrize("swap", [False, True])
def test_closed_forms_of_hand_placed_pairs(swap):
    d = 0.1
    # a vertex into the side (the octahedron's, turned off the axes so that no edge is
    # square to the cylinder's axis): depth d along x, the vertex and the side's point
    # level with it the witnesses
    rot = _rot(np.array([1.0, 0.0, 0.0]), 0.3)
    cases = [
        (OCTA, rot, [2.0 - d, 0.0, 0.5], d, [1.0, 0.0, 0.0], [1.0 - d, 0.0, 0.5]),
        # a vertex into the top cap, from above and off the axis: depth d along z
        (OCTA, _rot(np.array([0.0, 0.0, 1.0]), 0.4) @ _rot(np.array([1.0, 1.0, 0.0])
                                                             / np.sqrt(2), 0.2),
         None, d, [0.0, 0.0, 1.0], None),
    ]
    r2 = cases[1][1]
    low = (OCTA @ r2.T)[:, 2].min()
    lowest = (OCTA @ r2.T)[np.argmin((OCTA @ r2.T)[:, 2])]
    t2 = np.array([0.3, -0.2, 2.0 - d - low])
    cases[1] = (OCTA, r2, t2, d, [0.0, 0.0, 1.0], lowest + t2)
    for pts, rt, tr, depth, n, pb in cases:
        got, res = _hand(pts, rt, tr, swap)
        assert got == PRE_EXACT
        assert abs(res[0] - depth) < 1e-12
        if not swap:
            assert np.allclose(res[1:4], n, atol=1e-12)
            assert np.allclose(res[7:10], pb, atol=1e-12)
            assert np.allclose(res[4:7], np.asarray(pb) + depth * np.asarray(n), atol=1e-12)
        else:
            # A is the hull: the normal reversed, both in the hull's frame
            assert np.allclose(rt @ res[1:4], -np.asarray(n), atol=1e-12)
            assert np.allclose(rt @ res[4:7] + tr, pb, atol=1e-12)


def test_hand_placed_edge_into_the_rim_and_apart_pairs():
    # a thin long box (along y, turned about y, then x) over the top rim, placed (by a
    # search over poses) where the deepest direction is a rim's, against one of the
    # box's long edges: a root of the rim-arc problem, checked against GJK/EPA without
    # the fan
    box = np.array([[x, y, z] for x in (-0.05, 0.05) for y in (-2, 2) for z in (-0.05, 0.05)])
    rot = _rot(np.array([1.0, 0.0, 0.0]), 0.1) @ _rot(np.array([0.0, 1.0, 0.0]), 0.6)
    tr = np.array([0.9, 0.1, 2.0])
    # no vertex inside and the cylinder's centre outside the box, but the box's centre
    # lies in the cylinder (on its top cap): the overlap is proved without GJK's
    got, res = _hand(box, rot, tr)
    plain = build_table([{"type": "cylinder", "radius": 1.0, "height": 4.0},
                         {"type": "convex", "points": box.tolist()}], prune=False)
    sc, sh = [(plain.codes[i], plain.params[i], plain.vrange[i, 0], plain.vrange[i, 1])
              for i in (0, 1)]
    out = np.zeros(C.OUT_SIZE)
    gjk_epa(sc, sh, plain.verts, rot, tr, out)
    assert out[C.OUT_DIST] < -1e-3
    assert got == PRE_EXACT and abs(res[0] + out[C.OUT_DIST]) < 1e-8
    n = res[1:4]
    assert abs(n[2]) > 0.2 and np.hypot(n[0], n[1]) > 0.2      # a rim's normal
    assert np.max(np.abs(rot.T @ n)) < 0.99                     # not a box face's
    # pb on the box's edge and pa on the top rim
    assert abs(res[6] - 2.0) < 1e-12 and abs(np.hypot(res[4], res[5]) - 1.0) < 1e-12
    # the same box well above the top cap and well beside the side: apart, the gap a
    # lower bound of the distance, larger than ``stop``
    for tr2 in ([0.0, 0.0, 2.6], [1.8, 0.0, 0.0]):
        got, res = _hand(box, np.eye(3), tr2, stop=0.1)
        gjk_epa(sc, sh, plain.verts, np.eye(3), np.array(tr2), out)
        assert got == PRE_APART and 0.1 < -res[0] <= out[C.OUT_DIST] + 1e-12


@pytest.mark.parametrize("swap", [False, True])
def test_gjk_decides_pairs_no_vertex_centre_or_plane_proves(swap):
    # the thin long box over the top rim, tilted, its centre outside the cylinder: no
    # box vertex inside, neither centre inside the other, no face, side or cap plane
    # apart (hand-placed: without _cyl_gjk both would be UNPROVED).  _cyl_gjk
    # proves the first overlapping (then the exact depth, against GJK/EPA without the
    # fan) and the second apart, the gap a lower bound with the witnesses across it
    box = np.array([[x, y, z] for x in (-0.05, 0.05) for y in (-2, 2) for z in (-0.05, 0.05)])
    shapes = [{"type": "cylinder", "radius": 1.0, "height": 4.0},
              {"type": "convex", "points": box.tolist()}]
    plain = build_table(shapes, prune=False)
    sc, sh = [(plain.codes[i], plain.params[i], plain.vrange[i, 0], plain.vrange[i, 1])
              for i in (0, 1)]
    out = np.zeros(C.OUT_SIZE)
    x_axis, z_axis = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    for angles, tr, stop in (((-0.6, 0.6), [1.15, 0.0, 1.93], np.inf),
                             ((0.1, -0.9), [1.88, 0.0, 2.12], 0.05)):
        rot = _rot(x_axis, angles[0]) @ _rot(z_axis, angles[1])
        tr = np.array(tr)
        gjk_epa(sc, sh, plain.verts, rot, tr, out)
        dist = out[C.OUT_DIST]
        got, res = _hand(box, rot, tr, swap, stop=stop)
        if dist < 0.0:
            assert dist < -0.1 and got == PRE_EXACT and abs(res[0] + dist) < 1e-8
            continue
        assert dist > 0.1 and got == PRE_APART
        gap = -res[0]
        assert stop < gap <= dist + 1e-12
        n = res[1:4]
        assert abs(np.linalg.norm(n) - 1.0) < 1e-12
        assert abs(n @ (res[7:10] - res[4:7]) - gap) < 1e-12


def _pair_runs(n, seed, margin, swap):
    """Per case: (GJK/EPA's depth, outcome of the first call (no overlap known, ``stop``
    0), decided (again with the overlap known where GJK/EPA finds the cores
    overlapping, as gjk_epa_ws does), fan depth (with the margins), fan normal, GJK
    normal, witness residual (pb - pa + h n), scale, res), the kernel called directly."""
    shapes, _, _, pos, quat = pair_cases("cylinder", "convex", n, seed=seed)
    for s in shapes:
        s["margin"] = margin
    fan, plain = build_table(shapes), build_table(shapes, prune=False)
    assert np.all(fan.params[1::2, C.P_FAN_FACES] > 0)
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
        depth = -out[C.OUT_DIST]
        res[:] = np.nan
        args = (sa, sb, fan.verts, R[0], T[0], scale)
        first = collide_cylinder_convex(*args, False, 0.0, rows, roots, res)
        got = first
        if first == PRE_UNPROVED and depth > 2 * margin + 1e-9 * scale:
            got = collide_cylinder_convex(*args, True, 0.0, rows, roots, res)
        runs.append((depth, first, got == PRE_EXACT, res[0] + 2 * margin, res[1:4].copy(),
                     out[C.OUT_NORMAL:C.OUT_NORMAL + 3].copy(),
                     np.linalg.norm(res[7:10] - res[4:7] + res[0] * res[1:4]), scale,
                     res.copy()))
    return runs


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("margin", [0.0, 0.04])
def test_exact_depth_matches_gjk_epa(swap, margin):
    runs = _pair_runs(300, 41 + swap + int(100 * margin), margin, swap)
    cores = [r for r in runs if r[0] > 2 * margin + 1e-9 * r[7]]
    assert len(cores) > 60
    # its own proofs (_cyl_gjk's the last) hold only for overlapping pairs, and prove
    # nearly all of them (the rest: GJK's proof, then the kernel again, or EPA)
    proved = [r for r in runs if r[1] == PRE_EXACT]
    assert all(r[0] > 2 * margin for r in proved)
    assert len(proved) >= 0.98 * len(cores)
    assert sum(r[2] for r in cores) >= 0.98 * len(cores)
    for depth, _, dec, h, n, n_ref, resid, scale, _ in runs:
        if dec:
            assert abs(h - depth) <= 2e-8 * scale
            assert np.arccos(np.clip(n @ n_ref, -1.0, 1.0)) < 1e-3
            assert resid <= 1e-12 * scale


@pytest.mark.parametrize("swap", [False, True])
def test_planes_prove_pairs_apart(swap):
    margin = 0.02
    runs = _pair_runs(300, 51 + swap, margin, swap)
    apart = [r for r in runs if r[0] < 2 * margin - 1e-9 * r[7]]
    out = [r for r in runs if r[1] == PRE_APART]
    # (a face's plane, the side's or a cap's, or else _cyl_gjk's)
    assert len(apart) > 60 and len(out) >= 0.98 * len(apart)
    for depth, _, _, h, n, _, _, scale, res in out:
        gap = -(h - 2 * margin)                  # res[0] = -gap, for the cores
        assert gap > 0.0                         # beyond ``stop`` (0 here)
        assert gap <= -depth + 2 * margin + 1e-9 * scale   # a lower bound
        assert abs(np.linalg.norm(n) - 1.0) < 1e-12
        assert abs(n @ (res[7:10] - res[4:7]) - gap) <= 1e-9 * scale


@pytest.mark.parametrize("cutoff", [np.inf, 0.0])
def test_batch_kernel_takes_the_fan_and_agrees_with_gjk_epa(cutoff):
    # cutoff inf: exact distances; 0 (the pipeline's): a plane proving a pair farther
    # apart than the touching band ends it, the gap a lower bound on the distance
    shapes, fan, pairs, pos, quat = pair_cases("cylinder", "convex", 300, seed=61)
    plain = build_table(shapes, prune=False)
    outs, sts = [], []
    for t, cut in ((fan, cutoff), (plain, np.inf)):
        out, st = np.zeros((len(pairs), C.OUT_SIZE)), np.zeros(len(pairs), np.int64)
        collide_batch(t.codes, t.params, t.vrange, t.verts, pairs, pos, quat, C.M_AUTO,
                      cut, out, st)
        outs.append(out)
        sts.append(st)
    radius = fan.params[:, C.P_RADIUS]
    scale = radius[0::2] + radius[1::2]
    assert np.all(np.isfinite(outs[0])) and np.array_equal(sts[0], sts[1])
    deep = outs[1][:, C.OUT_DIST] < -1e-3 * scale
    assert deep.sum() > 80
    assert np.all(np.abs(outs[0][deep, 0] - outs[1][deep, 0]) <= 2e-8 * scale[deep])
    # the fan answered before GJK (one step) or after it in place of EPA
    steps = outs[0][deep, C.OUT_ITERS], outs[1][deep, C.OUT_ITERS]
    assert np.mean(steps[0] == 1) > 0.6 and steps[0].mean() < 0.5 * steps[1].mean()
    sep = sts[0] == C.ST_SEPARATED
    got, exact = outs[0][sep, C.OUT_DIST], outs[1][sep, C.OUT_DIST]
    assert sep.sum() > 50 and np.all(got > 0.0)
    assert np.all(got <= exact + 1e-9 * scale[sep])
    if cutoff == np.inf:
        assert np.all(np.abs(got - exact) <= 1e-8 * scale[sep])
