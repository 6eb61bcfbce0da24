"""Start-up: how long until the kernels are ready, in an empty numba cache and in a
filled one, for the library and for the installed node.

Rows (each a fresh process; "empty" is a new, empty ``XDG_CACHE_HOME``, so nothing this
machine compiled before is seen):
  - library, every kernel (``python -m mkcollision_ros.compile_progress``, what
    ``tools/setup.sh`` runs; two processes share a cold compile): empty cache, then
    the same cache again; with ``--one-process`` also ``--jobs 1`` in an empty cache;
  - library, import to the first ``collide()`` result, cached;
  - node: from starting the installed ``collision_node`` (``config/collision_node.yaml``,
    the swarm's 11 bodies) to the first ``contacts`` message received here, poses
    published every 50 ms from the start: cached (after the library rows), and with
    ``--cold-node`` also in an empty cache (the node compiles at start).

    . tools/env.sh && python bench/startup.py [--cold-node] [--skip-cold] [--one-process]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
os.environ["ROS_DOMAIN_ID"] = str(40 + os.getpid() % 50)
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

FIRST_COLLIDE = r"""
import time
t0 = time.perf_counter()
import mkcollision_ros
r = mkcollision_ros.collide({"type": "sphere", "radius": 1.0}, ([0, 0, 0], [0, 0, 0, 1]),
                            {"type": "box", "size": [1, 1, 1]}, ([1.2, 0, 0], [0, 0, 0, 1]))
print(f"{time.perf_counter() - t0:.3f}")
"""


def _env(cache):
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "NUMBA_CACHE_LOCATOR_CLASSES")}
    env["XDG_CACHE_HOME"] = cache
    return env


def library_all(cache, jobs=2):
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mkcollision_ros.compile_progress", "--jobs",
                    str(jobs)], cwd=ROOT, env=_env(cache), check=True,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def first_collide(cache):
    r = subprocess.run([sys.executable, "-c", FIRST_COLLIDE], cwd=ROOT, env=_env(cache),
                       check=True, capture_output=True, text=True)
    return float(r.stdout.split()[-1])


def node_first_answer(cache, timeout=1800.0):
    """Seconds from starting the node to the first contacts message received."""
    import numpy as np
    import rclpy
    import yaml
    from builtin_interfaces.msg import Time
    from mkcollision_msgs.msg import BodyPoseArray, ContactArray

    import msg_adapters
    from mkcollision_ros.demo import die_with_parent, node_executable

    params = os.path.join(ROOT, "config", "collision_node.yaml")
    with open(params) as f:
        names = yaml.safe_load(f)["/**"]["ros__parameters"]["bodies"]["names"]
    n = len(names)
    pos = np.zeros((n, 3))
    pos[:, 0] = 0.5 * np.arange(n)            # neighbours overlap: contacts every step
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    rclpy.init()
    probe = rclpy.create_node("startup_probe")
    got = []
    probe.create_subscription(ContactArray, "contacts", got.append, 10)
    pub = probe.create_publisher(BodyPoseArray, "body_poses", 10)
    t0 = time.perf_counter()
    node = subprocess.Popen([node_executable(), "--ros-args", "--params-file", params],
                            env=_env(cache), stdout=subprocess.DEVNULL,
                            stderr=subprocess.STDOUT, start_new_session=True,
                            preexec_fn=die_with_parent)
    try:
        nxt = t0
        while not got and time.perf_counter() - t0 < timeout:
            if time.perf_counter() >= nxt:
                now = time.time()
                pub.publish(msg_adapters.arrays_to_body_pose_array(
                    names, pos, quat, Time(sec=int(now), nanosec=int(now % 1 * 1e9))))
                nxt += 0.05
            rclpy.spin_once(probe, timeout_sec=0.01)
        took = time.perf_counter() - t0 if got else float("nan")
    finally:
        os.killpg(node.pid, 2)
        node.wait(timeout=30)
        probe.destroy_node()
        rclpy.shutdown()
    return took


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cold-node", action="store_true",
                    help="also time the node's start in an empty cache (compiles again)")
    ap.add_argument("--skip-cold", action="store_true",
                    help="leave out the library's empty-cache row")
    ap.add_argument("--one-process", action="store_true",
                    help="also the library's empty-cache compile in one process")
    args = ap.parse_args()
    rows = []
    if args.one_process:
        with tempfile.TemporaryDirectory() as cache:
            rows.append(("library, every kernel, one process", "empty",
                         library_all(cache, jobs=1)))
    with tempfile.TemporaryDirectory() as cache:
        if not args.skip_cold:
            rows.append(("library, every kernel", "empty", library_all(cache)))
        rows.append(("library, every kernel", "filled", library_all(cache)))
        rows.append(("library, import to first collide()", "filled", first_collide(cache)))
        rows.append(("node, start to first contacts", "filled", node_first_answer(cache)))
    if args.cold_node:
        with tempfile.TemporaryDirectory() as cache:
            rows.append(("node, start to first contacts", "empty", node_first_answer(cache)))
    flags = "".join(f" --{f}" for f in ("cold-node", "one-process")
                    if getattr(args, f.replace("-", "_")))
    print(f"`python bench/startup.py{flags}`, {os.cpu_count()} cores\n")
    print("| what | numba cache | s |")
    print("|---|---|---|")
    for what, cache, s in rows:
        print(f"| {what} | {cache} | {s:.1f} |")


if __name__ == "__main__":
    main()
