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
decrement of its reference count, and those atomics can be 60% of a closed-form
pair's time (perf: ``lock incq`` in NRT_incref).  Two tools remove them:
``borrow(a)`` gives a view of ``a`` without an owner (null meminfo, so numba's refcount
calls return at once), used by the batch kernels on their arguments and scratch
buffers; the owner must outlive the view, which ``keep_alive(owner)`` after the last use
guarantees (numba frees a variable after its last use).  A borrowed array must never
be returned to Python.  ``njit_inline`` is the policy of small helpers called once per
support point or per pair, and of the per-pair dispatch inside the batch loop
(narrowphase.collide_world_ws down to the closed-form switch); see "Inlining".

Inlining: an ``njit_inline`` kernel is typed and lowered by numba once per signature,
like any kernel, and marked ``alwaysinline`` for LLVM (numba's ``forceinline``), whose
inliner then puts its code into every caller that links it.  So the caller runs no call
and no reference counting across it (what numba-IR inlining, ``inline="always"``, would
also give), while numba's Python passes see each helper once instead of once per call
site and nesting level.  The first compile of every kernel takes about a third less
than with numba-IR inlining (bench/startup.py, both on the project's 2-core machine),
with bit-identical results (bench/same_results.py) and the same speed
(bench/vs_mujoco.py).
LLVM still optimises a copy at every site, so a helper's size times its sites stays the
measure of what it costs the first compile.  No kernel has numba's C-callable wrapper
(``no_cfunc_wrapper``: it is for ``cfunc`` and first-class function use, which the
project has none of), one more copy of each kernel's code less to compile.

Cache location: numba's own cache notices when a kernel's file changes but not when a
kernel it calls, in another file, changes — a stale cache would then run old code.  So
the cache lives in a folder named after a hash of every kernel source file (every .py
file under kernels/, sub-packages included, by sorted relative path):
``$XDG_CACHE_HOME/mkcollision_ros/numba-<hash>`` (default ``~/.cache``).  Any edit gives
a fresh folder; an unchanged install reuses its compiled kernels.  Inside it, numba
would file each source folder under a hash of its absolute path, so a second clone, a
worktree or a copied install would compile everything again; ``SharedCacheLocator``
files the package's kernels under the folder's path inside the package's parent alone
(``mkcollision_ros/kernels``, ``mkcollision_ros/kernels/pairs``, ``mkcollision_ros``),
which is safe because the folder's hash covers the sources and
numba's own per-file stamp is a hash of the file's content.  Setting
``NUMBA_CACHE_DIR`` overrides all of this (numba's own layout, per path).

First compile: two measures keep numba's own passes cheap, each active only while numba
compiles and neither changing what is computed:
- Python's cyclic collector: a compile makes millions of short-lived objects, and the
  collector's young-generation passes run every 700 allocations.  A listener on numba's
  ``numba:compile`` event (numba's documented event API) raises the thresholds to
  COMPILE_GC_THRESHOLDS from the start of the outermost compile to its end.
- Two of the same kind, in ``numba_speedups.py`` (imported here): SSA over the blocks
  that name a variable, and flag comparisons without properties.

Separate kernels (``njit_separate``): numba links a copy of every called kernel's code
into its caller's module, then optimises and generates machine code for the whole
module again; so each level of a call chain compiles everything below it once more
(``_collide_batch``, a loop of one call, took 26 s, all of it LLVM redoing
``_collide_block``).  A separate kernel is compiled once, and its callers call its
symbol: while a caller's library is finalised, a linked library that carries a separate
kernel's mark (set on its compile results) is not linked in; numba's declaration of the
callee stays a declaration, and LLVM's JIT resolves it against the kernel's own code,
loaded in the same engine.  A caller's library records what it needs that way (its own
separate callees and those of the libraries it links); the record goes into numba's
cache with the caller's object code, and loading the caller from the cache first loads
(or compiles) each of them, then checks its symbol, the name numba gave that compile,
is the one the caller calls.  When it is not (a callee's cache entry lost, then
compiled afresh) the caller is compiled again instead of being loaded
(``MissingSeparateKernel``).  The mark goes on kernels called at most once a pair: a
call by symbol costs a few ns and cannot be inlined, which a closed form or a support
mapping would feel (their callers keep linked copies).  Applied to numba 0.68.1 only,
whose code libraries it was written against; ``MKCOLLISION_LINK_ALL=1`` links every
kernel as numba does.

"Literal": an integer or boolean constant passed to a kernel (``njit_inline`` ones
too) is typed ``Literal[int](c)`` or ``Literal[bool](c)``, and so is a loop variable
before numba's type propagation has seen its later values (``k = 0`` ahead of ``k =
axis`` in a loop).  numba then compiles the callee once per literal value (and once
more for the plain type where a variable is passed), identical code, one more compile
each.  Such a constant or first value is written ``np.int64(c)`` or ``np.bool_(c)``,
typed int64 or bool at once (``tests/test_jit.py`` finds constant arguments at the call
sites).  ``bench/compile_time.py`` counts each kernel's compiles (a test cannot see
them: a cached kernel never compiles the kernels it calls).
"""
import gc
import hashlib
import importlib
import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numba
from numba.core import caching, cgutils, event, types
from numba.extending import intrinsic

from . import numba_speedups  # noqa: F401 - installs the compile-time measures


def _kernel_sources(here):
    """Every .py file under ``here`` (sub-packages included), as sorted paths relative
    to it with '/' separators."""
    found = []
    for root, dirs, files in os.walk(here):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        for name in files:
            if name.endswith(".py"):
                rel = os.path.relpath(os.path.join(root, name), here)
                found.append(rel.replace(os.sep, "/"))
    return sorted(found)


def _kernel_cache_dir():
    here = os.path.dirname(os.path.abspath(__file__))
    digest = hashlib.sha256(numba.__version__.encode())
    for rel in _kernel_sources(here):
        with open(os.path.join(here, *rel.split("/")), "rb") as f:
            digest.update(rel.encode() + b"\0" + f.read())
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "mkcollision_ros", f"numba-{digest.hexdigest()[:16]}")


_PACKAGE_DIR = os.path.realpath(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class SharedCacheLocator(caching.UserProvidedCacheLocator):
    """numba's locator for ``config.CACHE_DIR``, for this package's files only, with
    the subfolder named after the source's folder inside the package's parent
    (``mkcollision_ros/kernels``, ``mkcollision_ros/kernels/pairs``) instead of a hash
    of its path (see the module docstring); other files fall through to numba's own
    locators."""

    @classmethod
    def get_suitable_cache_subpath(cls, py_file):
        folder = os.path.dirname(os.path.realpath(py_file))
        return os.path.relpath(folder, os.path.dirname(_PACKAGE_DIR))

    @classmethod
    def from_function(cls, py_func, py_file):
        real = os.path.realpath(py_file)
        if os.path.commonpath([real, _PACKAGE_DIR]) != _PACKAGE_DIR:
            return None
        return super().from_function(py_func, py_file)


# numba's default locators, in numba's order, after ours (NUMBA_CACHE_LOCATOR_CLASSES)
_NUMBA_LOCATORS = ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator",
                   "IPythonCacheLocator", "ZipCacheLocator")

if not os.environ.get("NUMBA_CACHE_DIR"):
    numba.config.CACHE_DIR = _kernel_cache_dir()
    if not numba.config.CACHE_LOCATOR_CLASSES:
        numba.config.CACHE_LOCATOR_CLASSES = ",".join(
            (f"{__name__}.SharedCacheLocator",) + _NUMBA_LOCATORS)

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


njit_kernel = numba.njit(cache=True, fastmath=False, nogil=True, error_model="numpy",
                         no_cfunc_wrapper=True)
njit_parallel = numba.njit(cache=True, fastmath=False, nogil=True, parallel=True,
                           error_model="numpy", no_cfunc_wrapper=True)
njit_inline = numba.njit(cache=True, fastmath=False, nogil=True, error_model="numpy",
                         forceinline=True, no_cfunc_wrapper=True)
prange = numba.prange

# The library attribute that marks a compiled njit_separate kernel (its dependency
# record, see _Dependency) and the one holding a library's own dependencies.
_SEPARATE_TAG = "_mkcollision_separate"
_DEPENDS_TAG = "_mkcollision_depends"


class MissingSeparateKernel(Exception):
    """A cached kernel calls a separate kernel that is neither loaded nor in the cache
    under the symbol it was linked against: the cached kernel is compiled again."""


def _separate_linking():
    """Install the separate linking of njit_separate kernels in numba's code libraries
    (module docstring, "Separate kernels"); returns whether it is installed."""
    try:
        from numba.core import codegen
        lib_class = codegen.CPUCodeLibrary
        plain_finalize = lib_class.finalize
        plain_serialize = lib_class.serialize_using_object_code
        plain_unserialize = lib_class._unserialize.__func__
        plain_load = caching.Cache.load_overload
    except (ImportError, AttributeError):
        return False
    if getattr(plain_finalize, "_separate", False):
        return True
    if numba.__version__ != "0.68.1":
        return False

    def finalize(self):
        linked, depends = [], []
        for library in self._linking_libraries:
            dep = getattr(library, _SEPARATE_TAG, None)
            if dep is None:
                linked.append(library)
                depends.extend(getattr(library, _DEPENDS_TAG, ()))
            else:
                # a call by symbol: the declaration numba wrote stays one
                self._reload_init.update(library._reload_init)
                depends.append(dep)
        self._linking_libraries = linked
        setattr(self, _DEPENDS_TAG, tuple(dict.fromkeys(depends)))
        return plain_finalize(self)

    def serialize_using_object_code(self):
        name, kind, data = plain_serialize(self)
        return name, kind, data + (getattr(self, _DEPENDS_TAG, ()),)

    def _unserialize(cls, codegen_, state):
        name, kind, data = state
        depends = ()
        if kind == "object" and len(data) == 3:
            data, depends = data[:2], data[2]
            for dep in depends:
                dep.load(codegen_)
        library = plain_unserialize(cls, codegen_, (name, kind, data))
        setattr(library, _DEPENDS_TAG, depends)
        return library

    def load_overload(self, sig, target_context):
        try:
            return plain_load(self, sig, target_context)
        except MissingSeparateKernel:
            return None

    finalize._separate = True
    for name, fn in (("finalize", finalize),
                     ("serialize_using_object_code", serialize_using_object_code)):
        fn.__doc__ = getattr(lib_class, name).__doc__
        setattr(lib_class, name, fn)
    lib_class._unserialize = classmethod(_unserialize)
    caching.Cache.load_overload = load_overload
    return True


class _Dependency(tuple):
    """(module, qualname, argument types, symbol) of one compiled separate kernel:
    what a caller's cached code needs loaded before its own (pickled in numba's cache
    with the caller's object code)."""

    def load(self, codegen_):
        """Compile or load the kernel for these argument types; MissingSeparateKernel
        unless its symbol is then the one the caller was linked against."""
        module, qualname, args, symbol = self
        kernel = importlib.import_module(module)
        for part in qualname.split("."):
            kernel = getattr(kernel, part)
        kernel.compile(args)
        if not codegen_._engine.is_symbol_defined(symbol):
            raise MissingSeparateKernel(f"{module}.{qualname}{args}: {symbol}")


SEPARATE_LINKING = (not numba.config.DISABLE_JIT
                    and os.environ.get("MKCOLLISION_LINK_ALL", "") in ("", "0")
                    and _separate_linking())


def njit_separate(fn):
    """njit_kernel, compiled once for all its callers, which call its symbol instead of
    linking a copy of its code (module docstring, "Separate kernels")."""
    kernel = njit_kernel(fn)
    if not SEPARATE_LINKING:
        return kernel
    plain_add = kernel.add_overload

    def add_overload(cres):
        setattr(cres.library, _SEPARATE_TAG, _Dependency(
            (fn.__module__, fn.__qualname__, tuple(cres.signature.args),
             cres.fndesc.mangled_name)))
        plain_add(cres)

    kernel.add_overload = add_overload
    return kernel


def n_blocks(n_items, min_block):
    """How many blocks a parallel batch kernel should split ``n_items`` into (plain
    Python, for the kernel's caller: numba cannot cache a kernel that asks for the
    thread count itself): one per thread (numba's static schedule gives each thread
    one), fewer when blocks would hold less than ``min_block`` items, at least 1."""
    nb = min(numba.get_num_threads(), (n_items + min_block - 1) // min_block)
    return max(nb, 1)


class _BlockThreads:
    """The threads of run_blocks' blocks beyond the first: one pool of numba's most
    threads less one (numba.config.NUMBA_NUM_THREADS, the bound of
    numba.get_num_threads), made on first use; the pool starts a thread only when one
    is needed."""

    def __init__(self):
        self._lock = threading.Lock()
        self._pool = None

    def pool(self):
        with self._lock:
            if self._pool is None:
                self._pool = ThreadPoolExecutor(
                    max_workers=max(numba.config.NUMBA_NUM_THREADS - 1, 1),
                    thread_name_prefix="mkcollision-blocks")
            return self._pool


_BLOCK_THREADS = _BlockThreads()


def run_blocks(kernel, args, n_items, min_block):
    """Run ``kernel(*args, lo, hi)`` over the items [0, n_items) in nb =
    n_blocks(n_items, min_block) contiguous blocks, block b holding [b n / nb,
    (b + 1) n / nb) (sizes differing by at most 1), in parallel: the first block on the
    calling thread, the others on Python threads.  ``kernel`` is compiled with nogil,
    so the blocks run on separate cores; it writes each item's own slots, so the result
    does not depend on the block count.  Returns when every block is done.  One block
    (small batches) runs straight, with no hand-over; more cost ~20 us of it.

    Python threads rather than a numba ``prange`` over the blocks: a parallel kernel
    around a call to ``kernel`` costs ~25 s of the first compile (numba's parfor
    lowering, measured on collide_batch's), for a loop of two iterations on two cores."""
    nb = n_blocks(n_items, min_block)
    if nb == 1:
        kernel(*args, 0, n_items)
        return
    pool = _BLOCK_THREADS.pool()
    rest = [pool.submit(kernel, *args, b * n_items // nb, (b + 1) * n_items // nb)
            for b in range(1, nb)]
    try:
        kernel(*args, 0, n_items // nb)
    finally:
        for f in rest:
            f.result()


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
