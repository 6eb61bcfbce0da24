"""The narrow-phase fuzzer's command line (mkcollision_ros/fuzzing.py: what it draws and
what it checks): random pairs of every shape type through every method, checked call by
call; one line per failure with a repro, then a table per method.  Exit status 1 when
anything failed.

    PYTHONPATH=. python bench/fuzz.py --pairs 1000000 --seed 1 \\
        [--methods auto,gjk_epa,mpr,analytic,ellipsoid_exact,ellipsoid_sampled,distance]
        [--api-every 200] [--time-bound 0.05] [--chunk 20000]
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from mkcollision_ros.fuzzing import (METHODS, check_pairs, draw_pairs, make_pool,  # noqa: E402
                                     table)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs", type=int, default=10000, help="random pairs per method")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--pool", type=int, default=400, help="shapes per type")
    ap.add_argument("--chunk", type=int, default=20000, help="pairs per batch")
    ap.add_argument("--api-every", type=int, default=200,
                    help="every k-th pair also through the public API (0: none)")
    ap.add_argument("--time-bound", type=float, default=0.05, help="seconds per call")
    args = ap.parse_args(argv)
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    for m in methods:
        if m not in METHODS:
            ap.error(f"unknown method {m!r}; expected some of {', '.join(METHODS)}")
    rng = np.random.default_rng(args.seed)
    t0 = time.time()
    pool = make_pool(rng, args.pool)
    stats = {}
    done = 0
    while done < args.pairs:
        n = min(args.chunk, args.pairs - done)
        batch = draw_pairs(rng, pool, n)
        check_pairs(batch, methods, args.time_bound, args.api_every, stats=stats)
        done += n
        print(f"# {done:,} pairs per method, {time.time() - t0:.0f} s", file=sys.stderr,
              flush=True)
    print(table(stats))
    for s in stats.values():
        print(f"slowest {s.method}: {1e3 * s.slowest:.2f} ms, {s.slowest_repro}")
    bad = sum(s.failed + s.nan + s.other + s.disagree for s in stats.values())
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
