"""Fast DDS's shared-memory segment is 0.5 MB, so the pose and contact messages of large
scenes (a BodyPoseArray of ~8,000 bodies, a ContactArray of ~4,000 contacts) would go
over UDP in fragments, and a best-effort subscriber on a busy machine loses them whole.
The node, the demo and the benchmarks' processes take the package's profile with a 16 MB
segment (config/fastdds_large_messages.xml) unless the user names a profile file.  Fast
DDS reads it when the first participant is made: call before rclpy.init."""
import os

LARGE_MESSAGES_PROFILE = os.path.join("config", "fastdds_large_messages.xml")


def use_large_messages_profile():
    """Point Fast DDS at the package's large-messages profile, unless another RMW is
    chosen or a profile file is already named.  Returns the profile's path, or None."""
    if os.environ.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp") not in ("", "rmw_fastrtps_cpp"):
        return None
    if os.environ.get("FASTRTPS_DEFAULT_PROFILES_FILE") or os.environ.get(
            "FASTDDS_DEFAULT_PROFILES_FILE"):
        return None
    from ament_index_python.packages import PackageNotFoundError, get_package_share_directory
    try:
        path = os.path.join(get_package_share_directory("mkcollision_ros"),
                            LARGE_MESSAGES_PROFILE)
    except PackageNotFoundError:
        return None
    if not os.path.isfile(path):
        return None
    os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] = path
    return path
