"""Regenerate BENCHMARKS.md: run the benchmarks, keep each one's output in
``bench/results/<name>.md``, and write the page from those outputs.

    . tools/env.sh && python bench/report.py               # run every benchmark, write the page
    . tools/env.sh && python bench/report.py fuzz startup  # run these, keep the others' outputs
    . tools/env.sh && python bench/report.py --render      # only write the page from the outputs
    . tools/env.sh && python bench/report.py --list        # the benchmarks, their commands

The page is: the machine and the package versions (read when the page is written),
then, for every benchmark of SECTIONS, what it measures and against what goal, the
command, and the table that command printed, as it printed it (headings in its output
are put two levels down).  Timings need the machine to themselves: run nothing else
meanwhile.  Every benchmark's module docstring says exactly what it times.
"""
import argparse
import os
import platform
import re
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass
from importlib import metadata

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RESULTS = os.path.join(ROOT, "bench", "results")
PAGE = os.path.join(ROOT, "BENCHMARKS.md")


@dataclass(frozen=True)
class Section:
    name: str       # bench/results/<name>.md
    title: str
    args: tuple     # the command, run from the repository's root with tools/env.sh's env
    about: str      # what is measured and the goal it answers (no figures: they change)


SECTIONS = (
    Section(
        "vs_mujoco", "Narrow phase against MuJoCo, per shape pair",
        ("bench/vs_mujoco.py",),
        "Our batch kernel in contacts mode (auto, cutoff 0, one thread) against MuJoCo's "
        "collision pass on the same 2,000 seeded cases per shape pair (about half "
        "touching, a fifth within 1% of touching), timed in alternation round by round "
        "so that a slow spell of the shared machine hits both.  The ratio is of the "
        "fastest rounds.  Goal: at most half MuJoCo's time where a smooth shape "
        "(ellipsoid, capsule, cylinder) takes part, else at most MuJoCo's time.  MuJoCo "
        "has no cone: those rows have no baseline."),
    Section(
        "pipeline", "Whole scene step against MuJoCo, coal, python-fcl and pybullet",
        ("bench/pipeline.py",),
        "N bodies of mixed shapes (sphere, ellipsoid, box, capsule, cylinder, cone, "
        "convex), every body moving each step, at 0.2 and 2 touching pairs per body; "
        "every engine sees the same poses.  Ours is `Pipeline.step` (bounds, broad phase, "
        "filter, narrow phase, manifolds, arbiters); MuJoCo's `mj_collision` after "
        "`mj_kinematics`; coal's and fcl's dynamic AABB tree managers; pybullet's "
        "`performCollisionDetection`.  Goal at 10,000 bodies: the whole step in at most "
        "a quarter of MuJoCo's collision pass at both densities."),
    Section(
        "scene_ops", "Scene edits and proximity pairs",
        ("bench/pipeline.py", "--scene-ops", "--sizes", "1000", "10000", "--steps", "9"),
        "The bench scene at 0.2 touching pairs per body, every body moving: the step "
        "with proximity pairs off and at 0.1 m (the narrow phase measures every pair "
        "within max(contact margin, proximity); proximity pairs are not turned into "
        "arbiters), then the cost of one scene edit between steps and of the step after "
        "it.  An edit costs the same whatever the scene's size."),
    Section(
        "static_heavy", "Static-heavy scenes to 100,000 bodies",
        ("bench/static_heavy.py",),
        "The bench scene at 0.2 touching pairs per body with every body static but 1% or "
        "10% of them, which move each step (a warehouse: racks and stock that stay, "
        "robots that move).  The broad phase keeps the static bodies' grid from step to "
        "step and finds no static-static pair, so a step costs O(moving bodies).  "
        "MuJoCo (static bodies as world geoms, moving ones free) up to 10,000 bodies: "
        "its model build grows too fast beyond.  Goal: 100,000-body static-heavy scenes "
        "run, and are reported here."),
    Section(
        "startup", "Start-up",
        ("bench/startup.py", "--cold-node", "--one-process"),
        "Each row a fresh process; an empty cache is a new, empty `XDG_CACHE_HOME`, so "
        "nothing compiled before is seen.  Goal: the node's first answer within 60 s of "
        "its start from an empty cache, within 1 s once cached.  `bench/compile_time.py` "
        "lists what each kernel's compile takes."),
    Section(
        "node_latency", "The node end to end through DDS",
        ("bench/node_latency.py", "--bodies", "100", "1000", "--seconds", "10",
         "--executors", "events", "single_threaded"),
        "The installed node (`trigger: on_message`, the shipped defaults: markers at "
        "5 Hz, at most 200 body markers each), a publisher process at 100 Hz stamping "
        "each message just before publishing it, and a subscriber (rclpy's "
        "EventsExecutor) timing each `contacts` message against that stamp; the bench "
        "scene at 0.2 touching pairs per body, every body moving.  The node runs on each "
        "of its two executors (parameter `executor`).  All three processes take the "
        "package's Fast DDS profile (README, \"Large scenes\") and share the two cores.  "
        "\"published\" counts from the first message the node answered (the ones "
        "before are lost to discovery).  The node runs numba's OpenMP threads with "
        "`OMP_WAIT_POLICY=PASSIVE` (node.py): spinning threads would take a core from the "
        "other two processes.  The Python publisher builds each PoseArray message on the "
        "same two cores; the node reads it from its CDR bytes.  Goal: 1,000 bodies at "
        "100 Hz with every message answered and p99 under 3 ms."),
    Section(
        "node_shards", "Shards: one node or two at 10,000 bodies",
        ("bench/node_latency.py", "--bodies", "10000", "--rate", "30", "--inputs",
         "BodyPoseArray", "--markers", "off", "--shards", "1", "2", "--seconds", "10"),
        "The same end-to-end measurement at 10,000 bodies and 30 Hz, with the scene's "
        "pairs answered by one node, then by two node processes as its shards "
        "(README, \"Shards\"): a stamp counts as answered once both shards' contacts "
        "arrived, its latency that of the later one; \"node CPU\" adds the nodes'.  "
        "Four processes share the two cores.  Goal (10,000 bodies at 30 Hz): p99 under "
        "25 ms; the question: do two shards on this machine beat one node."),
    Section(
        "rerun", "Rerun logging",
        ("bench/rerun_cost.py", "--steps", "300"),
        "After each `Pipeline.step` of the bench scene (paced at 100 Hz, 10,000 bodies "
        "at 30 Hz), `RerunLog.log_step` to a file sink, timed alone.  The recorder runs "
        "in the logger's child process, so what a step waits for is the pickling and "
        "the hand-over; the child's CPU per step is beside it.  Goal: under 1 ms a step "
        "added to the node at 1,000 bodies."),
    Section(
        "rerun_memory", "Rerun logging: memory over time",
        ("bench/rerun_cost.py", "--memory-seconds", "120"),
        "1,000 bodies paced at 100 Hz, logged for two minutes to each sink in turn (a "
        "file, then serving with a 256 MiB buffer and no viewer); the resident memory of "
        "the bench process and its logger's child together, every 10 s.  The file is written "
        "without rerun's footer, whose index of every chunk rerun keeps in memory until "
        "the file closes."),
    Section(
        "fuzz", "Fuzzer: 10^6 random pairs per method",
        ("bench/fuzz.py", "--pairs", "1000000", "--seed", "1", "--api-every", "1000"),
        "Every shape type (plane-plane excluded), both orders, sizes 1 mm - 100 m, "
        "aspect ratios to 1:1000, margins, hulls of 4 - 300 points (some nearly flat); "
        "poses far apart, near, small inside big, coincident centres, and touching at "
        "round-off.  Each call through the batch kernel one pair at a time (timed), "
        "the parallel batch compared bit for bit, every 1,000th pair also through the "
        "public API.  The checks and tolerances are in mkcollision_ros/fuzzing.py's docstring; "
        "\"other failures\" are pairs failing a check other than FAILED, NaN or a "
        "disagreement.  A call over the 50 ms bound is timed again and counts only if "
        "it is slow again.  Goal: no FAILED, no NaN, no failure, no disagreement.  A "
        "failure prints a one-line repro, which becomes a case in tests/fuzz_cases.json "
        "(run by tests/test_fuzz.py with the slow oracle of tests/oracles.py beside it).  "
        "Beyond the checks: where GJK stalls (a needle-thin Minkowski difference: a long "
        "capsule core or a cone against a tiny body at its centre) and MPR finds "
        "contact, the depth is the smaller of h along MPR's and GJK's normals "
        "(gjk_epa._caps_fallback), an upper bound with the right status; the saved "
        "cases marked 'upper_bound' hold it to the oracle."),
)
BY_NAME = {s.name: s for s in SECTIONS}
INTRO = ("Written by `bench/report.py` from the outputs in `bench/results/`: each table is "
         "what the command above it printed, on this machine, with nothing else running.  "
         "Run `python bench/report.py NAME` to measure one again, `python bench/report.py` "
         "for all (after `. tools/env.sh`).  Which script answers which question: "
         "`bench/README.md`.")


def command_line(s):
    return "python " + " ".join(s.args)


def run(s):
    """Run one benchmark; its stdout goes to bench/results/<name>.md."""
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    print(f"[report] {command_line(s)}", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, *s.args], cwd=ROOT, env=env, check=False,
                         stdout=subprocess.PIPE, text=True)
    took = time.perf_counter() - t0
    if out.returncode not in (0, 1):     # 1: the fuzzer's "found failures", still a table
        raise SystemExit(f"{command_line(s)} exited {out.returncode}")
    os.makedirs(RESULTS, exist_ok=True)
    with open(os.path.join(RESULTS, s.name + ".md"), "w", encoding="utf-8") as f:
        f.write(out.stdout.strip() + "\n")
    print(f"[report] {s.name}: {took:.0f} s", file=sys.stderr, flush=True)


def _version(dist):
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "not installed"


def machine():
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f
                       if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2 ** 30
    pk = ", ".join(f"{d} {_version(d)}" for d in
                   ("numpy", "numba", "rerun-sdk", "mujoco", "coal", "python-fcl",
                    "pybullet"))
    return (f"- {os.cpu_count()} cores ({cpu}), {mem:.0f} GiB, Linux "
            f"{platform.release()}, Python {platform.python_version()}\n"
            f"- {pk}; ROS 2 Jazzy from the pinned wheels (requirements/lock.txt)")


def _demote(text):
    return re.sub(r"(?m)^(#+) ", lambda m: "#" * (len(m.group(1)) + 2) + " ", text)


def render():
    parts = ["# Benchmarks\n", textwrap.fill(INTRO, 88) + "\n", "## Machine\n",
             machine() + "\n"]
    for s in SECTIONS:
        path = os.path.join(RESULTS, s.name + ".md")
        parts.append(f"## {s.title}\n")
        parts.append(textwrap.fill(s.about, 88) + "\n")
        parts.append(f"    . tools/env.sh && {command_line(s)}\n")
        if os.path.exists(path):
            with open(path, encoding="utf-8") as f:
                parts.append(_demote(f.read().strip()) + "\n")
        else:
            parts.append(f"(not measured: run `python bench/report.py {s.name}`)\n")
    with open(PAGE, "w", encoding="utf-8") as f:
        f.write("\n".join(parts))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", metavar="NAME",
                    help=f"benchmarks to run (default all): {', '.join(BY_NAME)}")
    ap.add_argument("--render", action="store_true", help="run nothing, write the page")
    ap.add_argument("--list", action="store_true")
    args = ap.parse_args(argv)
    for name in args.names:
        if name not in BY_NAME:
            ap.error(f"unknown benchmark {name!r}; expected some of {', '.join(BY_NAME)}")
    if args.list:
        for s in SECTIONS:
            print(f"{s.name:14s} {command_line(s)}")
        return 0
    if not args.render:
        for name in args.names or BY_NAME:
            run(BY_NAME[name])
    render()
    print(f"[report] wrote {os.path.relpath(PAGE, ROOT)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
