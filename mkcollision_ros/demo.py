"""The demo: a scripted scene played to the real collision node, and a summary.

``demo --scene bowling|dominoes|marbles|stack|swarm`` (``python -m
mkcollision_ros.demo``) starts the installed ``collision_node`` executable as a
subprocess with the scene's params file (the package's ``config/demo_<scene>.yaml``;
``--bodies N`` generates one of N bodies for swarm), publishes ``BodyPoseArray``
messages of the scene's scripted motion (``mkcollision_ros.demo_scenes``) for
``--seconds``, listens to ``contacts`` and prints what happened: the totals and, per
scene, the contacts a viewer expects and whether they were seen.  ``--record
file.rrd`` makes the node record every step for the rerun viewer.  ``demo_publisher``
runs only the publisher, for use beside a node started with ``ros2 run``.
"""
import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time

from .config import bodies_from_params, load_params_file
from .demo_scenes import (SCENE_NAMES, Scene, demo_poses, make_scene, note_contacts,
                          params_body, swarm, write_params)
from .fastdds import use_large_messages_profile

__all__ = ["demo_poses", "run", "main", "publisher_main", "scene_params_file"]
DEFAULT_SCENE = "bowling"


def _share_config(name):
    """Path of ``config/<name>`` of the installed package (ament index), else of the
    source tree."""
    try:
        from ament_index_python.packages import get_package_share_directory
        path = os.path.join(get_package_share_directory("mkcollision_ros"), "config", name)
        if os.path.exists(path):
            return path
    except (ImportError, LookupError):
        pass
    return os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "config", name)


def default_params_file():
    """The installed package's config/collision_node.yaml, else the source tree's."""
    return _share_config("collision_node.yaml")


def scene_params_file(scene_name):
    """The installed params file of a scene: config/demo_<scene>.yaml."""
    return _share_config(f"demo_{scene_name}.yaml")


def node_executable():
    """Path of the installed ``collision_node`` (what ``ros2 run`` would start)."""
    from ament_index_python.packages import get_package_prefix
    return os.path.join(get_package_prefix("mkcollision_ros"), "lib", "mkcollision_ros",
                        "collision_node")


def die_with_parent():
    """``preexec_fn`` for a child node: the kernel sends it SIGTERM when the process that
    started it dies, even by SIGKILL, so no node is left running (Linux prctl
    PR_SET_PDEATHSIG; elsewhere a no-op).  The child also gets its own session, so the
    parent stops it with one killpg."""
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)          # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def prepare(scene_name, bodies=None, params_file=None):
    """(scene, params file path, temporary file or None) for the demo's arguments
    (``scene_name``: a name of SCENE_NAMES, or a demo_scenes.Scene built already).
    ``bodies`` (swarm only) writes a generated params file to a temporary file;
    ``params_file`` (swarm only) orbits that file's bodies.  ValueError when the
    arguments do not fit together."""
    if isinstance(scene_name, Scene):          # built already
        if bodies is not None or params_file is not None:
            raise ValueError("a built scene takes no --bodies or --params-file")
        return scene_name, scene_params_file(scene_name.name), None
    if scene_name not in SCENE_NAMES:
        raise ValueError(f"unknown scene {scene_name!r}; expected one of "
                         f"{', '.join(SCENE_NAMES)}")
    if scene_name != "swarm" and (bodies is not None or params_file is not None):
        raise ValueError(f"--bodies and --params-file apply to the swarm scene only, "
                         f"not to {scene_name!r}")
    if bodies is not None and params_file is not None:
        raise ValueError("give --bodies or --params-file, not both")
    if params_file is not None:
        found = bodies_from_params(load_params_file(params_file))
        scene = swarm(bodies=[params_body(b["name"], b["shape"], static=b["static"])
                              for b in found])
        return scene, os.path.abspath(params_file), None
    scene = make_scene(scene_name, bodies=bodies)
    if bodies is None:
        return scene, scene_params_file(scene_name), None
    fd, path = tempfile.mkstemp(prefix=f"mkcollision_swarm_{bodies}_", suffix=".yaml")
    os.close(fd)
    write_params(scene, path)
    return scene, path, path


class DemoPublisher:
    """Publishes a scene's scripted motion (an rclpy node's publisher).

    With ``rate_hz`` a timer publishes ``scene.pose`` of the time since ``restart``
    (times ``time_scale``); ``publish_at(t)`` publishes the pose at script time ``t``.
    ``script_time`` maps a published stamp back to its script time."""

    def __init__(self, node, scene, rate_hz=30.0, topic="body_poses", time_scale=1.0):
        from mkcollision_msgs.msg import BodyPoseArray

        self.scene = scene
        self.names = list(scene.moving)
        self.node = node
        self.pub = node.create_publisher(BodyPoseArray, topic, 10)
        self.time_scale = time_scale
        self.sent = 0
        self.script_time = {}
        self.restart()
        self.timer = node.create_timer(1.0 / rate_hz, self._tick) if rate_hz else None

    def restart(self):
        self.t0 = time.monotonic()

    def _tick(self):
        self.publish_at((time.monotonic() - self.t0) * self.time_scale)

    def publish_at(self, t):
        """Publish the poses at script time ``t``; returns the stamp (sec, nanosec)."""
        from msg_adapters import arrays_to_body_pose_array

        pos, quat = self.scene.pose(t)
        stamp = self.node.get_clock().now().to_msg()
        msg = arrays_to_body_pose_array(self.names, pos, quat, stamp)
        key = (stamp.sec, stamp.nanosec)
        self.script_time[key] = t
        if len(self.script_time) > 5000:          # keep the recent ones
            for old in list(self.script_time)[:1000]:
                del self.script_time[old]
        self.pub.publish(msg)
        self.sent += 1
        return key


class ContactTally:
    """Subscribes to ``contacts``, counts what arrives and which of the scene's
    expected contacts (``scene.expects``) were seen."""

    def __init__(self, node, scene=None, script_time=None, topic="contacts"):
        from mkcollision_msgs.msg import ContactArray

        self.scene = scene
        self.script_time = script_time if script_time is not None else {}
        self.reset()
        self.sub = node.create_subscription(ContactArray, topic, self.on_contacts, 10)

    def reset(self):
        self.steps = 0
        self.contacts = 0
        self.max_depth = 0.0
        self.pairs = set()
        self.ids = set()
        self.answered = set()
        self.seen = {e.label: set() for e in (self.scene.expects if self.scene else ())}

    def on_contacts(self, msg):
        key = (msg.header.stamp.sec, msg.header.stamp.nanosec)
        self.answered.add(key)
        self.steps += 1
        self.contacts += len(msg.depths)
        if len(msg.depths):
            self.max_depth = max(self.max_depth, float(max(msg.depths)))
        pairs = set(zip(msg.body_a, msg.body_b))
        self.pairs.update(pairs)
        self.ids.update(int(i) for i in msg.ids)
        t = self.script_time.get(key)
        if self.scene is not None and t is not None:
            note_contacts(self.scene, t, pairs, self.seen)


def run(seconds, scene=DEFAULT_SCENE, bodies=None, params_file=None, record=None, rate_hz=30.0,
        step_s=None, node_cmd=None, out=sys.stdout):
    """Start the node with the params file of ``scene`` (a name, or a demo_scenes.Scene
    built already), play the scene for ``seconds``
    (wall time at ``rate_hz``; or, with ``step_s``, script time in lockstep: the pose at
    each multiple of ``step_s`` up to ``seconds`` is sent once the node answered the
    previous one, and sent again, newly stamped, when no answer comes within 1 s), print and return the summary dict.  ``record``: a .rrd file the node
    records every step to.  The summary's "expected" maps each expectation's label to
    (subjects seen, subjects, the script's count or None); "seen" to the sets."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    scene_obj, params, temp = prepare(scene, bodies, params_file)
    node_cmd = list(node_cmd or [node_executable()])
    args = ["--ros-args", "--params-file", params]
    if record is not None:
        record = os.path.abspath(record)
        args += ["-p", f"rerun:=save:{record}"]
    print(f"[demo] scene {scene_obj.name}: {scene_obj.doc}", file=out)
    print(f"[demo] starting the collision node: {' '.join(node_cmd + args)}", file=out,
          flush=True)
    t_start = time.monotonic()
    proc = subprocess.Popen(node_cmd + args, start_new_session=True,
                            preexec_fn=die_with_parent)
    context = rclpy.Context()
    use_large_messages_profile()
    rclpy.init(context=context)
    node = rclpy.create_node("mkcollision_demo", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        pub = DemoPublisher(node, scene_obj, rate_hz=None if step_s else rate_hz)
        tally = ContactTally(node, scene_obj, pub.script_time)
        # wait for the node's first ContactArray before the clock starts, so a first
        # numba compile does not eat into the demo time
        deadline = time.monotonic() + 900.0   # a first compile takes minutes
        last = 0.0
        while tally.steps == 0 and time.monotonic() < deadline and proc.poll() is None:
            if time.monotonic() - last > 0.1:
                pub.publish_at(0.0)
                last = time.monotonic()
            executor.spin_once(timeout_sec=0.05)
        if tally.steps == 0:
            raise RuntimeError("the collision node did not answer "
                               f"(exit code {proc.poll()}); see its log above")
        ready = time.monotonic() - t_start
        tally.reset()  # count from here
        if step_s:
            k = 0
            while k * step_s <= seconds + 1e-9 and proc.poll() is None:
                for _ in range(5):        # inputs are best effort: resend a lost one
                    key = pub.publish_at(k * step_s)
                    wait = time.monotonic() + 1.0
                    while key not in tally.answered and time.monotonic() < wait:
                        executor.spin_once(timeout_sec=0.01)
                    if key in tally.answered:
                        break
                k += 1
            end = time.monotonic() + 0.3          # the last answers
            while time.monotonic() < end:
                executor.spin_once(timeout_sec=0.02)
        else:
            pub.restart()
            end = time.monotonic() + seconds
            while time.monotonic() < end and proc.poll() is None:
                executor.spin_once(timeout_sec=0.05)
        expected = {e.label: (len(tally.seen[e.label]), len(e.targets), e.wanted)
                    for e in scene_obj.expects}
        summary = {
            "scene": scene_obj.name, "bodies": len(scene_obj.bodies),
            "moving_bodies": len(pub.names), "seconds": seconds,
            "node_ready_s": round(ready, 2), "pose_messages": pub.sent,
            "steps": tally.steps, "contacts_seen": tally.contacts,
            "pairs_touching": len(tally.pairs), "distinct_contact_ids": len(tally.ids),
            "max_depth_m": round(tally.max_depth, 4),
        }
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)      # the node closes its recording
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
        if temp is not None:
            os.unlink(temp)
    print("[demo] summary", file=out)
    for key, value in summary.items():
        print(f"  {key:22s} {value}", file=out)
    if scene_obj.duration:
        print(f"  (the script runs {scene_obj.duration:.1f} s, holds its end for "
              f"{scene_obj.hold:.1f} s and starts again)", file=out)
    pairs = sorted(tally.pairs)
    print("  touching pairs: " + ", ".join(f"{a}-{b}" for a, b in pairs[:20])
          + (" ..." if len(pairs) > 20 else ""), file=out)
    print("[demo] expected contacts", file=out)
    for e in scene_obj.expects:
        print(f"  {e.report(tally.seen[e.label])}", file=out)
    if record is not None:
        if os.path.exists(record):
            print(f"recording: {record}; open it with: rerun {record}", file=out)
        else:
            print(f"[demo] the node wrote no recording to {record}; see its log above",
                  file=out)
    out.flush()
    summary["expected"] = expected
    summary["seen"] = {label: set(s) for label, s in tally.seen.items()}
    summary["recording"] = record if record is not None and os.path.exists(record) else None
    return summary


def _positive(kind):
    def check(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a {kind.__name__}, got {text!r}")
        if not value > 0:
            raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
        return value
    return check


def _parser(description, publisher=False):
    # the publisher's default fits a node started with config/collision_node.yaml
    default = "swarm" if publisher else DEFAULT_SCENE
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--scene", choices=SCENE_NAMES, default=default,
                        help=f"the scene to play (default {default})")
    parser.add_argument("--bodies", type=_positive(int), default=None,
                        help="swarm only: generate this many bodies (a temporary params "
                        "file)")
    parser.add_argument("--params-file", default=None,
                        help="swarm only: orbit the bodies of this params file")
    parser.add_argument("--rate", type=_positive(float), default=30.0,
                        help="pose messages per second (default 30)")
    if not publisher:
        parser.add_argument("--seconds", type=_positive(float), default=10.0,
                            help="how long to play after the node is ready (default 10)")
        parser.add_argument("--record", default=None, metavar="FILE.rrd",
                            help="the node records every step to this rerun file")
    return parser


def _check(parser, args):
    if args.scene != "swarm" and (args.bodies is not None or args.params_file is not None):
        parser.error(f"--bodies and --params-file apply to --scene swarm only, "
                     f"not to {args.scene}")
    if args.bodies is not None and args.params_file is not None:
        parser.error("give --bodies or --params-file, not both")
    if args.params_file is not None and not os.path.isfile(args.params_file):
        parser.error(f"--params-file {args.params_file}: no such file")
    record = getattr(args, "record", None)
    if record is not None:
        folder = os.path.dirname(os.path.abspath(record))
        if not record.endswith(".rrd"):
            parser.error(f"--record {record}: the file name must end in .rrd")
        if not os.path.isdir(folder):
            parser.error(f"--record {record}: no folder {folder}")


def main(argv=None):
    parser = _parser(__doc__.splitlines()[0])
    args = parser.parse_args(argv)
    _check(parser, args)
    summary = run(args.seconds, scene=args.scene, bodies=args.bodies,
                  params_file=args.params_file, record=args.record, rate_hz=args.rate)
    return 0 if summary["steps"] > 0 else 1


def publisher_main(argv=None):
    """Only the demo publisher (beside a node started with ``ros2 run ... --params-file
    config/demo_<scene>.yaml``; the default scene, swarm, moves the bodies of
    config/collision_node.yaml)."""
    import rclpy
    from rclpy.executors import ExternalShutdownException

    parser = _parser("publish a demo scene's motion (start the node with the scene's "
                     "params file)", publisher=True)
    args, ros_args = parser.parse_known_args(argv)
    _check(parser, args)
    scene, params, _ = prepare(args.scene, args.bodies, args.params_file)
    print(f"[demo_publisher] scene {scene.name}; start the node with: ros2 run "
          f"mkcollision_ros collision_node --ros-args --params-file {params}", flush=True)
    use_large_messages_profile()
    rclpy.init(args=ros_args)
    node = rclpy.create_node("mkcollision_demo_publisher")
    try:
        DemoPublisher(node, scene, args.rate)
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()     # a generated params file stays, for the node


if __name__ == "__main__":
    raise SystemExit(main())
