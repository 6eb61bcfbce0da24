"""The one numba decorator policy of the project.

Every kernel is compiled with ``njit_kernel``: nopython mode, on-disk cache (so a second
start of the node does not compile again), and ``fastmath`` off, because the narrow
phase relies on exact IEEE comparisons (NaN checks, signed zeros, strict ``<``).
``njit_parallel`` is the same policy with ``parallel=True`` for batch loops that write
into fixed, preallocated slots (results do not depend on the thread count).
"""
import numba

njit_kernel = numba.njit(cache=True, fastmath=False, nogil=True, error_model="numpy")
njit_parallel = numba.njit(cache=True, fastmath=False, nogil=True, parallel=True,
                           error_model="numpy")
prange = numba.prange
