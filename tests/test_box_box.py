"""The box-box separating-axis closed form (kernels/pairs/box_box.py, what ``auto``
runs for two boxes) against GJK/EPA on seeded random pairs: same status, depth and
normal, or an equally deep normal where two axes tie."""
import math

import numpy as np
import pytest

import oracles as O
from mkcollision_ros import collide
from oracles import gjk


# --- box-box separating-axis closed form (auto) against GJK/EPA ----------------------------
def test_collide_box_box_matches_gjk_epa():
    """auto runs SAT for boxes whose cores overlap (else GJK): the depth must equal
    GJK/EPA's (both exact for polytopes), the normal must be certified (its support value
    is the depth) and agree with EPA's where the minimum is unique, and the witness points
    must be on the surfaces with pb - pa = distance * normal."""
    rng = np.random.default_rng(2024)
    n, n_sat, n_edge_like = 400, 0, 0
    for k in range(n):
        sa = O.random_shape(rng, "box")
        sb = O.random_shape(rng, "box")
        if k % 3 == 0:
            sb["margin"] = float(rng.uniform(0.0, 0.2))
        q = O.random_quats(rng, 2)
        pa = ([0.0, 0.0, 0.0], q[0].tolist())
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        pb = ((u * rng.uniform(0.0, 1.6)).tolist(), q[1].tolist())
        if k % 7 == 0:      # aligned faces (flat contact features)
            pb = ((u * rng.uniform(0.0, 1.6)).tolist(), q[0].tolist())
        scale = O.bounding_radius(sa) + O.bounding_radius(sb)
        r = collide(sa, pa, sb, pb, method="auto")
        g = gjk(sa, pa, sb, pb)
        assert r.status == g.status or abs(g.distance) < 1e-6 * scale
        assert r.distance == pytest.approx(g.distance, abs=1e-9 * scale)
        assert r.point_b - r.point_a == pytest.approx(r.distance * r.normal, abs=1e-9 * scale)
        assert abs(O.surface_gap(sa, pa, r.point_a, r.normal)) < 1e-9 * scale
        assert abs(O.surface_gap(sb, pb, r.point_b, -r.normal)) < 1e-9 * scale
        h = O.cso_support(sa, pa, sb, pb, r.normal[None, :])[0]
        assert r.distance == pytest.approx(-h, abs=1e-9 * scale)
        if r.method == "analytic":
            n_sat += 1
            # the normal is EPA's unless another direction is (nearly) as deep
            hg = O.cso_support(sa, pa, sb, pb, g.normal[None, :])[0]
            if abs(r.distance) > 1e-3 * scale:
                ang = math.acos(min(1.0, float(r.normal @ g.normal)))
                if ang > 1e-3:
                    n_edge_like += 1
                    assert abs(h - hg) < 1e-7 * scale   # a tie: both minimise h
    assert n_sat > 0.3 * n
    assert n_edge_like < 0.05 * n
