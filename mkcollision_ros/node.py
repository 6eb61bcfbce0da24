"""The collision node: ROS wiring around ``mkcollision_ros.scene.Scene`` and
``mkcollision_ros.pipeline.Pipeline``.

Topics (names are parameters, relative to the node's namespace):
  in   ``body_poses``       mkcollision_msgs/BodyPoseArray   poses by body name
  in   ``pose_array``       geometry_msgs/PoseArray          poses in configured body order
  in   ``bodies.<name>.pose_topic``  geometry_msgs/PoseStamped  one body's pose (optional)
  out  ``contacts``         mkcollision_msgs/ContactArray    every step's contacts
  out  ``contact_markers``  visualization_msgs/MarkerArray   points + normal arrows
  out  ``contact_events``   mkcollision_msgs/ContactEvents   pairs and contacts that
                                                             began or ended
  out  ``proximity``        mkcollision_msgs/ProximityArray  near pairs (proximity > 0)
  out  ``scene``            mkcollision_msgs/Scene           the bodies, transient local,
                                                             on each change
  out  ``/diagnostics``     diagnostic_msgs/DiagnosticArray  health, once a period
Services:
  ``check_collision``       mkcollision_msgs/srv/CheckCollision  stateless query
  ``edit_scene``            mkcollision_msgs/srv/EditScene       add, replace and remove
                            bodies and set the allowed pairs, all or none

Pose inputs are best effort, keep last 1 (the sensor-data idea: a best-effort or a
reliable publisher connects, and a burst leaves only the newest message);
``reliable_inputs`` makes them reliable.  Outputs are reliable, keep last 10.

The node owns one scene (bodies, filters, stamped poses); pose messages write into it.
``trigger`` ``on_message`` steps once per accepted pose message, ``timer`` steps at
``rate_hz`` when new poses arrived since the last step (a stamp is never published
twice).  Each ContactArray carries the newest accepted pose stamp.  A body that has not
received a pose yet (and is not static or given an initial pose) does not collide; a
body whose pose is older than ``max_pose_age_s`` is stale (diagnostics; with
``stale_policy`` drop it stops colliding until a new pose arrives).

Parameters come from one table (node_parameters.PARAMETERS): each is declared with
its description, range and read-only flag (``ros2 param describe``).  The live ones
change with ``ros2 param set``: the value is checked before it is taken (a bad one is
refused with the reason and changes nothing) and applies from the next step;
``bodies.<name>.<key>`` changes that body's shape or filter.  A params file key the node
does not know stops the start with that key named.

Bad input never stops the node.  Messages in another frame, with a zero, far-future,
repeated or out-of-order stamp, or with lengths that do not match, are dropped; bad
entries inside a message (unknown or duplicate names, NaN, Inf, coordinates beyond
``max_abs_coordinate``, zero or non-unit quaternions) are dropped one by one and the
rest applied.  Each reason has its own throttled warning (an unknown name is warned
once) and its own count in diagnostics.  A stamp more than ``time_reset_s`` behind the
newest is a time reset (a bag loops, a simulator restarts): every contact ends, an INFO
is logged and the new time is taken.  A broken configuration is reported in one clear
line and the process exits with status 1 before spinning.
"""
import os

# numba's OpenMP threads spin-wait after each parallel region; in a node that sleeps
# between messages that spinning takes most of a core and slows the other processes
# (bench/node_latency.py measures the node's CPU and latency).  Set before numba starts
# its threads; a user's own setting wins.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import collections  # noqa: E402
import math
import time

import numpy as np
import rclpy
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseArray, PoseStamped
from mkcollision_msgs.msg import (BodyPoseArray, ContactArray, ContactEvents,
                                  ProximityArray)
from mkcollision_msgs.msg import Scene as SceneMsg
from mkcollision_msgs.srv import CheckCollision, EditScene
from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Header
from visualization_msgs.msg import MarkerArray

import msg_adapters

from . import compile_progress, rerun_log
from .fastdds import use_large_messages_profile
from .arbiters import EV_PERSISTED
from .config import bodies_from_params, pose_topics_from_params
from .crosscheck import cross_check, describe, repro
from .kernels import constants as C
from .node_parameters import PARAMETERS, PARAMS, ROS_PARAMETERS
from .pipeline import Pipeline, PipelineConfig
from .query import query_contacts
from .results import ContactSet
from .scene import POSE_PROBLEMS, Scene, pose_problems

PIPELINE_SETTINGS = ("method", "contact_margin", "proximity", "merge_distance",
                     "drift_threshold", "max_contacts", "stale_steps", "max_pairs",
                     "shard_index", "shard_count")
REPROS_PER_STEP = 10       # repro lines logged per step at most (failures, cross-check)
NO_ID = (1 << 64) - 1      # ContactArray id of a failed pair's entry (no persistent id)
LATENCY_WINDOW = 1000      # steps in the latency percentiles
RERUN_PARAMETERS = ("rerun", "rerun_pairs", "rerun_web_port", "rerun_memory_limit")


def _rerun_pairs(text):
    """The ``rerun_pairs`` parameter ("a:b, c:d") as [(a, b), ...]; ValueError if bad."""
    return rerun_log.parse_pairs([p.strip() for p in text.split(",") if p.strip()])


class ConfigError(ValueError):
    """The node's parameters cannot describe a valid scene."""


def _with_failed_pairs(res, scene, method):
    """The step's contacts plus one entry per failed pair: status FAILED, id NO_ID,
    depth 0, the points at the two bodies' origins and the normal between them."""
    a, b = res.failed_pairs[:, 0], res.failed_pairs[:, 1]
    pa, pb = scene.positions[a], scene.positions[b]
    d = pb - pa
    norm = np.linalg.norm(d, axis=1)
    normal = np.where(norm[:, None] > 0, d / np.where(norm > 0, norm, 1.0)[:, None],
                      [0.0, 0.0, 1.0])
    k = len(a)
    cat = np.concatenate
    return ContactSet(
        names=res.names, body_a=cat([res.body_a, a]), body_b=cat([res.body_b, b]),
        position=cat([res.position, 0.5 * (pa + pb)]), point_a=cat([res.point_a, pa]),
        point_b=cat([res.point_b, pb]), normal=cat([res.normal, normal]),
        depth=cat([res.depth, np.zeros(k)]),
        contact_id=cat([res.contact_id.astype(np.uint64), np.full(k, NO_ID, np.uint64)]),
        age=cat([res.age, np.zeros(k, np.int64)]),
        method=cat([res.method, np.full(k, method, np.int64)]),
        status=cat([res.status, np.full(k, C.ST_FAILED, np.int64)]))


def _seconds(stamp):
    """builtin_interfaces/Time -> float seconds."""
    return stamp.sec + 1e-9 * stamp.nanosec


class CollisionNode(Node):
    def __init__(self, node_name="collision_node", **node_kwargs):
        # the parameters are declared here, from the table and from the params file's
        # bodies.* block (free-form: its keys depend on the shape)
        super().__init__(node_name, automatically_declare_parameters_from_overrides=False,
                         **node_kwargs)
        self.cfg = self._declare_parameters()
        bodies = bodies_from_params(self._body_params())
        self.scene = Scene(bodies)
        self.pipeline = Pipeline(self.scene, config=PipelineConfig(
            **{k: self.cfg[k] for k in PIPELINE_SETTINGS}))
        # PoseArray poses go to the bodies in slot order: bodies.names at start
        self.order = np.flatnonzero(self.scene.used)
        # a first status before the kernels compile (minutes on a first start)
        self.pub_diag = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self._publish_diagnostics(DiagnosticStatus(
            level=DiagnosticStatus.WARN, name=f"{self.get_name()}: collision pipeline",
            message="warming up: compiling or loading the kernels",
            hardware_id=self.get_fully_qualified_name()))
        t0 = time.perf_counter()
        # a cold compile is shared with a second process (compile_progress.sharing)
        log = self.get_logger().info
        with compile_progress.reporting(log), compile_progress.sharing(log):
            self.pipeline.warm_up()
        self.warm_up_s = time.perf_counter() - t0
        self.get_logger().info(
            f"{len(self.scene)} bodies loaded; kernels ready in {self.warm_up_s:.2f} s")

        self.stamp = None            # newest accepted pose stamp (builtin Time)
        self.newest = -math.inf      # the same, in seconds
        self.dirty = False           # poses arrived since the last step
        self.steps = 0
        self.dropped = collections.Counter()      # reason -> entries or messages
        self.failures = 0                          # narrow-phase FAILED pairs, summed
        self.truncated_steps = 0
        self.cross_checked = 0
        self.disagreements = 0
        self.step_errors = 0
        self.latency = collections.deque(maxlen=LATENCY_WINDOW)
        self.n_stale = 0
        self.oldest_age = 0.0
        self.last = None                           # the last StepResult
        self._warned_at = {}
        self._warned_names = set()
        self._names_key = None            # (scene version, names) of _names_slots
        self._names_slots = None
        self.painter = msg_adapters.MarkerPainter()
        self._markers_at = -math.inf
        self.rerun = None                 # rerun_log.RerunLog while a sink is open
        self.rerun_errors = 0
        try:
            self._open_rerun()
        except (ValueError, OSError, RuntimeError) as err:
            raise ConfigError(f"parameter 'rerun': {err}") from None
        self._diag_steps = 0
        self._diag_t = time.monotonic()

        depth1 = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                            reliability=(ReliabilityPolicy.RELIABLE if self.cfg["reliable_inputs"]
                                         else ReliabilityPolicy.BEST_EFFORT))
        self.sub_named = self.create_subscription(
            BodyPoseArray, self.cfg["pose_topic"], self._on_body_poses, depth1)
        # PoseArray arrives as its CDR bytes, read by numpy (msg_adapters.poses)
        self.sub_array = self.create_subscription(
            PoseArray, self.cfg["pose_array_topic"], self._on_pose_array, depth1, raw=True)
        self.sub_stamped = [
            self.create_subscription(PoseStamped, topic,
                                     lambda msg, name=name: self._on_pose_stamped(msg, name),
                                     depth1)
            for name, topic in pose_topics_from_params(self._body_params()).items()]
        self.pub_contacts = self.create_publisher(ContactArray, self.cfg["contacts_topic"], 10)
        self.pub_markers = self.create_publisher(MarkerArray, self.cfg["markers_topic"], 10)
        self.pub_events = self.create_publisher(ContactEvents, self.cfg["events_topic"],
                                                QoSProfile(depth=100))
        self.pub_proximity = self.create_publisher(ProximityArray,
                                                   self.cfg["proximity_topic"], 10)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.pub_scene = self.create_publisher(SceneMsg, self.cfg["scene_topic"], latched)
        self.srv_check = self.create_service(CheckCollision, "check_collision",
                                             self._on_check_collision)
        self.srv_edit = self.create_service(EditScene, "edit_scene", self._on_edit_scene)
        self._publish_scene()
        self.timer = None
        if self.cfg["trigger"] == "timer":
            self.timer = self.create_timer(1.0 / self.cfg["rate_hz"], self._on_timer)
        self.diag_timer = self.create_timer(self.cfg["diagnostics_period_s"],
                                            self._publish_diagnostics)
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

    # -- parameters ---------------------------------------------------------------
    def _declare_parameters(self):
        overrides = self._parameter_overrides      # rclpy: name -> Parameter (params file)
        for name in overrides:
            if not (name in PARAMS or name.startswith("bodies.") or name in ROS_PARAMETERS
                    or name.startswith("qos_overrides.")):
                raise ConfigError(f"unknown parameter '{name}' (a typo?); the node's "
                                  f"parameters are {sorted(PARAMS)} and bodies.*")
        cfg = {}
        for p in PARAMETERS:
            given = overrides.get(p.name)
            if given is not None and isinstance(p.default, float) \
                    and given.type_ == Parameter.Type.INTEGER:
                # YAML `30` for a float parameter: take it as 30.0
                overrides[p.name] = Parameter(p.name, value=float(given.value))
            given = overrides.get(p.name)
            if given is not None:
                why = p.check(given.value)
                if why:
                    raise ConfigError(f"parameter {why} ({p.description})")
            cfg[p.name] = self.declare_parameter(p.name, p.default, p.descriptor()).value
        for name, given in overrides.items():
            if name.startswith("bodies.") and not self.has_parameter(name):
                self.declare_parameter(name, given.value,
                                       ParameterDescriptor(description="a body's shape key "
                                                           "(config/collision_node.yaml)"))
        if not self._body_params():
            ns = self.get_namespace()
            raise ConfigError(
                f"no bodies configured for node '{self.get_name()}' in namespace '{ns}': "
                f"the params file needs bodies.names and one block per body under "
                f"'/**:' or '{self.get_fully_qualified_name()}:' (see "
                f"config/collision_node.yaml)")
        return cfg

    def _body_params(self):
        return {f"bodies.{k}": p.value
                for k, p in self.get_parameters_by_prefix("bodies").items()}

    def _check_parameters(self, params):
        """on-set: refuse the whole set (with the reason) if any value is bad."""
        changes, bodies = {}, self._body_params()
        for prm in params:
            if prm.name in PARAMS:
                value = prm.value
                if isinstance(PARAMS[prm.name].default, float) \
                        and prm.type_ == Parameter.Type.INTEGER:
                    value = float(value)
                why = PARAMS[prm.name].check(value)
                if why:
                    return SetParametersResult(successful=False, reason=why)
                changes[prm.name] = value
            elif prm.name == "bodies.names":
                if list(prm.value) != list(bodies["bodies.names"]):
                    return SetParametersResult(successful=False, reason=(
                        "bodies.names cannot change while running: a body's keys "
                        "(bodies.<name>.<key>) can"))
            elif prm.name.endswith(".pose_topic"):
                return SetParametersResult(successful=False, reason=(
                    f"{prm.name} is fixed at start (its subscription)"))
            elif prm.name.startswith("bodies."):
                if prm.name.split(".")[1] not in self.scene:
                    return SetParametersResult(successful=False, reason=(
                        f"{prm.name}: the body is no longer in the scene (edit_scene "
                        f"removed it)"))
                bodies[prm.name] = prm.value
            elif prm.name not in ROS_PARAMETERS:
                return SetParametersResult(successful=False,
                                           reason=f"unknown parameter '{prm.name}'")
        try:
            self.pipeline.config.replace(**{k: v for k, v in changes.items()
                                            if k in PIPELINE_SETTINGS})
            rerun_log.parse_sink(changes.get("rerun", self.cfg["rerun"]))
            _rerun_pairs(changes.get("rerun_pairs", self.cfg["rerun_pairs"]))
            bodies_from_params(bodies)
        except ValueError as err:
            return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, params):
        """post-set: take the checked values (from the next step on)."""
        settings, touched, names = {}, set(), {p.name for p in params}
        for prm in params:
            if prm.name in PARAMS:
                value = prm.value
                if isinstance(PARAMS[prm.name].default, float):
                    value = float(value)
                self.cfg[prm.name] = value
                if prm.name in PIPELINE_SETTINGS:
                    settings[prm.name] = value
            elif prm.name.startswith("bodies.") and prm.name != "bodies.names":
                touched.add(prm.name.split(".")[1])
        if settings:
            self.pipeline.configure(**settings)
        if touched:
            for body in bodies_from_params(self._body_params()):
                if body["name"] in touched and body["name"] in self.scene:
                    old = self.scene.body(body["name"])
                    body = dict(body)
                    body.pop("pose", None)          # a shape edit keeps the current pose
                    if (body["shape"], body["static"], body["group"], body["mask"]) != (
                            old.shape, old.static, old.group, old.mask):
                        self.scene.replace_body(body)
            self._scene_changed()
        if names & set(RERUN_PARAMETERS):
            try:
                self._open_rerun()
            except (ValueError, OSError, RuntimeError) as err:
                self.rerun_errors += 1
                self.get_logger().error(f"rerun sink {self.cfg['rerun']!r} not opened, "
                                        f"rerun logging is off: {err}")
        if "rate_hz" in names and self.timer is not None:
            self.destroy_timer(self.timer)
            self.timer = self.create_timer(1.0 / self.cfg["rate_hz"], self._on_timer)

    # -- input --------------------------------------------------------------------
    def _warn(self, reason, text, count=1):
        """Count ``count`` dropped items under ``reason``; warn at most once per
        warn_throttle_s per reason."""
        self.dropped[reason] += count
        now = time.monotonic()
        if now - self._warned_at.get(reason, -math.inf) >= self.cfg["warn_throttle_s"]:
            self._warned_at[reason] = now
            self.get_logger().warning(text)

    def _on_body_poses(self, msg):
        try:
            names, pos, quat = msg_adapters.body_pose_array_to_arrays(msg)
        except ValueError as err:
            self._warn("length mismatch", f"dropped a BodyPoseArray: {err}")
            return
        if not self._message_ok(msg.header, len(names), "BodyPoseArray"):
            return
        slots = self._slots_of(names)
        if not (slots >= 0).all():
            unknown = [n for n, s in zip(names, slots) if s < 0]
            self.dropped["unknown name"] += len(unknown)
            new = sorted(set(unknown) - self._warned_names)
            if new:
                self._warned_names.update(new)
                self.get_logger().warning(f"BodyPoseArray names unknown bodies (warned once "
                                          f"per name): {new[:20]}")
            ok = slots >= 0
            slots, pos, quat = slots[ok], pos[ok], quat[ok]
        self._ingest(msg.header.stamp, slots, pos, quat, "BodyPoseArray")

    def _slots_of(self, names):
        """Slots of ``names`` (-1: unknown), remembered for the next message with the
        same names in the same order (a publisher's usual case) until the scene changes."""
        key = (self.scene.version, names)
        if self._names_key is None or self._names_key[0] != key[0] \
                or self._names_key[1] != names:
            index = self.scene.index
            slots = np.fromiter((index.get(n, -1) for n in names), np.int64, len(names))
            self._names_key, self._names_slots = key, slots
        return self._names_slots

    def _on_pose_array(self, data):
        try:
            sec, nanosec, frame, pos, quat = msg_adapters.pose_array_from_cdr(data)
        except ValueError as err:
            self._warn("malformed message", f"dropped a PoseArray: {err}")
            return
        n = len(self.order)
        if len(pos) != n:
            self._warn("length mismatch", f"dropped a PoseArray with {len(pos)} poses: "
                       f"the node has {n} bodies, and PoseArray poses are matched to "
                       f"bodies by order")
            return
        header = Header(stamp=Time(sec=sec, nanosec=nanosec), frame_id=frame)
        if not self._message_ok(header, n, "PoseArray"):
            return
        self._ingest(header.stamp, self.order, pos, quat, "PoseArray")

    def _on_pose_stamped(self, msg, name):
        if name not in self.scene:
            self._warn("unknown name", f"dropped a PoseStamped of '{name}': no such body")
            return
        if not self._message_ok(msg.header, 1, "PoseStamped"):
            return
        p, q = msg.pose.position, msg.pose.orientation
        self._ingest(msg.header.stamp, np.array([self.scene.index[name]], np.int64),
                     np.array([[p.x, p.y, p.z]]), np.array([[q.x, q.y, q.z, q.w]]),
                     "PoseStamped")

    def _message_ok(self, header, n_entries, kind):
        """The whole-message checks: frame, stamp, size."""
        frame = self.cfg["frame_id"]
        if header.frame_id != frame:
            self._warn("wrong frame_id", f"dropped a {kind} in frame '{header.frame_id}': "
                       f"the node works in '{frame}' (parameter frame_id)")
            return False
        t = _seconds(header.stamp)
        if t == 0.0:
            self._warn("zero stamp", f"dropped a {kind} with a zero stamp: stamp poses "
                       f"with the time they are valid at")
            return False
        now = _seconds(self.get_clock().now().to_msg())
        if t > now + self.cfg["max_future_s"]:
            self._warn("future stamp", f"dropped a {kind} stamped {t:.3f} s, more than "
                       f"max_future_s = {self.cfg['max_future_s']} s ahead of the node's "
                       f"clock ({now:.3f} s)")
            return False
        if n_entries > self.cfg["max_bodies"]:
            self._warn("too many entries", f"dropped a {kind} with {n_entries} entries "
                       f"(max_bodies = {self.cfg['max_bodies']})")
            return False
        if t < self.newest - self.cfg["time_reset_s"]:
            self.get_logger().info(
                f"time reset: a {kind} stamped {t:.3f} s is {self.newest - t:.3f} s behind "
                f"the newest pose; every contact ends and the new time is taken")
            self.pipeline.end_contacts()
            self.scene.stamps[:] = np.nan
            self.newest = -math.inf
        return True

    def _ingest(self, stamp, slots, pos, quat, kind):
        t = _seconds(stamp)
        old = self.scene.stamps[slots] >= t          # NaN (no pose yet) compares False
        if old.any():
            self._warn("stale stamp", f"{kind}: dropped {int(old.sum())} pose(s) stamped "
                       f"{t:.6f} s, not newer than the bodies' last poses (out of order or "
                       f"repeated)", int(old.sum()))
            keep = ~old
            slots, pos, quat = slots[keep], pos[keep], quat[keep]
        if not len(slots):
            return
        applied, problems = self.scene.set_poses_at(
            slots, pos, quat, t, max_abs=self.cfg["max_abs_coordinate"],
            quat_tolerance=self.cfg["quaternion_tolerance"])
        by_reason = collections.defaultdict(list)
        for text in problems:
            name, _, reason = text.rpartition(": ")
            by_reason[reason].append(name)
        for reason, names in by_reason.items():
            self._warn(reason, f"{kind}: dropped {len(names)} entr"
                       f"{'y' if len(names) == 1 else 'ies'} ({reason}): {names[:5]}"
                       f"{' ...' if len(names) > 5 else ''}", len(names))
        if not applied:
            return
        if t >= self.newest:
            self.newest, self.stamp = t, stamp
        self.dirty = True
        if self.cfg["trigger"] == "on_message":
            self._step()

    # -- the step -----------------------------------------------------------------
    def _on_timer(self):
        if self.dirty:
            self._step()

    def _apply_stale_policy(self):
        sc = self.scene
        age = self.newest - sc.stamps
        stale = sc.used & ~sc.static & (age > self.cfg["max_pose_age_s"])
        self.n_stale = int(np.count_nonzero(stale))
        finite = np.isfinite(age) & sc.used
        self.oldest_age = float(age[finite].max()) if finite.any() else 0.0
        sc.set_enabled(~stale if self.cfg["stale_policy"] == "drop"
                       else np.ones(sc.n_slots, bool))

    def _step(self):
        self.dirty = False
        try:
            self._apply_stale_policy()
            res = self.pipeline.step(stamp=self.newest)
        except Exception as err:  # noqa: BLE001 - the node must keep running
            self.step_errors += 1
            self._warn("step error", f"collision step failed, skipped: {err!r}")
            return
        self.steps += 1
        self.failures += res.n_failed_pairs
        self.truncated_steps += res.n_truncated_pairs > 0
        self.last = res
        if res.n_truncated_pairs:
            self._warn("truncated step", f"step truncated: {res.n_truncated_pairs} of "
                       f"{res.n_narrowphase_pairs} pairs not run (max_pairs = "
                       f"{self.cfg['max_pairs']})", 0)
        contacts = res
        if res.n_failed_pairs:
            for a, b in res.failed_pairs[:REPROS_PER_STEP]:
                self.get_logger().error(
                    f"narrow phase failed on {res.names[a]}-{res.names[b]}; repro: "
                    f"{repro(self.scene, a, b, self.cfg['method'])}")
            contacts = _with_failed_pairs(contacts, self.scene, C.METHOD_NAMES.index(self.cfg["method"]))
        if self.cfg["cross_check"]:
            self._cross_check(res.pairs)
        finite = (np.isfinite(contacts.position).all(axis=1)
                  & np.isfinite(contacts.normal).all(axis=1)
                  & np.isfinite(contacts.point_a).all(axis=1)
                  & np.isfinite(contacts.point_b).all(axis=1) & np.isfinite(contacts.depth))
        if not finite.all():           # never publish a NaN or an Inf
            self._warn("non-finite contact", "dropped non-finite contacts",
                       int((~finite).sum()))
            contacts = ContactSet.select(contacts, finite)
        frame = self.cfg["frame_id"]
        shard = (self.cfg["shard_index"], self.cfg["shard_count"])
        self.pub_contacts.publish(
            msg_adapters.contacts_to_contact_array(contacts, self.stamp, frame, shard))
        if np.any(res.events.kind != EV_PERSISTED):
            self.pub_events.publish(msg_adapters.events_to_contact_events(
                res.events, res.names, self.stamp, frame, shard))
        if self.cfg["proximity"] > 0.0:
            self.pub_proximity.publish(msg_adapters.proximity_to_proximity_array(
                res.proximity, res.names, self.stamp, frame, shard))
        now = time.monotonic()
        if self.cfg["publish_markers"] and now - self._markers_at >= 1.0 / self.cfg[
                "marker_rate_hz"]:
            self._markers_at = now
            self.pub_markers.publish(self.painter.marker_array(
                self.scene, contacts, self.stamp, frame, self.cfg["marker_normal_length"],
                self.cfg["marker_deep_depth"],
                # one shard draws the bodies; each its own contact markers
                bodies=self.cfg["marker_bodies"] and shard[0] == 0,
                max_bodies=self.cfg["marker_max_bodies"], contact_marker_id=shard[0]))
        now = _seconds(self.get_clock().now().to_msg())
        self.latency.append(now - self.newest)
        if self.rerun is not None:
            try:
                self.rerun.log_step(self.scene, res, self.steps, latency=now - self.newest)
            except Exception as err:  # noqa: BLE001 - logging must not stop the node
                self.rerun_errors += 1
                self._warn("rerun error", f"rerun logging failed this step: {err!r}")

    def _open_rerun(self):
        """(Re)open the rerun sink the parameters name (closing the previous one)."""
        if self.rerun is not None:
            self.rerun.close()
            self.rerun = None
        sink = rerun_log.parse_sink(self.cfg["rerun"])
        if sink.kind == "off":
            return
        self.rerun = rerun_log.RerunLog(
            sink, _rerun_pairs(self.cfg["rerun_pairs"]), deep=self.cfg["marker_deep_depth"],
            normal_length=self.cfg["marker_normal_length"],
            memory_limit=self.cfg["rerun_memory_limit"],
            web_port=self.cfg["rerun_web_port"], application_id="mkcollision_ros",
            recording_id=self.get_fully_qualified_name())
        self.get_logger().info(f"rerun: {self.rerun.where}")

    def destroy_node(self):
        if self.rerun is not None:
            self.rerun.close()
            self.rerun = None
        return super().destroy_node()

    def _cross_check(self, pairs):
        n, found = cross_check(self.scene, pairs, self.cfg["cross_check_depth_tol"],
                               self.cfg["cross_check_angle_tol"])
        self.cross_checked += n
        self.disagreements += len(found)
        for d in found[:REPROS_PER_STEP]:
            self.get_logger().warning(describe(d, self.scene))

    # -- diagnostics --------------------------------------------------------------
    def diagnostics(self):
        """The node's health as a DiagnosticStatus (level, message and values)."""
        now = time.monotonic()
        rate = (self.steps - self._diag_steps) / max(now - self._diag_t, 1e-9)
        self._diag_steps, self._diag_t = self.steps, now
        lat = np.array(self.latency) if self.latency else np.zeros(1)
        res = self.last
        level, why = DiagnosticStatus.OK, "ok"
        if self.step_errors:
            level, why = DiagnosticStatus.ERROR, f"{self.step_errors} step(s) failed"
        elif self.stamp is None:
            level, why = DiagnosticStatus.WARN, "no pose received yet"
        elif self.n_stale:
            level, why = DiagnosticStatus.WARN, f"{self.n_stale} stale bodies"
        elif self.failures:
            level, why = DiagnosticStatus.WARN, f"{self.failures} narrow-phase failures"
        elif self.truncated_steps:
            level, why = DiagnosticStatus.WARN, f"{self.truncated_steps} truncated steps"
        elif self.disagreements:
            level, why = DiagnosticStatus.WARN, (f"{self.disagreements} MPR / GJK-EPA "
                                                 f"disagreements")
        elif self.rerun_errors:
            level, why = DiagnosticStatus.WARN, f"{self.rerun_errors} rerun logging errors"
        elif sum(self.dropped.values()):
            level, why = DiagnosticStatus.WARN, "input dropped: " + ", ".join(
                f"{k} {v}" for k, v in sorted(self.dropped.items()))
        values = {
            "kernels ready (s)": f"{self.warm_up_s:.2f}",
            "shard": f"{self.cfg['shard_index']} of {self.cfg['shard_count']}",
            "steps": self.steps, "step rate (Hz)": f"{rate:.1f}",
            "latency p50 (ms)": f"{1e3 * np.percentile(lat, 50):.3f}",
            "latency p99 (ms)": f"{1e3 * np.percentile(lat, 99):.3f}",
            "bodies": len(self.scene), "stale bodies": self.n_stale,
            "oldest pose age (s)": f"{self.oldest_age:.3f}",
            "narrow-phase pairs": res.n_narrowphase_pairs if res else 0,
            "touching pairs": len(res.pairs) if res else 0,
            "contacts": len(res.contact_id) if res else 0,
            "narrow-phase failures": self.failures, "step errors": self.step_errors,
            "truncated steps": self.truncated_steps,
            "cross-checked pairs": self.cross_checked,
            "cross-check disagreements": self.disagreements,
            "rerun": self.cfg["rerun"], "rerun errors": self.rerun_errors,
        }
        values.update({f"dropped: {k}": v for k, v in sorted(self.dropped.items())})
        return DiagnosticStatus(
            level=level, name=f"{self.get_name()}: collision pipeline", message=why,
            hardware_id=self.get_fully_qualified_name(),
            values=[KeyValue(key=k, value=str(v)) for k, v in values.items()])

    def _publish_diagnostics(self, status=None):
        msg = DiagnosticArray()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.status = [self.diagnostics() if status is None else status]
        self.pub_diag.publish(msg)

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

    def _on_edit_scene(self, request, response):
        flat = list(request.allowed_pairs)
        try:
            if len(flat) % 2:
                raise ValueError(f"allowed_pairs needs an even number of names, got "
                                 f"{len(flat)}")
            bodies = [msg_adapters.body_msg_to_body(b) for b in request.bodies]
            self.scene.edit(
                remove=list(request.remove), bodies=bodies,
                allowed_pairs=([flat[i:i + 2] for i in range(0, len(flat), 2)]
                               if request.set_allowed_pairs else None))
        except ValueError as err:
            response.success, response.message = False, f"nothing changed: {err}"
            return response
        self._scene_changed()
        response.success = True
        response.message = (f"removed {len(request.remove)}, added or replaced "
                            f"{len(request.bodies)}; {len(self.scene)} bodies")
        return response

    def _scene_changed(self):
        # PoseArray poses go to the bodies in slot order
        self.order = np.flatnonzero(self.scene.used)
        self._publish_scene()

    def _publish_scene(self):
        self.pub_scene.publish(msg_adapters.scene_to_scene_msg(
            self.scene, self.get_clock().now().to_msg(), self.cfg["frame_id"]))

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
            why = pose_problems(gp, gq, self.cfg["max_abs_coordinate"],
                                self.cfg["quaternion_tolerance"])
            bad = [f"{n}: {POSE_PROBLEMS[w]}" for n, w in zip(names, why) if w]
            if bad:
                raise ValueError("bad poses: " + "; ".join(bad))
            pos[idx], quat[idx] = gp, gq / np.linalg.norm(gq, axis=1)[:, None]
            posed[idx] = True
        missing = [n for n, i in zip(names, idx) if not posed[i]]
        idx = idx[posed[idx]]
        contacts = query_contacts(sc.table, sc.names, idx, pos, quat, sc.static,
                                  C.METHOD_NAMES.index(self.cfg["method"]))
        return contacts, missing


def spin(node):
    """Run ``node``'s callbacks until the context shuts down, on the executor its
    ``executor`` parameter names.  spin_once in a loop rather than spin(): the
    EventsExecutor's spin() does not return when a SIGTERM shuts the context down."""
    if node.cfg["executor"] == "events":
        from rclpy.experimental import EventsExecutor
        executor = EventsExecutor()
    else:
        executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        while rclpy.ok():
            executor.spin_once(timeout_sec=0.2)
    finally:
        executor.remove_node(node)


def main(args=None):
    log = rclpy.logging.get_logger("collision_node")
    use_large_messages_profile()
    try:
        rclpy.init(args=args)
    except Exception as err:  # noqa: BLE001 - e.g. a missing or unparsable params file
        log.fatal(f"cannot start: {str(err).splitlines()[0] if str(err) else err!r}")
        return 1
    node = None
    code = 0
    try:
        try:
            node = CollisionNode()
        except ValueError as err:  # ConfigError and invalid bodies: one clear line, exit 1
            log.fatal(f"invalid configuration: {err}")
            return 1
        except (KeyboardInterrupt, ExternalShutdownException):
            return 0
        except Exception as err:  # noqa: BLE001 - rclpy's own parameter errors at start
            log.fatal(f"invalid configuration: {type(err).__name__}: {err}")
            return 1
        try:
            spin(node)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        except Exception as err:  # noqa: BLE001
            # a Ctrl-C that lands inside a callback invalidates the context under a
            # publish (RCLError): that is the shutdown, not a failure
            if rclpy.ok():
                log.fatal(f"stopped by an error: {type(err).__name__}: {err}")
                code = 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


if __name__ == "__main__":
    raise SystemExit(main())
