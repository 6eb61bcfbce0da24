"""The one numba decorator policy of the project.

Every kernel is compiled with ``njit_kernel``: nopython mode, on-disk cache (so a second
start of the node does not compile again), and ``fastmath`` off, because the narrow
phase relies on exact IEEE comparisons (NaN checks, signed zeros, strict ``<``).
``njit_parallel`` is the same policy with ``parallel=True`` for batch loops that write
into fixed, preallocated slots (results do not depend on the thread count, since every
thread runs the same compiled code).  Note that fastmath off does not forbid LLVM from
fusing multiply-adds on CPUs with FMA, so two *different* compiled copies of the same
arithmetic may differ in the last bits; the project never mixes copies in one result.

Cache location: numba's own cache notices when a kernel's file changes but not when a
kernel it calls, in another file, changes — a stale cache would then run old code.  So
the cache lives in a folder named after a hash of every kernel source file:
``$XDG_CACHE_HOME/mkcollision_ros/numba-<hash>`` (default ``~/.cache``).  Any edit gives
a fresh folder; an unchanged install reuses its compiled kernels.  Setting
``NUMBA_CACHE_DIR`` overrides this.
"""
import hashlib
import os

import numba


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

njit_kernel = numba.njit(cache=True, fastmath=False, nogil=True, error_model="numpy")
njit_parallel = numba.njit(cache=True, fastmath=False, nogil=True, parallel=True,
                           error_model="numpy")
prange = numba.prange
