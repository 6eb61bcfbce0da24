"""The scratch workspace ``ws`` = (fs, fv, iv) of gjk_epa.gjk_epa_ws: its row offsets
(below), its allocation (``make_gjk_workspace``; ``make_gjk_workspace_traced`` with a
trace region, gjk_epa.py, "Trace"), owner-less views of it (``borrow_gjk_workspace``),
and the rows where a polish step leaves its minimum (``_store_min``,
``_take_polished``).
"""
import numpy as np

from .constants import BC_MAX_LEVEL, EPA_MAX_FACES, EPA_MAX_ITERS, EPA_POLISH_ITERS
from .jit import borrow, njit_inline, njit_kernel
from .pairs.normal_fan import HE_ROWS
from .tracebuf import TR_HEADER_ROWS

# Scratch buffers ``ws`` = (fs, fv, iv) of one GJK/EPA call, allocated once per chunk of
# pairs by the batch kernel and reused pair after pair; no state survives from one pair
# to the next.  Three
# backing arrays only (numba reference-counts every array passed to a function, so a
# tuple of many small arrays costs more per call than the work of an analytic pair):
#   fs float64 (_FS_ROWS, 3): simplex W, WA, WB and their saved copies, 3-vector scratch
#      rows t3 (see below), the growth candidates, EPA vertices V, VA, VB and the unit
#      direction VD whose support each vertex is (zero for the starting tetrahedron),
#      the samples of Newton's method (directions PN, support points of A - B PW),
#      face normals FN
#   fv float64 (_FV_SIZE,): barycentric weights lam / lam_prev, l3, vol, the EPA result
#      res (10), GJK's closest point v (3), face offsets FD
#   iv uint64 (_IV_ROWS, 3): faces F, horizon edges (a, b, face beyond as in ADJ),
#      the flood-fill stack and the alive flags, the new faces and the free face
#      slots, the face adjacency ADJ (4 g + eg: the face g across edge e = F[f, e] ->
#      F[f, (e + 1) % 3], which is g's edge eg), then per vertex u the horizon edge
#      starting at u and the one ending at u of the current step, so each new face
#      finds its neighbours across its two spokes in O(1).  The six lists lie in
#      _epa's flat view of iv (iv.reshape), two per block of rows, each contiguous.
#      Unsigned because numba wraps negative indices (idx + len when idx < 0) only for
#      signed integers: an index loaded from an int64 array costs three more
#      instructions and the view's length kept in a register or spilled (measured:
#      deep GJK/EPA pairs with a cylinder 7-10% faster as uint64, the same results).
#      Mind numba's typing: int64 and uint64 unify to float64, so a variable that takes
#      both (a slot index from ``free`` or from ``nf``) is cast with np.uint64.
# The t3 rows: 3-vectors of fs, from _T3 on, each named for its use.  Rows whose users
# never run at the same time share a row under two names.
_NVMAX = EPA_MAX_ITERS + 4
_PK = EPA_POLISH_ITERS + 4    # samples of the local polish: <= 4 given + one per step
_W, _WA, _WB, _WP, _WAP, _WBP = 0, 4, 8, 12, 16, 20
_T3 = 24
_T_NRM, _T_PA, _T_PB = _T3, _T3 + 1, _T3 + 2   # gjk_epa's answer: normal, witnesses on A, B
_T_FACE_CAP = _T3 + 3       # column 0: the cap a face test proved (polish_faces._face_basin)
# gjk_epa's check of GJK's estimate when GJK's cap is hit: direction, support points
_T_EST_D, _T_EST_WA, _T_EST_WB, _T_EST_W = _T3 + 4, _T3 + 5, _T3 + 6, _T3 + 7
# the current search direction and its support points on A, B and A - B (_gjk,
# _grow_to_tetra, _epa, polish_crease, polish_newton)
_T_D, _T_WA, _T_WB, _T_W = _T3 + 8, _T3 + 9, _T3 + 10, _T3 + 11
_T_VPREV = _T3 + 12          # _gjk: the previous closest point
_T_CIN = _T3 + 12            # _epa: a point inside the polytope
_T_UD, _T_UWA = _T3 + 13, _T3 + 14   # _epa: the best upper bound's direction, A's point
_T_SHIFT = _T3 + 13          # gjk._witness_by_gjk: the shifted t_ab
# a polish's minimum (_store_min): direction n, difference point w, witnesses on A and B
_T_MIN_D, _T_MIN_W, _T_MIN_WA, _T_MIN_WB = _T3 + 15, _T3 + 16, _T3 + 17, _T3 + 18
# _grow_to_tetra's best candidate: difference point, A's and B's points, direction
_T_BEST_W, _T_BEST_WA, _T_BEST_WB, _T_BEST_DIR = _T3 + 15, _T3 + 16, _T3 + 17, _T3 + 18
# epa._polish_min_support's pattern search: direction, support points, two tangents
_T_PAT_D, _T_PAT_WA, _T_PAT_WB, _T_PAT_W = _T3 + 19, _T3 + 20, _T3 + 21, _T3 + 22
_T_PAT_E1, _T_PAT_E2 = _T3 + 23, _T3 + 24
_CAND = _T3 + 25
_V = _CAND + 6
_VA = _V + _NVMAX
_VB = _VA + _NVMAX
_VD = _VB + _NVMAX
_PN = _VD + _NVMAX
_PW = _PN + _PK
_FN = _PW + _PK
_FS_ROWS = _FN + EPA_MAX_FACES
_BC_ROWS = BC_MAX_LEVEL + 8   # box_cylinder's scratch, in the EPA vertex rows (free then)


assert _V + HE_ROWS <= _FS_ROWS   # ellipsoid_convex's scratch rows likewise, before GJK


_LAM, _LAMP, _L3, _VOL, _RES, _VV = 0, 4, 8, 11, 15, 25
_FD = 28
_FV_SIZE = _FD + EPA_MAX_FACES
_IF = 0
_IE = EPA_MAX_FACES
_IS = _IE + 3 * EPA_MAX_FACES
_IC = _IS + EPA_MAX_FACES
_IA = _IC + EPA_MAX_FACES
_IH = _IA + EPA_MAX_FACES
_IV_ROWS = _IH + _NVMAX


@njit_kernel
def make_gjk_workspace():
    """Fresh scratch buffers for ``gjk_epa_ws``: the tuple ``ws`` = (fs, fv, iv) above
    (a plain tuple: kernels import only numpy, numba and math)."""
    return (np.empty((_FS_ROWS, 3)), np.zeros(_FV_SIZE),
            np.zeros((_IV_ROWS, 3), dtype=np.uint64))


@njit_kernel
def make_gjk_workspace_traced(rows):
    """``make_gjk_workspace()`` with a trace region of ``rows`` (>= TR_HEADER_ROWS) rows
    after fs's working rows (gjk_epa.py, "Trace"), its header and options zero:
    the same array types, so ``gjk_epa_ws`` runs the same compiled code."""
    fs = np.empty((_FS_ROWS + rows, 3))
    for r in range(_FS_ROWS, _FS_ROWS + TR_HEADER_ROWS):
        for c in range(3):
            fs[r, c] = 0.0
    return (fs, np.zeros(_FV_SIZE), np.zeros((_IV_ROWS, 3), dtype=np.uint64))


@njit_inline
def borrow_gjk_workspace(ws):
    """A ``make_gjk_workspace()`` tuple as owner-less views (geometry.borrow_args says
    why); the caller keeps the owner alive."""
    return (borrow(ws[0]), borrow(ws[1]), borrow(ws[2]))


@njit_inline
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit_inline
def _store_min(fs, nx, ny, nz, wx, wy, wz, ax, ay, az, bx, by, bz):
    """A minimum found by a polish (Newton's method, the crease searches, the face
    tests) into ws t3 rows 15-18: direction n, the difference point w, the witnesses
    a on A and b on B."""
    pd, pw, pwa, pwb = fs[_T_MIN_D], fs[_T_MIN_W], fs[_T_MIN_WA], fs[_T_MIN_WB]
    pd[0], pd[1], pd[2] = nx, ny, nz
    pw[0], pw[1], pw[2] = wx, wy, wz
    pwa[0], pwa[1], pwa[2] = ax, ay, az
    pwb[0], pwb[1], pwb[2] = bx, by, bz


@njit_inline
def _take_polished(fs, d, w, wa, wb):
    """Copy the polished minimum (ws t3 rows 15-18: direction, difference point,
    support points of A and B) into EPA's d, w, wa, wb."""
    for c in range(3):
        d[c] = fs[_T_MIN_D, c]
        w[c] = fs[_T_MIN_W, c]
        wa[c] = fs[_T_MIN_WA, c]
        wb[c] = fs[_T_MIN_WB, c]
