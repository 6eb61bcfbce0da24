"""The collision node in-process over real DDS: a test node publishes poses, the
collision node answers with ContactArray / MarkerArray, checked against closed forms."""
import math

import numpy as np
import pytest
from ros_harness import RosHarness  # noqa: I001  (sets ROS_DOMAIN_ID before rclpy)

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseArray
from mkcollision_msgs.msg import BodyPoseArray, ContactArray
from mkcollision_msgs.srv import CheckCollision
from rclpy.parameter import Parameter
from visualization_msgs.msg import MarkerArray

import msg_adapters
from msg_adapters.poses import arrays_to_pose_array
from mkcollision_ros.node import CollisionNode

RADII = {"a": 0.5, "b": 0.3}
ELL = (0.6, 0.3, 0.2)


def overrides():
    return [
        Parameter("bodies.names", value=["a", "b", "egg", "crate"]),
        Parameter("bodies.a.type", value="sphere"), Parameter("bodies.a.radius", value=0.5),
        Parameter("bodies.b.type", value="sphere"), Parameter("bodies.b.radius", value=0.3),
        Parameter("bodies.egg.type", value="ellipsoid"),
        Parameter("bodies.egg.radii", value=list(ELL)),
        Parameter("bodies.crate.type", value="box"),
        Parameter("bodies.crate.size", value=[1.0, 1.0, 1.0]),
        Parameter("rate_hz", value=100.0),
        Parameter("warn_throttle_s", value=0.0),
    ]


@pytest.fixture
def ros():
    h = RosHarness()
    node = h.add(CollisionNode(context=h.context, parameter_overrides=overrides()))
    probe = h.node("probe")
    got = {"contacts": [], "markers": []}
    probe.create_subscription(ContactArray, "contacts", got["contacts"].append, 10)
    probe.create_subscription(MarkerArray, "contact_markers", got["markers"].append, 10)
    pub = probe.create_publisher(BodyPoseArray, "body_poses", 10)
    pub_array = probe.create_publisher(PoseArray, "pose_array", 10)
    client = probe.create_client(CheckCollision, "check_collision")
    yield h, node, pub, pub_array, client, got
    h.close()


FAR = {"egg": [20.0, 0.0, 0.0], "crate": [-20.0, 0.0, 0.0]}
IDENTITY = [0.0, 0.0, 0.0, 1.0]


def publish_and_wait(h, pub, got, names, pos, quat, sec):
    """Publish one BodyPoseArray stamped ``sec`` and return the first ContactArray that
    carries that stamp."""
    msg = msg_adapters.arrays_to_body_pose_array(names, pos, quat, Time(sec=sec))
    got["contacts"].clear()

    def answered():
        return any(m.header.stamp.sec == sec for m in got["contacts"])

    assert h.spin_until(answered, timeout=60.0, step=lambda: pub.publish(msg)), \
        "the collision node did not answer"
    return next(m for m in got["contacts"] if m.header.stamp.sec == sec)


def expected_sphere_contact(pa, pb, ra, rb):
    d = np.linalg.norm(pb - pa)
    n = (pb - pa) / d
    return ra + rb - d, n, pa + ra * n, pb - rb * n


def test_sphere_pairs_match_closed_form_over_dds(ros):
    h, node, pub, _, _, got = ros
    rng = np.random.default_rng(7)
    hits = 0
    for trial in range(12):
        pa = rng.uniform(-1, 1, 3)
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        dist = rng.uniform(0.3, 1.1)     # contact iff dist < 0.8
        pb = pa + dist * direction
        names = ["a", "b", "egg", "crate"]
        pos = np.array([pa, pb, FAR["egg"], FAR["crate"]])
        quat = np.tile(IDENTITY, (4, 1))
        msg = publish_and_wait(h, pub, got, names, pos, quat, sec=100 + trial)
        c = msg_adapters.contact_array_to_arrays(msg)
        if dist >= 0.8:
            assert len(c["depth"]) == 0
            continue
        hits += 1
        depth, n, wa, wb = expected_sphere_contact(pa, pb, 0.5, 0.3)
        assert list(zip(c["body_a"], c["body_b"])) == [("a", "b")]
        assert c["depth"][0] == pytest.approx(depth, abs=1e-9)
        np.testing.assert_allclose(c["normal"][0], n, atol=1e-9)
        np.testing.assert_allclose(c["point_a"][0], wa, atol=1e-9)
        np.testing.assert_allclose(c["point_b"][0], wb, atol=1e-9)
        np.testing.assert_allclose(c["position"][0], 0.5 * (wa + wb), atol=1e-9)
        assert msg.header.frame_id == "world"
    assert 3 <= hits <= 10  # the random cases exercise both outcomes


def test_contact_id_persists_and_markers_follow(ros):
    h, node, pub, _, _, got = ros
    names = ["a", "b", "egg", "crate"]
    ids = []
    for k in range(5):
        pos = np.array([[0, 0, 0], [0.7 + 0.01 * k, 0, 0], FAR["egg"], FAR["crate"]], float)
        msg = publish_and_wait(h, pub, got, names, pos, np.tile(IDENTITY, (4, 1)), 200 + k)
        c = msg_adapters.contact_array_to_arrays(msg)
        assert len(c["depth"]) >= 1
        ids.append(set(c["contact_id"].tolist()))
    assert all(s == ids[0] for s in ids), ids
    assert h.spin_until(lambda: len(got["markers"]) > 0, timeout=10.0)
    markers = {(m.ns, m.id): m for m in got["markers"][-1].markers}
    assert markers[("contacts", 0)].type == markers[("contacts", 0)].SPHERE_LIST
    assert len(markers[("contacts", 0)].points) >= 1
    assert len(markers[("normals", 0)].points) == 2 * len(markers[("contacts", 0)].points)
    a, b = markers[("bodies", 0)], markers[("bodies", 1)]       # 6 cm deep: red
    assert (a.color.r, a.color.g) == (1.0, 0.0) and (b.color.r, b.color.g) == (1.0, 0.0)
    assert markers[("bodies", 2)].color.r == pytest.approx(0.6)   # the egg, far: grey


def test_sphere_against_ellipsoid_along_its_long_axis(ros):
    h, node, pub, _, _, got = ros
    names = ["egg", "b", "a", "crate"]
    x = 0.85   # ellipsoid semi-axis 0.6 along x, sphere radius 0.3: depth 0.05
    pos = np.array([[1.0, 2.0, 3.0], [1.0 + x, 2.0, 3.0], [-20, 5, 0], FAR["crate"]])
    msg = publish_and_wait(h, pub, got, names, pos, np.tile(IDENTITY, (4, 1)), 300)
    c = msg_adapters.contact_array_to_arrays(msg)
    assert list(zip(c["body_a"], c["body_b"])) == [("b", "egg")]  # lower configured index first
    assert c["depth"][0] == pytest.approx(0.6 + 0.3 - x, abs=1e-6)
    np.testing.assert_allclose(c["normal"][0], [-1.0, 0.0, 0.0], atol=1e-6)  # from b to egg


def test_pose_array_input_in_configured_order(ros):
    h, node, _, pub_array, _, got = ros
    pos = np.array([[0, 0, 0], [0, 0.75, 0], FAR["egg"], FAR["crate"]], float)
    msg = arrays_to_pose_array(pos, np.tile(IDENTITY, (4, 1)))
    msg.header.stamp = Time(sec=400)
    got["contacts"].clear()
    assert h.spin_until(lambda: any(m.header.stamp.sec == 400 and len(m.depths)
                                    for m in got["contacts"]),
                        timeout=30.0, step=lambda: pub_array.publish(msg))
    m = next(m for m in got["contacts"] if m.header.stamp.sec == 400)
    assert m.depths[0] == pytest.approx(0.05, abs=1e-9)


def test_bad_input_is_dropped_and_the_rest_applied(ros):
    h, node, pub, pub_array, _, got = ros
    # wrong lengths: the whole message is dropped, the node keeps running
    bad = BodyPoseArray(names=["a", "b"])
    bad.positions = [0.0, 0.0]
    pub.publish(bad)
    # a PoseArray of the wrong length is dropped too
    pub_array.publish(arrays_to_pose_array(np.zeros((2, 3)), np.tile(IDENTITY, (2, 1))))
    # NaN for b, a zero quaternion for egg, an unknown name: only those entries dropped
    names = ["a", "b", "egg", "nobody", "crate"]
    pos = np.array([[0, 0, 0], [math.nan, 0, 0], [0.9, 0, 0], [0, 0, 0], FAR["crate"]])
    quat = np.tile(IDENTITY, (5, 1))
    quat[2] = 0.0
    msg = publish_and_wait(h, pub, got, names, pos, quat, 500)
    c = msg_adapters.contact_array_to_arrays(msg)
    assert len(c["depth"]) == 0          # b and egg have no valid pose yet
    assert np.isfinite(node.scene.positions).all()
    # a valid follow-up is applied
    pos = np.array([[0, 0, 0], [0.6, 0, 0], FAR["egg"], FAR["crate"]])
    msg = publish_and_wait(h, pub, got, ["a", "b", "egg", "crate"], pos,
                           np.tile(IDENTITY, (4, 1)), 501)
    c = msg_adapters.contact_array_to_arrays(msg)
    assert c["depth"][0] == pytest.approx(0.2, abs=1e-9)
    for m in got["contacts"]:
        for field in (m.positions, m.normals, m.depths, m.points_a, m.points_b):
            assert np.isfinite(np.asarray(field)).all()


def test_check_collision_service_does_not_change_the_scene(ros):
    h, node, pub, _, client, got = ros
    names = ["a", "b", "egg", "crate"]
    scene = np.array([[0, 0, 0], [5, 0, 0], FAR["egg"], FAR["crate"]], float)
    publish_and_wait(h, pub, got, names, scene, np.tile(IDENTITY, (4, 1)), 600)
    assert h.spin_until(client.service_is_ready, timeout=10.0)

    def call(request):
        future = client.call_async(request)
        assert h.spin_until(future.done, timeout=30.0)
        return future.result()

    req = CheckCollision.Request(names=["a", "b"])
    req.positions = [0.0, 0.0, 0.0, 0.0, 0.0, 0.7]
    req.orientations = IDENTITY + IDENTITY
    res = call(req)
    assert res.success, res.message
    assert len(res.contacts) == 1
    c = res.contacts[0]
    assert (c.body_a, c.body_b) == ("a", "b")
    assert c.depth == pytest.approx(0.1, abs=1e-9)
    assert (c.normal.x, c.normal.y, c.normal.z) == pytest.approx((0.0, 0.0, 1.0), abs=1e-9)
    assert c.signed_distance == pytest.approx(-0.1, abs=1e-9)
    # the scene's own poses are untouched: a and b are still 5 m apart
    res = call(CheckCollision.Request(names=[]))
    assert res.success and len(res.contacts) == 0
    np.testing.assert_allclose(node.scene.positions[1], [5, 0, 0])
    # malformed requests get success = false and a reason
    res = call(CheckCollision.Request(names=["a", "ghost"]))
    assert not res.success and "ghost" in res.message
    bad = CheckCollision.Request(names=["a", "b"])
    bad.positions = [0.0, 0.0, 0.0]
    res = call(bad)
    assert not res.success and "positions" in res.message
