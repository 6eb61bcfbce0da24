"""Where a row's time goes: the cases of a shape row split by regime, each subset timed
on its own, our contacts mode (auto, cutoff 0, one thread) alternated with MuJoCo's
collision pass (defaults) as bench/vs_mujoco.py does (the ratio of each peer's fastest
round; figures of runs timed back to back wandered by 2x on this machine).

    PYTHONPATH=. .venv/bin/python bench/dev/regimes.py [ROW ...] [--n 2000] [--rounds 41]

Regimes: apart with bounding spheres apart (both sides' pre-test ends them), apart
with bounding spheres overlapping (the narrow phase proves them apart), touching or
shallow (depth up to 1e-3 * scale) and deep.  "share" is the subset's part of our
time over the whole row (pairs times time per pair).  The cases are the row's in
bench/vs_mujoco.py (bench/narrowphase.py's seed formula).
"""
import argparse
import os
import sys

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

from bench.common import pair_cases  # noqa: E402
from bench.narrowphase import run_ours  # noqa: E402
from bench.vs_mujoco import alternated, row_seed, summary  # noqa: E402
from mkcollision_ros.kernels.constants import M_AUTO, ST_PENETRATING, ST_TOUCHING  # noqa: E402
from mkcollision_ros.shapes import build_table  # noqa: E402

ROWS = ("cylinder-cylinder", "box-cylinder", "ellipsoid-cylinder", "ellipsoid-box",
        "ellipsoid-convex", "cylinder-convex")


def subset(shapes, pos, quat, idx):
    """The cases idx as a table of their own (pairs (2k, 2k + 1))."""
    pick = np.stack([2 * idx, 2 * idx + 1], 1).ravel()
    sub = [shapes[i] for i in pick]
    return sub, build_table(sub), np.arange(len(pick)).reshape(-1, 2), pos[pick], quat[pick]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rows", nargs="*", default=ROWS)
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=41)
    args = ap.parse_args()
    numba.set_num_threads(1)
    print("| pair | regime | pairs | contacts µs | mujoco µs | ratio | share of our time |")
    print("|---|---|---|---|---|---|---|")
    for row in args.rows:
        a, b = row.split("-")
        shapes, table, pairs, pos, quat = pair_cases(a, b, args.n, seed=row_seed(a, b))
        _, st, out = run_ours(table, pairs, pos, quat, M_AUTO, 1, 0.0)
        hit = (st == ST_TOUCHING) | (st == ST_PENETRATING)
        radius = table.params[:, 7]
        scale = radius[0::2] + radius[1::2]
        spheres_apart = np.linalg.norm(pos[1::2] - pos[0::2], axis=1) > scale
        parts = []
        for name, sel in (("apart, spheres apart", ~hit & spheres_apart),
                          ("apart, spheres overlap", ~hit & ~spheres_apart),
                          ("touching or shallow", hit & (-out[:, 0] <= 1e-3 * scale)),
                          ("deep", hit & (-out[:, 0] > 1e-3 * scale))):
            idx = np.flatnonzero(sel)
            if len(idx) == 0:
                continue
            got = alternated(*subset(shapes, pos, quat, idx), args.rounds, 1)
            parts.append((name, len(idx), None if got is None else summary(*got)))
        total = sum(k * s[0] for _, k, s in parts if s is not None)
        for name, k, s in parts:
            if s is None:
                print(f"| {row} | {name} | {k} | n/a | n/a | n/a | n/a |")
                continue
            print(f"| {row} | {name} | {k} | {s[0]:.3f} | {s[1]:.3f} | {s[2]:.2f} "
                  f"| {100 * k * s[0] / total:.0f}% |", flush=True)


if __name__ == "__main__":
    main()
