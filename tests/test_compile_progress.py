"""Progress lines while numba compiles, and none for work that needs no compile."""
import numba

from mkcollision_ros.compile_progress import reporting


def test_each_outermost_compile_is_reported_with_an_estimate():
    @numba.njit
    def inner(x):
        return x + 1

    @numba.njit
    def outer_kernel(x):
        return inner(x) * 2

    lines = []
    with reporting(lines.append, {"outer_kernel": 3.0, "other_kernel": 7.0},
                   heartbeat=0) as listener:
        assert outer_kernel(1) == 4
        assert outer_kernel(2) == 6                   # compiled once
    assert len(lines) == 2                            # the nested compile is not listed
    assert lines[0].startswith("compiling kernels: ") and "outer_kernel" in lines[0]
    assert "outer_kernel" in lines[1] and "(1 of 2 expected kernels, about 7 s left)" in \
        lines[1]
    assert list(listener.seconds) == [lines[1].split()[1]]
    # outside the block nothing is reported
    @numba.njit
    def later(x):
        return x
    later(1)
    assert len(lines) == 2


def test_a_long_compile_keeps_reporting():
    import time
    lines = []
    with reporting(lines.append, {"slow": 1.0}, heartbeat=0.05) as listener:
        class Ev:                      # one outermost compile of 0.3 s, by hand
            data = {"dispatcher": type("D", (), {"py_func": staticmethod(lambda: 0)})()}
        Ev.data["dispatcher"].py_func.__name__ = "slow"
        listener.on_start(Ev)
        time.sleep(0.3)
        listener.on_end(Ev)
    beats = [x for x in lines if x.startswith("still compiling slow:")]
    assert len(beats) >= 3 and "of about 1 s" in beats[0]
    assert lines[-1].startswith("compiled slow in 0 s")
