"""The collision node: ROS wiring around ``mkcollision_ros.pipeline.Pipeline``.

Topics (names are parameters, relative to the node's namespace):
  in   ``body_poses``       mkcollision_msgs/BodyPoseArray   poses by body name
  in   ``pose_array``       geometry_msgs/PoseArray          poses in configured body order
  out  ``contacts``         mkcollision_msgs/ContactArray    every step's contacts
  out  ``contact_markers``  visualization_msgs/MarkerArray   points + normal arrows
Services:
  ``check_collision``       mkcollision_msgs/srv/CheckCollision  stateless query

The node owns one ``scene.Scene`` (bodies, filters, stamped poses); pose messages
write into it.  One timer at ``rate_hz`` steps the pipeline on the newest poses once any
pose has arrived; the ContactArray carries the stamp of the newest pose message.  A
body that has not received a pose yet (and is not static or given an initial pose)
does not collide.

Bad input never stops the node: malformed messages are dropped, bad entries inside a
message (unknown names, NaN, zero quaternions) are dropped one by one, each with a
throttled warning; the rest is applied.  A broken configuration is reported in one
clear line and the process exits with status 1 before spinning.
"""
import time

import numpy as np
import rclpy
from geometry_msgs.msg import PoseArray
from mkcollision_msgs.msg import BodyPoseArray, ContactArray
from mkcollision_msgs.srv import CheckCollision
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from visualization_msgs.msg import MarkerArray

import msg_adapters

from .config import bodies_from_params
from .kernels import constants as C
from .pipeline import Pipeline, PipelineConfig
from .query import query_contacts
from .scene import POSE_PROBLEMS, Scene, pose_problems

# name, default, description.  The type is the default's type; floats must be written
# with a decimal point in YAML.  Bounds are checked in ``_read_parameters``.
PARAMETERS = (
    ("frame_id", "world", "frame of the poses and of every published point"),
    ("rate_hz", 30.0, "collision steps per second (> 0)"),
    ("method", "auto", "narrow-phase method: auto | gjk_epa | mpr"),
    ("contact_margin", 0.001, "m (>= 0); a touching pair keeps touching within this gap"),
    ("proximity", 0.0, "m (>= 0); pairs this close are measured (library: StepResult.proximity)"),
    ("merge_distance", 0.02, "m (> 0); a new contact this close to a stored one updates it"),
    ("drift_threshold", 0.01, "m (> 0); a stored contact whose points drift this far is dropped"),
    ("max_contacts", 4, "contacts kept per touching pair (>= 1)"),
    ("stale_steps", 3, "steps an unconfirmed pair is kept (>= 1)"),
    ("publish_markers", True, "publish the MarkerArray"),
    ("marker_normal_length", 0.2, "m; length of the normal arrows"),
    ("max_marker_arrows", 500, "cap on normal arrows per MarkerArray"),
    ("warn_throttle_s", 2.0, "s; minimum interval between repeated input warnings"),
    ("pose_topic", "body_poses", "BodyPoseArray input topic"),
    ("pose_array_topic", "pose_array", "geometry_msgs/PoseArray input topic"),
    ("contacts_topic", "contacts", "ContactArray output topic"),
    ("markers_topic", "contact_markers", "MarkerArray output topic"),
)
METHODS = {"auto": C.M_AUTO, "gjk_epa": C.M_GJK_EPA, "mpr": C.M_MPR}


class ConfigError(ValueError):
    """The node's parameters cannot describe a valid scene."""


class CollisionNode(Node):
    def __init__(self, node_name="collision_node", **node_kwargs):
        # Body parameters are free-form (their keys depend on the shape), so every
        # override is declared; the fixed parameters of PARAMETERS get defaults.
        super().__init__(node_name, automatically_declare_parameters_from_overrides=True,
                         **node_kwargs)
        self.cfg = self._read_parameters()
        bodies = bodies_from_params(
            {f"bodies.{k}": p.value
             for k, p in self.get_parameters_by_prefix("bodies").items()})
        self.scene = Scene(bodies)
        self.pipeline = Pipeline(self.scene, config=PipelineConfig(
            method=self.cfg["method"], contact_margin=self.cfg["contact_margin"],
            proximity=self.cfg["proximity"], merge_distance=self.cfg["merge_distance"],
            drift_threshold=self.cfg["drift_threshold"], max_contacts=self.cfg["max_contacts"],
            stale_steps=self.cfg["stale_steps"]))
        t0 = time.perf_counter()
        self.pipeline.warm_up()
        self.get_logger().info(
            f"{len(self.scene)} bodies loaded; kernels ready in {time.perf_counter() - t0:.2f} s")

        reliable = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
        self.sub_named = self.create_subscription(
            BodyPoseArray, self.cfg["pose_topic"], self._on_body_poses, reliable)
        self.sub_array = self.create_subscription(
            PoseArray, self.cfg["pose_array_topic"], self._on_pose_array, reliable)
        self.pub_contacts = self.create_publisher(ContactArray, self.cfg["contacts_topic"], 10)
        self.pub_markers = self.create_publisher(MarkerArray, self.cfg["markers_topic"], 10)
        self.srv_check = self.create_service(CheckCollision, "check_collision",
                                             self._on_check_collision)
        # PoseArray poses go to the configured bodies in their order
        self.order = np.array([self.scene.index[b["name"]] for b in bodies], np.int64)
        self.stamp = None
        self.steps = 0
        self.timer = self.create_timer(1.0 / self.cfg["rate_hz"], self._on_timer)

    # -- parameters ---------------------------------------------------------------
    def _read_parameters(self):
        cfg = {}
        for name, default, description in PARAMETERS:
            if not self.has_parameter(name):
                self.declare_parameter(name, default)
            value = self.get_parameter(name).value
            if isinstance(default, float) and isinstance(value, int) \
                    and not isinstance(value, bool):
                value = float(value)  # YAML `30` for a float parameter: accept it
            if type(value) is not type(default):
                raise ConfigError(f"parameter '{name}' ({description}) must be a "
                                  f"{type(default).__name__}, got {value!r}")
            cfg[name] = value
        checks = (
            ("rate_hz", cfg["rate_hz"] > 0.0), ("proximity", cfg["proximity"] >= 0.0),
            ("contact_margin", cfg["contact_margin"] >= 0.0),
            ("merge_distance", cfg["merge_distance"] > 0.0),
            ("drift_threshold", cfg["drift_threshold"] > 0.0),
            ("max_contacts", cfg["max_contacts"] >= 1), ("stale_steps", cfg["stale_steps"] >= 1),
            ("marker_normal_length", cfg["marker_normal_length"] >= 0.0),
            ("max_marker_arrows", cfg["max_marker_arrows"] >= 0),
            ("warn_throttle_s", cfg["warn_throttle_s"] >= 0.0),
            ("method", cfg["method"] in METHODS),
        )
        for name, ok in checks:
            if not ok:
                desc = dict((n, d) for n, _, d in PARAMETERS)[name]
                raise ConfigError(f"parameter '{name}' = {cfg[name]!r} is invalid: {desc}")
        if not self.get_parameters_by_prefix("bodies"):
            raise ConfigError("no bodies configured: give a params file with bodies.names "
                              "and one block per body (see config/collision_node.yaml)")
        return cfg

    # -- input --------------------------------------------------------------------
    def _warn(self, text):
        self.get_logger().warning(text, throttle_duration_sec=self.cfg["warn_throttle_s"])

    def _on_body_poses(self, msg):
        try:
            names, pos, quat = msg_adapters.body_pose_array_to_arrays(msg)
        except ValueError as err:
            self._warn(f"dropped a BodyPoseArray: {err}")
            return
        _, problems = self.scene.set_poses(names, pos, quat, _seconds(msg.header.stamp))
        self._accept(msg.header.stamp, problems, "BodyPoseArray")

    def _on_pose_array(self, msg):
        n = len(self.order)
        if len(msg.poses) != n:
            self._warn(f"dropped a PoseArray with {len(msg.poses)} poses: the node has {n} "
                       f"bodies, and PoseArray poses are matched to bodies by order")
            return
        pos, quat = msg_adapters.pose_array_to_arrays(msg)
        _, problems = self.scene.set_poses_at(self.order, pos, quat,
                                              _seconds(msg.header.stamp))
        self._accept(msg.header.stamp, problems, "PoseArray")

    def _accept(self, stamp, problems, kind):
        if problems:
            shown = "; ".join(problems[:5]) + (" ..." if len(problems) > 5 else "")
            self._warn(f"{kind}: dropped {len(problems)} bad entr"
                       f"{'y' if len(problems) == 1 else 'ies'}: {shown}")
        self.stamp = stamp

    # -- the step -----------------------------------------------------------------
    def _on_timer(self):
        if self.stamp is None:
            return
        try:
            res = self.pipeline.step(stamp=_seconds(self.stamp))
        except Exception as err:  # noqa: BLE001 - the node must keep running
            self.get_logger().error(f"collision step failed, skipped: {err!r}",
                                    throttle_duration_sec=self.cfg["warn_throttle_s"])
            return
        self.steps += 1
        frame = self.cfg["frame_id"]
        self.pub_contacts.publish(
            msg_adapters.contacts_to_contact_array(res, self.stamp, frame))
        if self.cfg["publish_markers"]:
            self.pub_markers.publish(msg_adapters.contacts_to_marker_array(
                res, self.stamp, frame, self.cfg["marker_normal_length"],
                self.cfg["max_marker_arrows"]))

    # -- services -----------------------------------------------------------------
    def _on_check_collision(self, request, response):
        try:
            contacts, missing = self._check(request)
        except ValueError as err:
            response.success = False
            response.message = str(err)
            return response
        response.success = True
        response.contacts = msg_adapters.contacts_to_contact_list(contacts)
        response.message = f"{len(response.contacts)} touching pair(s)"
        if missing:
            response.message += f"; skipped bodies without a pose: {missing}"
        return response

    def _check(self, request):
        sc = self.scene
        names = list(request.names) or [n for n in sc.names if n is not None]
        unknown = [n for n in names if n not in sc]
        if unknown:
            raise ValueError(f"unknown bodies: {unknown}")
        if len(set(names)) != len(names):
            raise ValueError("names has duplicates")
        idx = np.array([sc.index[n] for n in names], dtype=np.int64)
        pos, quat = sc.positions.copy(), sc.orientations.copy()
        posed = sc.posed.copy()
        if len(request.positions) or len(request.orientations):
            _, gp, gq = msg_adapters.body_pose_array_to_arrays(request)
            bad = [f"{n}: {POSE_PROBLEMS[why]}" for n, why in zip(names, pose_problems(gp, gq))
                   if why]
            if bad:
                raise ValueError("bad poses: " + "; ".join(bad))
            pos[idx], quat[idx] = gp, gq / np.linalg.norm(gq, axis=1)[:, None]
            posed[idx] = True
        missing = [n for n, i in zip(names, idx) if not posed[i]]
        idx = idx[posed[idx]]
        contacts = query_contacts(sc.table, sc.names, idx, pos, quat, sc.static,
                                  METHODS[self.cfg["method"]])
        return contacts, missing


def _seconds(stamp):
    """builtin_interfaces/Time -> float seconds."""
    return stamp.sec + 1e-9 * stamp.nanosec


def main(args=None):
    rclpy.init(args=args)
    node = None
    code = 0
    try:
        node = CollisionNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ValueError as err:  # ConfigError and invalid bodies: one clear line, exit 1
        rclpy.logging.get_logger("collision_node").fatal(f"invalid configuration: {err}")
        code = 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


if __name__ == "__main__":
    raise SystemExit(main())
