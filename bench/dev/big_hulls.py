"""Convex shapes given as large point sets: what dropping the points inside the hull
(mkcollision_ros.hull) saves, against the same table with every point kept, and
against MuJoCo (which builds its own hull of the same points), one thread.

    PYTHONPATH=. .venv/bin/python bench/dev/big_hulls.py [--n 500] [--points 1000]

Cases: bench.common.pair_cases with the convex shape's points drawn from one of two
clouds of --points points about the origin, the bounding size of the narrow-phase
benchmark's hulls:
  * blob:  a Gaussian cloud (most points inside the hull: what a point cloud or a
           non-convex mesh's vertices look like);
  * shell: points on an ellipsoid (every point a hull vertex: nothing to drop, the
           control).
Columns: µs per pair for our contacts mode (auto, cutoff 0) with the pruned table and
with the whole one, MuJoCo's collision pass, and the points per shape (mean) kept.
"""
import argparse
import os
import sys

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

import bench.common as common  # noqa: E402
from bench.narrowphase import run_mujoco, run_ours  # noqa: E402
from mkcollision_ros.kernels.constants import CONVEX, M_AUTO  # noqa: E402
from mkcollision_ros.shapes import build_table  # noqa: E402

ROWS = ("sphere-convex", "box-convex", "cylinder-convex", "ellipsoid-convex",
        "convex-convex")


def cloud(kind, points):
    """A point generator for bench.common.random_hull_points' place."""
    def draw(rng, size=0.5, n=None):
        d = rng.normal(size=(points, 3))
        if kind == "shell":
            d /= np.linalg.norm(d, axis=1, keepdims=True)
        else:
            d /= np.linalg.norm(d, axis=1).max()    # the farthest point at 1
        return d * size * rng.uniform(0.6, 1.0, size=3)
    return draw


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rows", nargs="*", default=ROWS)
    ap.add_argument("--n", type=int, default=500)
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    numba.set_num_threads(1)
    for kind in ("blob", "shell"):
        common.random_hull_points = cloud(kind, args.points)
        for row in args.rows:
            a, b = row.split("-")
            shapes, table, pairs, pos, quat = common.pair_cases(
                a, b, args.n, seed=1 + 101 * common.KINDS.index(a) + common.KINDS.index(b))
            whole = build_table(shapes, prune=False)
            t_p, st_p, _ = run_ours(table, pairs, pos, quat, M_AUTO, args.repeat, 0.0)
            t_w, st_w, _ = run_ours(whole, pairs, pos, quat, M_AUTO, args.repeat, 0.0)
            assert np.array_equal(st_p, st_w)
            t_mj = run_mujoco(shapes, pos, quat, args.n, args.repeat)[0]
            kept = table.vrange[table.codes == CONVEX, 1].mean()
            mj = "  n/a" if t_mj is None else f"{t_mj * 1e6:6.2f}"
            ratio = "" if t_mj is None else f"  pruned/mujoco {t_p / t_mj:5.2f}"
            print(f"{kind:5s} {row:17s} points kept {kept:7.1f} of {args.points}  "
                  f"us per pair: pruned {t_p * 1e6:6.2f}  whole {t_w * 1e6:6.2f}  "
                  f"mujoco {mj}  pruned/whole {t_p / t_w:5.2f}{ratio}", flush=True)


if __name__ == "__main__":
    main()
