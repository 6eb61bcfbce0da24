"""The demo's scripted scenes: the contacts a viewer expects happen, in the scripted
geometry (the library's pipeline stepping the script) and through the real installed
node (``demo.run`` in lockstep: one pose message per script step, each sent once the
node answered the last), at the same script times, so both see the same poses."""
import io
import math
import os

import numpy as np
import pytest
from ros_harness import RosHarness  # noqa: I001  (first: a private ROS domain)

from mkcollision_ros import collide, demo, demo_scenes
from mkcollision_ros.config import bodies_from_params, flatten
from mkcollision_ros.pipeline import Pipeline

STEP = 1.0 / 30.0                 # s of script per step, as the demo publishes at 30 Hz
SCRIPTED = ("bowling", "dominoes", "marbles", "stack")
CONFIG = os.path.join(os.path.dirname(__file__), "..", "config")


@pytest.fixture(scope="module")
def scenes():
    return {name: demo_scenes.make_scene(name) for name in SCRIPTED}


def _play(scene, step=STEP, seconds=None):
    """Step the library's pipeline through the script at multiples of ``step``:
    ({Expect label: subjects seen}, {pair: deepest contact (m)})."""
    bodies = bodies_from_params(flatten(scene.params()["/**"]["ros__parameters"]))
    pipe = Pipeline(bodies)
    seen, deepest = {}, {}
    for k in range(int(round((seconds or scene.duration) / step)) + 1):
        t = k * step
        pos, quat = scene.pose(t)
        pipe.scene.set_poses(scene.moving, pos, quat)
        res = pipe.step(stamp=1.0 + t)
        pairs = {(res.names[a], res.names[b]) for a, b in zip(res.body_a, res.body_b)}
        demo_scenes.note_contacts(scene, t, pairs, seen)
        for a, b, d in zip(res.body_a, res.body_b, res.depth):
            key = (res.names[a], res.names[b])
            deepest[key] = max(deepest.get(key, 0.0), float(d))
    return seen, deepest


def _all_wanted(scene, seen):
    """Every expectation with a known count has at least that many subjects seen."""
    return {e.label: (len(seen.get(e.label, ())), e.wanted) for e in scene.expects
            if e.wanted is not None and len(seen.get(e.label, ())) < e.wanted}


# -- the scripts, in-process ------------------------------------------------------------
@pytest.mark.parametrize("name", demo_scenes.SCENE_NAMES)
def test_shipped_params_files_are_the_scenes_bodies(scenes, name):
    scene = scenes[name] if name in scenes else demo_scenes.make_scene(name)
    with open(os.path.join(CONFIG, f"demo_{name}.yaml"), encoding="utf-8") as f:
        assert f.read() == demo_scenes.params_yaml(scene), \
            "regenerate with: python -m mkcollision_ros.demo_scenes config"


def test_domino_lean_puts_the_edge_the_reach_deep_into_the_next_domino():
    c = demo_scenes.DOMINO
    th, h, s, reach = c["thick"], c["tall"], c["spacing"], c["reach"]
    box = {"type": "box", "size": [th, c["wide"], h]}

    def pose(x_front, tilt):       # turned about its front bottom edge at (x_front, 0)
        cx, cz = demo_scenes._xz_turn(np.array(tilt), np.array([-0.5 * th, 0.5 * h]))
        return [x_front + cx, 0.0, cz], demo_scenes._y_turn(np.array(tilt))

    for phi in np.radians([0.0, 10.0, 30.0, 50.0, 70.0, 90.0]):
        theta = float(demo_scenes.domino_lean(phi, s, th, h, reach))
        r = collide(box, pose(0.0, theta), box, pose(s, phi))
        assert r.distance == pytest.approx(-reach, abs=2e-5), (math.degrees(phi), r)
    # the first touch: the tilt at which the top edge reaches the next, upright domino
    first = math.asin((s - th) / h)
    r = collide(box, pose(0.0, first), box, pose(s, 0.0))
    assert abs(r.distance) < 1e-6


@pytest.mark.parametrize("name", SCRIPTED)
def test_scripted_geometry_makes_the_expected_contacts(scenes, name):
    scene = scenes[name]
    seen, deepest = _play(scene)
    assert not _all_wanted(scene, seen), (seen, deepest)
    if name == "bowling":
        assert set(scene.hit_by_ball) <= seen["ball-pin contacts"]
        assert len(scene.hit_by_ball) >= 2 and len(scene.toppled) >= 5
        assert set(scene.toppled) <= seen["toppled pins on the floor"]
    if name == "dominoes":
        assert {(f"domino_{i}", f"domino_{i + 1}") for i in range(13)} <= set(deepest)
    # contacts are touches, not bodies passing through each other
    limit = 0.035 if name == "bowling" else 0.0045
    assert max(deepest.values()) < limit, sorted(deepest.items(), key=lambda kv: -kv[1])[:3]


@pytest.mark.parametrize("name", SCRIPTED)
def test_scripts_are_smooth_and_hold_their_end(scenes, name):
    scene = scenes[name]
    times = np.arange(0.0, scene.period, 0.01)
    poses = [scene.pose(t) for t in times]
    pos = np.array([p for p, _ in poses])
    quat = np.array([q for _, q in poses])
    assert np.isfinite(pos).all() and np.allclose(np.linalg.norm(quat, axis=2), 1.0)
    # no body jumps: at most 6 m/s (the fastest pin) between samples 10 ms apart
    assert np.linalg.norm(np.diff(pos, axis=0), axis=2).max() < 0.06
    end = scene.pose(scene.duration)[0]
    assert np.allclose(scene.pose(scene.duration + 0.5 * scene.hold)[0], end)
    assert np.allclose(scene.pose(scene.period + 0.25)[0], scene.pose(0.25)[0])


def test_swarm_generates_n_bodies_on_orbits_that_meet():
    scene = demo_scenes.make_scene("swarm", bodies=200)
    assert len(scene.moving) == 200 and scene.bodies[-1]["name"] == "floor"
    seen, deepest = _play(scene, step=0.1, seconds=6.0)
    moving = set(scene.moving)
    assert len([p for p in deepest if set(p) <= moving]) >= 20
    with pytest.raises(ValueError, match="swarm scene only"):
        demo_scenes.make_scene("bowling", bodies=10)
    with pytest.raises(ValueError, match="positive integer"):
        demo_scenes.make_scene("swarm", bodies=0)


# -- the command line ---------------------------------------------------------------------
@pytest.mark.parametrize("argv, message", [
    (["--scene", "nope"], "invalid choice"),
    (["--scene", "bowling", "--bodies", "5"], "apply to --scene swarm only"),
    (["--scene", "swarm", "--bodies", "0"], "must be > 0"),
    (["--seconds", "-1"], "must be > 0"),
    (["--rate", "abc"], "expected a float"),
    (["--record", "/no/such/folder/x.rrd"], "no folder"),
    (["--record", "demo.txt"], "must end in .rrd"),
])
def test_bad_arguments_exit_2_with_a_message(capsys, argv, message):
    with pytest.raises(SystemExit) as err:
        demo.main(argv)
    assert err.value.code == 2
    assert message in capsys.readouterr().err


def test_publisher_sends_the_scripts_poses(scenes):
    import msg_adapters
    from mkcollision_msgs.msg import BodyPoseArray
    scene = scenes["stack"]
    h = RosHarness()
    try:
        node = h.node("demo_pub")
        got = []
        h.node("probe").create_subscription(BodyPoseArray, "body_poses", got.append, 10)
        pub = demo.DemoPublisher(node, scene, rate_hz=None)
        times = [0.0, 0.9, 1.35, 2.0, 3.5]
        assert h.spin_until(lambda: len(got) > 0, timeout=20.0,
                            step=lambda: pub.publish_at(times[0]))
        got.clear()
        for t in times:
            pub.publish_at(t)
            assert h.spin_until(lambda: got, timeout=10.0)
            msg = got.pop()
            names, pos, quat = msg_adapters.body_pose_array_to_arrays(msg)
            want_pos, want_quat = scene.pose(t)
            assert list(names) == scene.moving
            assert pub.script_time[(msg.header.stamp.sec, msg.header.stamp.nanosec)] == t
            assert np.allclose(pos, want_pos) and np.allclose(quat, want_quat)
            got.clear()
    finally:
        h.close()


# -- the real node ------------------------------------------------------------------------
def _run(scene, seconds, **kw):
    out = io.StringIO()
    summary = demo.run(seconds, scene=scene, step_s=kw.pop("step_s", STEP), out=out, **kw)
    return summary, out.getvalue()


@pytest.mark.parametrize("name", SCRIPTED)
def test_node_sees_the_expected_contacts(scenes, name, tmp_path):
    scene = scenes[name]
    record = str(tmp_path / "scene.rrd") if name == "dominoes" else None
    summary, text = _run(scene, scene.duration, record=record)
    assert summary["steps"] >= int(scene.duration / STEP), text
    seen = summary["seen"]
    assert not _all_wanted(scene, seen), text
    # the node sees what the library sees in the same script steps
    lib_seen, _ = _play(scene)
    for e in scene.expects:
        assert seen[e.label] == lib_seen.get(e.label, set()), (e.label, text)
    if name == "bowling":
        assert len(seen["ball-pin contacts"]) >= 2, text
        assert set(scene.toppled) <= seen["toppled pins on the floor"], text
    if name == "dominoes":
        assert seen["domino-next contacts"] == {f"domino_{i}" for i in range(13)}, text
        assert f"recording: {record}; open it with: rerun {record}" in text
        from mkcollision_ros.rerun_log import read_recording
        assert "/world/contacts" in read_recording(record)
    if name == "marbles":
        assert seen["marble-plank contacts"] == seen["marbles in the tray"] == \
            set(scene.moving), text
    if name == "stack":
        assert seen["ball-tower contacts"] == {"block_6"}, text     # hit at 0.62 m
        assert len(seen["blocks on the floor after the fall"]) == 8, text
    for e in scene.expects:
        assert e.report(seen[e.label]) in text


def test_node_swarm_of_200_bodies_has_contacts_between_moving_bodies():
    summary, text = _run("swarm", 4.0, bodies=200, step_s=0.1)
    touching = summary["seen"]["moving bodies touching another"]
    assert len(touching) >= 20, text
    assert summary["moving_bodies"] == 200 and summary["bodies"] == 201, text
