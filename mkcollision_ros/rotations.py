"""Unit quaternions, xyzw (ROS's order), in numpy: the one rotation helper of the
library, the message adapters, the benchmarks and the tests.  The kernels have their own
scalar forms in kernels/geometry.py (numba), with the same formulas.

Every function takes arrays with any leading axes, (..., 4) quaternions and (..., 3)
vectors, and broadcasts them; a quaternion q rotates v as q v q^-1.  Nothing here
normalises its input unless it says so.
"""
import math

import numpy as np


def quat_to_matrix(q):
    """Rotation matrices (..., 3, 3) of unit quaternions q (..., 4)."""
    q = np.asarray(q, np.float64)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r = np.empty(q.shape[:-1] + (3, 3))
    r[..., 0, 0] = 1 - 2 * (y * y + z * z)
    r[..., 0, 1] = 2 * (x * y - z * w)
    r[..., 0, 2] = 2 * (x * z + y * w)
    r[..., 1, 0] = 2 * (x * y + z * w)
    r[..., 1, 1] = 1 - 2 * (x * x + z * z)
    r[..., 1, 2] = 2 * (y * z - x * w)
    r[..., 2, 0] = 2 * (x * z - y * w)
    r[..., 2, 1] = 2 * (y * z + x * w)
    r[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def quat_mul(a, b):
    """The Hamilton product a b (..., 4): the rotation b, then a."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    ax, ay, az, aw = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bx, by, bz, bw = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz], axis=-1)


def _cross(a, b):
    """Cross product of (..., 3) arrays (broadcasting; np.cross is slow on small ones)."""
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-1)


def quat_rotate(q, v):
    """The vectors v (..., 3) rotated by the unit quaternions q (..., 4)."""
    q, v = np.asarray(q, np.float64), np.asarray(v, np.float64)
    u, w = q[..., :3], q[..., 3:]
    t = 2.0 * _cross(u, v)
    return v + w * t + _cross(u, t)


def quat_axis_angle(axis, angle):
    """Quaternions (..., 4) of turns by ``angle`` (rad, (...)) about ``axis`` (..., 3),
    which is normalised here."""
    axis = np.asarray(axis, np.float64)
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    half = 0.5 * np.asarray(angle, np.float64)
    return np.concatenate([axis * np.sin(half)[..., None], np.cos(half)[..., None]], -1)


def quat_from_z(n):
    """The unit quaternion (4,) turning +z onto the unit vector n (3,) along the shortest
    arc (a half turn about x for n = -z)."""
    c = float(n[2])
    if c < -1.0 + 1e-12:
        return np.array([1.0, 0.0, 0.0, 0.0])
    q = np.array([-float(n[1]), float(n[0]), 0.0, 1.0 + c])
    return q / np.linalg.norm(q)


def matrix_to_quat(R):
    """The unit quaternion (4,) xyzw, w >= 0, of a rotation matrix R (3, 3) (Shepperd's
    method: the largest of w, x, y, z is taken from the diagonal, the others from
    off-diagonal sums and differences).  A matrix printed with finite digits comes back
    as the nearest unit quaternion's rotation, by the final normalisation."""
    R = np.asarray(R, dtype=np.float64)
    t = np.trace(R)
    cands = [t, R[0, 0], R[1, 1], R[2, 2]]
    k = int(np.argmax(cands))
    if k == 0:
        s = 2.0 * math.sqrt(max(1.0 + t, 0.0))
        w = 0.25 * s
        x = (R[2, 1] - R[1, 2]) / s
        y = (R[0, 2] - R[2, 0]) / s
        z = (R[1, 0] - R[0, 1]) / s
    elif k == 1:
        s = 2.0 * math.sqrt(max(1.0 + R[0, 0] - R[1, 1] - R[2, 2], 0.0))
        x = 0.25 * s
        w = (R[2, 1] - R[1, 2]) / s
        y = (R[0, 1] + R[1, 0]) / s
        z = (R[0, 2] + R[2, 0]) / s
    elif k == 2:
        s = 2.0 * math.sqrt(max(1.0 - R[0, 0] + R[1, 1] - R[2, 2], 0.0))
        y = 0.25 * s
        w = (R[0, 2] - R[2, 0]) / s
        x = (R[0, 1] + R[1, 0]) / s
        z = (R[1, 2] + R[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(max(1.0 - R[0, 0] - R[1, 1] + R[2, 2], 0.0))
        z = 0.25 * s
        w = (R[1, 0] - R[0, 1]) / s
        x = (R[0, 2] + R[2, 0]) / s
        y = (R[1, 2] + R[2, 1]) / s
    q = np.array([x, y, z, w])
    q /= np.linalg.norm(q)
    return q if q[3] >= 0 else -q


def random_quat(rng, n):
    """``n`` unit quaternions (n, 4), uniform over rotations (normalised Gaussians)."""
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)
