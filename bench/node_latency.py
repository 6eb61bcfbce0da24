"""End to end through DDS: the installed collision_node, a publisher process and this
subscriber process.

For each case (bodies, rate, input message, markers on or off):
  - a params file with the bench scene's bodies (``common.scene``, density 0.2, mixed
    shapes) and ``trigger: on_message``;
  - the installed ``collision_node`` started as ``ros2 run`` would start it, on a
    private ROS_DOMAIN_ID;
  - a publisher process streaming the bodies' poses (every body moving, as in
    ``bench/pipeline.py``) at the rate for ``--seconds``, stamped with the wall clock
    once the message is built, just before it is published, as ``BodyPoseArray`` or
    ``geometry_msgs/PoseArray`` (a Python publisher builds a 1,000-pose PoseArray in
    ~5 ms, so it may fall short of the rate: "published" says how many it sent);
  - here, a subscriber on rclpy's EventsExecutor timing each ``contacts`` message
    against its stamp (latency = receive wall time - stamp).
All three take the package's Fast DDS profile (config/fastdds_large_messages.xml), as
the README asks of a large scene's publisher.
Reported: messages published from the first one the node answered on (the ones before
were lost to discovery), how many of those were answered (distinct stamps), the
unanswered share, latency p50 / p99 / max (ms) over the answered ones after the first
second, and the node's CPU (user + system time over the run / its length, 1.0 = one
core).  With ``--shards 1 2``, each case also runs as two node processes, the shards of
the scene (shard_index 0 and 1 of shard_count 2): a stamp is answered once both shards'
messages arrived, its latency that of the later one, and the CPU is the two nodes'.

    . tools/env.sh && python bench/node_latency.py [--bodies 100 1000] [--seconds 10]
        [--shards 1 2] [--executors events single_threaded]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import yaml

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
os.environ["ROS_DOMAIN_ID"] = str(40 + os.getpid() % 50)
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

from bench.common import print_table, scene  # noqa: E402
from mkcollision_ros.fastdds import use_large_messages_profile  # noqa: E402

# every process here (this subscriber, the publisher, the nodes) takes the package's
# Fast DDS profile, as the README asks of a large scene's publisher
use_large_messages_profile()

PUBLISHER = r"""
import sys, time
import numpy as np
import rclpy
sys.path.insert(0, sys.argv[1])
from bench.common import move, scene
import msg_adapters
from builtin_interfaces.msg import Time
from mkcollision_msgs.msg import BodyPoseArray
from geometry_msgs.msg import PoseArray
n, rate, seconds, kind = int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
bodies, pos, quat, _ = scene(n, 0.2)
names = [b["name"] for b in bodies]
rclpy.init()
node = rclpy.create_node("latency_publisher")
pub = node.create_publisher(BodyPoseArray if kind == "BodyPoseArray" else PoseArray,
                            "body_poses" if kind == "BodyPoseArray" else "pose_array", 10)
time.sleep(2.0)                        # discovery
rng = np.random.default_rng(1)
stamps, t0 = [], time.time()
nxt = t0
while time.time() < t0 + seconds:
    pos, quat = move(rng, pos, quat)
    if kind == "BodyPoseArray":
        msg = msg_adapters.arrays_to_body_pose_array(names, pos, quat)
    else:
        msg = msg_adapters.poses.arrays_to_pose_array(pos, quat)
    now = time.time()                  # stamped once built: the latency is the node's
    msg.header.stamp = Time(sec=int(now), nanosec=int((now % 1) * 1e9))
    pub.publish(msg)
    stamps.append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)
    nxt += 1.0 / rate
    time.sleep(max(0.0, nxt - time.time()))
print(" ".join(repr(s) for s in stamps), flush=True)
node.destroy_node()
rclpy.shutdown()
"""


def params_file(n, markers, path, executor="events"):
    bodies, _, _, _ = scene(n, 0.2)
    block = {"names": [b["name"] for b in bodies]}
    for b in bodies:
        shape = dict(b["shape"])
        if "points" in shape:
            shape["points"] = [float(x) for p in shape["points"] for x in p]
        block[b["name"]] = shape
    doc = {"/**": {"ros__parameters": {
        "trigger": "on_message", "publish_markers": markers, "warn_throttle_s": 10.0,
        "executor": executor,
        "max_pose_age_s": 10.0, "bodies": block}}}
    with open(path, "w") as f:
        yaml.safe_dump(doc, f)


def cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def run_case(n, rate, kind, markers, seconds, shards=1, executor="events"):
    import rclpy
    from mkcollision_msgs.msg import ContactArray
    from rclpy.experimental import EventsExecutor
    from mkcollision_ros.demo import die_with_parent, node_executable
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "params.yaml")
        params_file(n, markers, path, executor)
        shard_args = [[] if shards == 1 else
                      ["-r", f"__node:=collision_node_{k}", "-p", f"shard_index:={k}",
                       "-p", f"shard_count:={shards}"] for k in range(shards)]
        nodes = [subprocess.Popen([node_executable(), "--ros-args", "--params-file", path,
                                   *extra], stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True,
                                  start_new_session=True, preexec_fn=die_with_parent)
                 for extra in shard_args]
        ready = time.time() + 900
        for node in nodes:
            for line in node.stdout:                      # wait for "kernels ready"
                if "kernels ready" in line or time.time() > ready:
                    break
        rclpy.init()
        sub = rclpy.create_node("latency_subscriber")
        seen, parts = {}, {}

        def on_contacts(msg):
            s = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
            got = parts.setdefault(s, set())
            got.add(msg.shard_index)
            if len(got) == shards:                        # the stamp's whole answer
                seen.setdefault(s, time.time() - s)
        sub.create_subscription(ContactArray, "contacts", on_contacts, 100)
        pub = subprocess.Popen([sys.executable, "-c", PUBLISHER, root, str(n), str(rate),
                                str(seconds), kind], stdout=subprocess.PIPE, text=True)
        c0, w0 = sum(cpu_seconds(node.pid) for node in nodes), time.time()
        spinner = EventsExecutor()
        spinner.add_node(sub)
        while pub.poll() is None:
            spinner.spin_once(timeout_sec=0.01)
        end = time.time() + 1.0
        while time.time() < end:
            spinner.spin_once(timeout_sec=0.01)
        spinner.remove_node(sub)
        cpu = (sum(cpu_seconds(node.pid) for node in nodes) - c0) / (time.time() - w0)
        sent = [float(x) for x in pub.stdout.read().split()]
        sub.destroy_node()
        rclpy.shutdown()
        for node in nodes:
            node.terminate()
            node.wait(timeout=30)
    stamps = sorted(seen)
    lat = np.array([seen[s] for s in stamps if s > stamps[0] + 1.0]) if stamps else np.zeros(1)
    # messages sent once the node had answered one (before that: discovery)
    published = [s for s in sent if stamps and s >= stamps[0]]
    answered = set(stamps) & set(published)
    return [str(n), f"{rate:g}", kind, "on" if markers else "off", str(shards), executor,
            str(len(published)),
            str(len(answered)), f"{1 - len(answered) / max(len(published), 1):.1%}",
            f"{1e3 * np.percentile(lat, 50):.2f}", f"{1e3 * np.percentile(lat, 99):.2f}",
            f"{1e3 * lat.max():.2f}", f"{cpu:.2f}"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bodies", type=int, nargs="+", default=[100, 1000])
    ap.add_argument("--rate", type=float, default=100.0)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--inputs", nargs="+", default=["BodyPoseArray", "PoseArray"])
    ap.add_argument("--markers", nargs="+", default=["off", "on"])
    ap.add_argument("--shards", type=int, nargs="+", default=[1],
                    help="node processes sharing the scene's pairs, one case each")
    ap.add_argument("--executors", nargs="+", default=["events"],
                    choices=["events", "single_threaded"],
                    help="the nodes' executor parameter, one case each")
    args = ap.parse_args()
    rows = []
    for n in args.bodies:
        for kind in args.inputs:
            for markers in args.markers:
                for shards in args.shards:
                    for executor in args.executors:
                        rows.append(run_case(n, args.rate, kind, markers == "on",
                                             args.seconds, shards, executor))
                        print("  done", rows[-1][:6], file=sys.stderr, flush=True)
    head = ["bodies", "rate Hz", "input", "markers", "shards", "executor", "published",
            "answered", "unanswered", "p50 ms", "p99 ms", "max ms", "node CPU"]
    print_table(head, rows)


if __name__ == "__main__":
    main()
