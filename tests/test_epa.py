"""EPA's polytope (kernels/epa.py): the face set-up flips a face wound toward the
interior point, and a degenerate face gets no plane."""
import math

import numpy as np


def test_epa_face_setup_flips_a_face_wound_toward_the_interior():
    # EPA sets up its new faces with _face_plane, which only flags a face wound toward
    # the interior point, and flips flagged faces in a second pass (_face_setup): check
    # both on one face in either winding and on a degenerate face.
    from mkcollision_ros.kernels.epa import _face_plane, _face_setup
    V = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [2.0, 0.0, 0.0]])
    cin = np.zeros(3)
    out_n, out_d = np.ones(3) / math.sqrt(3.0), 1.0 / math.sqrt(3.0)
    for wound, inward in (([0, 1, 2], False), ([0, 2, 1], True)):
        F = np.array([wound], np.int64)
        FN, FD = np.zeros((1, 3)), np.zeros(1)
        assert _face_plane(V, F, FN, FD, 0, cin) == inward
        assert list(F[0]) == wound                   # the plane pass writes no indices
        assert np.allclose(FN[0], out_n if not inward else -out_n, atol=1e-15)
        assert _face_setup(V, F, FN, FD, 0, cin)
        assert list(F[0]) == [0, 1, 2]               # outward winding either way
        assert np.allclose(FN[0], out_n, atol=1e-15) and abs(FD[0] - out_d) <= 1e-15
    F = np.array([[0, 3, 0]], np.int64)              # zero area
    FN, FD = np.zeros((1, 3)), np.zeros(1)
    assert not _face_setup(V, F, FN, FD, 0, cin)
    assert FD[0] == np.inf and not np.any(FN[0])
