"""Pose messages <-> arrays.  Positions (N, 3) in metres, orientations (N, 4) quat_xyzw."""
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
