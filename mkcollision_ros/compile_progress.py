"""Progress of numba's first compile, for people watching a terminal.

A first start compiles the kernels for minutes (README, "First-run cost"); a cached start
loads them in about a second and compiles nothing.  ``reporting(report)`` is a context
manager that listens to numba's ``numba:compile`` event (numba's documented event API;
it fires only when a kernel is compiled, never when it is loaded from the cache) and
calls ``report(line)`` when an outermost compile starts, every HEARTBEAT_S while it
lasts (one kernel takes minutes), and when it ends: which kernel, how long it took, how
many of the expected kernels are done and an estimate of the time left.  The estimate
comes from EXPECTED_SECONDS, the outermost compiles of ``warm_up_all`` (the pipeline's
warm-up, what the node compiles at start, then the pair API's) measured in an empty
cache on the project's 2-core machine (``python -m mkcollision_ros.compile_progress
--measure`` measures them again); other kernels count as unknown.
"""
import contextlib
import threading
import time

from numba.core import event

# outermost compiles of a cold warm-up: kernel name -> seconds (see the module docstring)
EXPECTED_SECONDS = {
    "normalise_poses": 0,
    "world_aabbs": 2,
    "find_pairs": 16,
    "filter_pairs": 1,
    "_collide_block": 281,
    "split_pairs": 0,
    "_manifold_block": 8,
    "arbiter_step": 6,
    "_fan_build": 2,
    "_collide_batch": 23,
    "_manifold_batch": 3,
    "collide_world": 13,
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


def warm_up_all(report=print):
    """Compile (or load from the cache) every kernel any entry point reaches: the
    pipeline's (``Pipeline.warm_up``: what the node compiles at start) and the pair
    API's (``mkcollision_ros.warm_up``: ``collide``, ``distance``, each method),
    reporting progress to ``report``.  Returns the seconds it took."""
    t0 = time.perf_counter()
    with reporting(report):
        _compile_everything()
    return time.perf_counter() - t0


def _compile_everything():
    from .narrowphase import warm_up
    from .pipeline import Pipeline
    Pipeline([{"name": "a", "shape": {"type": "sphere", "radius": 1.0}}]).warm_up()
    warm_up()


def _measure():
    """Compile what the warm-ups reach and print the outermost kernels' seconds as
    EXPECTED_SECONDS (run it with an empty cache: NUMBA_CACHE_DIR=$(mktemp -d))."""
    with reporting(print, {}, heartbeat=0) as listener:
        _compile_everything()
    print("EXPECTED_SECONDS = {")
    for name, s in listener.seconds.items():
        print(f"    {name!r}: {s:.0f},")
    print("}")


def main(argv=None):
    """``python -m mkcollision_ros.compile_progress``: compile every kernel into the
    cache, with progress lines (what ``tools/setup.sh`` runs; about a second once
    cached).  ``--measure``: print EXPECTED_SECONDS instead."""
    import argparse
    parser = argparse.ArgumentParser(prog="python -m mkcollision_ros.compile_progress",
                                     description=main.__doc__)
    parser.add_argument("--measure", action="store_true",
                        help="print the outermost compiles' seconds as EXPECTED_SECONDS")
    args = parser.parse_args(argv)
    if args.measure:
        _measure()
        return 0

    def say(line):
        print(f"[kernels] {line}", flush=True)

    took = warm_up_all(say)
    say(f"every kernel ready in {took:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
