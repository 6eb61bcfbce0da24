"""The closed-form dispatcher: ``collide_analytic`` (either order of a pair with a
closed form, A's frame), ``closed_form_ordered`` (a pair in canonical order, for the
narrow phase's dispatch).  The closed forms are in kernels/pairs/: sphere against a
sphere, box, capsule, cylinder, cone or an ellipsoid without margin (sphere_shape.py),
capsule-capsule (capsule_capsule.py), box-capsule (box_capsule.py) and a half-space
(plane) against any shape (plane_shape.py); box-box SAT (box_box.py) is the
dispatcher's auto method's, before GJK (kernels/narrowphase.py), not part of
``collide_analytic``: separated boxes need GJK for their exact distance, and their SAT
gap is only a lower bound, which the dispatcher keeps for pairs beyond its distance
cutoff.

The closed forms work on scalars (numba keeps them in registers): no array is allocated
on the per-pair path.

Frames and signs (as everywhere, see mkcollision_ros/results.py): inputs ``r_ab``
(3, 3) and ``t_ab`` (3,) are B's pose in A's frame (float64, metres); every output is in
A's frame; ``out`` float64[OUT_SIZE] receives the signed distance (> 0 apart), the unit
normal from A to B, witness points ``pa`` on A's surface and ``pb`` on B's surface with
``pb - pa == dist * normal``, iterations (1) and ``M_ANALYTIC``.

Pairs are accepted in either order (A, B) or (B, A); unsupported pairs and plane-plane
return ST_NOT_RUN and leave ``out`` untouched.
"""
import numpy as np

from .constants import (BOX, CAPSULE, M_ANALYTIC, OUT_DIST, OUT_ITERS, OUT_METHOD, OUT_NORMAL,
                        OUT_PA, OUT_PB, PLANE, SPHERE, ST_NOT_RUN)
from .geometry import borrow_args, inflation, shape_scale
from .jit import borrow, njit_inline, njit_kernel, njit_separate
from .pairs.box_capsule import collide_box_capsule
from .pairs.capsule_capsule import collide_capsule_capsule
from .pairs.core_distance import _point_point_s, classify
from .pairs.plane_shape import collide_shape_plane
from .pairs.sphere_shape import collide_sphere_shape, has_point_form


@njit_kernel
def _mv(r, v):
    """r @ v for a (3, 3) matrix and a (3,) vector (no BLAS)."""
    o = np.empty(3)
    for i in range(3):
        o[i] = r[i, 0] * v[0] + r[i, 1] * v[1] + r[i, 2] * v[2]
    return o


@njit_kernel
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit_inline
def _ordered(sa, sb, verts, r_ab, t_ab, out):
    """Closed form for code_a <= code_b; returns (ran, dist)."""
    ca, cb = sa[0], sb[0]
    if cb == PLANE:
        if ca == PLANE:
            return False, 0.0
        return True, collide_shape_plane(sa, sb, verts, r_ab, t_ab, out)
    ra = inflation(ca, sa[1])
    rb = inflation(cb, sb[1])
    if ca == SPHERE and cb == SPHERE:
        return True, _point_point_s(0.0, 0.0, 0.0, t_ab[0], t_ab[1], t_ab[2], ra, rb, out)
    if ca == SPHERE and has_point_form(cb, sb[1]):
        return True, collide_sphere_shape(sa, sb, r_ab, t_ab, out)
    if ca == CAPSULE and cb == CAPSULE:
        return True, collide_capsule_capsule(sa, sb, r_ab, t_ab, ra, rb, out)
    if ca == BOX and cb == CAPSULE:
        return True, collide_box_capsule(sa, sb, r_ab, t_ab, ra, rb, out)
    return False, 0.0


@njit_inline
def closed_form_ordered(sa, sb, verts, r_ab, t_ab, out):
    """Signed distance (m) of a pair in canonical order that has a closed form (the
    dispatcher checks which); writes ``out`` as ``collide_analytic`` does."""
    ran, dist = _ordered(sa, sb, verts, r_ab, t_ab, out)
    return dist


@njit_separate
def collide_analytic(sa, sb, verts, r_ab, t_ab, out):
    """Exact closed-form collision of a supported pair; ST_NOT_RUN otherwise.

    sa, sb  shape tuples (code int64, prm float64[8], v0 int64, vn int64)
    verts   float64 (M, 3) convex vertices (body frames), used by plane-vs-convex
    r_ab    float64 (3, 3), t_ab float64 (3,): pose of B in A's frame (m)
    out     float64[OUT_SIZE]: signed distance (m), unit normal A -> B, pa, pb (A's
            frame, pb - pa = dist * normal), iterations = 1, method = M_ANALYTIC
    Returns the status code under the touching rule (scale = sum of bounding radii).
    Either order of a supported pair is accepted.
    """
    # owner-less views: no reference counting on them (geometry.borrow_args)
    sa, sb, verts, r_ab, t_ab = borrow_args(sa, sb, verts, r_ab, t_ab)
    out = borrow(out)
    if sa[0] <= sb[0]:
        ran, dist = _ordered(sa, sb, verts, r_ab, t_ab, out)
        if not ran:
            return ST_NOT_RUN
        return classify(dist, shape_scale(sa, sb))
    # swapped: solve (B, A) in B's frame, then map back and flip the normal
    r_ba = np.ascontiguousarray(r_ab.T)
    t_ba = -_mv(r_ba, t_ab)
    tmp = np.empty(out.shape[0])
    ran, dist = _ordered(sb, sa, verts, r_ba, t_ba, tmp)
    if not ran:
        return ST_NOT_RUN
    n = -_mv(r_ab, tmp[OUT_NORMAL:OUT_NORMAL + 3])
    pa = _mv(r_ab, tmp[OUT_PB:OUT_PB + 3]) + t_ab
    pb = _mv(r_ab, tmp[OUT_PA:OUT_PA + 3]) + t_ab
    out[OUT_DIST] = dist
    for i in range(3):
        out[OUT_NORMAL + i] = n[i]
        out[OUT_PA + i] = pa[i]
        out[OUT_PB + i] = pb[i]
    out[OUT_ITERS] = tmp[OUT_ITERS]
    out[OUT_METHOD] = M_ANALYTIC
    return classify(dist, shape_scale(sa, sb))
