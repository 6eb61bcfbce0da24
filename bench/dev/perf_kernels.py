"""Where a row's narrow-phase time goes, kernel by kernel: ``perf record`` on the batch
kernel (contacts mode, one thread), samples mapped to numba's compiled functions.

numba's JIT code carries no symbols perf can read, so the samples are mapped by hand:
the batch loop ``narrowphase._collide_block`` is loaded from numba's on-disk cache,
whose ``.nbc`` file holds the ELF object code with every compiled function's offset and
size.  The child process reports the run-time address of ``_collide_block``'s entry;
its offset in the object gives the load base, and each sample's address minus the base
falls in one function of the object (inlined helpers count as their caller).  Needs
``perf`` (linux-tools) and a kernel that lets a user record (perf_event_paranoid <= 2).

    PYTHONPATH=. .venv/bin/python bench/dev/perf_kernels.py cylinder-cylinder [--seconds 20]
        [--subset all|epa] [--n 2000] [--calls]

``--subset epa``: only the pairs that reach GJK (iterations > 1).  ``--calls``: also
count, per function, the call sites of numba's reference-count helpers (NRT_incref,
NRT_decref): a called kernel that does not re-borrow its array arguments
(geometry.borrow_args) keeps them, and each call spills the live registers.
"""
import argparse
import bisect
import collections
import os
import re
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

CHILD = r"""
import sys, time
import numba, numpy as np
from bench.common import pair_cases
from bench.vs_mujoco import row_seed
from mkcollision_ros.kernels import narrowphase as NP
from mkcollision_ros.kernels.constants import M_AUTO, OUT_ITERS, OUT_SIZE
numba.set_num_threads(1)
row, n, subset, seconds, anchor_path = sys.argv[1:6]
a, b = row.split("-")
shapes, table, pairs, pos, quat = pair_cases(a, b, int(n), seed=row_seed(a, b))
def run(sel):
    out = np.zeros((len(sel), OUT_SIZE))
    st = np.zeros(len(sel), np.int64)
    NP.collide_batch(table.codes, table.params, table.vrange, table.verts, sel, pos, quat,
                     M_AUTO, 0.0, out, st)
    return out
out = run(pairs)
sel = pairs[out[:, OUT_ITERS] > 1] if subset == "epa" else pairs
cres = NP._collide_block.overloads[NP._collide_block.signatures[0]]
name = cres.fndesc.llvm_func_name
with open(anchor_path, "w") as f:
    f.write(f"{name} {cres.library.get_pointer_to_function(name):x} {len(sel)}\n")
t0 = time.perf_counter()
while time.perf_counter() - t0 < float(seconds):
    run(sel)
"""


def object_code():
    """The ELF object of _collide_block's cache entry (bytes): the file numba's index
    for it names (the newest of them if it names several), in this checkout's cache
    folder (numba names that folder after the source folder and a hash of its path)."""
    from mkcollision_ros.kernels import narrowphase
    cache = narrowphase._collide_block._cache
    names = list(cache._cache_file._load_index().values())
    if not names:
        sys.exit(f"no cached _collide_block in {cache._cache_path}: run the row once first")
    files = [os.path.join(cache._cache_path, name) for name in names]
    raw = open(max(files, key=os.path.getmtime), "rb").read()
    elf = raw[raw.find(b"\x7fELF"):]
    shoff = struct.unpack_from("<Q", elf, 0x28)[0]
    shentsize, shnum = struct.unpack_from("<HH", elf, 0x3A)
    return elf[:shoff + shentsize * shnum]


def short(symbol):
    """module.function of a numba-mangled symbol (the symbol itself otherwise)."""
    m = re.match(r"_ZN15mkcollision_ros7kernels(\d+)", symbol)
    if not m:
        return symbol[:60]
    rest = symbol[m.end():]
    mod, rest = rest[:int(m.group(1))], rest[int(m.group(1)):]
    k = re.match(r"\d+", rest)
    return f"{mod}.{rest[k.end():k.end() + int(k.group(0))]}"


def functions(obj_path):
    """[(offset, size, name)] of the object's defined code symbols, by offset."""
    text = subprocess.run(["nm", "-S", "--defined-only", obj_path], capture_output=True,
                          text=True, check=True).stdout
    ents = []
    for line in text.splitlines():
        p = line.split()
        if len(p) == 4 and p[2] in "tTW":
            ents.append((int(p[0], 16), int(p[1], 16), p[3]))
    return sorted(ents)


def nrt_sites(obj_path):
    """{function: call sites of NRT_incref / NRT_decref} from the disassembly."""
    text = subprocess.run(["objdump", "-dr", "--no-show-raw-insn", obj_path],
                          capture_output=True, text=True, check=True).stdout
    sites = collections.Counter()
    cur, regs, last = None, {}, None
    for line in text.splitlines():
        m = re.match(r"^[0-9a-f]+ <(.*)>:", line)
        if m:
            cur, regs = short(m.group(1)), {}
            continue
        m = re.search(r"movabs \$0x0,%(\w+)", line)
        if m:
            last = m.group(1)
            continue
        m = re.search(r"R_X86_64_64\s+(\S+)", line)
        if m and last:
            regs[last], last = m.group(1), None
            continue
        m = re.search(r"\tcall\s+\*%(\w+)", line)
        if m and regs.get(m.group(1), "").startswith("NRT_"):
            sites[cur] += 1
    return sites


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("row")
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--subset", choices=("all", "epa"), default="all")
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--top", type=int, default=20)
    ap.add_argument("--calls", action="store_true")
    args = ap.parse_args()
    sys.path.insert(0, ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        anchor, data = os.path.join(tmp, "anchor"), os.path.join(tmp, "perf.data")
        env = dict(os.environ, PYTHONPATH=ROOT, NUMBA_NUM_THREADS="1")
        subprocess.run(["perf", "record", "-q", "-o", data, sys.executable, "-c", CHILD,
                        args.row, str(args.n), args.subset, str(args.seconds), anchor],
                       cwd=ROOT, env=env, check=True)
        name, addr, n_sel = open(anchor).read().split()
        obj_path = os.path.join(tmp, "kernels.o")
        with open(obj_path, "wb") as f:
            f.write(object_code())
        ents = functions(obj_path)
        base = int(addr, 16) - next(o for o, _, s in ents if s == name)
        starts = [e[0] for e in ents]
        ips = subprocess.run(["perf", "script", "-i", data, "-F", "ip,dso"],
                             capture_output=True, text=True).stdout
        counts, total, jitted = collections.Counter(), 0, 0
        for line in ips.splitlines():
            p = line.split()
            if not p:
                continue
            total += 1
            if "perf-" not in line:      # JIT code: perf names it after its missing map
                continue
            jitted += 1
            ip = int(p[0], 16) - base
            i = bisect.bisect_right(starts, ip) - 1
            inside = i >= 0 and ip < ents[i][0] + ents[i][1]
            counts[short(ents[i][2]) if inside else "(other JIT code: numba's NRT, ...)"] += 1
        sites = nrt_sites(obj_path) if args.calls else {}
    print(f"## {args.row}, contacts mode, {args.subset} pairs ({n_sel}), "
          f"{args.seconds:g} s: {jitted} of {total} samples in compiled code\n")
    print("| share of compiled code | function (inlined helpers count as their caller) |"
          + (" NRT call sites |" if args.calls else ""))
    print("|---|---|" + ("---|" if args.calls else ""))
    for fn, c in counts.most_common(args.top):
        extra = f" {sites.get(fn, 0)} |" if args.calls else ""
        print(f"| {c / max(jitted, 1):.1%} | {fn} |{extra}")


if __name__ == "__main__":
    main()
