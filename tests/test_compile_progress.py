"""Progress lines while numba compiles, and none for work that needs no compile."""
import numba

from mkcollision_ros.compile_progress import reporting


def test_each_outermost_compile_is_reported_with_an_estimate():
    @numba.njit
    def inner(x):
        return x + 1

    @numba.njit
    def outer_kernel(x):
        return inner(x) * 2

    lines = []
    with reporting(lines.append, {"outer_kernel": 3.0, "other_kernel": 7.0},
                   heartbeat=0) as listener:
        assert outer_kernel(1) == 4
        assert outer_kernel(2) == 6                   # compiled once
    assert len(lines) == 2                            # the nested compile is not listed
    assert lines[0].startswith("compiling kernels: ") and "outer_kernel" in lines[0]
    assert "outer_kernel" in lines[1] and "(1 of 2 expected kernels, about 7 s left)" in \
        lines[1]
    assert list(listener.seconds) == [lines[1].split()[1]]
    # outside the block nothing is reported
    @numba.njit
    def later(x):
        return x
    later(1)
    assert len(lines) == 2


def test_a_long_compile_keeps_reporting():
    import time
    lines = []
    with reporting(lines.append, {"slow": 1.0}, heartbeat=0.05) as listener:
        class Ev:                      # one outermost compile of 0.3 s, by hand
            data = {"dispatcher": type("D", (), {"py_func": staticmethod(lambda: 0)})()}
        Ev.data["dispatcher"].py_func.__name__ = "slow"
        listener.on_start(Ev)
        time.sleep(0.3)
        listener.on_end(Ev)
    beats = [x for x in lines if x.startswith("still compiling slow:")]
    assert len(beats) >= 3 and "of about 1 s" in beats[0]
    assert lines[-1].startswith("compiled slow in 0 s")


_AFTER_WARM_UP = r"""
import numpy as np
from numba.core import event


class Seen(event.Listener):
    def __init__(self):
        self.names = []

    def on_start(self, ev):
        func = getattr((ev.data or {}).get("dispatcher"), "py_func", None)
        self.names.append(f"{getattr(func, '__module__', '?')}.{getattr(func, '__qualname__', '?')}")

    def on_end(self, ev):
        pass


seen = Seen()
event.register("numba:compile", seen)
from mkcollision_ros.compile_progress import warm_up_all
warm_up_all(lambda line: None)
start = len(seen.names)

import mkcollision_ros
from mkcollision_ros.pipeline import Pipeline, PipelineConfig
rng = np.random.default_rng(5)
kinds = [{"type": "sphere", "radius": 0.2}, {"type": "box", "size": [0.3, 0.2, 0.4]},
         {"type": "capsule", "radius": 0.1, "length": 0.3},
         {"type": "cylinder", "radius": 0.15, "height": 0.3},
         {"type": "cone", "radius": 0.15, "height": 0.3},
         {"type": "ellipsoid", "radii": [0.2, 0.15, 0.1]},
         {"type": "convex", "points": rng.normal(size=(12, 3)).tolist()}]
bodies = [{"name": f"b{i}", "shape": kinds[i % len(kinds)]} for i in range(600)]
bodies.append({"name": "floor", "shape": {"type": "plane", "normal": [0, 0, 1],
                                          "offset": 0.0}, "static": True})
n = len(bodies)
pos = rng.uniform(0.0, 2.5, size=(n, 3))
quat = rng.normal(size=(n, 4))
quat /= np.linalg.norm(quat, axis=1, keepdims=True)
touching = 0
for method in ("auto", "gjk_epa", "mpr"):
    p = Pipeline(bodies, PipelineConfig(method=method))
    for k in range(3):
        touching += len(p.step(pos + 0.01 * k, quat, 0.1 * k).pairs)
pose = ([0, 0, 0], [0, 0, 0, 1])
for a in kinds:
    for b in kinds:
        for m in ("auto", "gjk_epa", "mpr", "analytic", "ellipsoid_exact",
                  "ellipsoid_sampled"):
            mkcollision_ros.collide(a, pose, b, ([0.2, 0, 0], [0, 0, 0, 1]), m)
        mkcollision_ros.distance(a, pose, b, ([1.0, 0, 0], [0, 0, 0, 1]))
late = [x for x in seen.names[start:] if x.startswith("mkcollision_ros")]
print(touching, "|".join(late) or "-")
"""


def test_after_the_warm_up_no_entry_point_compiles(tmp_path):
    """Once ``warm_up_all`` (what tools/setup.sh runs) is done, a 600-body scene of every
    shape type (the threaded paths included) through each pipeline method, and
    ``collide`` / ``distance`` with every method on every shape pair, compile nothing
    more of the package."""
    import os
    import subprocess
    import sys
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = subprocess.run([sys.executable, "-c", _AFTER_WARM_UP], cwd=root,
                         capture_output=True, text=True, check=True,
                         timeout=1800).stdout.split()
    assert int(out[0]) > 256             # enough pairs for the threaded narrow phase
    assert out[1] == "-", out[1].split("|")


_TOY = """
import numba


@numba.njit(cache=True)
def leaf_a(x):
    return x + 1.0


@numba.njit(cache=True)
def leaf_b(x):
    return 2.0 * x


@numba.njit(cache=True)
def top(x):
    return leaf_a(x) + leaf_b(x)
"""

_SHARED_TOP = r"""
import glob
import os
import tempfile
import time
from numba import types
from numba.core import event
from mkcollision_ros import compile_progress
import toy_kernels


class Seen(event.Listener):
    def __init__(self):
        self.names = []

    def on_start(self, ev):
        name = ev.data["dispatcher"].py_func.__name__
        self.names.append(name)
        if name == "leaf_a":
            # hold this compile until the helper has claimed leaf_b (the claims folder
            # is the one under this process's TMPDIR), so the test sees a real split
            claim = os.path.join(tempfile.gettempdir(), "mkcollision-compile-*",
                                 "toy_kernels.leaf_b.claim")
            t0 = time.time()
            while not glob.glob(claim) and time.time() - t0 < 120:
                time.sleep(0.05)

    def on_end(self, ev):
        pass


seen = Seen()
event.register("numba:compile", seen)
lines = []
plan = {"toy_kernels:leaf_a": (types.float64,), "toy_kernels:leaf_b": (types.float64,)}
with compile_progress.sharing(lines.append, 2, plan=plan):
    value = toy_kernels.top(1.0)
print(value)
print(",".join(seen.names))
print("|".join(lines))
"""


def _toy_env(tmp_path):
    import os
    src = tmp_path / "src"
    src.mkdir(exist_ok=True)
    (src / "toy_kernels.py").write_text(_TOY)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    return dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
                PYTHONPATH=os.pathsep.join([str(src), root]))


def test_two_processes_share_a_cold_compile_and_compile_each_kernel_once(tmp_path):
    """``sharing``: the helper process and this one split the planned kernels, this one
    from the plan's start and the helper from its end, each compiled by one of them
    only; the other loads it from the cache."""
    import subprocess
    import sys
    env = dict(_toy_env(tmp_path), TMPDIR=str(tmp_path))
    r = subprocess.run([sys.executable, "-c", _SHARED_TOP], env=env,
                       capture_output=True, text=True, check=True, timeout=300)
    value, here, helper = r.stdout.splitlines()
    assert float(value) == 4.0
    # this process compiles leaf_a (the plan's start, its lead) and then top, the helper
    # leaf_b (the plan's end), which this process then loads from the cache
    assert here.split(",") == ["leaf_a", "top"], (here, helper)
    assert helper.split("|") == ["(second process) compiled leaf_b in 0 s"], helper


def test_the_helper_skips_a_claimed_kernel_and_fills_the_cache(tmp_path):
    """The helper compiles its plan from the end into the cache, every kernel but the
    ones the other process has claimed, and marks each done."""
    import os
    import subprocess
    import sys
    from numba import types
    from mkcollision_ros import compile_progress as cp
    folder = tmp_path / "claims"
    folder.mkdir()
    plan = {"toy_kernels:leaf_a": (types.float64,), "toy_kernels:leaf_b": (types.float64,)}
    (folder / cp._PLAN_FILE).write_text("".join(f"{k}\t{s!r}\n" for k, s in plan.items()))
    (folder / "toy_kernels.leaf_a.claim").write_text("")      # the other process's
    r = subprocess.run([sys.executable, "-m", "mkcollision_ros.compile_progress",
                        "--helper", str(folder)], env=_toy_env(tmp_path),
                       capture_output=True, text=True, check=True, timeout=300)
    assert r.stdout.splitlines() == ["compiled leaf_b in 0 s"]
    assert (folder / "toy_kernels.leaf_b.done").exists()
    assert not (folder / "toy_kernels.leaf_a.done").exists()
    cached = [n for _, _, files in os.walk(tmp_path / "cache") for n in files
              if n.endswith(".nbi")]
    assert len(cached) == 1 and "leaf_b" in cached[0], cached


def test_the_compile_plan_holds_the_signatures_the_kernels_are_compiled_for():
    """compile_plan.py's signature of each shared kernel is the one the warm-up's
    callers compile it for (else the helper would compile an unused copy)."""
    from mkcollision_ros import compile_progress as cp
    cp._compile_everything()                     # loads from the cache set up
    plan = cp.planned_signatures()
    assert list(plan) == list(cp.SHARED_KERNELS)
    for key in cp.SHARED_KERNELS:
        assert plan[key] in cp.cached_signatures(key), \
            f"{key}: run python -m mkcollision_ros.compile_progress --write-plan"


def test_no_kernel_is_compiled_for_a_literal_argument():
    """No cached signature of the package's kernels holds a Literal type: a constant
    argument typed as a literal compiles the callee once per value (kernels/jit.py,
    "Literal")."""
    import os
    import pickle
    import numba
    from mkcollision_ros import compile_progress as cp
    cp._compile_everything()
    found, literal = 0, []
    # the package's own kernels (scripts of other tests may cache theirs here too)
    for folder, _, files in os.walk(os.path.join(numba.config.CACHE_DIR, "mkcollision_ros")):
        for name in files:
            if name.endswith(".nbi"):
                with open(os.path.join(folder, name), "rb") as f:
                    pickle.load(f)                        # numba's index version
                    _, overloads = pickle.loads(f.read())
                for key in overloads:
                    found += 1
                    if "Literal" in repr(key[0]):
                        literal.append((name, repr(key[0])))
    assert found > 50
    assert literal == []
