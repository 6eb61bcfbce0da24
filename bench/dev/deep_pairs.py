"""GJK/EPA (or MPR) alone on the deep pairs of fixed seeded cases: time per pair, results
against a saved reference, and where the time goes under ``perf``.

Why a separate harness: bench/narrowphase.py times whole rows (half of the pairs are
apart) and places its cases by bisection with our own kernel, so a kernel edit moves
the cases themselves.  Here the cases are generated once and kept (``--cases``, one
pickle per row), the deep pairs (depth > 1e-3 * scale in the reference run) are timed
through ``gjk_epa_ws`` / ``mpr_ws`` with borrowed arrays, as the batch kernel calls
them (owned arrays there cost ~1.3 us more per deep pair in reference counting), and a
later run compares depth, normal and status with the reference.

    PYTHONPATH=. .venv/bin/python bench/dev/deep_pairs.py --save [ROW ...]   # reference
    PYTHONPATH=. .venv/bin/python bench/dev/deep_pairs.py [ROW ...]          # compare
    ... [--mpr] [--cases DIR]                                            # MPR instead
    ... --apart      # the apart pairs whose bounding spheres overlap, not the deep ones

Profile (numba keeps the object code only of what it compiles in the process, so the
kernel cache must start empty; ``perf`` is a system tool, not a dependency):

    XDG_CACHE_HOME=$(mktemp -d) PYTHONPATH=. perf record -o /tmp/perf.data \\
        .venv/bin/python bench/dev/deep_pairs.py --profile 8 cylinder-cylinder
    perf script -i /tmp/perf.data -F ip > /tmp/ips.txt
    PYTHONPATH=. .venv/bin/python bench/dev/deep_pairs.py --report /tmp/ips.txt

``--profile S`` loops the timed call for S seconds and writes the map of every compiled
function (address, object file, offset, symbol) next to the cases; ``--report`` counts
the samples per function and per 256-byte block of the hottest function (annotate with
``objdump -d`` on the object file it names).
"""
import argparse
import bisect
import collections
import os
import pickle
import subprocess
import sys
import time

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

from bench.common import KINDS, pair_cases, relative_poses  # noqa: E402
from mkcollision_ros.kernels import gjk_epa as G  # noqa: E402
from mkcollision_ros.kernels import mpr as MP  # noqa: E402
from mkcollision_ros.kernels.constants import OUT_ITERS, OUT_SIZE, ST_SEPARATED  # noqa: E402
from mkcollision_ros.kernels.jit import borrow  # noqa: E402

ROWS = ("cylinder-cylinder", "box-cylinder", "ellipsoid-cylinder", "capsule-cylinder",
        "cylinder-convex", "cone-cone", "box-convex", "convex-convex", "ellipsoid-box",
        "ellipsoid-ellipsoid")
N = 2000


@numba.njit(cache=False)
def _run(codes, params, vrange, verts, pairs, rot, tr, out, st, ws0, mbuf, use_mpr, reps):
    codes, params, vrange, verts = borrow(codes), borrow(params), borrow(vrange), borrow(verts)
    pairs, rot, tr, out, st = borrow(pairs), borrow(rot), borrow(tr), borrow(out), borrow(st)
    ws = (borrow(ws0[0]), borrow(ws0[1]), borrow(ws0[2]))
    mbuf = borrow(mbuf)
    for _ in range(reps):
        for k in range(pairs.shape[0]):
            i, j = pairs[k, 0], pairs[k, 1]
            sa = (codes[i], params[i], vrange[i, 0], vrange[i, 1])
            sb = (codes[j], params[j], vrange[j, 0], vrange[j, 1])
            if use_mpr:
                st[k] = MP.mpr_ws(sa, sb, verts, rot[k], tr[k], out[k], mbuf)
            else:
                st[k] = G.gjk_epa_ws(sa, sb, verts, rot[k], tr[k], out[k], ws, 0.0)


def load_cases(folder, row):
    """The row's cases, generated (seeded) on the first call and kept in ``folder``."""
    path = os.path.join(folder, f"cases_{row}.pkl")
    if not os.path.exists(path):
        a, b = row.split("-")
        cases = pair_cases(a, b, N, seed=7 + 101 * KINDS.index(a) + KINDS.index(b))
        with open(path, "wb") as f:
            pickle.dump(cases, f)
    with open(path, "rb") as f:
        return pickle.load(f)


def write_symbols(path):
    """Address, object file, offset and symbol of every function compiled in this
    process under ``_run`` (numba's private CodeLibrary API: object code and linked
    libraries)."""
    folder = os.path.dirname(path)
    seen, lines = set(), []

    def walk(lib):
        if id(lib) in seen:
            return
        seen.add(id(lib))
        try:
            obj = lib._get_compiled_object()
        except (RuntimeError, ValueError):   # from the cache, or numba's own runtime
            obj = None
        if obj:
            fn = os.path.join(folder, f"lib{len(seen)}.o")
            with open(fn, "wb") as f:
                f.write(obj)
            nm = subprocess.run(["nm", fn], capture_output=True, text=True).stdout
            for s in nm.splitlines():
                p = s.split()
                if len(p) == 3 and p[1] in "tT":
                    lines.append(f"{lib.get_pointer_to_function(p[2]):#x} {fn} {p[0]} {p[2]}")
        for sub in getattr(lib, "_linking_libraries", []):
            walk(sub)

    for cres in _run.overloads.values():
        walk(cres.library)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return len(lines)


def report(ips_path, sym_path):
    syms = sorted((int(a, 16), obj, int(off, 16), name) for a, obj, off, name in
                  (s.split() for s in open(sym_path) if s.strip()))
    starts = [s[0] for s in syms]
    per, blocks = collections.Counter(), collections.defaultdict(collections.Counter)
    for line in open(ips_path):
        a = int(line.strip(), 16)
        i = bisect.bisect_right(starts, a) - 1
        if i < 0 or a - starts[i] > 0x20000:
            continue
        addr, obj, off, name = syms[i]
        per[(name, obj)] += 1
        blocks[(name, obj)][(a - addr + off) // 256 * 256] += 1
    total = sum(per.values())
    print(f"{total} samples in compiled kernels")
    for (name, obj), c in per.most_common(8):
        print(f"{100 * c / total:6.1f}%  {name[:70]}  ({obj})")
    (name, obj), c = per.most_common(1)[0]
    print(f"hottest 256-byte blocks of {name[:60]} (objdump -d {obj}):")
    for off, k in blocks[(name, obj)].most_common(12):
        print(f"  {off:#07x}  {100 * k / c:5.1f}%")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rows", nargs="*", default=ROWS)
    ap.add_argument("--save", action="store_true", help="write the reference results")
    ap.add_argument("--mpr", action="store_true", help="time mpr_ws instead of gjk_epa_ws")
    ap.add_argument("--cases", default="/tmp/mkc_deep_pairs", help="folder of cases and references")
    ap.add_argument("--apart", action="store_true",
                    help="time the apart pairs that pass the bounding-sphere test instead")
    ap.add_argument("--profile", type=float, default=0.0, metavar="S",
                    help="loop the timed call S seconds, then write the symbol map")
    ap.add_argument("--report", metavar="IPS", help="map `perf script -F ip` output")
    args = ap.parse_args()
    os.makedirs(args.cases, exist_ok=True)
    sym_path = os.path.join(args.cases, "symbols.txt")
    if args.report:
        report(args.report, sym_path)
        return
    numba.set_num_threads(1)
    ws = G.make_gjk_workspace()
    mbuf = np.empty((MP.MPR_WS_ROWS, 3))
    tag = "mpr" if args.mpr else "gjk_epa"
    for row in args.rows:
        shapes, table, pairs, pos, quat = load_cases(args.cases, row)
        rot, tr = relative_poses(pos, quat)
        scale = table.params[0::2, 7] + table.params[1::2, 7]
        out, st = np.zeros((N, OUT_SIZE)), np.zeros(N, np.int64)
        _run(table.codes, table.params, table.vrange, table.verts, pairs, rot, tr, out, st,
             ws, mbuf, args.mpr, 1)
        ref_path = os.path.join(args.cases, f"ref_{row}_{tag}.npz")
        if args.save:
            np.savez(ref_path, out=out, st=st)
        ref = np.load(ref_path)
        if args.apart:
            # apart, yet their bounding spheres (P_RADIUS = params[:, 7]) overlap: the
            # pairs the batch kernel hands to GJK, which stops at the first separating
            # support plane (cutoff 0)
            gap = np.linalg.norm(tr, axis=1) - scale
            sel = np.flatnonzero((ref["st"] == ST_SEPARATED) & (gap <= 0.0))
        else:
            sel = np.flatnonzero(ref["out"][:, 0] < -1e-3 * scale)
        dargs = (table.codes, table.params, table.vrange, table.verts, pairs[sel], rot[sel],
                 tr[sel], np.zeros((len(sel), OUT_SIZE)), np.zeros(len(sel), np.int64),
                 ws, mbuf, args.mpr)
        ts = []
        for _ in range(7):
            t0 = time.perf_counter()
            _run(*dargs, 3)
            ts.append((time.perf_counter() - t0) / 3 / len(sel))
        ro = ref["out"]
        ang = 2.0 * np.arcsin(np.minimum(1.0, 0.5 * np.linalg.norm(out[sel, 1:4]
                                                                   - ro[sel, 1:4], axis=1)))
        print(f"{row:20s} {tag} {'apart' if args.apart else 'deep'} pairs {len(sel):4d}: "
              f"{np.median(ts) * 1e6:6.3f} us, "
              f"iterations {dargs[7][:, OUT_ITERS].mean():5.1f}; vs reference: status "
              f"{np.mean(st == ref['st']) * 100:5.1f}% same (all pairs); on these: depth "
              f"max {np.max(np.abs(out[sel, 0] - ro[sel, 0]) / scale[sel]):.1e} * scale, "
              f"normal max {ang.max():.1e} rad", flush=True)
        if args.profile > 0:
            t0 = time.time()
            while time.time() - t0 < args.profile:
                _run(*dargs, 20)
    if args.profile > 0:
        print(f"{write_symbols(sym_path)} symbols -> {sym_path}")


if __name__ == "__main__":
    main()
