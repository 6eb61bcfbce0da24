"""The installed executable, started as a user would (what `ros2 run mkcollision_ros
collision_node --ros-args --params-file ...` starts), with the package's config."""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from ros_harness import RosHarness, run_to_exit, start_node, stop  # noqa: I001

from builtin_interfaces.msg import Time
from mkcollision_msgs.msg import BodyPoseArray, ContactArray

import msg_adapters
from mkcollision_ros.config import bodies_from_params, load_params_file
from mkcollision_ros.demo import default_params_file, node_executable


def test_installed_executable_and_config_are_where_ros2_run_looks():
    exe = node_executable()
    assert exe.endswith(os.path.join("lib", "mkcollision_ros", "collision_node"))
    assert os.access(exe, os.X_OK)
    cfg = default_params_file()
    assert cfg.endswith(os.path.join("share", "mkcollision_ros", "config", "collision_node.yaml"))
    # the ament index marker `ros2 pkg list` reads
    from ament_index_python import get_resource
    assert get_resource("packages", "mkcollision_ros") is not None


@pytest.mark.parametrize("executor, sig", [("events", signal.SIGINT),
                                           ("events", signal.SIGTERM),
                                           ("single_threaded", signal.SIGTERM)])
def test_executable_with_config_file_answers_poses(executor, sig):
    """Each executor answers, and the node exits cleanly on Ctrl-C and on SIGTERM (what
    launch and systemd send)."""
    params_file = default_params_file()
    bodies = bodies_from_params(load_params_file(params_file))
    radius = {b["name"]: b["shape"].get("radius") for b in bodies}
    proc = start_node(params_file, "-p", f"executor:={executor}")
    h = RosHarness()
    try:
        probe = h.node("probe")
        got = []
        probe.create_subscription(ContactArray, "contacts", got.append, 10)
        pub = probe.create_publisher(BodyPoseArray, "body_poses", 10)
        # every moving body far apart and above the floor, except ball_0 and ball_1
        moving = [b["name"] for b in bodies if not b["static"]]
        pos = np.array([[5.0 * i, 0.0, 3.0] for i in range(len(moving))])
        i0, i1 = moving.index("ball_0"), moving.index("ball_1")
        pos[i0] = [0.0, 0.0, 3.0]
        pos[i1] = [0.0, 0.45, 3.0]
        quat = np.tile([0.0, 0.0, 0.0, 1.0], (len(moving), 1))
        msg = msg_adapters.arrays_to_body_pose_array(moving, pos, quat, Time(sec=77))
        # a liveness bound, not a speed figure: in a fresh clone the executable first
        # compiles the pipeline's kernels (up to 6.5 min measured, README), longer in a
        # slow spell of a shared machine: 480 s is not always enough
        ok = h.spin_until(lambda: any(m.header.stamp.sec == 77 for m in got),
                          timeout=900.0, step=lambda: pub.publish(msg))
        assert ok, "no ContactArray from the executable:\n" + stop(proc)
        m = next(m for m in got if m.header.stamp.sec == 77)
        assert list(zip(m.body_a, m.body_b)) == [("ball_0", "ball_1")]
        assert m.depths[0] == pytest.approx(radius["ball_0"] + radius["ball_1"] - 0.45, abs=1e-9)
        assert tuple(m.normals) == pytest.approx((0.0, 1.0, 0.0), abs=1e-9)
    finally:
        h.close()
        log = stop(proc, sig)
    assert proc.returncode == 0, log


def test_broken_config_exits_with_a_clear_message(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("collision_node:\n  ros__parameters:\n    bodies:\n"
                   "      names: [x]\n      x: {type: sphere, radius: -1.0}\n")
    code, log = run_to_exit(str(bad))
    assert code == 1, log
    assert "invalid configuration" in log and "'radius' must be > 0" in log, log


def test_missing_params_file_and_typo_give_one_line(tmp_path):
    code, log = run_to_exit(str(tmp_path / "missing.yaml"))
    assert code == 1, log
    assert "Traceback" not in log and "cannot start" in log, log
    typo = tmp_path / "typo.yaml"
    typo.write_text("/**:\n  ros__parameters:\n    rate_hzz: 5.0\n    bodies:\n"
                    "      names: [x]\n      x: {type: sphere, radius: 1.0}\n")
    code, log = run_to_exit(str(typo))
    assert code == 1, log
    assert "unknown parameter 'rate_hzz'" in log and "Traceback" not in log, log


def test_shipped_params_work_under_a_namespace_and_a_new_node_name():
    proc = start_node(default_params_file(), "-r", "__ns:=/robot1", "-r", "__node:=checker")
    h = RosHarness()
    try:
        probe = h.node("probe")
        got = []
        probe.create_subscription(ContactArray, "/robot1/contacts", got.append, 10)
        pub = probe.create_publisher(BodyPoseArray, "/robot1/body_poses", 10)
        msg = msg_adapters.arrays_to_body_pose_array(
            ["ball_0", "ball_1"], np.array([[0.0, 0, 3], [0.0, 0.45, 3]]),
            np.tile([0.0, 0, 0, 1], (2, 1)), Time(sec=78))
        ok = h.spin_until(lambda: any(m.header.stamp.sec == 78 for m in got),
                          timeout=900.0, step=lambda: pub.publish(msg))
        assert ok, "no ContactArray under /robot1:\n" + stop(proc)
        m = next(m for m in got if m.header.stamp.sec == 78)
        assert ("ball_0", "ball_1") in list(zip(m.body_a, m.body_b))
    finally:
        h.close()
        log = stop(proc)
    assert proc.returncode == 0, log


def test_demo_runs_the_real_node_and_reports_contacts():
    out = subprocess.run([sys.executable, "-m", "mkcollision_ros.demo", "--seconds", "4"],
                         capture_output=True, text=True, timeout=400)
    assert out.returncode == 0, out.stdout + out.stderr
    lines = dict(line.split(None, 1) for line in out.stdout.splitlines()
                 if line.startswith("  ") and len(line.split(None, 1)) == 2)
    assert int(lines["steps"]) > 0
    assert int(lines["contacts_seen"]) > 0, out.stdout
    assert int(lines["pairs_touching"]) > 0


PARENT = r"""
import subprocess, sys, time
from mkcollision_ros.demo import die_with_parent, node_executable
proc = subprocess.Popen([node_executable(), "--ros-args", "--params-file", sys.argv[1]],
                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                        start_new_session=True, preexec_fn=die_with_parent)
print(proc.pid, flush=True)
time.sleep(600)
"""


def _running(pid):
    """True while pid exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/status") as f:
            return not any(line.startswith("State:") and "Z" in line.split()[1]
                           for line in f)
    except FileNotFoundError:
        return False


def test_node_started_by_demo_dies_with_its_parent():
    """A node started the demo's way does not outlive a parent killed outright."""
    parent = subprocess.Popen([sys.executable, "-c", PARENT, default_params_file()],
                              stdout=subprocess.PIPE, text=True)
    try:
        child = int(parent.stdout.readline())
        time.sleep(2.0)
        assert _running(child)
    finally:
        parent.kill()
        parent.wait()
    deadline = time.monotonic() + 120.0
    while _running(child) and time.monotonic() < deadline:
        time.sleep(0.2)
    alive = _running(child)
    if alive:
        os.killpg(child, signal.SIGKILL)
    assert not alive, "the node outlived its parent"


def test_large_messages_profile_is_taken_unless_the_user_names_one(monkeypatch):
    """The node points Fast DDS at the installed profile, whose shared-memory segment
    holds a 10,000-body BodyPoseArray; a user's own profile or another RMW is left alone."""
    import xml.etree.ElementTree as ET
    from mkcollision_ros.fastdds import use_large_messages_profile
    for var in ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE",
                "RMW_IMPLEMENTATION"):
        monkeypatch.delenv(var, raising=False)
    path = use_large_messages_profile()
    assert path is not None and os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] == path
    assert path.endswith(os.path.join("share", "mkcollision_ros", "config",
                                      "fastdds_large_messages.xml"))
    ns = {"p": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}
    root = ET.parse(path).getroot()
    shm = [d for d in root.iterfind("p:transport_descriptors/p:transport_descriptor", ns)
           if d.findtext("p:type", namespaces=ns) == "SHM"]
    assert len(shm) == 1
    one_message = 10_000 * (7 * 8 + 4 + len("body_00000") + 1) + 1024
    assert int(shm[0].findtext("p:segment_size", namespaces=ns)) >= 4 * one_message
    # the participant keeps UDP too (shards on several machines)
    used = [t.text for t in root.iterfind("p:participant/p:rtps/p:userTransports/"
                                          "p:transport_id", ns)]
    kinds = {d.findtext("p:transport_id", namespaces=ns): d.findtext("p:type", namespaces=ns)
             for d in root.iterfind("p:transport_descriptors/p:transport_descriptor", ns)}
    assert sorted(kinds[t] for t in used) == ["SHM", "UDPv4"]
    monkeypatch.setenv("FASTRTPS_DEFAULT_PROFILES_FILE", "/my/profile.xml")
    assert use_large_messages_profile() is None
    assert os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] == "/my/profile.xml"
    monkeypatch.delenv("FASTRTPS_DEFAULT_PROFILES_FILE")
    monkeypatch.setenv("RMW_IMPLEMENTATION", "rmw_cyclonedds_cpp")
    assert use_large_messages_profile() is None
    assert "FASTRTPS_DEFAULT_PROFILES_FILE" not in os.environ
