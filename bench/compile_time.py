"""Where the first compile goes: the first ``collide_batch`` call (what
``bench/narrowphase.py``'s start-up row times) in a fresh, empty numba cache, with the
time numba spent compiling each kernel, from numba's ``numba:compile`` events; with
``--all``, every kernel the setup compiles (``compile_progress.warm_up_all``).

    PYTHONPATH=. .venv/bin/python bench/compile_time.py [--top 30] [--all]

"own s" is a kernel's compile less that of the kernels it calls that are compiled as
functions of their own (nested ``numba:compile`` events), ``njit_inline`` helpers
included: LLVM's work on their inlined copies counts as the caller's own.  A kernel
listed with more than one compile was typed for more than one signature (e.g. an
integer argument seen once as a literal constant).  Takes 2-4 minutes; run it with
nothing else on the machine.
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from bench.narrowphase import STARTUP  # noqa: E402

TIMER = r"""
import time
from numba.core import event


class Timer(event.Listener):
    def __init__(self):
        self.stack, self.rows = [], []

    def on_start(self, ev):
        d = ev.data or {}
        name = d["dispatcher"].py_func.__qualname__ if "dispatcher" in d else "?"
        self.stack.append([time.perf_counter(), name, 0.0])

    def on_end(self, ev):
        t0, name, inner = self.stack.pop()
        dt = time.perf_counter() - t0
        self.rows.append((name, dt, dt - inner))
        if self.stack:
            self.stack[-1][2] += dt


timer = Timer()
event.register("numba:compile", timer)
"""

ROWS = r"""
for name, incl, own in timer.rows:
    print("ROW", name, incl, own)
"""
# the start-up row's own script between the timer and the rows (it prints "import_s first_s")
CHILD = TIMER + STARTUP + ROWS
# every kernel of the setup's compile (it prints "import_s total_s")
EVERYTHING = r"""
import time
t0 = time.perf_counter()
from mkcollision_ros import compile_progress
t1 = time.perf_counter()
compile_progress.warm_up_all(lambda line: None)
print(f"{t1 - t0:.3f} {time.perf_counter() - t0:.3f}")
"""
CHILD_ALL = TIMER + EVERYTHING + ROWS


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--top", type=int, default=30, help="kernels listed (by own time)")
    ap.add_argument("--all", action="store_true",
                    help="every kernel the setup compiles, not the first collide_batch's")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache,
                   PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
        w0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-c", CHILD_ALL if args.all else CHILD], env=env,
                           cwd=ROOT,
                           capture_output=True, text=True, check=True)
        wall = time.perf_counter() - w0
    total, agg = 0.0, {}
    for line in r.stdout.splitlines():
        parts = line.split()
        if parts[0] == "ROW":
            a = agg.setdefault(parts[1], [0, 0.0, 0.0])
            a[0] += 1
            a[1] += float(parts[2])
            a[2] += float(parts[3])
        elif len(parts) == 2:
            total = float(parts[1])
    what = "every kernel of the setup" if args.all else "first collide_batch call"
    print(f"{what}, empty cache: {total:.1f} s (process wall {wall:.1f} s)\n")
    print("| kernel | own s | with its called kernels s | compiles |")
    print("|---|---|---|---|")
    for name, (n, incl, own) in sorted(agg.items(), key=lambda kv: -kv[1][2])[:args.top]:
        print(f"| {name} | {own:.1f} | {incl:.1f} | {n} |")


if __name__ == "__main__":
    main()
