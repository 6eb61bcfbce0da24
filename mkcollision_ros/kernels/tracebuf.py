"""Trace regions: where the iterative kernels (mpr.py, gjk_epa.py) record their
iterations when a caller hands them a scratch buffer larger than they need.

A trace region is a run of rows ``[base, buf.shape[0])`` of a float64 (rows, 3) scratch
buffer, after the rows the kernel works in (mpr_ws: MPR_WS_ROWS; gjk_epa_ws: fs rows
after gjk_epa_workspace._FS_ROWS).  A buffer with fewer than TR_HEADER_ROWS rows after those
records nothing.  With the options row zero the kernel's results are bit-identical with
and without a trace region (the records are only written, never read).

Layout (the contract the Python reader, mkcollision_ros/trace.py, relies on):
  row base          header: (records written, records dropped, rows used by the
                    records), as floats; reset by the kernel at its start
  row base + 1      options, written by the caller and only read by the kernel:
                    column 0 > 0 asks gjk_epa_ws to run GJK/EPA where one of its
                    closed forms would answer (gjk_epa.py, "Trace"); zeros otherwise
  rows base + 2 ... records, one after the other, each a record header row
                    (kind, n1, n2) followed by n1 + n2 rows:
    TR_MPR_DISCOVERY, TR_MPR_REFINEMENT  n1 rows: the interior point v0 and the
                    portal vertices found so far (v0, v1 [, v2 [, v3]]), points of the
                    whole shapes' Minkowski difference A - B; n2 = 0
    TR_GJK          n1 rows: the GJK simplex (1-4 points of the cores' difference);
                    n2 = 0
    TR_EPA          n1 rows: the polytope's vertices (points of the cores' difference),
                    then n2 rows: its live faces as vertex indices (i, j, k) stored as
                    floats, wound outward (counter-clockwise seen from outside)
All points in A's frame (A's origin), metres.  A record that does not fit in the rows
left is dropped whole and counted in the header; later, smaller records may still fit.
"""
import numpy as np

from .jit import njit_inline

TR_MPR_DISCOVERY = 1
TR_MPR_REFINEMENT = 2
TR_GJK = 3
TR_EPA = 4
TR_HEADER_ROWS = 2     # the header and the options row, before the records


@njit_inline
def trace_reset(buf, base):
    """Empty the trace region starting at row ``base`` of ``buf`` (float64 (rows, 3))."""
    buf[base, 0] = 0.0
    buf[base, 1] = 0.0
    buf[base, 2] = 0.0


@njit_inline
def trace_open(buf, base, kind, n1, n2):
    """Reserve a record of kind ``kind`` with n1 + n2 rows: returns the row of its first
    data row, or -1 (the record counted as dropped) when it does not fit."""
    used = int(buf[base, 2])
    top = base + TR_HEADER_ROWS + used
    if top + 1 + n1 + n2 > buf.shape[0]:
        buf[base, 1] += 1.0
        return -1
    buf[top, 0] = kind
    buf[top, 1] = n1
    buf[top, 2] = n2
    buf[base, 0] += 1.0
    buf[base, 2] = used + 1 + n1 + n2
    return top + 1


@njit_inline
def trace_rows(buf, base, kind, src, n):
    """Record rows 0..n-1 of ``src`` (float64 (>= n, 3)) as a record of ``kind``."""
    r = trace_open(buf, base, kind, n, np.int64(0))
    if r >= 0:
        for i in range(n):
            buf[r + i, 0] = src[i, 0]
            buf[r + i, 1] = src[i, 1]
            buf[r + i, 2] = src[i, 2]
