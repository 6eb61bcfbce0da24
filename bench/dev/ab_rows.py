"""Contacts-mode time per pair of chosen rows, to four decimals: for alternated A/B runs
of two checkouts on the closed-form rows, whose times bench/narrowphase.py rounds to
0.01 us.

    PYTHONPATH=. .venv/bin/python bench/dev/ab_rows.py sphere-box sphere-cylinder ...

Each row: bench.common.pair_cases(a, b, 2000, seed=0), then the fastest of three
medians of 9 timed runs of the batch kernel (method auto, cutoff 0, one thread).
"""
import os
import sys

import numba

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

from bench.common import pair_cases  # noqa: E402
from bench.narrowphase import run_ours  # noqa: E402
from mkcollision_ros.kernels.constants import M_AUTO  # noqa: E402


def main():
    numba.set_num_threads(1)
    for row in sys.argv[1:]:
        a, b = row.split("-")
        shapes, table, pairs, pos, quat = pair_cases(a, b, 2000, seed=0)
        t = min(run_ours(table, pairs, pos, quat, M_AUTO, 9, 0.0)[0] for _ in range(3))
        print(f"{row:18s} {t * 1e6:7.4f} us per pair")


if __name__ == "__main__":
    main()
