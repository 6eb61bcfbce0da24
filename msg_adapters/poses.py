"""Pose messages <-> arrays.  Positions (N, 3) in metres, orientations (N, 4) quat_xyzw."""
import struct

import numpy as np
from geometry_msgs.msg import Pose, PoseArray
from mkcollision_msgs.msg import BodyPoseArray

from ._arrays import pack, view


def body_pose_array_to_arrays(msg):
    """``BodyPoseArray`` -> (names list[str], positions (N, 3), orientations (N, 4)).

    The float arrays are read-only zero-copy views of the message.  Raises ValueError
    when the field lengths do not match the stride contract (3 and 4 values per name);
    element values are not checked here (see ``mkcollision_ros.scene.Scene.set_poses``).
    """
    names = list(msg.names)
    n = len(names)
    if len(msg.positions) != 3 * n or len(msg.orientations) != 4 * n:
        raise ValueError(
            f"BodyPoseArray with {n} names needs {3 * n} positions and {4 * n} orientation "
            f"values, got {len(msg.positions)} and {len(msg.orientations)}")
    return names, view(msg.positions).reshape(n, 3), view(msg.orientations).reshape(n, 4)


def arrays_to_body_pose_array(names, positions, orientations, stamp=None, frame_id="world"):
    """Arrays -> ``BodyPoseArray`` (``stamp`` a builtin_interfaces Time or None)."""
    msg = BodyPoseArray()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.names = list(names)
    msg.positions = pack(positions, "d", np.float64)
    msg.orientations = pack(orientations, "d", np.float64)
    return msg


def pose_array_to_arrays(msg):
    """``geometry_msgs/PoseArray`` -> (positions (N, 3), orientations (N, 4)).

    PoseArray carries no names: pose i belongs to the i-th configured body.  One pass
    over the poses (the message is already Python objects; ~0.6 ms per 1,000 poses).
    """
    poses = msg.poses
    flat = np.fromiter(
        (v for p in poses for v in (p.position.x, p.position.y, p.position.z,
                                    p.orientation.x, p.orientation.y, p.orientation.z,
                                    p.orientation.w)),
        dtype=np.float64, count=7 * len(poses)).reshape(-1, 7)
    return flat[:, :3], flat[:, 3:]


def _aligned(at, origin, size):
    return origin + -(-(at - origin) // size) * size


def pose_array_from_cdr(data):
    """A serialized ``geometry_msgs/PoseArray`` (the bytes a ``raw=True`` subscription
    receives: little-endian CDR) -> (sec, nanosec, frame_id, positions (N, 3),
    orientations (N, 4)), the arrays read-only zero-copy views of ``data``.

    A PoseArray is a header then N poses of seven float64 each, so numpy reads them
    in one view instead of rclpy building 3 N Python objects (~4.8 ms at 1,000
    poses).  Raises ValueError for a buffer that is not a little-endian PoseArray."""
    buf = memoryview(data)
    if len(buf) < 20 or buf[0] != 0 or buf[1] != 1:
        raise ValueError("not a little-endian CDR PoseArray")
    origin = 4                          # CDR alignment counts from after the 4-byte header
    sec, nanosec, n = struct.unpack_from("<iII", buf, 4)
    at = 16
    if n < 1 or at + n > len(buf):
        raise ValueError("PoseArray frame_id runs past the end of the buffer")
    frame_id = bytes(buf[at:at + n - 1]).decode("utf-8", errors="replace")
    at = _aligned(at + n, origin, 4)
    if at + 4 > len(buf):
        raise ValueError("PoseArray ends before its pose count")
    (count,) = struct.unpack_from("<I", buf, at)
    at = _aligned(at + 4, origin, 8) if count else at + 4
    if at + 56 * count > len(buf):
        raise ValueError(f"PoseArray of {count} poses needs {at + 56 * count} bytes, got "
                         f"{len(buf)}")
    flat = np.frombuffer(buf, np.float64, 7 * count, at).reshape(count, 7)
    return sec, nanosec, frame_id, flat[:, :3], flat[:, 3:]


def arrays_to_pose_array(positions, orientations, stamp=None, frame_id="world"):
    """Arrays -> ``geometry_msgs/PoseArray`` (for users and tests that publish it)."""
    msg = PoseArray()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    for p, q in zip(np.asarray(positions, float), np.asarray(orientations, float)):
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = (float(v) for v in p)
        (pose.orientation.x, pose.orientation.y, pose.orientation.z,
         pose.orientation.w) = (float(v) for v in q)
        msg.poses.append(pose)
    return msg
