"""The scene's current poses: names -> index, validated and normalised pose arrays.

Plain numpy.  Bad entries (unknown names, NaN/Inf, zero quaternions) are dropped one by
one and reported; everything else in the same update is applied.
"""
import numpy as np


class PoseStore:
    """Current poses of N named bodies.

    positions float64 (N, 3) metres, world frame; orientations float64 (N, 4) unit
    quat_xyzw; ``known`` bool (N,) whether the body has received a pose (static bodies
    start known at the origin with identity orientation)."""

    def __init__(self, names, static=None):
        self.names = list(names)
        self.index = {n: i for i, n in enumerate(self.names)}
        n = len(self.names)
        self.positions = np.zeros((n, 3))
        self.orientations = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        self.known = np.zeros(n, dtype=bool) if static is None else np.array(static, bool)
        self.version = 0

    def update_indexed(self, idx, positions, orientations):
        """Set poses of bodies ``idx`` (int64 (K,)).  Returns (n_applied, problems): rows
        with non-finite values or a quaternion of norm < 1e-9 are skipped and described
        in ``problems`` (list of str)."""
        positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        orientations = np.asarray(orientations, dtype=np.float64).reshape(-1, 4)
        norms = np.linalg.norm(orientations, axis=1)
        finite = np.isfinite(positions).all(axis=1) & np.isfinite(orientations).all(axis=1)
        good = finite & (norms > 1e-9)
        problems = []
        if not good.all():
            for k in np.flatnonzero(~good):
                why = "non-finite value" if not finite[k] else "zero quaternion"
                problems.append(f"{self.names[idx[k]]}: {why}")
        sel = idx[good]
        self.positions[sel] = positions[good]
        self.orientations[sel] = orientations[good] / norms[good, None]
        self.known[sel] = True
        if len(sel):
            self.version += 1
        return int(len(sel)), problems

    def update_named(self, names, positions, orientations):
        """Set poses by name; unknown names are skipped and reported."""
        idx = np.fromiter((self.index.get(n, -1) for n in names), dtype=np.int64,
                          count=len(names))
        ok = idx >= 0
        problems = [f"{n}: unknown body" for n, i in zip(names, idx) if i < 0]
        applied, bad = self.update_indexed(idx[ok], np.asarray(positions)[ok],
                                           np.asarray(orientations)[ok])
        return applied, problems + bad
