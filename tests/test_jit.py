"""The numba policy module (kernels/jit.py): the collector thresholds while compiling."""
import gc

import numba
from numba.core import event

from mkcollision_ros.kernels import jit


class _Seen(event.Listener):
    def __init__(self):
        self.at_start = []

    def on_start(self, ev):
        self.at_start.append(gc.get_threshold())

    def on_end(self, ev):
        pass


def test_collector_thresholds_raised_while_compiling_and_restored():
    before = gc.get_threshold()
    seen = _Seen()
    # registered after the package's listener, so it sees the thresholds that one set
    event.register("numba:compile", seen)
    try:
        @numba.njit(cache=False)
        def twice(x):
            return 2.0 * x

        assert twice(1.5) == 3.0
    finally:
        event.unregister("numba:compile", seen)
    assert seen.at_start and all(t == jit.COMPILE_GC_THRESHOLDS for t in seen.at_start)
    assert gc.get_threshold() == before != jit.COMPILE_GC_THRESHOLDS
