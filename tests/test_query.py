"""The stateless query behind the check_collision service (mkcollision_ros/query.py)."""
import numpy as np
import pytest

from mkcollision_ros.kernels import constants as C
from mkcollision_ros.pipeline import Pipeline, PipelineConfig
from mkcollision_ros.query import query_contacts

BODIES = [
    {"name": "floor", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0},
     "static": True},
    {"name": "ball", "shape": {"type": "sphere", "radius": 0.5}},
    {"name": "crate", "shape": {"type": "box", "size": [1.0, 1.0, 1.0]}},
]
POS = np.array([[0.0, 0, 0], [0.0, 0, 0.49], [0.95, 0, 0.48]])
QUAT = np.tile([0.0, 0.0, 0.0, 1.0], (3, 1))


@pytest.mark.parametrize("method", ["auto", "gjk_epa", "mpr"])
def test_query_answers_plane_pairs_under_every_method_as_the_pipeline(method):
    """A pair with a plane takes the closed form whatever the method, in the query as in
    the pipeline: the ball and the crate on the floor, and against each other."""
    p = Pipeline(BODIES, PipelineConfig(method=method))
    r = p.step(POS, QUAT, 0.0)
    sc = p.scene
    q = query_contacts(sc.table, sc.names, np.arange(3), POS, QUAT, sc.static,
                       C.METHOD_NAMES.index(method))
    got = {(sc.names[a], sc.names[b]): d for a, b, d in zip(q.body_a, q.body_b, q.depth)}
    assert set(got) == {("floor", "ball"), ("floor", "crate"), ("ball", "crate")}
    assert set(got) == {(sc.names[a], sc.names[b]) for a, b in r.pairs}
    assert got[("floor", "ball")] == pytest.approx(0.01, abs=1e-12)
    assert got[("floor", "crate")] == pytest.approx(0.02, abs=1e-12)
    assert got[("ball", "crate")] == pytest.approx(0.05, abs=1e-9)
    plane_rows = q.body_a == 0
    assert np.all(q.method[plane_rows] == C.M_ANALYTIC)
