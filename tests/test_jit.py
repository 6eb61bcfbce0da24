"""The numba policy module (kernels/jit.py): the collector thresholds while compiling."""
import gc

import numba
from numba.core import event

from mkcollision_ros.kernels import jit


class _Seen(event.Listener):
    def __init__(self):
        self.at_start = []

    def on_start(self, ev):
        self.at_start.append(gc.get_threshold())

    def on_end(self, ev):
        pass


def test_collector_thresholds_raised_while_compiling_and_restored():
    before = gc.get_threshold()
    seen = _Seen()
    # registered after the package's listener, so it sees the thresholds that one set
    event.register("numba:compile", seen)
    try:
        @numba.njit(cache=False)
        def twice(x):
            return 2.0 * x

        assert twice(1.5) == 3.0
    finally:
        event.unregister("numba:compile", seen)
    assert seen.at_start and all(t == jit.COMPILE_GC_THRESHOLDS for t in seen.at_start)
    assert gc.get_threshold() == before != jit.COMPILE_GC_THRESHOLDS


_PROBE = """
import numpy as np
from mkcollision_ros.kernels import narrowphase
from mkcollision_ros.kernels.constants import OUT_SIZE
out = np.zeros(OUT_SIZE)
narrowphase._blank(out, np.int64(3))
s = narrowphase._blank.stats
print(narrowphase.__file__, sum(s.cache_hits.values()), sum(s.cache_misses.values()),
      out[-1])
"""


def test_two_copies_of_the_package_share_one_cache(tmp_path):
    """Two clones (here: two copies of the package at different paths) load each other's
    compiled kernels (jit.SharedCacheLocator); a third copy with one kernel file changed
    gets a cache folder of its own."""
    import os
    import shutil
    import subprocess
    import sys

    src = os.path.dirname(os.path.dirname(jit.__file__))
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "NUMBA_CACHE_LOCATOR_CLASSES")}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")

    def run(copy):
        dst = tmp_path / copy
        if not dst.exists():
            shutil.copytree(src, dst / "mkcollision_ros",
                            ignore=shutil.ignore_patterns("__pycache__"))
        env["PYTHONPATH"] = str(dst)
        out = subprocess.run([sys.executable, "-c", _PROBE], env=env, cwd=dst,
                             capture_output=True, text=True, check=True).stdout.split()
        assert out[0].startswith(str(dst)), out
        return int(out[1]), int(out[2]), float(out[3])

    assert run("a") == (0, 1, 3.0)      # compiled and saved
    assert run("b") == (1, 0, 3.0)      # loaded: the other copy's kernel
    changed = tmp_path / "c" / "mkcollision_ros"
    shutil.copytree(src, changed, ignore=shutil.ignore_patterns("__pycache__"))
    with open(changed / "kernels" / "constants.py", "a") as f:
        f.write("\n# a change\n")
    assert run("c") == (0, 1, 3.0)      # a fresh folder: compiled again
    assert len(os.listdir(tmp_path / "cache" / "mkcollision_ros")) == 2



def test_cache_folder_covers_sub_packages_and_files_them_apart():
    """The cache folder's hash covers every kernel source, kernels/pairs/ included (an
    edit there must not reuse a stale cache), and SharedCacheLocator files each source
    folder under its own path inside the package's parent."""
    import os

    here = os.path.dirname(jit.__file__)
    rels = jit._kernel_sources(here)
    assert rels == sorted(rels)
    assert "gjk_epa.py" in rels and "pairs/ellipsoid_box.py" in rels
    sub = jit.SharedCacheLocator.get_suitable_cache_subpath
    assert sub(os.path.join(here, "gjk.py")) == os.path.join("mkcollision_ros", "kernels")
    assert sub(os.path.join(here, "pairs", "box_box.py")) == os.path.join(
        "mkcollision_ros", "kernels", "pairs")

# nested njit_inline helpers (the inlining test and numba_speedups' tests)
_NESTED_KERNEL = '''
import numpy as np
from mkcollision_ros.kernels import jit


@jit.njit_inline
def inner(x, k):
    y = 0.0
    for i in range(k):
        y = y * x + i if y < 10.0 else y - x
    return y


@jit.njit_inline
def middle(v):
    s = 0.0
    for j in range(v.shape[0]):
        s += inner(v[j], 3) - inner(v[j] + 1.0, 2)
        if s > 5.0:
            s = np.sqrt(s) + v.sum()
    return s


def outer(v):
    a = middle(v)
    b = middle(v[1:]) if v.shape[0] > 1 else 0.0
    c = 0.0
    for k in range(4):
        c = c + inner(a, k) if c < 3.0 else c * 0.5
    return a * b + c


kernel = __import__("numba").njit(cache=False)(outer)
'''

_NESTED = _NESTED_KERNEL + '''
import json
value = kernel(np.arange(4.0))
llvm = "\\n".join(kernel.inspect_llvm().values())
inner, middle = inner.py_func, middle.py_func       # the helpers as plain Python
print(json.dumps({"value": value, "python": outer(np.arange(4.0)), "llvm": llvm}))
'''


def test_njit_inline_helpers_leave_no_call_and_no_copy_in_their_caller(tmp_path):
    """jit.py, "Inlining": LLVM puts nested njit_inline helpers into the optimised
    caller, which neither calls nor defines them, and computes what Python does."""
    import json
    import os
    import re
    import subprocess
    import sys

    script = tmp_path / "nested.py"
    script.write_text(_NESTED)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))  # not the kernels' cache
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         env=env, check=True).stdout
    run = json.loads(out.strip().splitlines()[-1])
    expected = run["python"]
    assert abs(run["value"] - expected) <= 1e-12 * max(1.0, abs(expected))
    llvm = run["llvm"]
    assert re.search(r"^define .*@\S*5outer", llvm, re.M)
    helpers = re.compile(r"@\S*(5inner|6middle)")
    assert not [line for line in llvm.splitlines()
                if helpers.search(line) and ("call" in line or line.startswith("define"))]


def _compiled_kernel_calls_with_constants():
    """(file, line, kernel, argument) for every call of a kernel (njit_kernel,
    njit_separate, njit_parallel, njit_inline) inside kernels/ whose argument is an
    integer or boolean constant: numba types such an argument as a literal and compiles
    the callee once per value (jit.py, "Literal")."""
    import ast
    import pathlib
    root = pathlib.Path(jit.__file__).parent
    trees = {p: ast.parse(p.read_text()) for p in sorted(root.rglob("*.py"))}
    compiled = {n.name for t in trees.values() for n in ast.walk(t)
                if isinstance(n, ast.FunctionDef) and n.decorator_list
                and ast.unparse(n.decorator_list[0])
                in ("njit_kernel", "njit_separate", "njit_parallel", "njit_inline")}
    found = []
    for path, tree in trees.items():
        # calls from compiled code only (a call from Python passes a plain int64)
        jitted = [f for f in ast.walk(tree) if isinstance(f, ast.FunctionDef)
                  and f.decorator_list
                  and ast.unparse(f.decorator_list[0]).startswith("njit_")]
        for n in (c for f in jitted for c in ast.walk(f)):
            if not isinstance(n, ast.Call):
                continue
            name = getattr(n.func, "id", None) or getattr(n.func, "attr", None)
            if name not in compiled:
                continue
            for a in n.args + [k.value for k in n.keywords]:
                v = a.operand if isinstance(a, ast.UnaryOp) else a
                if isinstance(v, ast.Constant) and isinstance(v.value, (bool, int)):
                    found.append((path.relative_to(root).as_posix(), n.lineno, name,
                                  ast.unparse(a)))
    return found


def test_no_compiled_kernel_is_called_with_a_literal_constant():
    assert _compiled_kernel_calls_with_constants() == [], \
        "write the constant as np.int64(c) or np.bool_(c) (kernels/jit.py, 'Literal')"


def test_run_blocks_covers_every_item_once_on_the_thread_count_asked_for():
    import threading
    seen, threads = [], set()

    def kernel(tag, lo, hi):
        assert tag == "t"
        seen.append((lo, hi))
        threads.add(threading.get_ident())

    old = numba.get_num_threads()
    try:
        for n_threads, n_items, min_block, blocks in ((1, 1000, 10, 1), (2, 1000, 10, 2),
                                                      (2, 10, 10, 1), (2, 0, 10, 1)):
            numba.set_num_threads(n_threads)
            seen.clear()
            threads.clear()
            jit.run_blocks(kernel, ("t",), n_items, min_block)
            assert len(seen) == blocks
            covered = sorted(seen)
            assert covered[0][0] == 0 and covered[-1][1] == n_items
            assert all(a[1] == b[0] for a, b in zip(covered, covered[1:]))
            assert max(hi - lo for lo, hi in covered) - min(hi - lo for lo, hi in covered) <= 1
            assert len(threads) == blocks      # the first block on this thread, one more
    finally:
        numba.set_num_threads(old)


def test_run_blocks_raises_a_failing_block_after_every_block_ends():
    done = []

    def kernel(lo, hi):
        if lo > 0:
            raise ValueError("block failed")
        done.append(lo)

    old = numba.get_num_threads()
    try:
        numba.set_num_threads(2)
        try:
            jit.run_blocks(kernel, (), 100, 10)
        except ValueError as e:
            assert "block failed" in str(e)
        else:
            raise AssertionError("the failing block's error was not raised")
        assert done == [0]
    finally:
        numba.set_num_threads(old)


_SEPARATE_MODULE = '''
import numpy as np
from mkcollision_ros.kernels import jit


@jit.njit_separate
def big(a, x):
    s = 0.0
    for i in range(a.shape[0]):
        s += np.sin(a[i] * x)
    return s


@jit.njit_kernel
def mid(a, x):
    return big(a, x) + 1.0


@jit.njit_kernel
def top(a):
    t = 0.0
    for k in range(3):
        t += mid(a, float(k))
    return t
'''

_SEPARATE_RUN = '''
import json, sys
import numpy as np
from mkcollision_ros.kernels import jit
import sepkern

value = sepkern.top(np.arange(5.0))
sig = sepkern.top.signatures[0]
info = {"installed": jit.SEPARATE_LINKING, "value": value,
        "top_hits": sum(sepkern.top.stats.cache_hits.values()),
        "big_loaded": len(sepkern.big.signatures)}
if not info["top_hits"]:
    symbol = sepkern.big.overloads[sepkern.big.signatures[0]].fndesc.mangled_name
    llvm = {k.__name__: k.inspect_llvm(k.signatures[0]) for k in (sepkern.mid, sepkern.top)}
    info["defines"] = {n: ("define" in t and any(symbol in line for line in t.splitlines()
                                                  if line.startswith("define")))
                       for n, t in llvm.items()}
    info["declares"] = {n: any(symbol in line for line in t.splitlines()
                               if line.startswith("declare")) for n, t in llvm.items()}
print(json.dumps(info))
'''


def _run_separate(tmp_path, cache, link_all=False):
    import json
    import os
    import subprocess
    import sys
    (tmp_path / "sepkern.py").write_text(_SEPARATE_MODULE)
    (tmp_path / "run.py").write_text(_SEPARATE_RUN)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache),
               MKCOLLISION_LINK_ALL="1" if link_all else "0",
               PYTHONPATH=str(tmp_path) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, str(tmp_path / "run.py")], env=env,
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_a_separate_kernel_is_called_by_its_callers_and_loaded_before_them(tmp_path):
    """jit.njit_separate: callers declare the separate kernel's symbol instead of
    defining a linked copy of it (with MKCOLLISION_LINK_ALL=1 they link the copy); a
    caller loaded from numba's cache loads the separate kernel first; with the separate
    kernel's cache entries gone, the caller is compiled again instead of calling a
    symbol that no longer exists, and every run gives the same value.  (A linked copy
    LLVM inlines everywhere is dropped, so the linked callers neither define nor
    declare it.)"""
    import numpy as np
    expected = sum(np.sin(np.arange(5.0) * k).sum() + 1.0 for k in range(3))
    cache = tmp_path / "cache"
    first = _run_separate(tmp_path, cache)
    assert first["installed"] is True
    assert first["top_hits"] == 0
    assert first["declares"] == {"mid": True, "top": True}
    assert first["defines"] == {"mid": False, "top": False}
    cached = _run_separate(tmp_path, cache)
    assert cached["top_hits"] == 1 and cached["big_loaded"] == 1
    for path in cache.rglob("sepkern.big*"):
        path.unlink()
    recompiled = _run_separate(tmp_path, cache)
    assert recompiled["top_hits"] == 0
    linked = _run_separate(tmp_path, tmp_path / "linked_cache", link_all=True)
    assert linked["installed"] is False
    assert linked["declares"] == {"mid": False, "top": False}
    for run in (first, cached, recompiled, linked):
        assert abs(run["value"] - expected) < 1e-12


_SPEEDUP_KERNEL = _NESTED_KERNEL + '''
import json
from mkcollision_ros.kernels import numba_speedups
value = kernel(np.arange(4.0))
llvm = "\\n".join(kernel.inspect_llvm().values())
print(json.dumps({"on": [numba_speedups.SSA_WHERE_NAMED, numba_speedups.QUICK_FLAG_COMPARISONS],
                  "value": value, "llvm": llvm}))
'''


def _speedup_run(tmp_path, plain):
    import json
    import os
    import subprocess
    import sys
    script = tmp_path / "speedups.py"
    script.write_text(_SPEEDUP_KERNEL)
    # a cache of each run's own, apart from the kernels' cache
    env = dict(os.environ, MKCOLLISION_PLAIN_NUMBA=plain,
               NUMBA_CACHE_DIR=str(tmp_path / f"cache-{plain}"))
    out = subprocess.run([sys.executable, str(script)], env=env, capture_output=True,
                         text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_the_compile_speedups_change_how_numba_compiles_not_what(tmp_path):
    """kernels/numba_speedups: with the SSA and flag measures the LLVM IR is the same
    text as numba's own and the value is the same; each measure is installed only when
    asked for."""
    plain = _speedup_run(tmp_path, "1")
    ssa_only = _speedup_run(tmp_path, "flags")
    every = _speedup_run(tmp_path, "0")
    assert plain["on"] == [False, False]
    assert ssa_only["on"] == [True, False]
    assert every["on"] == [True, True]
    assert len(plain["llvm"]) > 5000 and "define" in plain["llvm"]
    assert every["llvm"] == plain["llvm"] == ssa_only["llvm"]
    assert plain["value"] == ssa_only["value"] == every["value"]


def test_the_ssa_measure_renames_as_numba_does():
    """numba_speedups' SSA over the blocks that name a variable gives the same blocks,
    statement for statement, as numba's own pass on a function whose variables are
    assigned in several blocks."""
    import numba
    from numba.core import compiler, ssa
    from mkcollision_ros.kernels import numba_speedups

    def f(n, x):
        s = 0.0
        t = 1.0
        for i in range(n):
            if x > i:
                s = s + x
                t = t * 0.5
            else:
                s = s - 1.0
            if s > 3.0:
                t = s
        return s + t

    def blocks_text(run):
        func_ir = compiler.run_frontend(f)
        blocks = run(func_ir.blocks)
        return "\n".join(f"{label}: {stmt}" for label in sorted(blocks)
                         for stmt in blocks[label].body)

    assert numba_speedups.SSA_WHERE_NAMED
    plain = numba_speedups._PLAIN_SSA_RUN
    assert blocks_text(ssa._run_ssa) == blocks_text(plain)
    assert "phi" in blocks_text(ssa._run_ssa)
    assert numba.__version__ == "0.68.1"
