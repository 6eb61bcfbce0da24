"""Two installed collision_node processes as the two shards of one scene (shard_index,
shard_count) against a third, alone: on the same pose messages, the shards' contacts
together are the lone node's, with the same contact ids."""
import numpy as np
from ros_harness import RosHarness, start_node, stop  # noqa: I001

from builtin_interfaces.msg import Time
from mkcollision_msgs.msg import BodyPoseArray, ContactArray

import msg_adapters
from mkcollision_ros.config import bodies_from_params, load_params_file
from mkcollision_ros.demo import default_params_file

STEPS = 12


def _poses(names, k):
    """Step k: the bodies on a ring that shrinks and grows again, turning (neighbours
    touch, part and touch again), above the floor."""
    n = len(names)
    r = 0.5 + 0.35 * abs(np.cos(0.35 * k))
    a = 2 * np.pi * np.arange(n) / n + 0.05 * k
    pos = np.stack([r * np.cos(a), r * np.sin(a), 0.45 + 0.04 * np.sin(a + k)], axis=1)
    half = 0.1 * k + 0.3 * np.arange(n)
    quat = np.stack([np.zeros(n), np.sin(half), np.zeros(n), np.cos(half)], axis=1)
    return pos, quat


def _rows(msg):
    """A ContactArray's contacts as a set of (body_a, body_b, id, position, depth)."""
    pos = np.asarray(msg.positions).reshape(-1, 3)
    return {(a, b, int(i), tuple(np.round(p, 9)), round(float(d), 9))
            for a, b, i, p, d in zip(msg.body_a, msg.body_b, msg.ids, pos, msg.depths)}


def test_two_shards_answer_as_one_node_with_the_same_ids():
    params = default_params_file()
    bodies = bodies_from_params(load_params_file(params))
    moving = [b["name"] for b in bodies if not b["static"]]
    procs = [start_node(params, "-r", "__ns:=/single")]
    procs += [start_node(params, "-r", "__ns:=/shards", "-r", f"__node:=collision_node_{k}",
                         "-p", f"shard_index:={k}", "-p", "shard_count:=2")
              for k in range(2)]
    h = RosHarness()
    try:
        probe = h.node("shard_probe")
        single, shards = {}, {}
        probe.create_subscription(
            ContactArray, "/single/contacts",
            lambda m: single.setdefault(m.header.stamp.sec, m), 10)
        probe.create_subscription(
            ContactArray, "/shards/contacts",
            lambda m: shards.setdefault((m.header.stamp.sec, m.shard_index), m), 10)
        pubs = [probe.create_publisher(BodyPoseArray, f"/{ns}/body_poses", 10)
                for ns in ("single", "shards")]
        for k in range(1, STEPS + 1):
            pos, quat = _poses(moving, k)
            msg = msg_adapters.arrays_to_body_pose_array(moving, pos, quat, Time(sec=k))

            def send(msg=msg):
                for p in pubs:
                    p.publish(msg)
            # each stamp until all three answered it (a repeated stamp is dropped), so
            # every node steps on every pose message; a liveness bound, not a speed figure
            ok = h.spin_until(lambda: k in single and (k, 0) in shards and (k, 1) in shards,
                              timeout=600.0, step=send)
            assert ok, "\n".join(stop(p) for p in procs)
        touching = 0
        ids = set()
        for k in range(1, STEPS + 1):
            one = single[k]
            parts = [shards[(k, s)] for s in range(2)]
            assert (one.shard_index, one.shard_count) == (0, 1)
            assert [(m.shard_index, m.shard_count) for m in parts] == [(0, 2), (1, 2)]
            a, b = _rows(parts[0]), _rows(parts[1])
            assert not a & b, k
            assert a | b == _rows(one), k
            touching += len(one.ids)
            ids |= set(one.ids)
        assert touching > 20 and len(ids) > 5          # the scene did touch, and change
        for s in range(2):                             # and each shard had a share
            assert any(len(shards[(k, s)].ids) for k in range(1, STEPS + 1)), s
    finally:
        h.close()
        logs = [stop(p) for p in procs]
    for p, log in zip(procs, logs):
        assert p.returncode == 0, log
