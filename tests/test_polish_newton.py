"""Newton's polish of a smooth minimum (kernels/polish_newton.py): a sphere deep in an
ellipsoid with a margin against the exact depth (oracles.inner_distance), and the
normal Newton's method returns is a stationary point of h_{A-B} on the unit sphere."""
import numpy as np

import oracles as O
from mkcollision_ros.kernels.constants import OUT_DIST, ST_PENETRATING
from oracles import gjk, pose


def test_sphere_deep_in_ellipsoid_with_margin_against_the_exact_depth():
    # An ellipsoid with a margin is no ellipsoid, so a sphere against it goes through
    # GJK/EPA, not the closed form (sphere_shape.has_point_form): with the sphere's centre
    # c inside the ellipsoid E, the depth is c's distance to E's boundary plus the
    # margin and the sphere's radius (the shapes are E and c grown by those radii).
    # EPA takes a Newton minimum there under the 0.5 rad basin cap of pairs with
    # point-like or ellipsoid cores (_polish_is_global), a rule measured on random
    # pairs, not proved (a hull's vertex in an ellipsoid can have a local minimum 0.29
    # rad from a deeper one).  Here 2,000 random deep pairs (on 100,000, all within
    # 3.6e-9 * scale) must be within EPA's
    # tolerance, EPA_REL_TOL = 1e-8 * scale, of the exact depth (the closed form's
    # point-ellipsoid distance, sphere_shape._point_ellipsoid, itself checked against a
    # bisection here).
    from mkcollision_ros.kernels.pairs.sphere_shape import _point_ellipsoid
    from mkcollision_ros.kernels.constants import M_GJK_EPA, OUT_SIZE
    from mkcollision_ros.kernels.narrowphase import collide_batch
    from mkcollision_ros.shapes import build_table
    rng = np.random.default_rng(2025)
    n = 2000
    shapes, pos, quat, want, scale = [], [], [], [], []
    for k in range(n):
        radii = rng.uniform(0.15, 0.5, 3) * (rng.uniform(0.3, 1.0, 3) if k % 2 else 1.0)
        margin = float(rng.choice([1e-6, 1e-3, 0.02]))
        rs = float(rng.uniform(0.001, 0.1))
        y = rng.uniform(-1.0, 1.0, 3) * radii
        while np.sum((y / radii) ** 2) >= 1.0:
            y = rng.uniform(-1.0, 1.0, 3) * radii
        d = _point_ellipsoid(radii[0], radii[1], radii[2], y[0], y[1], y[2])[0]
        if k < 50:
            assert abs(-d - O.inner_distance(np.zeros(3), np.diag(radii ** 2), y)[0]) <= 1e-12
        q = O.random_quats(rng, 1)[0]
        shapes += [{"type": "ellipsoid", "radii": radii.tolist(), "margin": margin},
                   {"type": "sphere", "radius": rs}]
        pos += [[0.0, 0.0, 0.0], (O.quat_matrix(q) @ y).tolist()]
        quat += [q.tolist(), [0.0, 0.0, 0.0, 1.0]]
        want.append(d - margin - rs)
        scale.append(radii.max() + margin + rs)
    t = build_table(shapes)
    out = np.zeros((n, OUT_SIZE))
    st = np.zeros(n, np.int64)
    collide_batch(t.codes, t.params, t.vrange, t.verts, np.arange(2 * n).reshape(-1, 2),
                  np.array(pos), np.array(quat), M_GJK_EPA, np.inf, out, st)
    assert np.all(st == ST_PENETRATING)
    err = np.abs(out[:, OUT_DIST] - np.array(want)) / np.array(scale)
    assert err.max() <= 1e-8, (err.max(), int(np.argmax(err)))


def test_newton_minimum_is_stationary():
    # Newton's method (polish_newton._newton_min_support) ends once the step it would take
    # next is below POLISH_STEP_DONE (1e-6 rad): the normal it returns must be a
    # stationary point of h = h_{A-B} on the unit sphere to that order (|grad| about
    # h'' times the step, h'' ~ scale).  The gradient of h there is the tangential part
    # of the support point s of A - B along the normal, computed here by the numpy
    # oracle; at the exact minimum it is zero.  Deep ellipsoid pairs, with their cores
    # overlapping (EPA's Newton step) or apart (GJK's).  Measured: median |grad|
    # 6.4e-8 * scale, p90 5.6e-7, the largest 1.4e-6 (h then within ~1e-12 * scale of
    # its minimum).
    rng = np.random.default_rng(18)
    grads = []
    for _ in range(200):
        ra, rb = rng.uniform(0.2, 1.0, 3), rng.uniform(0.2, 1.0, 3)
        sa = {"type": "ellipsoid", "radii": ra.tolist()}
        sb = {"type": "ellipsoid", "radii": rb.tolist()}
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        pa = pose([0.0, 0.0, 0.0], O.random_quats(rng, 1)[0])
        pb = pose(u * rng.uniform(0.0, 0.8) * (ra.max() + rb.min()), O.random_quats(rng, 1)[0])
        r = gjk(sa, pa, sb, pb)
        scale = ra.max() + rb.max()
        if not r.depth > 1e-3 * scale:
            continue
        n = np.asarray(r.normal)
        s = []
        for shape, p, d in ((sa, pa, n), (sb, pb, -n)):
            m = O.quat_matrix(np.asarray(p[1]))
            s.append(m @ O.support_np(shape, m.T @ d) + np.asarray(p[0]))
        w = s[0] - s[1]
        assert abs(-(w @ n) - r.distance) <= 1e-12 * scale     # the depth is h(normal)
        grads.append(np.linalg.norm(w - (w @ n) * n) / scale)
    assert len(grads) >= 150
    assert np.quantile(grads, 0.9) <= 1e-6 and max(grads) <= 5e-6
