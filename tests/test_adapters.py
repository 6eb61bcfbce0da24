"""msg_adapters: struct-of-arrays layouts, zero-copy reads, round trips, length checks."""
import math

import numpy as np
import pytest
from ros_harness import RosHarness  # noqa: F401,I001  (sets ROS_DOMAIN_ID before rclpy)

from mkcollision_msgs.msg import BodyPoseArray
from rclpy.serialization import deserialize_message, serialize_message

import msg_adapters
from msg_adapters.poses import arrays_to_pose_array
from mkcollision_ros.results import ContactSet


def contacts(n, seed=0):
    rng = np.random.default_rng(seed)
    pa = rng.normal(size=(n, 3))
    normal = rng.normal(size=(n, 3))
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    depth = rng.uniform(0, 0.1, n)
    pb = pa - depth[:, None] * normal
    return ContactSet(names=["a", "b", "c"], body_a=np.zeros(n, np.int64),
                      body_b=rng.integers(1, 3, n), position=0.5 * (pa + pb), point_a=pa,
                      point_b=pb, normal=normal, depth=depth,
                      contact_id=rng.integers(1, 2 ** 40, n), age=rng.integers(0, 99, n),
                      method=np.full(n, 1), status=np.full(n, 2))


def test_body_pose_array_round_trip_through_cdr_is_exact():
    rng = np.random.default_rng(1)
    names = [f"b{i}" for i in range(1000)]
    pos, quat = rng.normal(size=(1000, 3)), rng.normal(size=(1000, 4))
    msg = msg_adapters.arrays_to_body_pose_array(names, pos, quat, frame_id="map")
    back = deserialize_message(serialize_message(msg), BodyPoseArray)
    n2, p2, q2 = msg_adapters.body_pose_array_to_arrays(back)
    assert n2 == names and back.header.frame_id == "map"
    assert np.array_equal(p2, pos) and np.array_equal(q2, quat)
    assert not p2.flags.writeable          # views of the message: copy before mutating


@pytest.mark.parametrize("n_pos, n_quat", [(5, 8), (6, 7), (0, 0)])
def test_body_pose_array_length_contract(n_pos, n_quat):
    msg = BodyPoseArray(names=["a", "b"])
    msg.positions = [0.0] * n_pos
    msg.orientations = [0.0] * n_quat
    with pytest.raises(ValueError, match="needs 6 positions and 8 orientation"):
        msg_adapters.body_pose_array_to_arrays(msg)


def test_pose_array_order_is_kept():
    pos = np.arange(12.0).reshape(4, 3)
    quat = np.tile([0.0, 0.0, 0.6, 0.8], (4, 1))
    p2, q2 = msg_adapters.pose_array_to_arrays(arrays_to_pose_array(pos, quat))
    assert np.array_equal(p2, pos) and np.array_equal(q2, quat)


def test_contact_array_and_contact_list_carry_every_field():
    c = contacts(7)
    msg = msg_adapters.contacts_to_contact_array(c, frame_id="world")
    back = msg_adapters.contact_array_to_arrays(msg)
    assert back["body_a"] == ["a"] * 7
    assert back["body_b"] == [c.names[i] for i in c.body_b]
    for key in ("position", "point_a", "point_b", "normal", "depth"):
        assert np.array_equal(back[key], getattr(c, key)), key
    assert back["contact_id"].tolist() == c.contact_id.tolist()
    assert back["age"].tolist() == c.age.tolist()
    items = msg_adapters.contacts_to_contact_list(c)
    assert [x.id for x in items] == c.contact_id.tolist()
    for x, d in zip(items, c.depth):
        assert x.signed_distance == pytest.approx(-d, abs=1e-12)
        assert x.status == x.STATUS_PENETRATING and x.method == x.METHOD_GJK_EPA


def test_markers_points_and_normals_batched():
    c = contacts(10)
    out = msg_adapters.contacts_to_marker_array(c, normal_length=0.5).markers
    points, normals = out
    assert (points.ns, points.type, len(points.points)) == ("contacts", points.SPHERE_LIST, 10)
    assert (normals.ns, normals.type, len(normals.points)) == ("normals", normals.LINE_LIST, 20)
    tip = normals.points[1]
    expected = c.position[0] + (0.5 + c.depth[0]) * c.normal[0]
    assert (tip.x, tip.y, tip.z) == pytest.approx(tuple(expected))
    empty = msg_adapters.contacts_to_marker_array(contacts(0)).markers
    assert [m.action for m in empty] == [empty[0].DELETE] * 2       # nothing stale


def test_body_markers_follow_the_scene_with_stable_ids():
    from mkcollision_ros.scene import Scene
    from msg_adapters.markers import MarkerPainter
    sc = Scene([{"name": n, "shape": s, "pose": ([float(i), 0.0, 0.0], [0, 0, 0, 1])}
                for i, (n, s) in enumerate([
                    ("ball", {"type": "sphere", "radius": 0.5}),
                    ("egg", {"type": "ellipsoid", "radii": [0.3, 0.2, 0.1]}),
                    ("crate", {"type": "box", "size": [1.0, 2.0, 3.0]}),
                    ("can", {"type": "cylinder", "radius": 0.2, "height": 1.0}),
                    ("pill", {"type": "capsule", "radius": 0.1, "length": 0.5}),
                    ("cone", {"type": "cone", "radius": 0.3, "height": 0.6}),
                    ("tet", {"type": "convex", "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0],
                                                           [0, 0, 1]]}),
                    ("floor", {"type": "plane", "normal": [0, 0, 1], "offset": 0.0})])])
    painter = MarkerPainter()
    c = contacts(0)
    c.names = sc.names
    out = painter.marker_array(sc, c).markers
    body = {m.id: m for m in out if m.ns == "bodies"}
    assert sorted(body) == list(range(8))
    kinds = [body[i].type for i in range(8)]
    M = out[0]
    assert kinds == [M.SPHERE, M.SPHERE, M.CUBE, M.CYLINDER, M.TRIANGLE_LIST,
                     M.TRIANGLE_LIST, M.TRIANGLE_LIST, M.CUBE]
    assert (body[1].scale.x, body[1].scale.y, body[1].scale.z) == (0.6, 0.4, 0.2)
    assert body[2].pose.position.x == 2.0
    # the hull's triangles lie on the hull: every point is one of its vertices
    pts = {(p.x, p.y, p.z) for p in body[6].points}
    assert pts <= {(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)}
    # the capsule's points are on its surface
    for p in body[4].points:
        z = min(max(p.z, -0.25), 0.25)
        assert math.hypot(p.x, p.y, p.z - z) == pytest.approx(0.1, abs=1e-12)
    # the plane's patch: its top face on z = 0
    assert body[7].pose.position.z == pytest.approx(-0.001) and body[7].scale.x == 20.0
    # a removed body's marker is deleted, the others keep their ids and objects
    sc.remove_body("egg")
    again = painter.marker_array(sc, c).markers
    gone = [m for m in again if m.ns == "bodies" and m.action == m.DELETE]
    assert [m.id for m in gone] == [1]
    assert {m.id for m in again if m.ns == "bodies" and m.action == m.ADD} == set(body) - {1}

@pytest.mark.parametrize("n, frame", [(0, "world"), (1, ""), (7, "map"), (1000, "odom_x")])
def test_pose_array_from_cdr_equals_rclpy(n, frame):
    from geometry_msgs.msg import PoseArray
    from msg_adapters.poses import pose_array_from_cdr
    rng = np.random.default_rng(n)
    pos, quat = rng.normal(size=(n, 3)), rng.normal(size=(n, 4))
    msg = arrays_to_pose_array(pos, quat, frame_id=frame)
    msg.header.stamp.sec, msg.header.stamp.nanosec = 12, 345
    data = serialize_message(msg)
    back = deserialize_message(data, PoseArray)
    sec, nsec, fr, p, q = pose_array_from_cdr(data)
    assert (sec, nsec, fr) == (12, 345, frame) == (back.header.stamp.sec,
                                                   back.header.stamp.nanosec,
                                                   back.header.frame_id)
    want_p, want_q = msg_adapters.pose_array_to_arrays(back)
    assert np.array_equal(p, want_p) and np.array_equal(q, want_q)
    with pytest.raises(ValueError):
        pose_array_from_cdr(data[:len(data) - 8] if n else data[:10])


def test_large_scenes_draw_their_bodies_in_turns():
    from mkcollision_ros.scene import Scene
    from msg_adapters.markers import MarkerPainter
    sc = Scene([{"name": f"b{i}", "shape": {"type": "sphere", "radius": 0.1},
                 "pose": ([float(i), 0.0, 0.0], [0, 0, 0, 1])} for i in range(10)])
    c = contacts(0)
    painter = MarkerPainter()
    seen = []
    for _ in range(3):
        out = painter.marker_array(sc, c, max_bodies=4).markers
        seen.append([m.id for m in out if m.ns == "bodies"])
    assert seen == [[0, 1, 2, 3], [4, 5, 6, 7], [8, 9, 0, 1]]
    sc.remove_body("b5")                       # deleted at once, not in its turn
    out = painter.marker_array(sc, c, max_bodies=4).markers
    assert [m.id for m in out if m.ns == "bodies" and m.action == m.DELETE] == [5]
