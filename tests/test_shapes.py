"""Shape dicts: validation with clear errors, OBJ hulls, margins, planes, poses."""
import math

import numpy as np
import pytest

from mkcollision_ros import collide
from mkcollision_ros.shapes import build_table, load_obj_vertices, shape_row, validate_pose

I = [0.0, 0.0, 0.0, 1.0]
OCTAHEDRON = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]


def write_obj(path, points):
    lines = ["# octahedron", "o hull"] + [f"v {x} {y} {z}" for x, y, z in points]
    lines += ["f 1 3 5", "f 3 2 5", "vn 0 0 1"]
    path.write_text("\n".join(lines) + "\n")


def test_obj_mesh_is_the_hull_of_its_vertices(tmp_path):
    obj = tmp_path / "octa.obj"
    write_obj(obj, OCTAHEDRON)
    assert load_obj_vertices(str(obj)).shape == (6, 3)
    sphere = {"type": "sphere", "radius": 0.5}
    rng = np.random.default_rng(3)
    for _ in range(20):
        p = rng.uniform(-1.5, 1.5, 3)
        a = collide({"type": "convex", "mesh": str(obj)}, ([0, 0, 0], I), sphere, (p, I))
        b = collide({"type": "convex", "points": OCTAHEDRON}, ([0, 0, 0], I), sphere, (p, I))
        assert a.distance == pytest.approx(b.distance, abs=1e-12)
        # closed form: distance from p to the octahedron |x|+|y|+|z| <= 1 (outside,
        # in the face region) is (|x|+|y|+|z| - 1)/sqrt(3) when that region applies
        s = np.abs(p)
        if s.sum() > 1 and np.all(s - (s.sum() - 1) / 3 >= 0):
            assert a.distance == pytest.approx((s.sum() - 1) / math.sqrt(3) - 0.5, abs=1e-9)


def test_mesh_path_relative_to_base_dir(tmp_path):
    write_obj(tmp_path / "m.obj", OCTAHEDRON)
    table = build_table([{"type": "convex", "mesh": "m.obj"}], base_dir=str(tmp_path))
    assert table.vrange.tolist() == [[0, 6]]
    with pytest.raises(ValueError, match="no 'v' vertex lines"):
        (tmp_path / "empty.obj").write_text("# nothing\n")
        shape_row({"type": "convex", "mesh": str(tmp_path / "empty.obj")})


def test_margin_grows_the_shape():
    box = {"type": "box", "size": [1.0, 1.0, 1.0], "margin": 0.1}
    r = collide(box, ([0, 0, 0], I), {"type": "sphere", "radius": 0.2}, ([0.75, 0, 0], I))
    assert r.depth == pytest.approx(0.5 + 0.1 + 0.2 - 0.75, abs=1e-12)
    grown = collide({"type": "sphere", "radius": 0.5, "margin": 0.25}, ([0, 0, 0], I),
                    {"type": "sphere", "radius": 0.5}, ([1.2, 0, 0], I))
    assert grown.depth == pytest.approx(0.05, abs=1e-12)


def test_plane_normal_is_normalised_with_its_offset():
    code, prm, _ = shape_row({"type": "plane", "normal": [0, 0, 2.0], "offset": 1.0})
    assert prm[:4].tolist() == [0.0, 0.0, 1.0, 0.5]
    r = collide({"type": "plane", "normal": [0, 0, 2.0], "offset": 1.0}, ([0, 0, 0], I),
                {"type": "sphere", "radius": 0.25}, ([3, 4, 0.6], I))
    assert r.depth == pytest.approx(0.15, abs=1e-12)


@pytest.mark.parametrize("shape, message", [
    ({"radius": 1.0}, "unknown shape type None"),
    ({"type": "torus"}, "unknown shape type 'torus'"),
    ({"type": "sphere", "radius": 1.0, "size": 2}, r"unknown key\(s\) \['size'\]"),
    ({"type": "sphere"}, "'radius' must be a number"),
    ({"type": "sphere", "radius": -1.0}, "'radius' must be > 0"),
    ({"type": "sphere", "radius": 0.0}, "'radius' must be > 0"),
    ({"type": "sphere", "radius": math.inf}, "finite"),
    ({"type": "ellipsoid", "radii": [1.0, math.nan, 1.0]}, "finite"),
    ({"type": "box", "size": [1.0, 1.0]}, "3 numbers"),
    ({"type": "capsule", "radius": 1.0, "length": -0.5}, "'length' must be >= 0"),
    ({"type": "cone", "radius": 1.0, "height": 0.0}, "'height' must be > 0"),
    ({"type": "convex"}, "exactly one of"),
    ({"type": "convex", "points": [[0, 0]]}, r"list of \[x, y, z\]"),
    ({"type": "convex", "points": [[0, 0, math.nan]]}, "finite"),
    ({"type": "plane", "normal": [0, 0, 0], "offset": 0.0}, "non-zero"),
    ({"type": "sphere", "radius": 1.0, "margin": -0.1}, "'margin' must be >= 0"),
    ("sphere", "must be a dict"),
])
def test_invalid_shapes_raise_clear_errors(shape, message):
    with pytest.raises(ValueError, match=message):
        shape_row(shape)


@pytest.mark.parametrize("pose, message", [
    (([0, 0], I), "3 numbers"),
    (([0, 0, 0], [0, 0, 1]), "quaternion 4"),
    (([0, 0, math.nan], I), "finite"),
    (([0, 0, 0], [0, 0, 0, math.inf]), "finite"),
    (([0, 0, 0], [0, 0, 0, 0]), "zero quaternion"),
    (None, "expected"),
])
def test_invalid_poses_raise_clear_errors(pose, message):
    with pytest.raises(ValueError, match=message):
        validate_pose(pose)


def test_non_unit_quaternion_is_normalised():
    p, q = validate_pose(([1, 2, 3], [0, 0, 3.0, 4.0]))
    assert q.tolist() == pytest.approx([0, 0, 0.6, 0.8])


def _core_support_gap(radii, roll, rng, n=400):
    """max over direction pairs (u, v) of u . s_K(v) - u . s_K(u) for the ellipsoid core
    with rolling radius ``roll``: <= 0 (to round-off) iff every s_K(u) is a support
    point of one convex body, i.e. h_E - roll |u| is a support function."""
    from mkcollision_ros.kernels import constants as C
    from mkcollision_ros.kernels.geometry import support_core
    prm = np.zeros(C.N_PARAMS)
    prm[:3] = radii
    prm[C.P_ROLL] = roll
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    pts = np.empty((n, 3))
    for k in range(n):
        support_core(np.int64(C.ELLIPSOID), prm, np.zeros((0, 3)), np.int64(0),
                     np.int64(0), u[k], pts[k])
    vals = u @ pts.T                     # vals[i, j] = u_i . s_K(u_j)
    return float((vals - np.diag(vals)[:, None]).max())


def test_ellipsoid_core_is_convex_and_grows_back_to_the_ellipsoid():
    from mkcollision_ros.kernels import constants as C
    from mkcollision_ros.kernels.geometry import inflation, support_full
    rng = np.random.default_rng(3)
    for radii in ([1.0, 1.0, 1.0], [2.0, 1.0, 0.5], [0.3, 0.05, 0.2], [1e3, 1.0, 2.0]):
        code, prm, _ = shape_row({"type": "ellipsoid", "radii": radii, "margin": 0.01})
        roll = prm[C.P_ROLL]
        assert roll == pytest.approx(min(radii) ** 2 / max(radii))
        assert inflation(code, prm) == pytest.approx(roll + 0.01)
        # core + inflation is the ellipsoid (grown by its margin), along any direction
        a = np.asarray(radii, dtype=float)
        for d in rng.normal(size=(50, 3)):
            x = np.empty(3)
            support_full(code, prm, np.zeros((0, 3)), np.int64(0), np.int64(0), d, x)
            u = d / np.linalg.norm(d)
            e = a * a * u / np.sqrt(np.sum((a * u) ** 2)) + 0.01 * u
            assert np.allclose(x, e, atol=1e-12 * max(radii))
        # the core is convex at the rolling radius, and the check can fail: a radius
        # 30% above the smallest radius of curvature folds the core over itself (near
        # the long axis: random directions find it for moderate axis ratios)
        scale = max(radii)
        assert _core_support_gap(radii, roll, rng) <= 1e-12 * scale
        if 1.0 < max(radii) / min(radii) <= 10.0:
            assert _core_support_gap(radii, 1.3 * roll, rng, n=2000) > 1e-6 * roll
