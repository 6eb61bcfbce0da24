"""The collision node's parameters, QoS, triggering, stamps, bad input and diagnostics,
in-process over real DDS: a probe node publishes, calls the parameter services as
``ros2 param`` does, and reads the outputs."""
import math

import numpy as np
import pytest
from ros_harness import RosHarness  # noqa: I001  (sets ROS_DOMAIN_ID before rclpy)

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from mkcollision_msgs.msg import ContactArray
from mkcollision_msgs.msg import BodyPoseArray
from rcl_interfaces.srv import DescribeParameters, SetParameters
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy

import msg_adapters
from mkcollision_ros.node import CollisionNode, ConfigError

ID = [0.0, 0.0, 0.0, 1.0]
NAMES = ["a", "b", "far"]


def overrides(**extra):
    base = {"bodies.names": NAMES, "bodies.a.type": "sphere", "bodies.a.radius": 0.5,
            "bodies.b.type": "sphere", "bodies.b.radius": 0.5,
            "bodies.far.type": "box", "bodies.far.size": [1.0, 1.0, 1.0],
            "warn_throttle_s": 0.0, "diagnostics_period_s": 0.2}
    base.update(extra)
    return [Parameter(k, value=v) for k, v in base.items()]


class Probe:
    """A node under test plus a probe: publish poses, wait for answers."""

    def __init__(self, **extra):
        self.h = RosHarness()
        self.node = self.h.add(CollisionNode(context=self.h.context,
                                             parameter_overrides=overrides(**extra)))
        self.probe = self.h.node("probe")
        self.contacts, self.diag = [], []
        self.probe.create_subscription(ContactArray, "contacts", self.contacts.append, 50)
        self.probe.create_subscription(DiagnosticArray, "/diagnostics", self.diag.append, 10)
        self.best_effort = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.pub = self.probe.create_publisher(BodyPoseArray, "body_poses", self.best_effort)
        self.sec = 100

    def msg(self, gap=0.1, sec=None, names=NAMES, pos=None, quat=None, frame="world",
            nanosec=0):
        if pos is None:
            pos = [[0.0, 0, 0], [1.0 + gap, 0, 0], [20.0, 0, 0]]
        if quat is None:
            quat = [ID] * len(names)
        if sec is None:
            self.sec += 1
            sec = self.sec
        return msg_adapters.arrays_to_body_pose_array(
            names, np.asarray(pos, float), np.asarray(quat, float),
            Time(sec=sec, nanosec=nanosec), frame)

    def send(self, msg, wait=True, timeout=20.0):
        """Publish until the node answers with msg's stamp (or, wait=False, spin a bit
        and return whether it answered)."""
        stamp = (msg.header.stamp.sec, msg.header.stamp.nanosec)

        def answered():
            return any((m.header.stamp.sec, m.header.stamp.nanosec) == stamp
                       for m in self.contacts)
        if wait:
            assert self.h.spin_until(answered, timeout, step=lambda: self.pub.publish(msg)), \
                "the node did not answer"
            return next(m for m in self.contacts
                        if (m.header.stamp.sec, m.header.stamp.nanosec) == stamp)
        for _ in range(5):
            self.pub.publish(msg)
            self.h.spin_until(lambda: False, 0.1)
        return answered()

    def call(self, srv_type, name, request):
        """Call a service of the node (a bare name: one of its parameter services)."""
        client = self.probe.create_client(srv_type, name if "/" in name
                                          else f"/collision_node/{name}")
        assert client.wait_for_service(timeout_sec=10.0)
        fut = client.call_async(request)
        assert self.h.spin_until(fut.done, 10.0)
        return fut.result()

    def set(self, name, value):
        req = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
        return self.call(SetParameters, "set_parameters", req).results[0]

    def close(self):
        self.h.close()


@pytest.fixture
def probe():
    p = Probe()
    yield p
    p.close()


def test_parameters_are_described_with_ranges_and_read_only_flags(probe):
    req = DescribeParameters.Request(names=["max_contacts", "contact_margin", "trigger",
                                            "method"])
    d = {x.name: x for x in probe.call(DescribeParameters, "describe_parameters",
                                       req).descriptors}
    assert d["max_contacts"].integer_range[0].from_value == 1
    assert d["max_contacts"].integer_range[0].to_value == 16
    assert d["contact_margin"].floating_point_range[0].to_value == 1.0
    assert d["trigger"].read_only and not d["method"].read_only
    assert "gjk_epa" in d["method"].description and d["contact_margin"].description


def test_param_set_is_checked_and_applies_live(probe):
    probe.send(probe.msg(gap=-0.1))
    for name, value, reason in [("max_contacts", -1, "max_contacts"), ("method", "foo", "method"),
                                ("contact_margin", float("nan"), "contact_margin"),
                                ("bodies.a.radius", -1.0, "radius"),
                                ("bodies.names", ["a"], "cannot change"),
                                ("trigger", "timer", "read-only")]:
        r = probe.set(name, value)
        assert not r.successful and reason in r.reason, (name, r.reason)
    assert probe.node.pipeline.config.max_contacts == 4
    assert probe.node.get_parameter("method").value == "auto"
    assert probe.set("method", "mpr").successful
    assert probe.set("max_contacts", 2).successful
    assert probe.node.pipeline.config.method == "mpr"
    assert probe.node.pipeline.config.max_contacts == 2
    m = probe.send(probe.msg(gap=-0.1))
    assert list(m.methods) == [2]                                    # M_MPR
    # a body's shape, live: a grows from 0.5 to 0.7, so a 0.1 gap becomes 0.1 deep
    assert probe.set("bodies.a.radius", 0.7).successful
    m = probe.send(probe.msg(gap=0.1))
    assert list(zip(m.body_a, m.body_b)) == [("a", "b")]
    assert m.depths[0] == pytest.approx(0.1, abs=1e-9)


def test_unknown_or_bad_parameters_stop_the_start_naming_the_key():
    h = RosHarness()
    try:
        with pytest.raises(ConfigError, match="unknown parameter 'rate_hzz'"):
            CollisionNode(context=h.context, parameter_overrides=overrides(rate_hzz=5.0))
        with pytest.raises(ConfigError, match=r"'max_contacts' must be in \[1, 16\]"):
            CollisionNode(context=h.context, parameter_overrides=overrides(max_contacts=0))
        with pytest.raises(ConfigError, match="no bodies configured for node 'collision_node'"
                                              " in namespace '/robot1'"):
            CollisionNode(context=h.context, namespace="robot1",
                          parameter_overrides=[Parameter("rate_hz", value=5.0)])
        node = CollisionNode(context=h.context, parameter_overrides=overrides(rate_hz=50))
        assert node.cfg["rate_hz"] == 50.0                     # a YAML int for a float
        node.destroy_node()
    finally:
        h.close()


def test_best_effort_publisher_is_heard_and_bad_messages_are_dropped(probe):
    node = probe.node
    good = probe.send(probe.msg(gap=-0.1))
    assert len(good.depths) == 1
    t_good = good.header.stamp.sec
    # each of these is dropped, counted under its reason, and the node stays alive
    cases = [
        ("wrong frame_id", probe.msg(frame="map")),
        ("zero stamp", probe.msg(sec=0)),
        ("future stamp", probe.msg(sec=2_000_000_000)),
        ("stale stamp", probe.msg(sec=t_good)),                    # repeated
        ("stale stamp", probe.msg(sec=t_good - 1, nanosec=500_000_000)),     # older
        ("coordinate beyond the limit", probe.msg(pos=[[1e308, 0, 0], [1.0, 0, 0], [20.0, 0, 0]])),
        ("non-finite value", probe.msg(pos=[[np.nan, 0, 0], [1.0, 0, 0], [20.0, 0, 0]])),
        ("zero quaternion", probe.msg(quat=[[0, 0, 0, 0], ID, ID])),
        ("non-unit quaternion", probe.msg(quat=[[0, 0, 0, 1.5], ID, ID])),
        ("duplicate body in one update", probe.msg(names=["a", "a", "far"])),
        ("unknown name", probe.msg(names=["a", "zz", "far"])),
    ]
    for reason, msg in cases:
        before = node.dropped[reason]
        probe.send(msg, wait=False)
        assert node.dropped[reason] > before, reason
    # the entries that were fine in those messages were applied; nothing non-finite
    assert np.isfinite(node.scene.positions).all()
    assert node.scene.positions[0, 0] == 0.0
    # a length mismatch drops the whole message and changes nothing
    bad = probe.msg(gap=0.5)
    bad.positions = bad.positions[:-1]
    before = node.scene.positions.copy()
    probe.send(bad, wait=False)
    assert node.dropped["length mismatch"] > 0
    np.testing.assert_array_equal(node.scene.positions, before)
    # a slightly non-unit quaternion is normalised, and the node still answers
    m = probe.send(probe.msg(gap=-0.1, quat=[[0, 0, 0, 1.005], ID, ID]))
    assert len(m.depths) == 1 and m.depths[0] == pytest.approx(0.1, abs=1e-9)
    assert all(math.isfinite(v) for v in m.positions)


def test_unknown_names_are_warned_once_per_name(probe):
    logged = []
    probe.node.get_logger().warning = lambda text, **kw: logged.append(text)
    for _ in range(3):
        probe.send(probe.msg(names=["a", "zz", "far"]), wait=False)
    assert sum("zz" in t for t in logged) == 1
    assert probe.node.dropped["unknown name"] >= 3


def test_time_reset_ends_contacts_and_takes_the_new_time(probe):
    probe.send(probe.msg(gap=-0.1, sec=5000))
    ids = list(probe.send(probe.msg(gap=-0.1, sec=5001)).ids)
    m = probe.send(probe.msg(gap=-0.1, sec=10))                 # a bag looped
    assert m.header.stamp.sec == 10 and len(m.ids) == 1
    assert list(m.ids) != ids                                   # the contact began anew
    assert probe.send(probe.msg(gap=-0.1, sec=11)).ids[0] == m.ids[0]


def test_stale_bodies_are_reported_and_dropped_by_policy(probe):
    probe.send(probe.msg(gap=-0.1, sec=200))
    # b's pose stays at 200 while a and far move on to 203
    m = probe.send(probe.msg(names=["a", "far"], pos=[[0.0, 0, 0], [20.0, 0, 0]], sec=203))
    assert len(m.depths) == 1 and probe.node.n_stale == 1          # kept by default
    assert probe.set("stale_policy", "drop").successful
    m = probe.send(probe.msg(names=["a", "far"], pos=[[0.0, 0, 0], [20.0, 0, 0]], sec=204))
    assert len(m.depths) == 0 and probe.node.n_stale == 1
    m = probe.send(probe.msg(gap=-0.1, sec=205))                   # b fresh again
    assert len(m.depths) == 1 and probe.node.n_stale == 0


def test_diagnostics_report_counts_and_levels(probe):
    probe.send(probe.msg(gap=-0.1))
    probe.send(probe.msg(frame="map"), wait=False)
    probe.diag.clear()
    assert probe.h.spin_until(lambda: probe.diag, 10.0)
    status = probe.diag[-1].status[0]
    values = {kv.key: kv.value for kv in status.values}
    assert status.level == DiagnosticStatus.WARN and "wrong frame_id" in status.message
    assert int(values["dropped: wrong frame_id"]) >= 1
    assert int(values["steps"]) >= 1 and values["bodies"] == "3"
    assert float(values["latency p99 (ms)"]) >= float(values["latency p50 (ms)"]) >= 0.0
    assert "kernels ready (s)" in values and values["touching pairs"] == "1"


def test_timer_trigger_never_repeats_a_stamp():
    p = Probe(trigger="timer", rate_hz=50.0)
    try:
        p.send(p.msg(gap=-0.1))
        p.send(p.msg(gap=-0.1))
        p.h.spin_until(lambda: False, 0.5)              # 25 timer periods, no new poses
        stamps = [(m.header.stamp.sec, m.header.stamp.nanosec) for m in p.contacts]
        assert len(stamps) == len(set(stamps)) >= 2
    finally:
        p.close()


def _body(name, **kw):
    from mkcollision_msgs.msg import Body
    b = Body(name=name, default_filter=True)
    for k, v in kw.items():
        setattr(b, k, v)
    return b


def test_edit_scene_service_events_proximity_and_scene_readback():
    from geometry_msgs.msg import Point, Pose
    from mkcollision_msgs.msg import ContactEvents, ProximityArray
    from mkcollision_msgs.msg import Scene as SceneMsg
    from mkcollision_msgs.srv import EditScene
    from rclpy.qos import DurabilityPolicy
    from shape_msgs.msg import Mesh, SolidPrimitive
    p = Probe(proximity=0.5)
    try:
        events, prox = [], []
        p.probe.create_subscription(ContactEvents, "contact_events", events.append, 50)
        p.probe.create_subscription(ProximityArray, "proximity", prox.append, 50)
        m = p.send(p.msg(gap=-0.1))
        assert p.h.spin_until(lambda: events, 5.0)
        assert list(events[-1].kinds) == [0, 0] and events[-1].ids[0] == -1
        assert (events[-1].body_a[0], events[-1].body_b[0]) == ("a", "b")
        cid = m.ids[0]
        # a bad edit changes nothing
        bad = EditScene.Request(remove=["a"], bodies=[
            _body("egg", type="ellipsoid", dimensions=[0.3, 0.2])])
        r = p.call(EditScene, "/edit_scene", bad)
        assert not r.success and "takes 3 dimensions" in r.message
        assert "a" in p.node.scene
        # remove b, add a SolidPrimitive box next to a, an ellipsoid near it, a mesh far off
        pose = Pose()
        pose.position.x, pose.orientation.w = 1.0, 1.0
        tet = Mesh(vertices=[Point(x=x, y=y, z=z) for x, y, z in
                             [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]])
        far = Pose()
        far.position.x, far.orientation.w = -30.0, 1.0
        near = Pose()
        near.position.y, near.orientation.w = 0.7, 1.0
        req = EditScene.Request(remove=["b"], bodies=[
            _body("crate", primitive=SolidPrimitive(type=SolidPrimitive.BOX,
                                                    dimensions=[1.0, 1.0, 1.0]),
                  has_pose=True, pose=pose),
            _body("egg", type="ellipsoid", dimensions=[0.1, 0.1, 0.1], has_pose=True,
                  pose=near),
            _body("tet", mesh=tet, has_pose=True, pose=far)],
            set_allowed_pairs=True, allowed_pairs=["a", "tet"])
        r = p.call(EditScene, "/edit_scene", req)
        assert r.success, r.message
        m = p.send(p.msg(names=["a"], pos=[[0.0, 0, 0]]))
        pairs = list(zip(m.body_a, m.body_b))
        assert pairs == [("a", "crate")] and m.depths[0] == pytest.approx(0.0, abs=1e-9)
        assert p.h.spin_until(lambda: any(2 in e.kinds for e in events), 5.0)
        ended = next(e for e in events if 2 in e.kinds)
        kinds = list(zip(ended.kinds, ended.body_a, ended.body_b, ended.ids))
        assert (2, "a", "b", -1) in kinds and (2, "a", "b", cid) in kinds
        # proximity: egg is 0.1 from a
        assert p.h.spin_until(lambda: prox and "egg" in prox[-1].body_b, 5.0)
        last = prox[-1]
        assert ("a", "egg") in list(zip(last.body_a, last.body_b))
        k = list(zip(last.body_a, last.body_b)).index(("a", "egg"))
        assert last.distances[k] == pytest.approx(0.1, abs=1e-9)
        # a late subscriber gets the current scene
        got = []
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        p.probe.create_subscription(SceneMsg, "scene", got.append, latched)
        assert p.h.spin_until(lambda: got, 5.0)
        names = [b.name for b in got[-1].bodies]
        assert sorted(names) == ["a", "crate", "egg", "far", "tet"]
        crate = next(b for b in got[-1].bodies if b.name == "crate")
        assert crate.type == "box" and list(crate.dimensions) == [1.0, 1.0, 1.0]
        assert list(got[-1].allowed_pairs) == ["a", "tet"]
        # a removed body's parameters are refused, the node lives on
        r = p.set("bodies.b.radius", 0.4)
        assert not r.successful and "no longer in the scene" in r.reason
        assert p.send(p.msg(names=["a"], pos=[[0.0, 0, 0]], sec=p.sec + 50))
    finally:
        p.close()


def test_failed_pairs_are_published_with_their_status_and_a_repro():
    from mkcollision_ros.node import NO_ID
    p = Probe()
    try:
        logged = []
        p.node.get_logger().error = lambda text, **kw: logged.append(text)
        real = p.node.pipeline.step

        def failing_step(**kw):          # the narrow phase fails on (a, far)
            res = real(**kw)
            res.failed_pairs = np.array([[0, 2]], np.int64)
            res.n_failed_pairs = 1
            return res
        p.node.pipeline.step = failing_step
        m = p.send(p.msg(gap=-0.1))
        rows = list(zip(m.body_a, m.body_b, m.statuses, m.ids))
        real_ids = [i for a, b, st, i in rows if (a, b, st) == ("a", "b", 2)]
        assert len(real_ids) == 1 and real_ids[0] < 2 ** 63      # a contact id, not NO_ID
        assert ("a", "far", 3, NO_ID) in rows
        assert all(math.isfinite(v) for v in m.positions)
        assert any("narrow phase failed on a-far; repro: collide(" in t for t in logged)
        assert p.node.failures == 1
    finally:
        p.close()


def test_cross_check_counts_pairs_and_disagreements():
    from mkcollision_ros.crosscheck import cross_check
    p = Probe(cross_check=True, cross_check_depth_tol=0.0, cross_check_angle_tol=0.0)
    try:
        p.send(p.msg(gap=-0.1))
        n, found = cross_check(p.node.scene, p.node.last.pairs, 0.0, 0.0)
        assert p.node.cross_checked == n == 1
        assert p.node.disagreements == len(found)
    finally:
        p.close()


def test_per_body_pose_stamped_topics():
    from geometry_msgs.msg import PoseStamped
    p = Probe(**{"bodies.b.pose_topic": "/mocap/b/pose"})
    try:
        p.send(p.msg(gap=0.5))                                   # apart
        pub = p.probe.create_publisher(PoseStamped, "/mocap/b/pose", p.best_effort)
        msg = PoseStamped()
        msg.header.frame_id = "world"
        msg.header.stamp = Time(sec=900)
        msg.pose.position.x, msg.pose.orientation.w = 0.9, 1.0
        got = lambda: any(m.header.stamp.sec == 900 for m in p.contacts)  # noqa: E731
        assert p.h.spin_until(got, 20.0, step=lambda: pub.publish(msg))
        m = next(m for m in p.contacts if m.header.stamp.sec == 900)
        assert list(zip(m.body_a, m.body_b)) == [("a", "b")]
        assert m.depths[0] == pytest.approx(0.1, abs=1e-9)
    finally:
        p.close()
