"""Bad input through real DDS to the installed executable, started as a user would:
after each bad item the node still answers a good pose message with finite contacts,
and /diagnostics counts the item under its reason."""
import numpy as np
import pytest
from ros_harness import RosHarness, start_node, stop  # noqa: I001  (sets ROS_DOMAIN_ID)

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray
from mkcollision_msgs.msg import BodyPoseArray, ContactArray
from mkcollision_msgs.srv import EditScene
from rcl_interfaces.srv import SetParameters
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy

import msg_adapters
from mkcollision_msgs.msg import Body

PARAMS = """/**:
  ros__parameters:
    warn_throttle_s: 0.0
    diagnostics_period_s: 0.2
    max_bodies: 10
    bodies:
      names: [a, b, far]
      a: {type: sphere, radius: 0.5}
      b: {type: sphere, radius: 0.5}
      far: {type: box, size: [1.0, 1.0, 1.0]}
"""
ID = [0.0, 0.0, 0.0, 1.0]
GOOD = [[0.0, 0, 0], [0.9, 0, 0], [20.0, 0, 0]]


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    path = tmp_path_factory.mktemp("bad") / "params.yaml"
    path.write_text(PARAMS)
    proc = start_node(str(path))
    h = RosHarness()
    probe = h.node("probe")
    got, diag = [], []
    probe.create_subscription(ContactArray, "contacts", got.append, 100)
    probe.create_subscription(DiagnosticArray, "/diagnostics", diag.append, 10)
    pub = probe.create_publisher(BodyPoseArray, "body_poses",
                                 QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
    state = {"sec": 1000}

    def msg(names=("a", "b", "far"), pos=GOOD, quat=None, sec=None, frame="world",
            nanosec=0):
        quat = [ID] * len(names) if quat is None else quat
        return msg_adapters.arrays_to_body_pose_array(
            list(names), np.asarray(pos, float), np.asarray(quat, float),
            Time(sec=state["sec"] if sec is None else sec, nanosec=nanosec), frame)

    def good(timeout=900.0):
        """A good message with a new stamp; True once it is answered with finite data."""
        state["sec"] += 1
        m, sec = msg(), state["sec"]
        ok = h.spin_until(lambda: any(c.header.stamp.sec == sec for c in got), timeout,
                          step=lambda: pub.publish(m))
        if not ok:
            return False
        c = next(c for c in got if c.header.stamp.sec == sec)
        return (list(zip(c.body_a, c.body_b)) == [("a", "b")]
                and np.isfinite(np.asarray(c.positions)).all())

    def bad(m, times=3):
        for _ in range(times):
            pub.publish(m)
            h.spin_until(lambda: False, 0.05)

    def dropped():
        """The node's latest diagnostics values."""
        diag.clear()
        assert h.spin_until(lambda: any(s.hardware_id == "/collision_node" for d in diag
                                        for s in d.status), 10.0)
        s = next(s for d in reversed(diag) for s in d.status
                 if s.hardware_id == "/collision_node")
        return {kv.key: kv.value for kv in s.values}

    assert good(), "the node never answered"
    yield h, probe, pub, msg, good, bad, dropped, state
    h.close()
    log = stop(proc)
    assert proc.returncode == 0, log


BAD_POSES = [
    ("non-finite value", dict(pos=[[np.nan, 0, 0], [0.9, 0, 0], [20, 0, 0]])),
    ("non-finite value", dict(pos=[[np.inf, 0, 0], [0.9, 0, 0], [20, 0, 0]])),
    ("coordinate beyond the limit", dict(pos=[[1e308, 0, 0], [0.9, 0, 0], [20, 0, 0]])),
    ("zero quaternion", dict(quat=[[0, 0, 0, 0], ID, ID])),
    ("zero quaternion", dict(quat=[[1e-310, 0, 0, 0], ID, ID])),       # subnormal
    ("non-unit quaternion", dict(quat=[[0, 0, 0, 1.2], ID, ID])),
    ("unknown name", dict(names=("a", "zz", "far"))),
    ("duplicate body in one update", dict(names=("a", "a", "far"))),
    ("wrong frame_id", dict(frame="map")),
    ("zero stamp", dict(sec=0)),
    ("future stamp", dict(sec=2_100_000_000)),
    ("too many entries", dict(names=[f"n{i}" for i in range(11)], pos=np.zeros((11, 3)))),
]


@pytest.mark.parametrize("reason, kw", BAD_POSES, ids=[f"{r}-{i}" for i, (r, _) in
                                                        enumerate(BAD_POSES)])
def test_a_bad_pose_message_is_dropped_and_counted(live, reason, kw):
    h, probe, pub, msg, good, bad, dropped, state = live
    state["sec"] += 1
    bad(msg(**kw))
    assert good(60.0), "no answer after the bad message"
    assert int(dropped().get(f"dropped: {reason}", 0)) >= 1


def test_stamps_out_of_order_repeated_and_reset(live):
    h, probe, pub, msg, good, bad, dropped, state = live
    assert good(60.0)
    newest = state["sec"]
    bad(msg(sec=newest))                                   # repeated
    bad(msg(sec=newest - 1, nanosec=500_000_000))          # out of order
    assert int(dropped()["dropped: stale stamp"]) >= 2
    state["sec"] = 10                                      # the bag looped
    assert good(60.0)


def test_length_mismatch_and_a_burst(live):
    h, probe, pub, msg, good, bad, dropped, state = live
    m = msg()
    m.orientations = m.orientations[:-1]
    bad(m)
    assert int(dropped()["dropped: length mismatch"]) >= 1
    for _ in range(1000):                                  # faster than it steps
        state["sec"] += 1
        pub.publish(msg())
    assert good(60.0)


def test_bad_parameter_and_bad_edit_change_nothing(live):
    h, probe, pub, msg, good, bad, dropped, state = live

    def call(srv, name, req):
        client = probe.create_client(srv, name)
        assert client.wait_for_service(timeout_sec=10.0)
        fut = client.call_async(req)
        assert h.spin_until(fut.done, 10.0)
        return fut.result()
    r = call(SetParameters, "/collision_node/set_parameters", SetParameters.Request(
        parameters=[Parameter("max_contacts", value=-1).to_parameter_msg()]))
    assert not r.results[0].successful and "max_contacts" in r.results[0].reason
    r = call(EditScene, "/edit_scene", EditScene.Request(
        remove=["far"], bodies=[Body(name="b", type="sphere", dimensions=[-1.0])]))
    assert not r.success and "radius" in r.message
    assert good(60.0)          # a and b still touch, far is still there and apart


def test_a_truncated_step_is_reported(live):
    h, probe, pub, msg, good, bad, dropped, state = live
    client = probe.create_client(SetParameters, "/collision_node/set_parameters")
    assert client.wait_for_service(timeout_sec=10.0)

    def set_max_pairs(n):
        fut = client.call_async(SetParameters.Request(
            parameters=[Parameter("max_pairs", value=n).to_parameter_msg()]))
        assert h.spin_until(fut.done, 10.0) and fut.result().results[0].successful
    set_max_pairs(1)
    state["sec"] += 1
    crowd = msg(pos=[[0.0, 0, 0], [0.9, 0, 0], [0.0, 0.9, 0]])     # three pairs overlap
    bad(crowd)
    assert int(dropped()["truncated steps"]) >= 1
    set_max_pairs(100000)
    assert good(60.0)
