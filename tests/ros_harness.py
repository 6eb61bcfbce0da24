"""Helpers for tests that talk to nodes over real DDS: a private rclpy context per test,
a test node, and spinning until a condition holds.

Importing this module pins ROS_DOMAIN_ID to a value derived from the process id (unless
set), so parallel runs on one machine do not hear each other.
"""
import os
import time

os.environ.setdefault("ROS_DOMAIN_ID", str(10 + os.getpid() % 90))
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
