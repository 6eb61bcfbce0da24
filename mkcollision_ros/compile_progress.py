"""Progress of numba's first compile, for people watching a terminal.

A first start compiles the kernels for minutes (README, "First-run cost"); a cached
start loads them in about a second and compiles nothing.  ``reporting(report)`` is a
context manager that listens to numba's ``numba:compile`` event (numba's documented
event API; it fires only when a kernel is compiled, never when it is loaded from the
cache) and calls ``report(line)`` when an outermost compile starts, every HEARTBEAT_S
while it lasts (one kernel can take over a minute), and when it ends: which kernel, how
long it took, how many of the expected kernels are done and an estimate of the time
left.  The estimate comes from EXPECTED_SECONDS, the outermost compiles of
``warm_up_all`` (the pipeline's warm-up, what the node compiles at start, then the pair
API's) in this process, with the compile shared by two (below), measured in an empty
cache on the project's 2-core machine (``python -m mkcollision_ros.compile_progress
--measure`` measures them again); other kernels count as unknown.

Two processes: ``sharing(report)`` splits a cold compile between this process and a
helper process (``python -m mkcollision_ros.compile_progress --helper DIR``), for the
machine's second core.  numba compiles a kernel together with every compiled kernel it
calls, and loads a called kernel from its on-disk cache when it is there; so the two
processes compile SHARED_KERNELS, subtrees of the call graph, into the cache, this one
from the list's start (its lead) and the helper from its end, so they meet wherever each
kernel's cost puts the middle; this process then runs the warm-up, which loads those and
compiles the rest.  The list's end is GJK/EPA itself, about a third of all the work,
which the helper compiles from the top down, and then the batch block above it (the
narrow phase's top, which would otherwise be this process's last compile); its start
holds the GJK loop and the two parts of GJK/EPA that compile reaches last (EPA, the GJK
witness pass), done here before the helper gets to them, then the kernels apart from
GJK/EPA's subtree, then GJK/EPA's other parts in the reverse of the order its compile
reaches them.  Every compile of a shared kernel, in either process, first claims it (a
file created with O_EXCL in DIR): the claimant compiles it and then marks it done; the
other process, needing it, waits for the mark and loads it from the cache, or skips it
(the lead and the helper's own loop).  The call graph has no cycles, so two processes
never wait for each other.  The helper compiles a kernel by its signature, written in
kernels' terms in ``compile_plan.py`` (``--write-plan`` rewrites it from the cache;
``tests/test_compile_progress.py`` checks it against the kernels' callers).  A signature
asked for that the plan does not hold compiles here, unshared, and is reported.
"""
import contextlib
import importlib
import os
import subprocess
import sys
import tempfile
import threading
import time

from numba.core import event

# outermost compiles of a cold warm-up: kernel name -> seconds (see the module docstring)
EXPECTED_SECONDS = {
    "_gjk": 17,
    "_witness_by_gjk": 0,
    "_epa": 12,
    "find_pairs": 13,
    "_manifold_block": 6,
    "arbiter_step": 6,
    "split_pairs": 0,
    "_fan_build": 2,
    "static_grid": 3,
    "static_pairs": 3,
    "normalise_poses": 0,
    "_world_aabbs_block": 1,
    "filter_pairs": 0,
    "_collide_batch": 1,
    "pair_shards": 0,
    "poses_unchanged": 0,
}
# s between two "still compiling" lines during one long compile
HEARTBEAT_S = 15.0


class _Listener(event.Listener):
    def __init__(self, report, expected, heartbeat):
        self.report = report
        self.expected = expected
        self.heartbeat = heartbeat
        self.depth = 0
        self.t0 = time.perf_counter()
        self.started = 0.0
        self.name = ""
        self.seconds = {}
        self._done = threading.Event()

    def _left(self):
        """s expected for the kernels not compiled yet, the current one's share gone."""
        left = sum(s for k, s in self.expected.items() if k not in self.seconds)
        if self.depth and self.name in self.expected and self.name not in self.seconds:
            left -= min(self.expected[self.name], time.perf_counter() - self.started)
        return max(left, 0.0)

    def _beat(self, done, name):
        # a line every `heartbeat` seconds while one compile lasts (numba's LLVM calls
        # release the GIL, so this thread runs)
        while not done.wait(self.heartbeat):
            took = time.perf_counter() - self.started
            about = (f" of about {self.expected[name]:.0f} s" if name in self.expected
                     else "")
            self.report(f"still compiling {name}: {took:.0f} s{about}; about "
                        f"{self._left():.0f} s left in all")

    def on_start(self, ev):
        if self.depth == 0:
            func = getattr(ev.data["dispatcher"], "py_func", None)
            self.name = getattr(func, "__name__", None) or str(ev.data["dispatcher"])
            self.started = time.perf_counter()
            self.report(f"compiling kernels: {self.name} ... "
                        f"({time.perf_counter() - self.t0:.0f} s so far)")
            self._done = threading.Event()
            if self.heartbeat:
                threading.Thread(target=self._beat, args=(self._done, self.name),
                                 daemon=True).start()
        self.depth += 1

    def on_end(self, ev):
        self.depth -= 1
        if self.depth:
            return
        self._done.set()
        took = time.perf_counter() - self.started
        self.seconds[self.name] = self.seconds.get(self.name, 0.0) + took
        known = [k for k in self.expected if k not in self.seconds]
        done = len([k for k in self.seconds if k in self.expected])
        total = len(self.expected)
        estimate = f", about {self._left():.0f} s left" if total and known else ""
        self.report(f"compiled {self.name} in {took:.0f} s "
                    f"({done} of {total} expected kernels{estimate})")


@contextlib.contextmanager
def reporting(report, expected=None, heartbeat=HEARTBEAT_S):
    """Call ``report(str)`` around each outermost numba compile inside the block, and
    every ``heartbeat`` s (0: never) while one lasts; yields the listener, whose
    ``seconds`` maps each compiled kernel to its time."""
    listener = _Listener(report, EXPECTED_SECONDS if expected is None else expected,
                         heartbeat)
    event.register("numba:compile", listener)
    try:
        yield listener
    finally:
        listener._done.set()
        event.unregister("numba:compile", listener)


# compiled kernels ("module:name") whose subtrees the two processes share, this one
# from the start, the helper from the end (module docstring, "Two processes")
SHARED_KERNELS = (
    # this process's lead: the GJK loop and the two parts of GJK/EPA its compile
    # reaches last, then kernels apart from GJK/EPA's subtree
    "mkcollision_ros.kernels.gjk:_gjk",
    "mkcollision_ros.kernels.gjk:_witness_by_gjk",
    "mkcollision_ros.kernels.epa:_epa",
    "mkcollision_ros.kernels.broadphase:find_pairs",
    "mkcollision_ros.kernels.mpr:mpr_ws",
    "mkcollision_ros.kernels.manifold:_manifold_block",
    "mkcollision_ros.kernels.persistence:arbiter_step",
    "mkcollision_ros.kernels.analytic:collide_analytic",
    "mkcollision_ros.kernels.ellipsoid:ellipsoid_exact",
    "mkcollision_ros.kernels.ellipsoid:ellipsoid_sampled",
    "mkcollision_ros.kernels.manifold:split_pairs",
    "mkcollision_ros.hull:_fan_build",
    "mkcollision_ros.kernels.broadphase:static_grid",
    "mkcollision_ros.kernels.broadphase:static_pairs",
    # GJK/EPA's other parts, in the reverse of the order its compile reaches them
    "mkcollision_ros.kernels.gjk_epa:_caps_fallback",
    "mkcollision_ros.kernels.pairs.ellipsoid_convex:collide_ellipsoid_convex",
    "mkcollision_ros.kernels.pairs.ellipsoid_box:_ellipsoid_box_bound",
    "mkcollision_ros.kernels.pairs.cylinder_convex:_cylinder_convex_ball_bound",
    "mkcollision_ros.kernels.pairs.cylinder_convex:collide_cylinder_convex",
    "mkcollision_ros.kernels.pairs.ellipsoid_cylinder:_ellipsoid_cylinder_bound",
    "mkcollision_ros.kernels.pairs.capsule_cylinder:_capsule_cylinder_bound",
    "mkcollision_ros.kernels.pairs.box_cylinder:_box_cylinder_bound",
    "mkcollision_ros.kernels.pairs.cylinder_cylinder:_cylinder_cylinder_bound",
    # the helper's second: the batch block above GJK/EPA (the narrow phase's top)
    "mkcollision_ros.kernels.narrowphase:_collide_block",
    # the helper's first: GJK/EPA itself, which reaches its parts from the top
    "mkcollision_ros.kernels.gjk_epa:gjk_epa_ws",
)
# s between two looks for a mark of the other process
POLL_S = 0.1


def dispatcher(key):
    """The numba dispatcher named by ``key`` ("module:name")."""
    module, name = key.split(":")
    return getattr(importlib.import_module(module), name)


def _type_names():
    from numba.core import types
    return dict(vars(types), bool=types.boolean)     # an array's repr names bool "bool"


def planned_signatures():
    """key -> the planned signature (a tuple of numba types) of each shared kernel, from
    compile_plan.py."""
    from . import compile_plan
    names = _type_names()
    return {key: eval(text, names) for key, text in compile_plan.SIGNATURES.items()}


def cached_signatures(key):
    """The signatures the on-disk cache holds for the kernel ``key``."""
    index = dispatcher(key)._cache._cache_file._load_index()
    return [k[0] for k in index]


class _Claims:
    """The claim and done marks of one shared compile in ``folder``, for the dispatchers
    of ``plan`` (key -> signature); the other process is alive while
    ``other_alive()``."""

    def __init__(self, folder, plan, other_alive, report):
        self.folder = folder
        self.plan = plan
        self.other_alive = other_alive
        self.report = report
        self.plain = {}

    def _path(self, key, what):
        return os.path.join(self.folder, f"{key.replace(':', '.')}.{what}")

    def claim(self, key):
        try:
            os.close(os.open(self._path(key, "claim"), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
            return True
        except FileExistsError:
            return False

    def done(self, key):
        return os.path.exists(self._path(key, "done"))

    def mark_done(self, key):
        with open(self._path(key, "done"), "w"):
            pass

    def wait_done(self, key):
        while not self.done(key) and self.other_alive():
            time.sleep(POLL_S)

    def install(self):
        """Route each planned kernel's compile through its claim (until ``remove``)."""
        for key in self.plan:
            disp = dispatcher(key)
            self.plain[key] = disp.compile
            disp.compile = self._gated(key, disp.compile)

    def remove(self):
        for key in self.plain:
            dispatcher(key).__dict__.pop("compile", None)
        self.plain = {}

    def _gated(self, key, plain):
        def compile(sig):
            if tuple(getattr(sig, "args", sig)) != self.plan[key]:
                self.report(f"{key} asked for a signature compile_plan.py does not hold: "
                            "compiled here (python -m mkcollision_ros.compile_progress "
                            "--write-plan)")
                return plain(sig)
            if self.claim(key):
                try:
                    return plain(sig)
                finally:
                    self.mark_done(key)
            self.wait_done(key)
            return plain(sig)         # from the cache, which the other process filled
        return compile


_PLAN_FILE = "plan.txt"          # the helper's kernels, one "key<TAB>signature" a line


def _cached(plan):
    try:
        return all(sig in cached_signatures(key) for key, sig in plan.items())
    except (OSError, EOFError, AttributeError):
        return False


@contextlib.contextmanager
def sharing(report=print, jobs=2, plan=None):
    """Inside the block, numba's compiles of the kernels of ``plan`` (key -> signature,
    in the order the block reaches them; default: SHARED_KERNELS and compile_plan.py)
    are split with a helper process (module docstring, "Two processes") when ``jobs`` >
    1 and the cache lacks any of them; the helper's lines go to ``report``.  Leaves
    the helper finished."""
    from numba import config
    if jobs < 2 or config.DISABLE_JIT:       # pure-Python runs compile nothing
        yield
        return
    if plan is None:
        full = planned_signatures()
        plan = {key: full[key] for key in SHARED_KERNELS if key in full}
    if _cached(plan):
        yield
        return
    with tempfile.TemporaryDirectory(prefix="mkcollision-compile-") as folder:
        with open(os.path.join(folder, _PLAN_FILE), "w") as f:
            f.writelines(f"{key}\t{sig!r}\n" for key, sig in plan.items())
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            p for p in (_PACKAGE_PARENT, os.environ.get("PYTHONPATH")) if p))
        helper = subprocess.Popen(
            [sys.executable, "-m", "mkcollision_ros.compile_progress", "--helper", folder],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)

        def relay():
            for line in helper.stdout:
                report(f"(second process) {line.rstrip()}")
        relaying = threading.Thread(target=relay, daemon=True)
        relaying.start()
        claims = _Claims(folder, plan, lambda: helper.poll() is None, report)
        claims.install()
        try:
            # this process's lead, from the plan's start (the quiet lines: the
            # reporting listener tells each compile already)
            _compile_share(claims, list(plan), lambda line: None)
            yield
        finally:
            claims.remove()
            if helper.poll() is None:
                helper.terminate()
            helper.wait()
            relaying.join(timeout=5.0)


_PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _read_plan(folder):
    names = _type_names()
    plan = {}
    with open(os.path.join(folder, _PLAN_FILE)) as f:
        for line in f:
            key, text = line.rstrip("\n").split("\t")
            plan[key] = eval(text, names)
    return plan


def _compile_share(claims, keys, say, go_on=lambda: True):
    """Compile each kernel of ``keys`` in order that nobody has claimed, claiming it
    first and marking it done after, while ``go_on()``; a line to ``say`` for each.
    A kernel that does not compile for its planned signature (a stale plan) is left
    to whichever warm-up reaches it."""
    for key in keys:
        if not go_on():
            break
        if claims.done(key) or not claims.claim(key):
            continue
        t0 = time.perf_counter()
        disp = dispatcher(key)
        hits = sum(disp.stats.cache_hits.values())
        name = key.split(":")[1]
        try:
            claims.plain[key](claims.plan[key])
        except Exception as err:  # noqa: BLE001 - a stale plan: the warm-up compiles it
            say(f"could not compile {name} for compile_plan.py's signature "
                f"({type(err).__name__}); left to the warm-up")
            continue
        finally:
            claims.mark_done(key)
        if sum(disp.stats.cache_hits.values()) > hits:
            say(f"loaded {name} from the cache")
        else:
            say(f"compiled {name} in {time.perf_counter() - t0:.0f} s")


def _helper(folder):
    """The helper process: compile the kernels of ``folder``'s plan from its end, each
    one nobody has claimed, until the parent process is gone or all are done."""
    parent = os.getppid()

    def say(line):
        print(line, flush=True)

    claims = _Claims(folder, _read_plan(folder), lambda: os.getppid() == parent, say)
    claims.install()
    _compile_share(claims, reversed(list(claims.plan)), say,
                   lambda: os.getppid() == parent)


def warm_up_all(report=print, jobs=2):
    """Compile (or load from the cache) every kernel any entry point reaches: the
    pipeline's (``Pipeline.warm_up``: what the node compiles at start) and the pair
    API's (``mkcollision_ros.warm_up``: ``collide``, ``distance``, each method),
    reporting progress to ``report``; ``jobs`` 2 shares a cold compile with a second
    process (``sharing``).  Returns the seconds it took."""
    t0 = time.perf_counter()
    with reporting(report), sharing(report, jobs):
        _compile_everything()
    return time.perf_counter() - t0


def _compile_everything():
    from .narrowphase import warm_up
    from .pipeline import Pipeline
    Pipeline([{"name": "a", "shape": {"type": "sphere", "radius": 1.0}}]).warm_up()
    warm_up()


def _measure(jobs):
    """Compile what the warm-ups reach and print the outermost kernels' seconds as
    EXPECTED_SECONDS (run it with an empty cache: XDG_CACHE_HOME=$(mktemp -d))."""
    with reporting(print, {}, heartbeat=0) as listener, sharing(print, jobs):
        _compile_everything()
    print("EXPECTED_SECONDS = {")
    for name, s in listener.seconds.items():
        print(f"    {name!r}: {s:.0f},")
    print("}")


def write_plan():
    """compile_plan.py's text: each shared kernel's signature in the cache (after the
    warm-ups, which fill it); ValueError unless each has exactly one."""
    _compile_everything()
    lines = []
    for key in SHARED_KERNELS:
        sigs = cached_signatures(key)
        if len(sigs) != 1:
            raise ValueError(f"{key}: {len(sigs)} signatures in the cache, want 1 "
                             "(run this with a fresh cache)")
        lines.append(f"    {key!r}:\n        {repr(sigs[0])!r},")
    return ('"""The signatures of compile_progress.SHARED_KERNELS, which the second process '
            'of a\ncold compile compiles by name (written by ``python -m '
            'mkcollision_ros.compile_progress\n--write-plan``; numba type reprs)."""\n'
            "SIGNATURES = {\n" + "\n".join(lines) + "\n}\n")


def main(argv=None):
    """``python -m mkcollision_ros.compile_progress``: compile every kernel into the
    cache, with progress lines (what ``tools/setup.sh`` runs; about a second once
    cached), in two processes unless ``--jobs 1``.  ``--measure``: print
    EXPECTED_SECONDS instead; ``--write-plan``: rewrite compile_plan.py."""
    import argparse
    parser = argparse.ArgumentParser(prog="python -m mkcollision_ros.compile_progress",
                                     description=main.__doc__)
    parser.add_argument("--jobs", type=int, default=2, choices=(1, 2),
                        help="processes of a cold compile (default 2)")
    parser.add_argument("--measure", action="store_true",
                        help="print the outermost compiles' seconds as EXPECTED_SECONDS")
    parser.add_argument("--write-plan", action="store_true",
                        help="rewrite compile_plan.py from the cache")
    parser.add_argument("--helper", metavar="DIR", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.helper:
        _helper(args.helper)
        return 0
    if args.measure:
        _measure(args.jobs)
        return 0
    if args.write_plan:
        text = write_plan()
        with open(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                               "compile_plan.py"), "w") as f:
            f.write(text)
        return 0

    def say(line):
        print(f"[kernels] {line}", flush=True)

    took = warm_up_all(say, args.jobs)
    say(f"every kernel ready in {took:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
