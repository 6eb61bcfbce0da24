"""GJK/EPA of this checkout against another git revision, in one process: results and
time per pair on the same seeded cases, timed in alternation.

Why: on this machine (a virtual machine) the time of one row drifts by 10-30% from one
minute to the next, so bench/dev/deep_pairs.py runs minutes apart do not resolve a change
of a few percent.  Here the revision's kernels are imported beside ours (its
``mkcollision_ros/kernels`` exported with ``git archive`` under another package name;
the kernels import nothing but each other, numpy, numba and math) and both are timed
round after round on the same pairs, as the batch kernel calls them (``gjk_epa_ws``,
borrowed arrays, one workspace, ``--cutoff`` 0 as in contacts mode).

    PYTHONPATH=. .venv/bin/python bench/dev/ab_deep.py REV [ROW ...] [--n 2000] [--rounds 7]
    ... --subset all|deep|apart     # which pairs are timed (default deep)
    ... --no-time --n 100000        # results only, on many pairs
    ... --check-n 100000            # also results only on that many other cases per
                                    # row (seed + 1), in the same process: one compile
    ... --cutoff inf                # exact distances: the pairs apart compare too
    ... --keep /tmp/ab_rev          # keep the exported revision and its numba cache:
                                    # the next run against it compiles only ours

Cases: bench.common.pair_cases(a, b, n, seed) with ``--seed``.  "deep" pairs are those
deeper than 1e-3 * scale by the revision's result, "apart" those it finds apart whose
bounding spheres overlap.  Results: statuses on all pairs; on the pairs penetrating in
both, the largest amounts by which our signed distance is lower and higher than the
revision's, over scale (each is within EPA_REL_TOL * scale of the true one: minus
h_{A-B} along a polished normal, at most the true distance, or minus EPA's nearest face
distance, at least it); pairs apart are left out (in contacts mode their distance is
the first separating plane's bound, which a kernel may tighten); and the largest normal
difference on pairs farther from touching than 1e-3 * scale in both (penetrating in
both unless --cutoff is inf: apart, a contacts-mode normal is any separating direction).
"""
import argparse
import importlib
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numba
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)

from bench.common import KINDS, pair_cases, relative_poses  # noqa: E402
from mkcollision_ros.kernels import gjk_epa as G  # noqa: E402
from mkcollision_ros.kernels.constants import OUT_ITERS, OUT_SIZE, ST_SEPARATED  # noqa: E402
from mkcollision_ros.kernels.jit import borrow  # noqa: E402


def import_revision(rev, folder):
    """REV's kernels as the package ``mkc_ab_rev.kernels`` (exported into folder, or
    reused from there when an earlier run exported the same commit: numba's cache files
    beside them then spare the revision's compile)."""
    pkg = os.path.join(folder, "mkc_ab_rev")
    sha = subprocess.run(["git", "-C", ROOT, "rev-parse", rev], check=True,
                         capture_output=True, text=True).stdout.strip()
    stamp = os.path.join(pkg, "REVISION")
    if not (os.path.exists(stamp) and open(stamp).read() == sha):
        shutil.rmtree(pkg, ignore_errors=True)
        os.makedirs(pkg)
        tar = subprocess.run(["git", "-C", ROOT, "archive", rev, "mkcollision_ros/kernels"],
                             check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", folder], input=tar, check=True)
        os.rename(os.path.join(folder, "mkcollision_ros", "kernels"),
                  os.path.join(pkg, "kernels"))
        open(os.path.join(pkg, "__init__.py"), "w").close()
        with open(stamp, "w") as f:
            f.write(sha)
    sys.path.insert(0, folder)
    return importlib.import_module("mkc_ab_rev.kernels.gjk_epa")


def make_run(gjk_epa_ws):
    """A timing loop over the pairs around one module's gjk_epa_ws."""
    @numba.njit(cache=False)
    def run(codes, params, vrange, verts, pairs, rot, tr, out, st, ws0, cutoff, reps):
        codes, params, vrange, verts = borrow(codes), borrow(params), borrow(vrange), borrow(verts)
        pairs, rot, tr, out, st = borrow(pairs), borrow(rot), borrow(tr), borrow(out), borrow(st)
        ws = (borrow(ws0[0]), borrow(ws0[1]), borrow(ws0[2]))
        for _ in range(reps):
            for k in range(pairs.shape[0]):
                i, j = pairs[k, 0], pairs[k, 1]
                sa = (codes[i], params[i], vrange[i, 0], vrange[i, 1])
                sb = (codes[j], params[j], vrange[j, 0], vrange[j, 1])
                st[k] = gjk_epa_ws(sa, sb, verts, rot[k], tr[k], out[k], ws, cutoff)
    return run


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rev")
    ap.add_argument("rows", nargs="*", default=["ellipsoid-cylinder", "ellipsoid-box",
                                                 "capsule-cylinder", "cylinder-cylinder",
                                                 "ellipsoid-capsule"])
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=12345)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--cutoff", type=float, default=0.0)
    ap.add_argument("--subset", choices=("all", "deep", "apart"), default="deep")
    ap.add_argument("--no-time", action="store_true")
    ap.add_argument("--check-n", type=int, default=0,
                    help="first compare results on this many cases per row (seed + 1)")
    ap.add_argument("--keep", metavar="DIR",
                    help="export the revision into DIR and keep it (and its compiled "
                         "kernels) for the next run against the same commit")
    args = ap.parse_args()
    numba.set_num_threads(1)
    with tempfile.TemporaryDirectory() as tmp:
        if args.keep:
            os.makedirs(args.keep, exist_ok=True)
        R = import_revision(args.rev, os.path.abspath(args.keep) if args.keep else tmp)
        runs = {"rev": (make_run(R.gjk_epa_ws), R.make_gjk_workspace()),
                "ours": (make_run(G.gjk_epa_ws), G.make_gjk_workspace())}
        jobs = [(row, args.check_n, args.seed + 1, False) for row in args.rows
                if args.check_n > 0]
        jobs += [(row, args.n, args.seed, not args.no_time) for row in args.rows]
        for row, n, seed0, timed in jobs:
            a, b = row.split("-")
            seed = seed0 + 101 * KINDS.index(a) + KINDS.index(b)
            shapes, table, pairs, pos, quat = pair_cases(a, b, n, seed=seed)
            rot, tr = relative_poses(pos, quat)
            scale = table.params[0::2, 7] + table.params[1::2, 7]
            res = {}
            for name, (run, ws) in runs.items():
                out, st = np.zeros((n, OUT_SIZE)), np.zeros(n, np.int64)
                run(table.codes, table.params, table.vrange, table.verts, pairs, rot, tr,
                    out, st, ws, args.cutoff, 1)
                res[name] = (out, st)
            (ro, rs), (oo, os_) = res["rev"], res["ours"]
            # over the pairs penetrating in both (apart in contacts mode a distance is
            # only the first separating plane's bound, which a kernel may tighten)
            pen = (ro[:, 0] < 0.0) & (oo[:, 0] < 0.0)
            lower = (ro[pen, 0] - oo[pen, 0]) / scale[pen]
            # normals where they are defined: apart in contacts mode (a finite cutoff) a
            # normal is any separating direction, which a kernel may tighten too
            far = (np.abs(ro[:, 0]) > 1e-3 * scale) & (np.abs(oo[:, 0]) > 1e-3 * scale)
            if np.isfinite(args.cutoff):
                far &= pen
            ang = 2.0 * np.arcsin(np.minimum(1.0, 0.5 * np.linalg.norm(
                oo[far, 1:4] - ro[far, 1:4], axis=1)))
            line = (f"{row:20s} n {n}: status same {np.mean(rs == os_) * 100:6.2f}%, "
                    f"penetrating {pen.sum()}: distance lower by <= "
                    f"{max(lower.max(initial=0.0), 0.0):.1e} * scale, higher by <= "
                    f"{max(-lower.min(initial=0.0), 0.0):.1e}, normal <= "
                    f"{(ang.max() if ang.size else 0.0):.1e} rad")
            if not np.isfinite(args.cutoff):
                # exact distances (cutoff inf): the pairs apart in both compare too
                apart = (ro[:, 0] > 0.0) & (oo[:, 0] > 0.0)
                diff = np.abs(ro[apart, 0] - oo[apart, 0]) / scale[apart]
                line += (f", apart {apart.sum()}: distance within "
                         f"{diff.max(initial=0.0):.1e} * scale")
            if timed:
                if args.subset == "deep":
                    sel = np.flatnonzero(ro[:, 0] < -1e-3 * scale)
                elif args.subset == "apart":
                    gap = np.linalg.norm(tr, axis=1) - scale
                    sel = np.flatnonzero((rs == ST_SEPARATED) & (gap <= 0.0))
                else:
                    sel = np.arange(n)
                ts = {name: [] for name in runs}
                for _ in range(args.rounds):
                    for name, (run, ws) in runs.items():
                        o, s = np.zeros((len(sel), OUT_SIZE)), np.zeros(len(sel), np.int64)
                        t0 = time.perf_counter()
                        run(table.codes, table.params, table.vrange, table.verts, pairs[sel],
                            rot[sel], tr[sel], o, s, ws, args.cutoff, 3)
                        ts[name].append((time.perf_counter() - t0) / 3 / len(sel))
                tr_, to_ = np.median(ts["rev"]), np.median(ts["ours"])
                line += (f"; {args.subset} pairs {len(sel)}: rev {tr_ * 1e6:.3f} us "
                         f"({ro[sel, OUT_ITERS].mean():.1f} steps), ours {to_ * 1e6:.3f} us "
                         f"({oo[sel, OUT_ITERS].mean():.1f}), ours/rev {to_ / tr_:.3f} "
                         f"(round ratios "
                         f"{min(np.divide(ts['ours'], ts['rev'])):.3f}-"
                         f"{max(np.divide(ts['ours'], ts['rev'])):.3f}; of the "
                         f"fastest rounds {min(ts['ours']) / min(ts['rev']):.3f})")
            if pen.any() and lower.max() > 1e-8:
                k = np.flatnonzero(pen)[np.argmax(lower)]
                ia, ib = 2 * k, 2 * k + 1
                line += (f"\n    worst pair {k}: rev distance {ro[k, 0]:.9g} normal "
                         f"{np.round(ro[k, 1:4], 6)}, ours {oo[k, 0]:.9g} normal "
                         f"{np.round(oo[k, 1:4], 6)}; A {shapes[ia]} at {pos[ia].tolist()} "
                         f"{quat[ia].tolist()}, B {shapes[ib]} at {pos[ib].tolist()} "
                         f"{quat[ib].tolist()}")
            print(line, flush=True)


if __name__ == "__main__":
    main()
