"""The collision node's parameters, one table: each ``Param`` gives its name, default
(which fixes its type), description, range or choices and whether it is read-only.
``CollisionNode`` declares them with their descriptors (``ros2 param describe``) and checks
every new value with ``Param.check``; ``parameter_table`` renders the README's table from
the same rows (``tools/readme_parameters.py``, kept equal by ``tests/test_config.py``)."""
from dataclasses import dataclass

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

from .pipeline import PIPELINE_METHODS


@dataclass(frozen=True)
class Param:
    """One node parameter: the default fixes its type; ``lo``/``hi`` its range
    (inclusive), ``choices`` its strings; ``read_only`` ones are fixed at start."""
    name: str
    default: object
    description: str
    lo: object = None
    hi: object = None
    choices: tuple = ()
    read_only: bool = False

    def descriptor(self):
        text = self.description
        if self.choices:
            text += f" (one of: {', '.join(self.choices)})"
        d = ParameterDescriptor(description=text, read_only=self.read_only)
        if self.lo is not None and isinstance(self.default, float):
            d.floating_point_range = [FloatingPointRange(from_value=float(self.lo),
                                                         to_value=float(self.hi), step=0.0)]
        elif self.lo is not None and isinstance(self.default, int):
            d.integer_range = [IntegerRange(from_value=int(self.lo), to_value=int(self.hi),
                                            step=1)]
        return d

    def check(self, value):
        """The reason ``value`` is refused, or None."""
        want = type(self.default)
        if type(value) is not want:
            return f"'{self.name}' must be a {want.__name__}, got {value!r}"
        if self.choices and value not in self.choices:
            return f"'{self.name}' must be one of {list(self.choices)}, got {value!r}"
        if self.lo is not None and not (self.lo <= value <= self.hi):
            return f"'{self.name}' must be in [{self.lo}, {self.hi}], got {value!r}"
        return None


PARAMETERS = (
    Param("frame_id", "world", "frame of the input poses (messages in another frame are "
          "dropped) and of every output"),
    Param("trigger", "on_message", "on_message: one step per accepted pose message (the "
          "newest; never a queue); timer: steps at rate_hz when new poses arrived",
          choices=("on_message", "timer"), read_only=True),
    Param("executor", "events", "events: rclpy's EventsExecutor (a C++ event queue, "
          "less CPU a message); single_threaded: rclpy's SingleThreadedExecutor",
          choices=("events", "single_threaded"), read_only=True),
    Param("rate_hz", 30.0, "Hz; steps per second with trigger timer", 0.1, 10000.0),
    Param("reliable_inputs", False, "pose subscriptions reliable instead of best effort",
          read_only=True),
    Param("method", "auto", "narrow-phase method", choices=PIPELINE_METHODS),
    Param("contact_margin", 0.001, "m; a touching pair keeps touching (and its contact "
          "ids) while its gap is within this", 0.0, 1.0),
    Param("proximity", 0.0, "m; pairs this close are measured (library: "
          "StepResult.proximity)", 0.0, 1000.0),
    Param("merge_distance", 0.02, "m; a new contact this close to a stored one keeps its "
          "id", 1e-9, 100.0),
    Param("drift_threshold", 0.01, "m; a stored contact whose points drift this far apart "
          "is dropped", 1e-9, 100.0),
    Param("max_contacts", 4, "contacts kept per touching pair", 1, 16),
    Param("stale_steps", 3, "steps an unconfirmed pair is kept", 1, 1000),
    Param("shard_index", 0, "this node's shard of the scene's pairs (README, \"Shards\")",
          0, 1023, read_only=True),
    Param("shard_count", 1, "nodes sharing the scene's pairs, each answering its shard; "
          "1: this node answers every pair", 1, 1024, read_only=True),
    Param("publish_markers", True, "publish the MarkerArray"),
    Param("marker_normal_length", 0.2, "m; a normal line is this plus the depth long",
          0.0, 1000.0),
    Param("marker_rate_hz", 5.0, "Hz; MarkerArrays per second at most (bodies, contact "
          "points, normals)", 0.1, 1000.0),
    Param("marker_bodies", True, "draw the bodies in the MarkerArray"),
    Param("marker_max_bodies", 200, "body markers per MarkerArray at most; larger scenes "
          "are drawn in turns of this many (1,000 body markers take ~50 ms to serialise)",
          1, 1000000),
    Param("marker_deep_depth", 0.01, "m; a body with a contact deeper than this is drawn "
          "red (touching: orange, free: grey)", 0.0, 1000.0),
    Param("rerun", "off", "rerun sink of each step: off, save:<file.rrd>, "
          "connect[:<url>] or serve[:[<ip>:]<port>] (serving binds 127.0.0.1 unless an "
          "address is named)"),
    Param("rerun_pairs", "", "pairs drawn with their Minkowski difference and the "
          "method's iterations in rerun, comma-separated name_a:name_b"),
    Param("rerun_web_port", 9090, "port of the serve sink's web viewer, on the serve "
          "address (0: none)", 0, 65535),
    Param("rerun_memory_limit", "256MiB", "the serve sink's buffer for viewers that "
          "connect late, oldest data dropped first (rerun's size syntax)"),
    Param("warn_throttle_s", 2.0, "s; least interval between two warnings of one reason",
          0.0, 3600.0),
    Param("max_abs_coordinate", 1.0e6, "m; a pose with a coordinate beyond this is dropped",
          1.0, 1.0e12),
    Param("quaternion_tolerance", 0.01, "a quaternion whose norm is farther than this from "
          "1 is dropped, a closer one normalised (tf2's tolerance)", 0.0, 1.0),
    Param("max_pose_age_s", 1.0, "s; a body whose pose is older than this, against the "
          "newest pose stamp, is stale", 0.0, 1.0e9),
    Param("stale_policy", "keep", "keep: a stale body keeps colliding at its last pose; "
          "drop: it does not collide until a new pose", choices=("keep", "drop")),
    Param("time_reset_s", 1.0, "s; a stamp this far behind the newest is a time reset "
          "(contacts end, the new time is taken); one less far behind is dropped as out "
          "of order", 0.0, 1.0e9),
    Param("max_future_s", 10.0, "s; a stamp this far ahead of the node's clock is dropped",
          0.0, 1.0e9),
    Param("max_bodies", 100000, "a pose message with more entries is dropped", 1, 10000000),
    Param("max_pairs", 100000, "narrow-phase pairs per step (0: no cap); past it a step "
          "runs the first ones and diagnostics report the truncation", 0, 100000000),
    Param("cross_check", False, "also run MPR and GJK/EPA on every touching pair and count "
          "their disagreements, each logged with a repro"),
    Param("cross_check_depth_tol", 1.0e-4, "m; depths further apart are a disagreement",
          0.0, 1000.0),
    Param("cross_check_angle_tol", 0.0175, "rad; normals further apart are a disagreement",
          0.0, 3.1416),
    Param("diagnostics_period_s", 1.0, "s; period of the /diagnostics status", 0.1, 3600.0,
          read_only=True),
    Param("pose_topic", "body_poses", "BodyPoseArray input topic", read_only=True),
    Param("pose_array_topic", "pose_array", "geometry_msgs/PoseArray input topic",
          read_only=True),
    Param("contacts_topic", "contacts", "ContactArray output topic", read_only=True),
    Param("markers_topic", "contact_markers", "MarkerArray output topic", read_only=True),
    Param("events_topic", "contact_events", "ContactEvents output topic", read_only=True),
    Param("proximity_topic", "proximity", "ProximityArray output topic (published while "
          "proximity > 0)", read_only=True),
    Param("scene_topic", "scene", "Scene output topic (transient local, on each change)",
          read_only=True),
)
PARAMS = {p.name: p for p in PARAMETERS}
# parameters every rclpy node may be given, which the node leaves to rclpy
ROS_PARAMETERS = ("use_sim_time", "start_type_description_service")


def parameter_table():
    """PARAMETERS as the README's markdown table (a test keeps the README equal to it)."""
    kinds = {str: "string", float: "double", int: "integer", bool: "bool"}
    rows = ["| parameter | type | default | range / values | live | meaning |",
            "|---|---|---|---|---|---|"]
    for p in PARAMETERS:
        values = (f"{p.lo:g} .. {p.hi:g}" if p.lo is not None
                  else " / ".join(p.choices))
        default = str(p.default).lower() if isinstance(p.default, bool) else p.default
        rows.append(f"| `{p.name}` | {kinds[type(p.default)]} | `{default}` | {values} | "
                    f"{'no' if p.read_only else 'yes'} | {p.description} |")
    return "\n".join(rows) + "\n"
