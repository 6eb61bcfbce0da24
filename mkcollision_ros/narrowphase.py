"""Public narrow-phase API: one pair of shapes at world poses.

    from mkcollision_ros import collide, distance
    r = collide(shape_a, pose_a, shape_b, pose_b, method="auto")
    d = distance(shape_a, pose_a, shape_b, pose_b)

A shape is a dict (see mkcollision_ros.shapes); a pose is ``(position [x, y, z],
quat_xyzw [x, y, z, w])`` in the world frame, metres (quaternions are normalised).  The
answer is a ``results.CollisionResult`` in the world frame: signed distance (negative
when penetrating), unit normal from A to B, witness points on A and B with
``point_b - point_a == distance * normal``.

Methods: "auto" (closed form when one exists, else GJK/EPA), "gjk_epa", "mpr",
"analytic", "ellipsoid_exact", "ellipsoid_sampled".  Invalid shapes, poses or method
names raise ValueError.
"""
import numpy as np

from .kernels.constants import METHOD_NAMES, OUT_SIZE
from .kernels.narrowphase import collide_batch
from .results import CollisionResult
from .shapes import point_count, shape_row, validate_pose

_METHODS = {name: code for code, name in enumerate(METHOD_NAMES)}
_ONE_PAIR = np.array([[0, 1]], dtype=np.int64)


def _method_code(method):
    if method not in _METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of "
                         f"{', '.join(METHOD_NAMES)}")
    return _METHODS[method]


def _pack(shape, base):
    code, prm, verts = shape_row(shape)
    count = point_count(code, prm, verts)
    return np.int64(code), prm, np.array([base, count], dtype=np.int64), verts


def collide(shape_a, pose_a, shape_b, pose_b, method="auto"):
    """Collide two shapes at world poses with the named method.

    shape_a, shape_b  shape dicts (mkcollision_ros.shapes)
    pose_a, pose_b    (position (3,), quat_xyzw (4,)), world frame, metres
    method            one of "auto", "gjk_epa", "mpr", "analytic", "ellipsoid_exact",
                      "ellipsoid_sampled"
    Returns a CollisionResult (world frame; status NOT_RUN when the method does not
    handle the pair).
    """
    m = _method_code(method)
    ca, pa, va, verts_a = _pack(shape_a, 0)
    cb, pb, vb, verts_b = _pack(shape_b, len(verts_a))
    pos_a, q_a = validate_pose(pose_a, "pose_a")
    pos_b, q_b = validate_pose(pose_b, "pose_b")
    verts = np.ascontiguousarray(np.concatenate([verts_a, verts_b]).reshape(-1, 3),
                                 dtype=np.float64)
    # a batch of one pair: the pipeline's own compiled loop, so collide() gives the
    # pipeline's numbers to the last bit, and no second copy of it is compiled
    out = np.zeros((1, OUT_SIZE))
    status = np.zeros(1, dtype=np.int64)
    collide_batch(np.array([ca, cb]), np.stack([pa, pb]), np.stack([va, vb]), verts,
                  _ONE_PAIR, np.stack([pos_a, pos_b]), np.stack([q_a, q_b]), np.int64(m),
                  np.inf, out, status)
    return CollisionResult.from_row(int(status[0]), out[0])


def distance(shape_a, pose_a, shape_b, pose_b):
    """Signed distance of two shapes (GJK/EPA, or the closed form when one exists):
    the same CollisionResult as ``collide``, with the closest points when apart."""
    return collide(shape_a, pose_a, shape_b, pose_b, method="auto")


def warm_up():
    """Compile (or load from the cache) the pair and batch kernels on tiny inputs."""
    codes = np.array([0, 6], dtype=np.int64)
    params = np.zeros((2, 8))
    params[0, 0] = params[0, 7] = 1.0
    params[1, 7] = 1.0
    vrange = np.array([[0, 0], [0, 4]], dtype=np.int64)
    verts = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0, 0, 0]])
    pairs = np.array([[0, 1]], dtype=np.int64)
    pos = np.array([[0.0, 0, 0], [3.0, 0, 0]])
    quat = np.array([[0.0, 0, 0, 1], [0.0, 0, 0, 1]])
    out = np.zeros((1, OUT_SIZE))
    status = np.zeros(1, dtype=np.int64)
    for m in range(len(METHOD_NAMES)):
        collide_batch(codes, params, vrange, verts, pairs, pos, quat, np.int64(m), np.inf,
                      out, status)
    collide(dict(type="sphere", radius=1.0), ([0, 0, 0], [0, 0, 0, 1]),
            dict(type="box", size=[1, 1, 1]), ([3, 0, 0], [0, 0, 0, 1]))
    collide(dict(type="sphere", radius=1.0), ([0, 0, 0], [0, 0, 0, 1]),
            dict(type="box", size=[1, 1, 1]), ([3, 0, 0], [0, 0, 0, 1]), "gjk_epa")
    return None
