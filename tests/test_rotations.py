"""mkcollision_ros/rotations.py against the kernels' scalar forms and against each other:
the matrix of a product is the product of the matrices, rotating a vector is the matrix
times it, and the matrix -> quaternion -> matrix round trip is exact to rounding."""
import numpy as np
import pytest

from mkcollision_ros import rotations as R
from mkcollision_ros.kernels.geometry import quat_to_matrix as kernel_quat_to_matrix


@pytest.fixture
def quats():
    return R.random_quat(np.random.default_rng(5), 200)


def test_matrices_are_rotations_and_equal_the_kernels(quats):
    m = R.quat_to_matrix(quats)
    assert m.shape == (200, 3, 3)
    assert np.allclose(m @ np.swapaxes(m, 1, 2), np.eye(3), atol=1e-14)
    assert np.allclose(np.linalg.det(m), 1.0, atol=1e-14)
    for q, mq in zip(quats[:20], m[:20]):
        assert np.array_equal(mq, kernel_quat_to_matrix(q))
    assert np.array_equal(R.quat_to_matrix(quats[0]), m[0])     # one quaternion, (4,)


def test_product_and_rotation_follow_the_matrices(quats):
    a, b = quats[:100], quats[100:]
    ab = R.quat_mul(a, b)
    assert np.allclose(R.quat_to_matrix(ab), R.quat_to_matrix(a) @ R.quat_to_matrix(b),
                       atol=1e-14)
    v = np.random.default_rng(6).normal(size=(100, 3))
    want = np.einsum("nij,nj->ni", R.quat_to_matrix(a), v)
    assert np.allclose(R.quat_rotate(a, v), want, atol=1e-13)


def test_axis_angle_and_from_z():
    q = R.quat_axis_angle([0.0, 0.0, 2.0], np.pi / 2)     # the axis is normalised
    assert np.allclose(R.quat_rotate(q, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-15)
    rng = np.random.default_rng(7)
    for n in list(rng.normal(size=(20, 3))) + [np.array([0.0, 0.0, -1.0]),
                                                np.array([0.0, 0.0, 1.0])]:
        n = n / np.linalg.norm(n)
        q = R.quat_from_z(n)
        assert abs(np.linalg.norm(q) - 1.0) < 1e-15
        assert np.allclose(R.quat_rotate(q, [0.0, 0.0, 1.0]), n, atol=1e-14)


def test_matrix_to_quat_round_trip(quats):
    # every branch of Shepperd's method: the largest of w, x, y, z in turn
    special = np.array([[0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0],
                        [0.0, 0.0, 1.0, 0.0]])
    for q in np.concatenate([quats, special]):
        back = R.matrix_to_quat(R.quat_to_matrix(q))
        assert back[3] >= 0.0
        assert np.allclose(back, q if q[3] >= 0 else -q, atol=1e-14)
