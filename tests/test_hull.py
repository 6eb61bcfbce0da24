"""A convex shape's points pruned to those its hull needs (mkcollision_ros.hull): every
hull vertex kept, only strictly interior points dropped, degenerate sets kept whole,
and the kernels' results unchanged bit for bit."""
import itertools

import numpy as np
import pytest

from mkcollision_ros.hull import (FAN_MAX_POINTS, GROUP_MIN_POINTS,
                                  GROUP_SIZE, HULL_MIN_POINTS, hull_keep,
                                  hull_points, support_groups)
from mkcollision_ros.kernels import constants as C
from mkcollision_ros.kernels.geometry import support_core_xyz
from mkcollision_ros.kernels.narrowphase import collide_batch
from mkcollision_ros.shapes import build_table, point_count, shape_row


def brute_planes(P):
    """Oracle: the planes (unit normal, offset) of every triple of points that has all
    the points on one side (within 1e-12 of the extent): the hull's facet planes and
    their triangulations, by exhaustion.  Returns (normals (K, 3), offsets (K,),
    triples (K, 3))."""
    size = np.linalg.norm(P.max(0) - P.min(0))
    tri = np.array(list(itertools.combinations(range(len(P)), 3)))
    normals, offsets, kept = [], [], []
    for block in np.array_split(tri, max(1, len(tri) // 20000)):
        a, b, c = P[block[:, 0]], P[block[:, 1]], P[block[:, 2]]
        n = np.cross(b - a, c - a)
        ln = np.linalg.norm(n, axis=1)
        ok = ln > 1e-12 * size * size
        n, a, block = n[ok] / ln[ok, None], a[ok], block[ok]
        d = np.einsum("ij,ij->i", n, a)
        s = P @ n.T - d
        up = (s <= 1e-12 * size).all(0)
        down = (s >= -1e-12 * size).all(0)
        for sel, sign in ((up, 1.0), (down & ~up, -1.0)):
            normals.append(sign * n[sel])
            offsets.append(sign * d[sel])
            kept.append(block[sel])
    return np.concatenate(normals), np.concatenate(offsets), np.concatenate(kept)


def clouds(rng):
    """Seeded point sets of 65-110 points: blobs with many interior points, shells with
    none, a box with points on its faces and edges and inside, far from the origin, tiny
    and huge."""
    out = []
    for k in range(12):
        n = int(rng.integers(HULL_MIN_POINTS + 1, 110))
        kind = k % 4
        if kind == 0:
            P = rng.normal(size=(n, 3)) * rng.uniform(0.2, 2.0, 3)
        elif kind == 1:
            d = rng.normal(size=(n, 3))
            P = d / np.linalg.norm(d, axis=1, keepdims=True) * rng.uniform(0.5, 1.5, 3)
        elif kind == 2:
            g = np.array(list(itertools.product([-1.0, -0.5, 0.0, 0.5, 1.0], repeat=3)))
            P = g[rng.permutation(len(g))[:n]] * rng.uniform(0.1, 1.0, 3)
        else:
            P = rng.uniform(-1.0, 1.0, size=(n, 3))
        scale = [1.0, 1e-4, 1e3][k % 3]
        offset = rng.normal(size=3) * (1e5 if k % 5 == 0 else 1.0)
        out.append(P * scale + offset * scale)
    return out


def test_hull_keeps_every_vertex_and_drops_only_interior_points():
    rng = np.random.default_rng(20261127)
    dropped_any = 0
    for P in clouds(rng):
        keep = hull_keep(P)
        assert np.all(np.diff(keep) > 0)            # ascending, no repeats
        normals, offsets, triples = brute_planes(P)
        size = np.linalg.norm(P.max(0) - P.min(0))
        # every point on a facet triple is kept (a hull vertex or on its boundary)
        assert set(np.unique(triples).tolist()) <= set(keep.tolist())
        # every dropped point lies strictly below every facet plane
        gone = np.setdiff1d(np.arange(len(P)), keep)
        if len(gone):
            assert (P[gone] @ normals.T - offsets).max() < 0.0
        # and every point well inside (1e-6 of the extent) is dropped
        deep = (P @ normals.T - offsets).max(1) < -1e-6 * size
        assert set(np.flatnonzero(deep).tolist()) <= set(gone.tolist())
        dropped_any += len(gone)
        # the first support point along any direction is the same point
        U = rng.normal(size=(2000, 3))
        assert np.array_equal(np.argmax(P @ U.T, axis=0),
                              keep[np.argmax(P[keep] @ U.T, axis=0)])
    assert dropped_any > 0


@pytest.mark.parametrize("name", ["flat", "collinear", "one point", "thin slab"])
def test_degenerate_sets_are_kept_whole_or_pruned_safely(name):
    rng = np.random.default_rng(5)
    n = 90
    P = rng.normal(size=(n, 3))
    if name == "flat":
        P[:, 2] = 0.25
    elif name == "collinear":
        P = np.outer(rng.normal(size=n), [1.0, 2.0, -0.5])
    elif name == "one point":
        P = np.tile([1.0, 2.0, 3.0], (n, 1))
    else:
        P[:, 2] *= 1e-3
    keep = hull_keep(P)
    if name != "thin slab":
        assert len(keep) == n
    else:
        normals, offsets, triples = brute_planes(P)
        assert set(np.unique(triples).tolist()) <= set(keep.tolist())
        assert len(keep) < n


def test_small_sets_are_not_pruned_and_large_ones_are():
    rng = np.random.default_rng(7)
    blob = rng.normal(size=(HULL_MIN_POINTS, 3))
    assert len(hull_points(blob)[0]) == HULL_MIN_POINTS and not len(hull_points(blob)[1])
    big = rng.normal(size=(500, 3))
    code, prm, verts = shape_row({"type": "convex", "points": big.tolist()})
    vn = point_count(code, prm, verts)
    assert vn < 100                                  # a Gaussian blob's hull: ~50 of 500
    assert prm[C.P_GROUPS] == 0                      # too few for groups
    assert (prm[C.P_FAN_FACES] > 0) == (vn <= FAN_MAX_POINTS)   # its fan if small
    verts = verts[:vn]
    # the same bounding radius (the farthest point is a vertex) and the given order
    assert prm[C.P_RADIUS] == pytest.approx(np.linalg.norm(big, axis=1).max(), rel=1e-15)
    idx = [int(np.flatnonzero((big == v).all(1))[0]) for v in verts]
    assert idx == sorted(idx)
    # the cache answers a repeated set with the same points
    assert np.array_equal(hull_points(big)[0], verts)


OTHERS = [{"type": "sphere", "radius": 0.3}, {"type": "box", "size": [0.5, 0.3, 0.4]},
          {"type": "cylinder", "radius": 0.25, "height": 0.6},
          {"type": "ellipsoid", "radii": [0.4, 0.2, 0.3]},
          {"type": "capsule", "radius": 0.15, "length": 0.4}]


def paired(clouds_, others):
    """Each cloud as a convex shape against each of ``others`` and against the first
    cloud: shapes (2k, 2k + 1) are pair k."""
    shapes = []
    for P in clouds_:
        for o in others + [{"type": "convex", "points": clouds_[0].tolist()}]:
            shapes += [{"type": "convex", "points": P.tolist()}, o]
    return shapes


def run_rounds(table, method, reps=40):
    """Statuses and outputs of ``reps`` rounds of seeded random poses over the table's
    pairs (2k, 2k + 1), the rounds stacked."""
    n = len(table.codes) // 2
    pairs = np.arange(2 * n, dtype=np.int64).reshape(n, 2)
    prng = np.random.default_rng(3)
    outs, sts = [], []
    for _ in range(reps):
        pos = prng.normal(size=(2 * n, 3)) * 0.35
        q = prng.normal(size=(2 * n, 4))
        q /= np.linalg.norm(q, axis=1, keepdims=True)
        out = np.zeros((n, C.OUT_SIZE))
        st = np.zeros(n, dtype=np.int64)
        collide_batch(table.codes, table.params, table.vrange, table.verts, pairs, pos, q,
                      np.int64(method), np.inf, out, st)
        outs.append(out)
        sts.append(st)
    return np.concatenate(outs), np.concatenate(sts)


def test_kernels_give_identical_results_with_the_pruned_points():
    """The whole point set against its pruned copy, through the batched kernel: GJK/EPA
    (and auto) give the same statuses, distances, normals and witness points bit for
    bit; MPR the same statuses.

    Not the same: the iteration count (one case in 1,440 here) and MPR's depth and
    normal, because a convex shape's interior point (geometry.centre_core, GJK's first
    direction and MPR's portal origin) is the mean of its points, which moves when
    interior points go; MPR's depth along its portal depends on that point (one of
    its documented errors against EPA)."""
    rng = np.random.default_rng(11)
    clouds_ = [rng.normal(size=(300, 3)) * [0.3, 0.5, 0.4] for _ in range(4)]
    clouds_ += [rng.uniform(-0.4, 0.4, size=(200, 3)) for _ in range(2)]
    shapes = paired(clouds_, OTHERS)
    pruned = build_table(shapes)
    whole = build_table(shapes, prune=False)
    # hulls of at most FAN_MAX_POINTS kept points carry their normal fan, which answers
    # an ellipsoid's pairs by another method (kernels/pairs/ellipsoid_convex.py): off here
    params = pruned.params.copy()
    fan = pruned.codes == C.CONVEX
    assert np.all(params[fan, C.P_FAN_FACES] > 0)
    params[np.ix_(fan, [C.P_FAN_FACES, C.P_FAN_EDGES, C.P_FAN_VERTS])] = 0.0
    pruned = pruned._replace(params=params)
    assert np.array_equal(pruned.params, whole.params)
    assert len(pruned.verts) < len(whole.verts)
    for method in (C.M_AUTO, C.M_GJK_EPA, C.M_MPR):
        results = {name: run_rounds(t, method) for name, t in (("pruned", pruned),
                                                               ("whole", whole))}
        (o1, s1), (o2, s2) = results["pruned"], results["whole"]
        hit = (s1 == C.ST_PENETRATING) | (s1 == C.ST_TOUCHING)
        assert 0 < hit.sum() < len(hit)              # both regimes are exercised
        assert np.array_equal(s1, s2)
        if method != C.M_MPR:
            cols = np.arange(C.OUT_SIZE) != C.OUT_ITERS
            assert np.array_equal(o1[:, cols], o2[:, cols])


def test_groups_cover_every_point_once_in_compact_runs():
    rng = np.random.default_rng(19)
    d = rng.normal(size=(700, 3))
    P = d / np.linalg.norm(d, axis=1, keepdims=True)
    Q, rows = support_groups(P)
    ng = len(rows) // 2
    assert ng >= 700 // GROUP_SIZE
    starts, counts = rows[1::2, 1].astype(int), rows[1::2, 2].astype(int)
    assert np.array_equal(starts, np.concatenate([[0], np.cumsum(counts)[:-1]]))
    assert counts.sum() == 700 and counts.max() <= GROUP_SIZE
    # the same points, each once
    assert np.array_equal(np.sort(Q.view("f8,f8,f8").ravel()), np.sort(P.view("f8,f8,f8").ravel()))
    # every run inside its ball, and the balls small beside the set (compact runs)
    for g in range(ng):
        run = Q[starts[g]:starts[g] + counts[g]]
        assert np.linalg.norm(run - rows[2 * g], axis=1).max() <= rows[2 * g + 1, 0]
    assert rows[1::2, 0].max() < 0.5
    # small sets: as given, no rows
    assert len(support_groups(P[:GROUP_MIN_POINTS])[1]) == 0


def test_grouped_support_is_the_pass_maximum():
    """The compiled support of hulls stored in groups against a pass over the same
    points (groups switched off), along random directions and the axes (ties)."""
    rng = np.random.default_rng(23)
    d = rng.normal(size=(900, 3))
    sets = [d / np.linalg.norm(d, axis=1, keepdims=True) * [0.5, 0.2, 0.3],
            rng.normal(size=(20000, 3)) * [1.0, 0.3, 2.0],
            d[:400] / np.linalg.norm(d[:400], axis=1, keepdims=True) * 1e-3 + 1e4]
    U = np.concatenate([rng.normal(size=(3000, 3)), np.eye(3), -np.eye(3),
                        [[1.0, 1.0, 0.0], [0.0, -1.0, 1.0]]])
    for P in sets:
        code, prm, rows = shape_row({"type": "convex", "points": P.tolist()})
        vn = point_count(code, prm, rows)
        if len(P) != 20000:                    # (a blob's ~50 hull points: no groups)
            assert prm[C.P_GROUPS] > 0
        passing = prm.copy()
        passing[C.P_GROUPS] = 0.0
        for u in U:
            a = support_core_xyz(code, prm, rows, 0, vn, u[0], u[1], u[2])
            b = support_core_xyz(code, passing, rows, 0, vn, u[0], u[1], u[2])
            va = a[0] * u[0] + a[1] * u[1] + a[2] * u[2]
            vb = b[0] * u[0] + b[1] * u[1] + b[2] * u[2]
            assert va == vb
            assert np.any(np.all(rows[:vn] == a, axis=1))


def test_kernels_agree_on_hulls_stored_in_groups():
    """Shells (every point a hull vertex, stored in groups) against the same points
    kept whole and passed over: the same statuses, distances within EPA's tolerance
    (another of tied support points may end EPA elsewhere in its band)."""
    rng = np.random.default_rng(29)
    shells = []
    for _ in range(3):
        d = rng.normal(size=(300, 3))
        shells.append(0.4 * d / np.linalg.norm(d, axis=1, keepdims=True))
    shapes = []
    for shell in shells:
        shapes += paired([shell], OTHERS[:4])
    grouped = build_table(shapes)
    assert np.all(grouped.params[grouped.codes == C.CONVEX, C.P_GROUPS] > 0)
    whole = build_table(shapes, prune=False)
    reps = 40
    scale = np.tile(grouped.params[0::2, C.P_RADIUS] + grouped.params[1::2, C.P_RADIUS], reps)
    o1, s1 = run_rounds(grouped, C.M_GJK_EPA, reps)
    o2, s2 = run_rounds(whole, C.M_GJK_EPA, reps)
    assert np.array_equal(s1, s2)
    assert np.all(np.abs(o1[:, C.OUT_DIST] - o2[:, C.OUT_DIST]) <= C.EPA_REL_TOL * scale)
    hits = int(((s1 == C.ST_PENETRATING) | (s1 == C.ST_TOUCHING)).sum())
    assert 0 < hits < len(s1)
