"""Broad phase against a brute-force oracle on seeded scenes (1 to 10,000 bodies)."""
import numpy as np
import pytest

from mkcollision_ros.kernels.broadphase import find_pairs, world_aabbs
from mkcollision_ros.kernels.constants import PLANE
from mkcollision_ros.kernels.geometry import quat_to_matrix
from mkcollision_ros.shapes import build_table
from oracles import random_quats


def random_shapes(rng, n, plane_every=0):
    out = []
    for i in range(n):
        if plane_every and i % plane_every == plane_every - 1:
            out.append({"type": "plane", "normal": list(rng.normal(size=3)),
                        "offset": float(rng.normal())})
            continue
        k = i % 6
        if k == 0:
            out.append({"type": "sphere", "radius": float(rng.uniform(0.05, 0.5))})
        elif k == 1:
            out.append({"type": "box", "size": list(rng.uniform(0.05, 1.0, 3)),
                        "margin": 0.01})
        elif k == 2:
            out.append({"type": "capsule", "radius": 0.1, "length": 0.4})
        elif k == 3:
            out.append({"type": "convex", "points": rng.normal(scale=0.3, size=(7, 3)).tolist()})
        elif k == 4:
            out.append({"type": "cylinder", "radius": 0.2, "height": 0.3})
        else:
            out.append({"type": "ellipsoid", "radii": list(rng.uniform(0.05, 0.4, 3))})
    return out


def aabbs(table, pos, quat, grow=0.0):
    n = len(table.codes)
    lo, hi, pw = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 4))
    world_aabbs(table.codes, table.params, table.vrange, table.verts, pos, quat, grow,
                lo, hi, pw)
    return lo, hi, pw


def brute_pairs(lo, hi, is_plane, pw):
    """The obvious oracle: every pair, closed intervals, in chunks of rows."""
    n = len(lo)
    keys = []
    body = np.flatnonzero(~is_plane)
    for s in range(0, len(body), 500):
        rows = body[s:s + 500]
        ov = np.all((lo[rows, None, :] <= hi[None, body, :])
                    & (lo[None, body, :] <= hi[rows, None, :]), axis=2)
        ii, jj = np.nonzero(ov)
        a, b = rows[ii], body[jj]
        keep = a < b
        keys.append(a[keep] * n + b[keep])
    for p in np.flatnonzero(is_plane):
        nw, dw = pw[p, :3], pw[p, 3]
        corner = np.where(nw > 0, lo[body], hi[body])
        hit = body[corner @ nw <= dw]
        keys.append(np.minimum(hit, p) * n + np.maximum(hit, p))
    k = np.sort(np.concatenate(keys)) if keys else np.zeros(0, np.int64)
    return np.stack([k // n, k % n], axis=1)


def sampled_extent(table, i, pos, quat, m=4000, seed=1):
    """Oracle for one AABB: the max of x . e_k over many support points."""
    from mkcollision_ros.kernels.geometry import support_full
    rng = np.random.default_rng(seed)
    r = quat_to_matrix(quat)
    best_hi = np.full(3, -np.inf)
    best_lo = np.full(3, np.inf)
    out = np.empty(3)
    for d in rng.normal(size=(m, 3)):
        support_full(table.codes[i], table.params[i], table.verts, table.vrange[i, 0],
                     table.vrange[i, 1], d, out)
        w = pos + r @ out
        best_hi = np.maximum(best_hi, w)
        best_lo = np.minimum(best_lo, w)
    return best_lo, best_hi


def test_aabbs_are_tight_and_conservative():
    rng = np.random.default_rng(3)
    shapes = random_shapes(rng, 12)
    t = build_table(shapes)
    pos = rng.normal(size=(12, 3))
    quat = random_quats(rng, 12)
    lo, hi, _ = aabbs(t, pos, quat)
    for i in range(12):
        slo, shi = sampled_extent(t, i, pos[i], quat[i])
        # every sampled support point is inside, and the box is nearly reached
        assert np.all(slo >= lo[i] - 1e-12) and np.all(shi <= hi[i] + 1e-12)
        assert np.all(shi >= hi[i] - 0.02) and np.all(slo <= lo[i] + 0.02)


def test_plane_aabb_and_grow():
    t = build_table([{"type": "plane", "normal": [0, 0, 1], "offset": 0.5, "margin": 0.1},
                     {"type": "sphere", "radius": 1.0}])
    pos = np.array([[0.0, 0.0, 1.0], [2.0, 0.0, 0.0]])
    quat = np.array([[0, 0, 0, 1.0], [0, 0, 0, 1.0]])
    lo, hi, pw = aabbs(t, pos, quat, grow=0.25)
    assert np.all(np.isinf(lo[0])) and lo[0].min() < 0
    assert hi[0, 0] == np.inf and hi[0, 1] == np.inf
    assert hi[0, 2] == pytest.approx(1.0 + 0.5 + 0.1 + 0.25)
    assert np.allclose(pw[0], [0, 0, 1, 1.85])
    assert np.allclose(lo[1], [0.75, -1.25, -1.25]) and np.allclose(hi[1], [3.25, 1.25, 1.25])
    # flipped plane (normal -z): the half-space z >= -d
    quat[0] = [1.0, 0, 0, 0]   # 180 deg about x
    lo, hi, pw = aabbs(t, pos, quat)
    assert hi[0, 2] == np.inf and lo[0, 2] == pytest.approx(1.0 - 0.6)


@pytest.mark.parametrize("n, layout, seed", [
    (1, "random", 0), (2, "random", 1), (7, "random", 2), (60, "random", 3),
    (500, "random", 4), (3000, "random", 5), (10000, "random", 6),
    (300, "stacked", 7), (2000, "line", 8), (400, "grid_touching", 9),
    (800, "far_clusters", 10), (600, "slabs", 11),
])
def test_find_pairs_matches_brute_force(n, layout, seed):
    """Both grids against brute force: the dense one (every layout but far clusters,
    whose table would be too large: the hashed grid), with big bodies (slabs) tested
    against every body."""
    rng = np.random.default_rng(seed)
    shapes = random_shapes(rng, n, plane_every=0 if n > 3000 else 97)
    t = build_table(shapes)
    quat = random_quats(rng, n)
    if layout == "random":
        half = 0.8 * max(n, 1) ** (1 / 3)
        pos = rng.uniform(-half, half, size=(n, 3))
    elif layout == "stacked":
        pos = np.zeros((n, 3)) + 0.3
    elif layout == "line":
        pos = np.zeros((n, 3))
        pos[:, 0] = np.arange(n) * 0.37
    elif layout == "far_clusters":          # two dense clusters 1.7 km apart
        pos = rng.uniform(-3.0, 3.0, size=(n, 3))
        pos[n // 2:] += 1000.0
    elif layout == "slabs":                 # small boxes among a few 8 m slabs
        shapes = [{"type": "box", "size": [8.0, 8.0, 0.2] if k % 100 == 0 else
                   [0.4, 0.3, 0.5]} for k in range(n)]
        t = build_table(shapes)
        pos = rng.uniform(-4.0, 4.0, size=(n, 3))
    else:  # boxes of side 1 on an integer grid: faces touch exactly (closed intervals)
        shapes = [{"type": "box", "size": [1.0, 1.0, 1.0]} for _ in range(n)]
        t = build_table(shapes)
        k = int(round(n ** 0.5))
        pos = np.zeros((n, 3))
        pos[:, 0] = np.arange(n) % k
        pos[:, 1] = np.arange(n) // k
        quat = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    is_plane = t.codes == PLANE
    lo, hi, pw = aabbs(t, pos, quat, grow=0.01)
    pairs, order, kind = find_pairs(lo, hi, is_plane, pw, np.empty(0, np.int64), -1)
    assert kind == (0 if layout == "far_clusters" else 1)
    want = brute_pairs(lo, hi, is_plane, pw)
    assert pairs.dtype == np.int64 and pairs.shape == want.shape
    assert np.array_equal(pairs, want)
    if len(pairs):
        assert np.all(pairs[:, 0] < pairs[:, 1])
    if layout == "stacked":
        m = int((~is_plane).sum())
        assert len(pairs) >= m * (m - 1) // 2
    if layout == "grid_touching":
        assert len(pairs) > 2 * n   # faces and corners touching count as overlapping
    # warm start: jiggle, re-run with the previous order, compare to a cold run
    pos2 = pos + rng.normal(scale=0.02, size=pos.shape)
    lo2, hi2, pw2 = aabbs(t, pos2, quat, grow=0.01)
    warm, _, _ = find_pairs(lo2, hi2, is_plane, pw2, order, -1)
    cold, _, _ = find_pairs(lo2, hi2, is_plane, pw2, np.empty(0, np.int64), -1)
    assert np.array_equal(warm, cold)
    assert np.array_equal(warm, brute_pairs(lo2, hi2, is_plane, pw2))


def test_random_scenes_are_representative():
    """The seeded random layout is neither empty nor all-pairs (hit rate of bodies)."""
    rng = np.random.default_rng(4)
    n = 500
    t = build_table(random_shapes(rng, n))
    half = 0.8 * n ** (1 / 3)
    pos = rng.uniform(-half, half, size=(n, 3))
    lo, hi, pw = aabbs(t, pos, random_quats(rng, n))
    pairs, _, _ = find_pairs(lo, hi, t.codes == PLANE, pw, np.empty(0, np.int64), -1)
    touched = np.zeros(n, bool)
    touched[pairs.ravel()] = True
    assert 0.3 <= touched.mean() <= 0.7


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_static_pairs_match_brute_force(seed):
    """The static grid's query against the brute-force oracle: every moving-static pair
    whose closed boxes overlap, once, with static bodies of every size (some big enough
    to be kept out of the cells), moving ones inside, across and outside the grid (one
    over very many cells), boxes touching exactly at a face."""
    from mkcollision_ros.kernels.broadphase import static_grid, static_pairs
    rng = np.random.default_rng(seed)
    ns, nm = 600, 80
    c = rng.uniform(0, 20, (ns, 3))
    half = rng.uniform(0.05, 0.6, (ns, 3))
    half[:5] = rng.uniform(5, 12, (5, 3))                  # big: out of the cells
    lo_s, hi_s = c - half, c + half
    cm = rng.uniform(-3, 23, (nm, 3))
    hm = rng.uniform(0.05, 1.0, (nm, 3))
    lo_m, hi_m = cm - hm, cm + hm
    lo_m[0], hi_m[0] = -1.0, 21.0                          # over every cell
    lo_m[1], hi_m[1] = 40.0, 41.0                          # outside the grid
    lo_m[2], hi_m[2] = hi_s[10], hi_s[10] + 0.5            # touching a corner exactly
    frame, keys, members, start, big = static_grid(lo_s, hi_s)
    assert len(big) >= 1 and np.all(np.diff(keys) >= 0) and len(start) > 1
    ov = np.all((lo_m[:, None] <= hi_s[None]) & (lo_s[None] <= hi_m[:, None]), axis=2)
    want = np.argwhere(ov)
    # the table of each cell's entries, and bisection in the keys (large grids)
    for table in (start, np.zeros(0, np.int64)):
        got = static_pairs(lo_m, hi_m, lo_s, hi_s, frame, keys, members, table, big)
        assert np.array_equal(got, want)
    assert [2, 10] in got.tolist()


def test_static_grid_of_no_bodies_answers_no_pairs():
    from mkcollision_ros.kernels.broadphase import static_grid, static_pairs
    lo_s = np.zeros((0, 3))
    grid = static_grid(lo_s, lo_s)
    got = static_pairs(np.zeros((2, 3)), np.ones((2, 3)), lo_s, lo_s, *grid)
    assert got.shape == (0, 2)
