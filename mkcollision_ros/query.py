"""Stateless collision queries over a subset of bodies (the CheckCollision service):
every pair among the given bodies, one deepest point per touching pair, no arbiters."""
import contextlib

import numpy as np

from .kernels import constants as C
from .kernels.narrowphase import collide_batch
from .results import ContactSet
from .shapes import ShapeTable


def collide_pairs(table, pairs, positions, orientations, method, cutoff, out, status,
                  threads=contextlib.nullcontext):
    """``kernels.narrowphase.collide_batch`` on ``pairs`` (int64 (P, 2), C-contiguous) of
    ``table``, except that a pair with a plane takes the closed form (M_AUTO) whatever
    ``method``: GJK/EPA and MPR do not run on a half-space.  Writes ``out`` (P,
    OUT_SIZE) and ``status`` (P,); ``threads(n)`` is entered around each batch of n
    pairs (the pipeline's choice of numba threads)."""
    if method == C.M_AUTO:
        with threads(len(pairs)):
            collide_batch(table.codes, table.params, table.vrange, table.verts, pairs,
                          positions, orientations, np.int64(method), cutoff, out, status)
        return
    is_plane = np.asarray(table.codes) == C.PLANE
    has_plane = is_plane[pairs[:, 0]] | is_plane[pairs[:, 1]]
    for sel, m in ((has_plane, C.M_AUTO), (~has_plane, method)):
        rows = np.flatnonzero(sel)
        if len(rows):
            o = np.empty((len(rows), C.OUT_SIZE))
            st = np.empty(len(rows), np.int64)
            with threads(len(rows)):
                collide_batch(table.codes, table.params, table.vrange, table.verts,
                              np.ascontiguousarray(pairs[rows]), positions, orientations,
                              np.int64(m), cutoff, o, st)
            out[rows] = o
            status[rows] = st


def query_contacts(table: ShapeTable, names, indices, positions, orientations, static,
                   method=C.M_AUTO):
    """Contacts among bodies ``indices`` (int64 (K,)) at the given world poses.

    ``positions`` (N, 3) / ``orientations`` (N, 4) unit quat_xyzw hold every body's pose
    (only rows in ``indices`` are read); static-static pairs are skipped; the pairs run
    through ``collide_pairs``, as the pipeline's.
    """
    idx = np.asarray(indices, dtype=np.int64)
    ii, jj = np.triu_indices(len(idx), k=1)
    pairs = np.stack([idx[ii], idx[jj]], axis=1).reshape(-1, 2)
    pairs = np.sort(pairs, axis=1)
    static = np.asarray(static, dtype=bool)
    pairs = np.ascontiguousarray(pairs[~(static[pairs[:, 0]] & static[pairs[:, 1]])])
    out = np.zeros((len(pairs), C.OUT_SIZE))
    status = np.zeros(len(pairs), dtype=np.int64)
    if len(pairs):
        collide_pairs(table, pairs, np.ascontiguousarray(positions, dtype=np.float64),
                      np.ascontiguousarray(orientations, dtype=np.float64), method, 0.0,
                      out, status)
    hit = (status == C.ST_TOUCHING) | (status == C.ST_PENETRATING)
    rows, pairs = out[hit], pairs[hit]
    pa, pb = rows[:, C.OUT_PA:C.OUT_PA + 3], rows[:, C.OUT_PB:C.OUT_PB + 3]
    n = len(rows)
    return ContactSet(
        names=list(names), body_a=pairs[:, 0], body_b=pairs[:, 1],
        position=0.5 * (pa + pb), point_a=pa, point_b=pb,
        normal=rows[:, C.OUT_NORMAL:C.OUT_NORMAL + 3],
        depth=np.maximum(0.0, -rows[:, C.OUT_DIST]),
        contact_id=np.zeros(n, np.int64), age=np.zeros(n, np.int64),
        method=rows[:, C.OUT_METHOD].astype(np.int64), status=status[hit])
