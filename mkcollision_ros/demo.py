"""The demo: moving bodies published to the real collision node, and a summary.

``demo`` (``python -m mkcollision_ros.demo``) starts the installed ``collision_node``
executable as a subprocess with a params file (default: the package's
``config/collision_node.yaml``), publishes ``BodyPoseArray`` messages of the configured
bodies moving on crossing orbits for ``--seconds``, listens to ``contacts`` and prints
what happened.  ``demo_publisher`` runs only the publisher, for use beside a node
started with ``ros2 run``.
"""
import argparse
import os
import signal
import subprocess
import sys
import time

import numpy as np

from .config import bodies_from_params, load_params_file


def demo_poses(n_bodies, t):
    """Poses of ``n_bodies`` at time ``t`` (s): dynamic bodies circle on two rings of
    radius 0.9 and 1.3 m at different angular speeds, so they meet every few seconds,
    and bob through z = 0.15..0.55 m over a floor at z = 0.
    Returns positions (N, 3), quat_xyzw (N, 4)."""
    i = np.arange(n_bodies, dtype=np.float64)
    ring = np.where(i % 2 == 0, 0.9, 1.3)
    omega = 0.6 + 0.25 * (i % 3) * np.where(i % 4 < 2, 1.0, -1.0)
    phase = 2.0 * np.pi * i / max(n_bodies, 1)
    angle = omega * t + phase
    pos = np.stack([ring * np.cos(angle), ring * np.sin(angle),
                    0.35 + 0.2 * np.sin(1.3 * t + 1.7 * i)], axis=1)
    half = 0.5 * (0.8 + 0.3 * i) * t          # spin about a tilted axis
    axis = np.stack([np.sin(i), np.cos(i), np.ones_like(i)], axis=1)
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    quat = np.concatenate([axis * np.sin(half)[:, None], np.cos(half)[:, None]], axis=1)
    return pos, quat


def default_params_file():
    """The installed package's config (ament index), else the source tree's."""
    try:
        from ament_index_python.packages import get_package_share_directory
        path = os.path.join(get_package_share_directory("mkcollision_ros"), "config",
                            "collision_node.yaml")
        if os.path.exists(path):
            return path
    except (ImportError, LookupError):
        pass
    return os.path.join(os.path.dirname(__file__), "..", "config", "collision_node.yaml")


def node_executable():
    """Path of the installed ``collision_node`` (what ``ros2 run`` would start)."""
    from ament_index_python.packages import get_package_prefix
    return os.path.join(get_package_prefix("mkcollision_ros"), "lib", "mkcollision_ros",
                        "collision_node")


def die_with_parent():
    """``preexec_fn`` for a child node: the kernel sends it SIGTERM when the process that
    started it dies, even by SIGKILL, so no node is left running (Linux prctl
    PR_SET_PDEATHSIG; elsewhere a no-op).  The child also gets its own session, so the
    parent stops it with one killpg."""
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)          # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


class DemoPublisher:
    """Publishes the demo motion of the bodies of a params file (an rclpy node)."""

    def __init__(self, node, params_file, rate_hz=30.0, topic="body_poses"):
        from mkcollision_msgs.msg import BodyPoseArray

        bodies = bodies_from_params(load_params_file(params_file))
        self.names = [b["name"] for b in bodies if not b["static"]]
        self.node = node
        self.pub = node.create_publisher(BodyPoseArray, topic, 10)
        self.t0 = time.monotonic()
        self.sent = 0
        self.timer = node.create_timer(1.0 / rate_hz, self.publish)

    def publish(self):
        from msg_adapters import arrays_to_body_pose_array

        pos, quat = demo_poses(len(self.names), time.monotonic() - self.t0)
        msg = arrays_to_body_pose_array(self.names, pos, quat,
                                        self.node.get_clock().now().to_msg())
        self.pub.publish(msg)
        self.sent += 1


class ContactTally:
    """Subscribes to ``contacts`` and counts what arrives."""

    def __init__(self, node, topic="contacts"):
        from mkcollision_msgs.msg import ContactArray

        self.reset()
        self.sub = node.create_subscription(ContactArray, topic, self.on_contacts, 10)

    def reset(self):
        self.steps = 0
        self.contacts = 0
        self.max_depth = 0.0
        self.pairs = set()
        self.ids = set()

    def on_contacts(self, msg):
        self.steps += 1
        self.contacts += len(msg.depths)
        if len(msg.depths):
            self.max_depth = max(self.max_depth, float(max(msg.depths)))
        self.pairs.update(zip(msg.body_a, msg.body_b))
        self.ids.update(int(i) for i in msg.ids)


def run(seconds, params_file, node_cmd=None, out=sys.stdout):
    """Start the node, publish for ``seconds``, print and return the summary dict."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    node_cmd = node_cmd or [node_executable()]
    bodies = bodies_from_params(load_params_file(params_file))
    print(f"[demo] starting the collision node: {' '.join(node_cmd)} "
          f"--ros-args --params-file {params_file}", file=out, flush=True)
    t_start = time.monotonic()
    proc = subprocess.Popen(node_cmd + ["--ros-args", "--params-file", params_file],
                            start_new_session=True, preexec_fn=die_with_parent)
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("mkcollision_demo", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        tally = ContactTally(node)
        # wait for the node's first ContactArray before the clock starts, so a first
        # numba compile does not eat into the demo time
        pub = DemoPublisher(node, params_file)
        deadline = time.monotonic() + 600.0   # a first compile takes ~170 s, more when loaded
        while tally.steps == 0 and time.monotonic() < deadline and proc.poll() is None:
            executor.spin_once(timeout_sec=0.1)
        if tally.steps == 0:
            raise RuntimeError("the collision node did not answer "
                               f"(exit code {proc.poll()}); see its log above")
        ready = time.monotonic() - t_start
        tally.reset()  # count from here
        end = time.monotonic() + seconds
        while time.monotonic() < end and proc.poll() is None:
            executor.spin_once(timeout_sec=0.05)
        summary = {
            "bodies": len(bodies), "moving_bodies": len(pub.names), "seconds": seconds,
            "node_ready_s": round(ready, 2), "pose_messages": pub.sent,
            "steps": tally.steps, "contacts_seen": tally.contacts,
            "pairs_touching": len(tally.pairs), "distinct_contact_ids": len(tally.ids),
            "max_depth_m": round(tally.max_depth, 4),
        }
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
    print("[demo] summary", file=out)
    for key, value in summary.items():
        print(f"  {key:22s} {value}", file=out)
    pairs = sorted(tally.pairs)
    print("  touching pairs: " + ", ".join(f"{a}-{b}" for a, b in pairs[:20])
          + (" ..." if len(pairs) > 20 else ""), file=out, flush=True)
    return summary


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0,
                        help="how long to publish after the node is ready (default 10)")
    parser.add_argument("--params-file", default=None,
                        help="node params file (default: the package's collision_node.yaml)")
    args = parser.parse_args(argv)
    summary = run(args.seconds, os.path.abspath(args.params_file or default_params_file()))
    return 0 if summary["steps"] > 0 else 1


def publisher_main(argv=None):
    """Only the demo publisher (beside a node started with ``ros2 run``)."""
    import rclpy
    from rclpy.executors import ExternalShutdownException

    parser = argparse.ArgumentParser(description="publish the demo motion")
    parser.add_argument("--params-file", default=None)
    parser.add_argument("--rate", type=float, default=30.0)
    args, ros_args = parser.parse_known_args(argv)
    rclpy.init(args=ros_args)
    node = rclpy.create_node("mkcollision_demo_publisher")
    try:
        DemoPublisher(node, args.params_file or default_params_file(), args.rate)
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    raise SystemExit(main())
