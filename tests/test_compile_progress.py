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
