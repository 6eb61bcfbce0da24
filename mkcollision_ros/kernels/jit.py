"""The one numba decorator policy of the project.

Every kernel is compiled with ``njit_kernel``: nopython mode, on-disk cache (so a second
start of the node does not compile again), and ``fastmath`` off, because the narrow
phase relies on exact IEEE comparisons (NaN checks, signed zeros, strict ``<``).
``njit_parallel`` is the same policy with ``parallel=True`` for batch loops that write
into fixed, preallocated slots (results do not depend on the thread count, since every
thread runs the same compiled code).  Note that fastmath off does not forbid LLVM from
fusing multiply-adds on CPUs with FMA, so two *different* compiled copies of the same
arithmetic may differ in the last bits; the project never mixes copies in one result.

Hot paths: numba passes every array to a called function with an atomic increment and
decrement of its reference count, and on this machine those atomics were 60% of a
closed-form pair's time (perf: ``lock incq`` in NRT_incref).  Two tools remove them:
``borrow(a)`` gives a view of ``a`` without an owner (null meminfo, so numba's refcount
calls return at once), used by the batch kernels on their arguments and scratch
buffers; the owner must outlive the view, which ``keep_alive(owner)`` after the last use
guarantees (numba frees a variable after its last use).  A borrowed array must never
be returned to Python.  ``njit_inline`` (numba-IR inlining) is the policy of small
helpers called once per support point or per pair, and of the per-pair dispatch
inside the batch loop (narrowphase.collide_world_ws down to the closed-form switch);
it makes the first compile longer and is kept to those.

Cache location: numba's own cache notices when a kernel's file changes but not when a
kernel it calls, in another file, changes — a stale cache would then run old code.  So
the cache lives in a folder named after a hash of every kernel source file:
``$XDG_CACHE_HOME/mkcollision_ros/numba-<hash>`` (default ``~/.cache``).  Any edit gives
a fresh folder; an unchanged install reuses its compiled kernels.  Setting
``NUMBA_CACHE_DIR`` overrides this.

First compile: numba's inliner deep-copies a callee's IR at every call site of an
``njit_inline`` function (and again for each level of nesting), millions of short-lived
Python objects, and Python's cyclic garbage collector ran its young-generation passes
over them every 700 allocations.  While numba compiles, a listener on numba's
``numba:compile`` event (numba's documented event API) raises the first threshold to
100,000 and gen1's to 20, and puts the old thresholds back when the outermost compile
ends; any compile in the process gets it (the node's warm-up, the first call of
``collide``, the tests).  Measured on the first ``collide_batch`` call in an empty cache
(BENCHMARKS.md, session 30): 382 s (with a pure-Python test run beside it) -> 265 s
(nothing beside it), peak memory the same (1.7 GB); with the collector off altogether
245 s but 5.4 GB; ``mpr_ws`` compiled alone, 40 -> 28 s with the collector off.

"Literal": an integer constant passed to a compiled (not inlined) kernel is typed
``Literal[int](c)``, and so is a loop variable before numba's type propagation has
seen its later values (``k = 0`` ahead of ``k = axis`` in a loop).  numba then compiles
the callee once for the literal and once more for int64, identical code, one wasted
compile each.  Such a constant or first value is written ``np.int64(c)``, typed int64
at once.  Session 31 found eight kernels compiled twice (``_set_out``, ``_face_test``,
``_hull_face_test``, ``_crossing_test``, ``_epa_polish``, ``_newton_min_support``,
``_blank``, ``_has_closed_form``) and ``ellipsoid._write_back`` compiled for two
literals; ``bench/compile_time.py`` counts each kernel's compiles (a test cannot see
them: a cached kernel never compiles the kernels it calls).
"""
import gc
import hashlib
import os

import numba
from numba.core import cgutils, event, types
from numba.extending import intrinsic


def _kernel_cache_dir():
    here = os.path.dirname(os.path.abspath(__file__))
    digest = hashlib.sha256(numba.__version__.encode())
    for name in sorted(os.listdir(here)):
        if name.endswith(".py"):
            with open(os.path.join(here, name), "rb") as f:
                digest.update(name.encode() + b"\0" + f.read())
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "mkcollision_ros", f"numba-{digest.hexdigest()[:16]}")


if not os.environ.get("NUMBA_CACHE_DIR"):
    numba.config.CACHE_DIR = _kernel_cache_dir()

COMPILE_GC_THRESHOLDS = (100_000, 20, 10)


class _FewerGcPassesWhileCompiling(event.Listener):
    """Python's collector thresholds raised to COMPILE_GC_THRESHOLDS from the start of
    the outermost numba compile to its end (nested compiles of called kernels run
    inside it; numba holds its compiler lock throughout, so one thread at a time)."""

    def __init__(self):
        self._depth = 0
        self._saved = gc.get_threshold()

    def on_start(self, ev):
        if self._depth == 0:
            self._saved = gc.get_threshold()
            gc.set_threshold(*COMPILE_GC_THRESHOLDS)
        self._depth += 1

    def on_end(self, ev):
        self._depth -= 1
        if self._depth == 0:
            gc.set_threshold(*self._saved)


if not numba.config.DISABLE_JIT:
    event.register("numba:compile", _FewerGcPassesWhileCompiling())

njit_kernel = numba.njit(cache=True, fastmath=False, nogil=True, error_model="numpy")
njit_parallel = numba.njit(cache=True, fastmath=False, nogil=True, parallel=True,
                           error_model="numpy")
njit_inline = numba.njit(cache=True, fastmath=False, nogil=True, error_model="numpy",
                         inline="always")
prange = numba.prange


def n_blocks(n_items, min_block):
    """How many blocks a parallel batch kernel should split ``n_items`` into (plain
    Python, for the kernel's caller: numba cannot cache a kernel that asks for the
    thread count itself): one per thread (numba's static schedule gives each thread
    one), fewer when blocks would hold less than ``min_block`` items, at least 1."""
    nb = min(numba.get_num_threads(), (n_items + min_block - 1) // min_block)
    return max(nb, 1)


@njit_inline
def block_bounds(n_items, nb, b):
    """Items [lo, hi) of block ``b`` of ``nb`` (contiguous, sizes differing by <= 1)."""
    return b * n_items // nb, (b + 1) * n_items // nb


@intrinsic
def borrow(typingctx, arr):
    """The same array without an owner (null meminfo and parent): numba then skips the
    atomic reference counting whenever it is passed on.  The caller keeps the owner
    alive for as long as the view is used (``keep_alive``) and never returns it."""
    if not isinstance(arr, types.Array):
        return None

    def codegen(context, builder, signature, args):
        src = context.make_array(arr)(context, builder, value=args[0])
        dst = context.make_array(arr)(context, builder)
        dst.meminfo = cgutils.get_null_value(dst.meminfo.type)
        dst.parent = cgutils.get_null_value(dst.parent.type)
        dst.nitems = src.nitems
        dst.itemsize = src.itemsize
        dst.data = src.data
        dst.shape = src.shape
        dst.strides = src.strides
        return dst._getvalue()

    return arr(arr), codegen


@intrinsic
def keep_alive(typingctx, obj):
    """A use of ``obj`` that emits no code: its owner lives at least until here."""
    def codegen(context, builder, signature, args):
        return context.get_dummy_value()

    return types.none(obj), codegen


if numba.config.DISABLE_JIT:
    # pure-Python runs (NUMBA_DISABLE_JIT=1, for debugging): plain objects, no owners
    def borrow(arr):  # noqa: F811 - the interpreted stand-in of the intrinsic above
        return arr

    def keep_alive(obj):  # noqa: F811
        return None
