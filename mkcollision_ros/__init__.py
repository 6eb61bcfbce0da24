"""mkcollision_ros: convex collision detection (GJK/EPA, MPR, closed forms) in numba,
usable as a plain Python library; the ROS 2 node lives in a separate module and is the
only part that imports rclpy (or rerun)."""
from .narrowphase import collide, distance, warm_up
from .results import CollisionResult, Status

__all__ = ["collide", "distance", "warm_up", "CollisionResult", "Status"]
