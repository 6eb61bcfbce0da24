"""Traced narrow phase (mkcollision_ros/trace.py and the kernels' trace regions,
kernels/tracebuf.py): on seeded random pairs of every support-mapped shape type, the
traced kernels give bit-identical results, the recorded iterations end where the
answer is (GJK's closest point, EPA's nearest face, MPR's portal), every recorded point
lies in A - B, the sampled hull of A - B holds the origin iff the pair penetrates, and
a small trace region keeps what fits and counts the rest."""
import itertools

import numpy as np
import pytest

import oracles as O
from mkcollision_ros import collide
from mkcollision_ros.kernels.constants import (EPA_FACE_TOL, OUT_DIST, OUT_NORMAL,
                                               OUT_SIZE, ST_PENETRATING, ST_SEPARATED,
                                               TOUCH_TOL)
from mkcollision_ros.kernels.gjk_epa import gjk_epa_ws
from mkcollision_ros.kernels.gjk_epa_workspace import make_gjk_workspace
from mkcollision_ros.kernels.mpr import MPR_WS_ROWS, mpr_ws
from mkcollision_ros.kernels.tracebuf import (TR_EPA, TR_GJK, TR_MPR_DISCOVERY,
                                              TR_MPR_REFINEMENT)
from mkcollision_ros.trace import (TRACE_ROWS, _Pair, _run_gjk_epa, _run_mpr,
                                   minkowski_difference, trace_pair)

PAIR_TYPES = list(itertools.combinations_with_replacement(O.TYPES, 2))
N_PER_TYPE = 8


def _cases(kind_a, kind_b, n=N_PER_TYPE, offset=(0.0, 1.1)):
    """n seeded random pairs (shape_a, pose_a, shape_b, pose_b, scale), every other one
    in the swapped order (the dispatcher then runs it as (B, A))."""
    rng = np.random.default_rng(1000 + 37 * O.TYPES.index(kind_a) + O.TYPES.index(kind_b))
    sa, pa, qa, sb, pb, qb = O.random_pairs(rng, kind_a, kind_b, n, offset=offset)
    out = []
    for k in range(n):
        a, b = (sa[k], (pa[k], qa[k])), (sb[k], (pb[k], qb[k]))
        if k % 2:
            a, b = b, a
        scale = O.bounding_radius(a[0]) + O.bounding_radius(b[0])
        out.append((a[0], a[1], b[0], b[1], scale))
    return out


def _all_cases():
    return [c for a, b in PAIR_TYPES for c in _cases(a, b)]


def _min_norm_point(P):
    """The point of the convex hull of the rows of P (<= 4) nearest the origin, by
    brute force over the subsets (affine projection with non-negative weights)."""
    best = None
    for r in range(1, len(P) + 1):
        for sub in itertools.combinations(range(len(P)), r):
            Q = P[list(sub)]
            E = (Q[1:] - Q[0]).T
            mu = -np.linalg.lstsq(E, Q[0], rcond=None)[0] if r > 1 else np.zeros(0)
            lam = np.concatenate([[1.0 - mu.sum()], mu])
            if lam.min() < -1e-12:
                continue
            x = Q[0] + E @ mu if r > 1 else Q[0]
            if best is None or np.linalg.norm(x) < np.linalg.norm(best):
                best = x
    return best


def _face_planes(V, F):
    """Unit outward normals and offsets of the faces F (by their winding); degenerate
    faces left out."""
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    ln = np.linalg.norm(n, axis=1)
    ok = ln > 0
    n = n[ok] / ln[ok, None]
    return n, np.einsum("ij,ij->i", n, V[F[ok, 0]])


def test_traced_kernels_give_bit_identical_results():
    for sa, pa, sb, pb, _ in _all_cases():
        pair = _Pair(sa, pa, sb, pb)
        args = (pair.sa, pair.sb, pair.verts, pair.r_ab, pair.t_ab)
        out = np.zeros(OUT_SIZE)
        st = gjk_epa_ws(*args, out, make_gjk_workspace(), np.inf)
        st_t, out_t, records, dropped = _run_gjk_epa(pair, TRACE_ROWS, False)
        assert st_t == st and np.array_equal(out_t, out), (sa, pa, sb, pb)
        assert dropped == 0
        out = np.zeros(OUT_SIZE)
        st = mpr_ws(*args, out, np.empty((MPR_WS_ROWS, 3)))
        st_t, out_t, records, dropped = _run_mpr(pair, TRACE_ROWS)
        assert st_t == st and np.array_equal(out_t, out), (sa, pa, sb, pb)
        assert len(records) > 0 and dropped == 0
        # trace_pair's result is collide's, and the method it names
        for method in ("auto", "mpr", "gjk_epa"):
            t = trace_pair(sa, pa, sb, pb, method)
            r = collide(sa, pa, sb, pb, method)
            assert t.result.status == r.status and t.result.distance == r.distance
            assert np.array_equal(t.result.normal, r.normal)
            assert np.array_equal(t.result.point_a, r.point_a)
            assert t.answered_by == r.method
            assert t.traced == ("mpr" if r.method == "mpr" else "gjk_epa")
            if t.traced == "mpr":
                assert t.mpr_portals and not t.gjk_simplices and not t.epa_polytopes
            else:
                assert t.gjk_simplices and not t.mpr_portals


def test_gjk_final_simplex_is_at_the_core_distance():
    n_apart = 0
    for sa, pa, sb, pb, scale in _all_cases():
        pair = _Pair(sa, pa, sb, pb)
        st, out, records, _ = _run_gjk_epa(pair, TRACE_ROWS, True)
        simplices = [p for k, p, _ in records if k == TR_GJK]
        assert 1 <= len(simplices[-1]) <= 4
        if st != ST_SEPARATED or out[OUT_DIST] < 1e-6 * scale:
            continue
        n_apart += 1
        core = out[OUT_DIST] + pair.core_radius
        v = np.linalg.norm(_min_norm_point(simplices[-1]))
        # the simplex lies in the cores' difference: |v| >= the distance; GJK stops
        # on its duality gap or polishes from a gap of 0.1 |v|^2 (gjk._gjk)
        assert v >= core - 1e-9 * scale
        assert v - core <= 0.1 * v + 1e-9 * scale, (sa, pa, sb, pb, v, core)
    assert n_apart > 50


def test_epa_final_polytope_is_at_the_depth():
    n_deep = n_face = 0
    for sa, pa, sb, pb, scale in _all_cases():
        pair = _Pair(sa, pa, sb, pb)
        st, out, records, _ = _run_gjk_epa(pair, TRACE_ROWS, True)
        polytopes = [(p, f.astype(np.int64)) for k, p, f in records if k == TR_EPA]
        if st != ST_PENETRATING or not polytopes:
            continue
        n_deep += 1
        V, F = polytopes[-1]
        normals, offsets = _face_planes(V, F)
        # a closed convex polytope about the origin, wound outward
        assert np.all(offsets > -1e-9 * scale)
        assert np.all(V @ normals.T <= offsets + 1e-9 * scale)
        depth_core = -out[OUT_DIST] - pair.core_radius
        # the nearest face is EPA's lower bound on the depth
        near = int(np.argmin(offsets))
        assert offsets[near] <= depth_core + 1e-9 * scale
        if np.abs(normals[near] - out[OUT_NORMAL:OUT_NORMAL + 3]).max() < 1e-12:
            # EPA ended on its gap: the answer is that face, the depth its distance
            n_face += 1
            assert abs(depth_core - offsets[near]) <= 1e-12 * scale, (sa, pa, sb, pb)
        else:
            # a polished minimum ended EPA, from a gain of EPA_FACE_TOL * scale at most
            assert depth_core - offsets[near] <= EPA_FACE_TOL * scale, (sa, pa, sb, pb)
    assert n_deep > 30 and n_face > 10


def test_mpr_final_portal_is_crossed_by_the_origin_ray():
    n_deep = 0
    for sa, pa, sb, pb, scale in _all_cases():
        pair = _Pair(sa, pa, sb, pb)
        st, out, records, _ = _run_mpr(pair, TRACE_ROWS)
        if st != ST_PENETRATING:
            continue
        kind, w, _ = records[-1]
        if kind == TR_MPR_DISCOVERY:
            # the origin on the segment v0-v1 (symmetric pairs): the ray meets v1
            assert len(w) == 2
            assert np.linalg.norm(np.cross(w[0], w[1])) <= 1e-12 * scale ** 2
            assert np.dot(w[0], w[1]) <= 0.0
            continue
        n_deep += 1
        assert kind == TR_MPR_REFINEMENT and len(w) == 4
        # v0 + t (0 - v0) = l1 v1 + l2 v2 + l3 v3, l1 + l2 + l3 = 1: t > 0, l >= 0
        A = np.column_stack([w[1] - w[0], w[2] - w[0], w[3] - w[0]])
        m = np.linalg.solve(A, -w[0])            # -v0 = sum m_i (v_i - v0)
        t = 1.0 / m.sum()
        assert t > 0.0
        assert (m * t).min() >= -1e-9, (sa, pa, sb, pb, m)
    assert n_deep > 30


def test_traces_lie_in_the_sampled_minkowski_difference():
    n_in = n_out = 0
    for sa, pa, sb, pb, scale in _all_cases():
        V, T = minkowski_difference(sa, pa, sb, pb)
        assert T.dtype == np.int32 and np.array_equal(np.unique(T), np.arange(len(V)))
        normals, offsets = _face_planes(V, T.astype(np.int64))
        assert len(normals) == len(T)
        # outward winding: every hull vertex below every face plane
        assert np.all(V @ normals.T <= offsets + 1e-9 * scale)
        # vertices on A - B: h(n) along each face normal is at least the face offset;
        # their gap is the sampling error, and the planes at h(n) enclose A - B
        h = O.cso_support(sa, pa, sb, pb, normals)
        err = h - offsets
        assert err.min() >= -1e-9 * scale
        grown = h + 1e-9 * scale
        for method in ("auto", "mpr"):
            t = trace_pair(sa, pa, sb, pb, method)
            pts = [p for _, p in t.mpr_portals] + t.gjk_simplices
            pts += [p for p, _ in t.epa_polytopes]
            for p in pts:
                assert np.all(p @ normals.T <= grown), (sa, pa, sb, pb, method)
            for p, f in t.epa_polytopes:
                # world-frame faces wound outward too: the centroid below each
                n_t, off_t = _face_planes(p, f.astype(np.int64))
                assert np.all(n_t @ p.mean(axis=0) <= off_t + 1e-9 * scale)
        # the origin inside the hull iff the pair penetrates, away from the band
        # that the sampling error leaves undecided
        r = collide(sa, pa, sb, pb, "gjk_epa")
        if abs(r.distance) > err.max() + TOUCH_TOL * scale:
            inside = bool(np.all(offsets > 0.0))
            assert inside == (r.distance < 0.0), (sa, pa, sb, pb)
            n_in += inside
            n_out += not inside
    assert n_in > 30 and n_out > 30


def test_small_trace_region_keeps_what_fits():
    for sa, pa, sb, pb, _ in _cases("ellipsoid", "box", offset=(0.0, 0.3)):
        full = trace_pair(sa, pa, sb, pb, "gjk_epa")
        rows = 2 + 40
        small = trace_pair(sa, pa, sb, pb, "gjk_epa", rows=rows)
        assert full.dropped == 0
        seq_full = full.gjk_simplices + [p for p, _ in full.epa_polytopes]
        seq_small = small.gjk_simplices + [p for p, _ in small.epa_polytopes]
        assert len(seq_small) + small.dropped == len(seq_full)
        assert small.dropped > 0
        # the kept records are the full run's, in order, none larger than the region
        it = iter(seq_full)
        assert all(any(np.array_equal(q, p) for p in it) for q in seq_small)
        used = (sum(1 + len(p) for p in small.gjk_simplices)
                + sum(1 + len(p) + len(f) for p, f in small.epa_polytopes))
        assert used <= rows - 2
    # MPR likewise
    sa, pa, sb, pb, _ = _cases("box", "convex", offset=(0.0, 0.3))[0]
    full = trace_pair(sa, pa, sb, pb, "mpr")
    small = trace_pair(sa, pa, sb, pb, "mpr", rows=2 + 12)
    assert len(small.mpr_portals) + small.dropped == len(full.mpr_portals)
    assert small.dropped > 0 and len(small.mpr_portals) > 0
    assert sum(1 + len(p) for _, p in small.mpr_portals) <= 12


def test_planes_and_bad_input_raise():
    plane = {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}
    ball = {"type": "sphere", "radius": 1.0}
    pose = ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="plane"):
        trace_pair(ball, pose, plane, pose)
    with pytest.raises(ValueError, match="plane"):
        minkowski_difference(plane, pose, ball, pose)
    with pytest.raises(ValueError, match="rows"):
        trace_pair(ball, pose, ball, pose, rows=1)
    with pytest.raises(ValueError, match="directions"):
        minkowski_difference(ball, pose, ball, pose, directions=np.zeros((5, 2)))
