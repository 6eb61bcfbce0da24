"""Time of one ``trace_pair`` call (mkcollision_ros/trace.py) and of one
``minkowski_difference`` call on a deep ellipsoid-box pair, after a warm-up call
(compiled kernels): the fastest and the median of --repeat calls, and what the trace
holds.

    PYTHONPATH=. .venv/bin/python bench/dev/trace_time.py [--repeat 50]
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

from mkcollision_ros import collide  # noqa: E402
from mkcollision_ros.trace import minkowski_difference, trace_pair  # noqa: E402

ELLIPSOID = {"type": "ellipsoid", "radii": [0.5, 0.3, 0.2]}
BOX = {"type": "box", "size": [0.8, 0.6, 0.4]}
POSE_E = ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
q = np.array([0.2, -0.3, 0.1, 0.9])
POSE_B = ([0.25, 0.1, -0.05], (q / np.linalg.norm(q)).tolist())


def timed(fn, repeat):
    """(fastest, median) seconds of ``repeat`` calls of fn() after one warm-up call."""
    fn()
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return min(ts), float(np.median(ts))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=50)
    args = ap.parse_args()
    r = collide(ELLIPSOID, POSE_E, BOX, POSE_B)
    t = trace_pair(ELLIPSOID, POSE_E, BOX, POSE_B)
    print(f"pair: ellipsoid {ELLIPSOID['radii']} - box {BOX['size']}, distance "
          f"{r.distance:.4f} m ({r.status.name}, answered by {t.answered_by}, traced "
          f"{t.traced}): {len(t.gjk_simplices)} GJK simplices, {len(t.epa_polytopes)} "
          f"EPA polytopes (last: {len(t.epa_polytopes[-1][0])} vertices, "
          f"{len(t.epa_polytopes[-1][1])} faces)")
    steps = (("collide (untraced)", lambda: collide(ELLIPSOID, POSE_E, BOX, POSE_B)),
             ("trace_pair", lambda: trace_pair(ELLIPSOID, POSE_E, BOX, POSE_B)),
             ("minkowski_difference (400 directions)",
              lambda: minkowski_difference(ELLIPSOID, POSE_E, BOX, POSE_B)))
    print(f"\n| call | fastest ms | median ms |  ({args.repeat} calls each)")
    print("|---|---|---|")
    for name, fn in steps:
        lo, med = timed(fn, args.repeat)
        print(f"| {name} | {lo * 1e3:.3f} | {med * 1e3:.3f} |")


if __name__ == "__main__":
    main()
