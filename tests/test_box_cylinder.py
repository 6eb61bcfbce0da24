"""A box and a cylinder in closed form before GJK (kernels/pairs/box_cylinder.py): the
certified depth is exact and global, against EPA on the box as a convex hull and the slow
oracle, in both orders."""
import math

import numpy as np
import pytest

import oracles as O
from mkcollision_ros.kernels.constants import OUT_DIST, OUT_NORMAL, OUT_PA, OUT_PB, ST_PENETRATING


def _box_hull(box):
    """The box as a convex hull of its eight corners (the same solid, solved by EPA)."""
    hx, hy, hz = (0.5 * s for s in box["size"])
    return {"type": "convex", "points": [[x, y, z] for x in (-hx, hx) for y in (-hy, hy)
                                         for z in (-hz, hz)]}


@pytest.mark.parametrize("cylinder_is_a", [False, True])
def test_box_cylinder_closed_form_depth_is_exact_and_global(cylinder_is_a):
    # A box and a cylinder whose cores overlap are solved in closed form with a
    # certificate (kernels/pairs/box_cylinder.py), EPA running only where it cannot certify (a
    # minimum on a box edge against a rim point, ~10% of random pairs).  The same
    # solid as a convex hull of the box's corners goes through EPA: statuses must
    # agree, depths within EPA's tolerance (EPA reports its nearest face, at most
    # EPA_REL_TOL * scale below the true depth; the closed form reports h_{A-B} along
    # its normal, the true depth to round-off where certified), normals within 1e-3
    # rad on pairs deeper than 1e-3 * scale.  Certified pairs have depth == h(normal)
    # to 1e-12 * scale and their witnesses on the two surfaces (support points along
    # +-n); at least 80% of the penetrating pairs must be (measured: 90%).
    rng = np.random.default_rng(23)
    n = 2000
    sb, pb, qb, sc, pc, qc = O.random_pairs(rng, "box", "cylinder", n, offset=(0.0, 0.8))
    sh = [_box_hull(s) for s in sb]
    if cylinder_is_a:
        out, st = O.run_batch(sc, pc, qc, sb, pb, qb)
        out_h, st_h = O.run_batch(sc, pc, qc, sh, pb, qb)
    else:
        out, st = O.run_batch(sb, pb, qb, sc, pc, qc)
        out_h, st_h = O.run_batch(sh, pb, qb, sc, pc, qc)
    scale = np.array([O.bounding_radius(a) + O.bounding_radius(b) for a, b in zip(sb, sc)])
    d, d_h = out[:, OUT_DIST], out_h[:, OUT_DIST]
    clear = np.abs(d_h) > 1e-6 * scale
    assert np.array_equal(st[clear], st_h[clear])
    pen = (st == ST_PENETRATING) & (st_h == ST_PENETRATING) & (d < -1e-6 * scale)
    assert pen.sum() >= 800
    assert np.all(np.abs(d[pen] - d_h[pen]) <= 2e-8 * scale[pen])
    deep = pen & (d < -1e-3 * scale)
    cos = np.sum(out[deep, OUT_NORMAL:OUT_NORMAL + 3] * out_h[deep, OUT_NORMAL:OUT_NORMAL + 3], 1)
    assert np.all(cos >= math.cos(1e-3))
    exact = 0
    for k in np.flatnonzero(pen):
        a, pa_, b, pb_ = ((sc[k], (pc[k], qc[k]), sb[k], (pb[k], qb[k])) if cylinder_is_a
                          else (sb[k], (pb[k], qb[k]), sc[k], (pc[k], qc[k])))
        nrm = out[k, OUT_NORMAL:OUT_NORMAL + 3]
        h = O.cso_support(a, pa_, b, pb_, nrm[None])[0]
        if abs(h + d[k]) > 1e-12 * scale[k]:
            continue
        exact += 1
        # the closed form is global: never shallower than EPA's lower bound
        assert d[k] <= d_h[k] + 1e-12 * scale[k]
        assert abs(O.surface_gap(a, pa_, out[k, OUT_PA:OUT_PA + 3], nrm)) <= 1e-9 * scale[k]
        assert abs(O.surface_gap(b, pb_, out[k, OUT_PB:OUT_PB + 3], -nrm)) <= 1e-9 * scale[k]
    assert exact >= 0.8 * pen.sum()
