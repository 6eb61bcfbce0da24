"""The closed form of any shape against a half-space (plane) B (``collide_shape_plane``,
A's frame; the result row as core_distance.py's, frames and signs: analytic.py).

Half-space: B = {x : n.x <= d} in B's frame (prm[0:3] = unit n, prm[3] = d).  The signed
distance of A is min over x in A of (n.x - d), reached at A's support point along -n; B
lies on the -n side, so the normal from A to B is -n (rotated into A's frame), and moving
B by the depth along it moves the boundary plane onto A's deepest point.
"""
from ..constants import (M_ANALYTIC, OUT_DIST, OUT_ITERS, OUT_METHOD, OUT_NORMAL, OUT_PA, OUT_PB,
                         P_MARGIN)
from ..geometry import support_full_xyz
from ..jit import njit_inline
from .core_distance import _b_to_a


@njit_inline
def collide_shape_plane(sa, sb, verts, r_ab, t_ab, out):
    """A = any non-plane shape, B = half-space n.x <= d (B's frame), grown by its
    margin m to n.x <= d + m."""
    nb = sb[1]
    d = sb[1][3] + sb[1][P_MARGIN]
    # plane normal in A's frame
    nax, nay, naz = _b_to_a(r_ab, nb[0], nb[1], nb[2])
    x0, x1, x2 = support_full_xyz(sa[0], sa[1], verts, sa[2], sa[3], -nax, -nay, -naz)
    # signed distance: n.(x in B's frame) - d
    y0, y1, y2 = x0 - t_ab[0], x1 - t_ab[1], x2 - t_ab[2]
    dist = -d
    for i in range(3):
        dist += nb[i] * (r_ab[0, i] * y0 + r_ab[1, i] * y1 + r_ab[2, i] * y2)
    out[OUT_DIST] = dist
    out[OUT_NORMAL] = -nax
    out[OUT_NORMAL + 1] = -nay
    out[OUT_NORMAL + 2] = -naz
    out[OUT_PA] = x0
    out[OUT_PA + 1] = x1
    out[OUT_PA + 2] = x2
    out[OUT_PB] = x0 - dist * nax
    out[OUT_PB + 1] = x1 - dist * nay
    out[OUT_PB + 2] = x2 - dist * naz
    out[OUT_ITERS] = 1.0
    out[OUT_METHOD] = M_ANALYTIC
    return dist
