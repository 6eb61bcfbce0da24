"""Where a row's time goes: bench/narrowphase.py's cases of a shape row split into the
pairs that are apart and those that touch (and the deep ones, > 1e-3 * scale), each
subset timed on its own with our contacts mode (auto, cutoff 0), our MPR and MuJoCo's
collision pass (defaults), one thread.

    PYTHONPATH=. .venv/bin/python bench/regimes.py [ROW ...] [--n 1000]

The cases are those of the narrow-phase benchmark with seed 1 (its default seed is 0;
any seed gives the same picture).
"""
import argparse
import os
import sys

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.common import KINDS, pair_cases  # noqa: E402
from bench.narrowphase import run_mujoco, run_ours  # noqa: E402
from mkcollision_ros.kernels.constants import (M_AUTO, M_MPR, ST_PENETRATING,  # noqa: E402
                                               ST_TOUCHING)
from mkcollision_ros.shapes import build_table  # noqa: E402

ROWS = ("cylinder-cylinder", "box-cylinder", "ellipsoid-cylinder", "convex-convex",
        "box-convex")


def subset(shapes, pos, quat, idx):
    """The cases idx as a table of their own (pairs (2k, 2k + 1))."""
    pick = np.stack([2 * idx, 2 * idx + 1], 1).ravel()
    sub = [shapes[i] for i in pick]
    return sub, build_table(sub), np.arange(len(pick)).reshape(-1, 2), pos[pick], quat[pick]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rows", nargs="*", default=ROWS)
    ap.add_argument("--n", type=int, default=1000)
    args = ap.parse_args()
    numba.set_num_threads(1)
    for row in args.rows:
        a, b = row.split("-")
        shapes, table, pairs, pos, quat = pair_cases(
            a, b, args.n, seed=1 + 101 * KINDS.index(a) + KINDS.index(b))
        _, st, out = run_ours(table, pairs, pos, quat, M_AUTO, 5)
        hit = (st == ST_TOUCHING) | (st == ST_PENETRATING)
        scale = table.params[0::2, 7] + table.params[1::2, 7]
        for name, sel in (("apart", ~hit), ("touching", hit),
                          ("deep", hit & (-out[:, 0] > 1e-3 * scale))):
            idx = np.flatnonzero(sel)
            if len(idx) == 0:
                continue
            sub, tb, pr, ps, qs = subset(shapes, pos, quat, idx)
            t_con = run_ours(tb, pr, ps, qs, M_AUTO, 7, 0.0)[0]
            t_mpr = run_ours(tb, pr, ps, qs, M_MPR, 7)[0]
            t_mj = run_mujoco(sub, ps, qs, len(idx), 7)[0]
            mj = "n/a" if t_mj is None else f"{t_mj * 1e6:5.2f}"
            ratio = "" if t_mj is None else f"   contacts/mujoco {t_con / t_mj:4.2f}"
            print(f"{row:20s} {name:8s} n={len(idx):4d}  us per pair: contacts "
                  f"{t_con * 1e6:5.2f}  mpr {t_mpr * 1e6:5.2f}  mujoco {mj}{ratio}",
                  flush=True)


if __name__ == "__main__":
    main()
