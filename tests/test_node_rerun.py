"""The collision node's rerun parameters, in-process over real DDS: a recording of the
steps it answered, a live change of sink, and a bad sink refused with the reason."""
import numpy as np
from ros_harness import RosHarness  # noqa: I001  (sets ROS_DOMAIN_ID before rclpy)

from builtin_interfaces.msg import Time
from mkcollision_msgs.msg import BodyPoseArray, ContactArray
from rclpy.parameter import Parameter

import msg_adapters
from mkcollision_ros.node import CollisionNode
from mkcollision_ros.rerun_log import read_recording

NAMES = ["a", "b"]


def overrides(path):
    return [
        Parameter("bodies.names", value=NAMES),
        Parameter("bodies.a.type", value="sphere"), Parameter("bodies.a.radius", value=0.5),
        Parameter("bodies.b.type", value="box"), Parameter("bodies.b.size", value=[1.0] * 3),
        Parameter("rerun", value=f"save:{path}"),
        Parameter("warn_throttle_s", value=0.0),
    ]


def test_node_records_its_steps_and_changes_sink_live(tmp_path):
    first, second = tmp_path / "first.rrd", tmp_path / "second.rrd"
    h = RosHarness()
    try:
        node = h.add(CollisionNode(context=h.context, parameter_overrides=overrides(first)))
        probe = h.node("probe")
        got = []
        probe.create_subscription(ContactArray, "contacts", got.append, 10)
        pub = probe.create_publisher(BodyPoseArray, "body_poses", 10)
        quat = np.tile([0.0, 0, 0, 1], (2, 1))

        def answer(sec, gap):
            pos = np.array([[0.0, 0, 0], [1.0 - gap, 0, 0]])
            msg = msg_adapters.arrays_to_body_pose_array(NAMES, pos, quat, Time(sec=sec))
            assert h.spin_until(lambda: any(m.header.stamp.sec == sec for m in got),
                                timeout=60.0, step=lambda: pub.publish(msg))
        for sec in (1, 2, 3):
            answer(sec, 0.1)
        bad = node.set_parameters([Parameter("rerun", value="tape:x")])[0]
        assert not bad.successful and "unknown rerun sink" in bad.reason
        bad = node.set_parameters([Parameter("rerun_pairs", value="a-b")])[0]
        assert not bad.successful and "name_a:name_b" in bad.reason
        ok = node.set_parameters([Parameter("rerun", value=f"save:{second}")])[0]
        assert ok.successful, ok.reason
        for sec in (4, 5):
            answer(sec, 0.2)
        values = {kv.key: kv.value for kv in node.diagnostics().values}
        assert values["rerun"] == f"save:{second}" and values["rerun errors"] == "0"
    finally:
        h.close()
    one, two = read_recording(first), read_recording(second)
    steps_one = [r for r in one["/world/contacts"] if "depth" in r]
    depths = [r["depth"] for r in steps_one]
    assert len(depths) == 3 and all(d == [depths[0][0]] for d in depths)
    assert abs(depths[0][0] - 0.1) < 1e-9
    assert [r["stamp"] for r in steps_one] == [1_000_000_000 * s
                                                             for s in (1, 2, 3)]
    later = [r["depth"] for r in two["/world/contacts"] if "depth" in r]
    assert len(later) == 2 and np.allclose(later, 0.2, atol=1e-9, rtol=0)
    # the node logs its own latency, pose stamp to publish, as the first series
    lat = [r["Scalars:scalars"][0] for r in two["/timing"] if "Scalars:scalars" in r]
    assert len(lat) == 2 and all(x > 0 for x in lat)
