"""Check that a speed change left the narrow phase's results unchanged: run
``collide_batch`` on the same seeded cases (``common.pair_cases``, every shape row) with
gjk_epa, mpr and contacts (auto, cutoff 0) in this checkout and in another git revision,
and compare status codes and all output columns exactly.

    PYTHONPATH=. .venv/bin/python bench/same_results.py REV [--n 1000]

The revision is exported with ``git archive`` to a temporary folder and run there in its
own process (its kernels compile on the first run, ~2 min).  Exit status 1 and a list of
the differing rows when anything differs.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

RUN = r"""
import sys
import numpy as np
from bench.common import KINDS, pair_cases
from mkcollision_ros.kernels.constants import M_AUTO, M_GJK_EPA, M_MPR, OUT_SIZE
from mkcollision_ros.kernels.narrowphase import collide_batch
n, path = int(sys.argv[1]), sys.argv[2]
res = {}
for ia, a in enumerate(KINDS):
    for b in KINDS[ia:]:
        if a == "plane" and b == "plane":
            continue
        shapes, table, pairs, pos, quat = pair_cases(a, b, n, seed=777 + 101 * ia + KINDS.index(b))
        for name, m, cut in (("gjk_epa", M_GJK_EPA, np.inf), ("mpr", M_MPR, np.inf),
                             ("contacts", M_AUTO, 0.0)):
            out = np.zeros((len(pairs), OUT_SIZE))
            st = np.zeros(len(pairs), np.int64)
            collide_batch(table.codes, table.params, table.vrange, table.verts, pairs, pos,
                          quat, m, cut, out, st)
            res[f"{a}-{b} {name} out"] = out
            res[f"{a}-{b} {name} status"] = st
np.savez(path, **res)
"""


def results(src_root, n, path):
    env = dict(os.environ, PYTHONPATH=src_root, NUMBA_NUM_THREADS="1")
    subprocess.run([sys.executable, "-c", RUN, str(n), path], cwd=src_root, env=env,
                   check=True)
    return np.load(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rev", help="git revision to compare with, e.g. HEAD~3")
    ap.add_argument("--n", type=int, default=1000, help="cases per shape row")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        other = os.path.join(tmp, "rev")
        os.mkdir(other)
        archive = subprocess.run(["git", "archive", args.rev, "mkcollision_ros", "bench"],
                                 cwd=ROOT, check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", other], input=archive, check=True)
        theirs = results(other, args.n, os.path.join(tmp, "theirs.npz"))
        ours = results(ROOT, args.n, os.path.join(tmp, "ours.npz"))
        differ = [k for k in sorted(ours.files)
                  if k not in theirs.files or not np.array_equal(ours[k], theirs[k])]
    print(f"{len(ours.files) - len(differ)} of {len(ours.files)} arrays identical "
          f"({args.n} cases per row) between {args.rev} and this checkout")
    for k in differ:
        print(f"  differs: {k}")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
