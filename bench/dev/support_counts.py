"""Support points per deep pair, counted in pure Python: where GJK + EPA spend their steps.

Times on this machine wander in spells; the number of support points a pair takes does
not, and an idea that saves none saves no time.  This counts the calls of
``minkowski_core_xyz`` in the GJK/EPA modules (every GJK, EPA and polish step makes one;
gjk.py, epa.py, polish_*.py, certificates.py, gjk_epa.py) for each deep
pair (depth > 1e-3 * scale in bench/dev/deep_pairs.py's reference run) through ``gjk_epa_ws``
in contacts mode, split by whether EPA ran (the cores overlap) or not (GJK alone on cores
apart, or a pair kernel before GJK (kernels/pairs/), whose supports are not counted:
0), and for a pair with a box by the box's feature along the answer's normal
(face, edge or vertex: how many of its axes are normal to it).  It also prints the
answer's largest departure from the reference depth.  Run it with numba off:

    NUMBA_DISABLE_JIT=1 PYTHONPATH=. .venv/bin/python bench/dev/support_counts.py ROW [--n N]

An edit to test goes into the kernels first (numba off, so no compile): the counts then
show the edit's effect in seconds on the same cases (bench/dev/deep_pairs.py --save ROW
writes them and the reference).
"""
import argparse
import collections
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

from bench.common import relative_poses  # noqa: E402
from bench.dev.deep_pairs import load_cases  # noqa: E402
from mkcollision_ros.kernels import (certificates, epa, gjk, gjk_epa,  # noqa: E402
                                     polish_crease, polish_faces, polish_newton, polish_pairs)
from mkcollision_ros.kernels.constants import BOX, OUT_SIZE  # noqa: E402

FEATURE = {0: "vertex", 1: "edge", 2: "face"}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("row")
    ap.add_argument("--n", type=int, default=1000, help="deep pairs at most")
    ap.add_argument("--cases", default="/tmp/mkc_deep_pairs", help="folder of cases and references")
    args = ap.parse_args()
    if os.environ.get("NUMBA_DISABLE_JIT") != "1":
        sys.exit("run with NUMBA_DISABLE_JIT=1: the count wraps Python functions")
    shapes, table, pairs, pos, quat = load_cases(args.cases, args.row)
    ref = np.load(os.path.join(args.cases, f"ref_{args.row}_gjk_epa.npz"))
    rot, tr = relative_poses(pos, quat)
    scale = table.params[0::2, 7] + table.params[1::2, 7]
    sel = np.flatnonzero(ref["out"][:, 0] < -1e-3 * scale)[:args.n]
    calls, ran = [0], [False]
    counted_modules = [m for m in (gjk, epa, polish_newton, polish_crease, polish_faces,
                                   polish_pairs, certificates, gjk_epa)
                       if hasattr(m, "minkowski_core_xyz")]
    support, epa_run = gjk.minkowski_core_xyz, gjk_epa._epa

    def counted(*a):
        calls[0] += 1
        return support(*a)

    def epa_seen(*a):
        ran[0] = True
        return epa_run(*a)

    for m in counted_modules:
        m.minkowski_core_xyz = counted
    gjk_epa._epa = epa_seen
    ws = gjk_epa.make_gjk_workspace()
    groups = collections.defaultdict(list)
    dev = 0.0
    for k in sel:
        i, j = pairs[k]
        sa = (table.codes[i], table.params[i], table.vrange[i, 0], table.vrange[i, 1])
        sb = (table.codes[j], table.params[j], table.vrange[j, 0], table.vrange[j, 1])
        out = np.zeros(OUT_SIZE)
        calls[0], ran[0] = 0, False
        gjk_epa.gjk_epa_ws(sa, sb, table.verts, rot[k], tr[k], out, ws, 0.0)
        dev = max(dev, abs(out[0] - ref["out"][k, 0]) / scale[k])
        feature = ""
        if BOX in (table.codes[i], table.codes[j]):
            # the normal in the box's frame (B's: rotated by r_ab^T)
            n = out[1:4] if table.codes[i] == BOX else rot[k].T @ out[1:4]
            feature = FEATURE[int(np.sum(np.abs(n) < 1e-6))]
        groups[("EPA" if ran[0] else "no EPA", feature)].append(calls[0])
    every = [c for g in groups.values() for c in g]
    print(f"{args.row}: {len(every)} deep pairs, {np.mean(every):.2f} supports per pair; "
          f"depth within {dev:.1e} * scale of the reference")
    for (phase, feature), g in sorted(groups.items()):
        print(f"  {phase:8s} {feature:6s} {len(g):4d} pairs  {np.mean(g):6.2f} supports  "
              f"{100 * sum(g) / sum(every):3.0f}% of all")


if __name__ == "__main__":
    main()
