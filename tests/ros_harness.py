"""Helpers for tests that talk to nodes over real DDS: a private rclpy context per test,
a test node, and spinning until a condition holds.

Importing this module pins ROS_DOMAIN_ID (unless set), so parallel runs on one machine do
not hear each other: from the process id, or, under pytest-xdist, from the run's parent
process id and the worker's number (two workers of one run never share a domain).
"""
import os
import signal
import subprocess
import time


def _domain_id():
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")      # "gw0", "gw1", ...
    if worker.startswith("gw") and worker[2:].isdigit():
        n = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
        slots = max(1, 90 // max(n, 1))
        return 10 + (os.getppid() % slots) * n + int(worker[2:]) % n
    return 10 + os.getpid() % 90


os.environ.setdefault("ROS_DOMAIN_ID", str(_domain_id()))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402


class RosHarness:
    """A private context with one executor; add nodes, spin until something happens."""

    def __init__(self):
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.nodes = []

    def node(self, name):
        n = rclpy.create_node(name, context=self.context)
        self.add(n)
        return n

    def add(self, node):
        self.executor.add_node(node)
        self.nodes.append(node)
        return node

    def spin_until(self, condition, timeout=30.0, step=None):
        """Spin until ``condition()`` is true (calling ``step()`` between spins);
        return whether it became true before ``timeout`` seconds."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if condition():
                return True
            if step is not None:
                step()
            self.executor.spin_once(timeout_sec=0.02)
        return condition()

    def close(self):
        self.executor.shutdown()
        for n in self.nodes:
            n.destroy_node()
        rclpy.try_shutdown(context=self.context)


def start_node(params_file, *ros_args):
    """The installed collision_node, as ``ros2 run`` starts it, output captured; it dies
    with the test process (demo.die_with_parent)."""
    from mkcollision_ros.demo import die_with_parent, node_executable
    return subprocess.Popen([node_executable(), "--ros-args", "--params-file", params_file,
                             *ros_args],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True, preexec_fn=die_with_parent)


def stop(proc, sig=signal.SIGINT):
    """Send ``sig`` to the node's process group (SIGKILL after 20 s); return its output."""
    if proc.poll() is None:
        os.killpg(proc.pid, sig)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.stdout.read()


def run_to_exit(params_file, timeout=240):
    """Start the node and wait for it to exit by itself: (return code, output)."""
    proc = start_node(params_file)
    try:
        proc.wait(timeout=timeout)
    finally:
        log = stop(proc)
    return proc.returncode, log
