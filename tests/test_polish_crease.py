"""The crease search along a cylinder's side (kernels/polish_crease.py): an ellipsoid
pressed into the side by less than its rolling radius lands on the side's crease from
GJK's early gap."""
import math

import numpy as np
import pytest

import oracles as O
from oracles import pose


@pytest.mark.parametrize("cylinder_is_a", [True, False])
def test_cylinder_side_minimum_on_the_crease_from_gjks_early_gap(cylinder_is_a):
    # An ellipsoid pressed into a cylinder's side (axis z, away from the rims) by less
    # than its rolling radius: the cores stay apart and GJK solves the pair.  The
    # deepest direction is horizontal, on the crease of the cylinder's support function
    # (its support there is a segment of the side), where GJK alone closes its gap
    # slowly.  The crease search (polish_crease._kink_polish) lands on it: the normal is
    # horizontal to round-off and the depth is h(n) to 1e-12 * scale; the cylinder's
    # witness lies on the side.  Once |v| proves that the shapes touch, GJK runs the
    # search from the face test's gap (0.1 |v|^2) rather than from GJK_POLISH_TOL
    # |v|^2: median 10 iterations with it, 15 without.  Depths
    # are checked against the slow oracle's direction search as in the hull test above.
    rng = np.random.default_rng(20)
    cyl = {"type": "cylinder", "radius": 0.9, "height": 2.0}
    iters = []
    for _ in range(50):
        radii = rng.uniform(0.15, 0.35, 3)
        q = O.random_quats(rng, 1)[0]
        r = O.quat_matrix(q)
        sigma = r @ np.diag(radii ** 2) @ r.T
        roll = radii.min() ** 2 / radii.max()
        depth = roll * rng.uniform(0.2, 0.9)
        phi = rng.uniform(0.0, 2.0 * math.pi)
        u = np.array([math.cos(phi), math.sin(phi), 0.0])
        # the ellipsoid's point farthest along -u at 0.9 - depth from the axis
        c = (0.9 - depth) * u + sigma @ u / math.sqrt(u @ sigma @ u)
        c[2] = rng.uniform(-0.5, 0.5)
        ell = {"type": "ellipsoid", "radii": radii.tolist()}
        scale = O.bounding_radius(cyl) + radii.max()
        res, n, h = O.pressed_in(cyl, ell, pose(c, q), cylinder_is_a, scale)
        assert abs(n[2]) <= 1e-12
        assert abs(h + res.distance) <= 1e-12 * scale           # depth == h(normal)
        side = np.asarray(res.point_a if cylinder_is_a else res.point_b)
        assert abs(math.hypot(side[0], side[1]) - 0.9) <= 1e-9 * scale
        assert abs(side[2]) <= 1.0
        iters.append(res.iterations)
    assert np.median(iters) <= 12
