"""Random-pair fuzzer of the narrow phase: every shape type, every method, checked call
by call.

The command line is bench/fuzz.py:

    PYTHONPATH=. python bench/fuzz.py --pairs 1000000 --seed 1 \\
        [--methods auto,gjk_epa,mpr,analytic,ellipsoid_exact,ellipsoid_sampled,distance]
        [--api-every 200] [--time-bound 0.05] [--chunk 20000]

Shapes (``fuzz_shape``): all eight types, sizes log-uniform from 1 mm to 100 m, aspect
ratios up to 1:1000 (thin rods, flat discs and slabs), a margin on a quarter of them,
convex hulls of 4 to 300 points, some nearly flat (thickness down to 1e-6 of their
width) or off their origin.  A pool of shapes per type (``make_pool``) is drawn into
pairs of every type combination but plane-plane, in both orders, so a tiny body meets a
huge one (size ratios up to 10^5).

Poses (``draw_pairs``), as fractions of the pair: far apart (bounding spheres apart),
near (centres closer than the sum of the bounding radii), small inside big (the smaller
body's centre inside the larger one's bounding ball), coincident centres (a third of
them with the same orientation too), and touching: a near pose moved along the auto
method's normal by its signed distance, so that |distance| ends up at round-off.

Per call (``check_pairs``), with scale = the sum of the two bounding radii (planes: 0)
and the touching rule of results.py:
  * a known status; NOT_RUN only where the method does not take the pair (a plane for
    gjk_epa and mpr, no closed form for analytic, anything but spheres and ellipsoids
    without margin for the ellipsoid methods); FAILED counted as a failure;
  * finite distance, normal and witness points; a unit normal;
  * the status follows the touching rule on the distance (not for the ellipsoid
    methods, whose status is their own test's); ``point_b - point_a == distance *
    normal`` within DEPTH_TOL * scale, the regression corpus' tolerance (not for MPR
    apart, whose point_b is no witness);
  * a touching answer: B moved by its depth (plus SELF_TOL * scale) along its normal
    is no longer penetrating by more than DEPTH_TOL * scale (judged by auto);
  * agreement with auto (the closed form where one exists, else GJK/EPA) outside the
    band |d| <= BAND * scale: the same touching flag; gjk_epa, analytic and the
    ellipsoid methods' distances within DEPTH_TOL * scale of auto's (the documented
    accuracy of GJK/EPA, gjk_epa.py, and the regression corpus' tolerance); MPR held to
    its own documented bounds (mpr.py): its depth not below auto's by more than
    DEPTH_TOL * scale, and when apart a lower bound, 0 <= d <= auto's + DEPTH_TOL *
    scale; ellipsoid_sampled held to its documented one-sided test (ellipsoid.py: a
    sample within reach proves contact, shallow overlaps may be missed): touching only
    where auto touches;
  * the batch kernel in parallel blocks (``collide_batch``) gives bit for bit the rows
    of the same kernel run one pair at a time (``_collide_block``, timed per call);
    no call takes longer than ``--time-bound`` seconds (a slow call is timed again
    before it counts, the machine being shared);
  * every ``--api-every``-th pair also goes through the public API (``collide`` with
    the method name, or ``distance``): the same status outside the band and the same
    distance within DEPTH_TOL * scale as the batch row (not for MPR: its depth is the
    portal's, which rounding differences of the two compiled copies can move by more,
    within its own bounds, checked on the batch row).  ``distance()`` is by contract
    ``collide(method="auto")``: its row checks auto's batch rows again and sends its
    API calls through ``distance()``.
Each failure prints one line: what failed, then a repro (crosscheck.repro_call) at 17
significant digits, which is the saved case of tests/fuzz_cases.json.  The summary
table gives per method: calls, FAILED, NaN, other failures, disagreements with auto,
the slowest call (ms; for ``distance``, of its public API calls, which include
validating and packing the shapes) and the API calls.
"""
import gc
import math
import time

import numpy as np

from .narrowphase import collide, distance
from .crosscheck import repro_call
from .kernels.constants import (
    M_AUTO, M_MPR, METHOD_NAMES, OUT_DIST, OUT_NORMAL, OUT_PA, OUT_PB, OUT_SIZE,
    P_RADIUS, ST_FAILED, ST_NOT_RUN, ST_PENETRATING, ST_SEPARATED, ST_TOUCHING,
    TOUCH_TOL)
from .kernels.narrowphase import _collide_block, collide_batch
from .rotations import random_quat
from .shapes import SHAPE_CODES, build_table

KINDS = ("sphere", "ellipsoid", "box", "capsule", "cylinder", "cone", "convex", "plane")
METHODS = METHOD_NAMES + ("distance",)
DEPTH_TOL = 1e-6      # depth / distance agreement, relative to scale
BAND = 1e-6           # touching flags compared only where auto's |d| > BAND * scale
ELL_BAND = 1e-5       # the ellipsoid tests' band: their rule is on A's unit-sphere frame
SELF_TOL = 1e-9       # |n| == 1, and the extra push of the separation check
REGIMES = ("far", "near", "inside", "coincident", "touching")
REGIME_P = (0.15, 0.3, 0.15, 0.1, 0.3)


# --- shapes -------------------------------------------------------------------------------
def _aspect(rng):
    """1 for a third of the shapes, else log-uniform up to 1000."""
    return 1.0 if rng.random() < 1 / 3 else float(10.0 ** rng.uniform(0.0, 3.0))


def _three(rng, size, aspect):
    """Three dimensions: the largest ``size``, the smallest ``size / aspect``."""
    d = size * np.array([1.0, 1.0 / aspect, aspect ** -rng.random()])
    return rng.permutation(d)


def fuzz_shape(rng, kind):
    """A random shape dict of ``kind``: size log-uniform 1 mm - 100 m, aspect up to
    1:1000, a margin on a quarter of the bounded ones."""
    size = float(10.0 ** rng.uniform(-3.0, 2.0))
    a = _aspect(rng)
    if kind == "plane":
        n = rng.normal(size=3)
        return {"type": "plane", "normal": (n / np.linalg.norm(n)).tolist(),
                "offset": float(rng.normal() * size)}
    if kind == "sphere":
        s = {"type": "sphere", "radius": size}
    elif kind == "ellipsoid":
        s = {"type": "ellipsoid", "radii": _three(rng, size, a).tolist()}
    elif kind == "box":
        s = {"type": "box", "size": (2.0 * _three(rng, size, a)).tolist()}
    elif kind in ("capsule", "cylinder", "cone"):
        long, short = size, size / a
        r, h = (short, long) if rng.random() < 0.5 else (long, short)
        key = "length" if kind == "capsule" else "height"
        if kind == "capsule" and rng.random() < 0.1:
            h = 0.0
        s = {"type": kind, "radius": r, key: 2.0 * h}
    elif kind == "convex":
        n = int(round(10.0 ** rng.uniform(math.log10(4), math.log10(300))))
        p = rng.normal(size=(n, 3))
        p /= np.linalg.norm(p, axis=1, keepdims=True)
        p *= rng.uniform(0.7, 1.0, size=(n, 1))
        axes = _three(rng, size, a)
        if rng.random() < 0.1:                 # nearly flat: thickness 1e-6 .. 1e-3
            axes[rng.integers(3)] = size * 10.0 ** rng.uniform(-6.0, -3.0)
        p = p * axes
        if rng.random() < 0.2:                 # the origin off the hull's centre
            p += rng.normal(size=3) * 0.5 * size
        s = {"type": "convex", "points": p.tolist()}
    else:
        raise ValueError(kind)
    if rng.random() < 0.25:
        s["margin"] = float(size * 10.0 ** rng.uniform(-4.0, 0.0))
    return s


class Pool:
    """Shapes per type packed into one table: ``shapes`` (list of dicts), ``table``
    (shapes.ShapeTable), ``by_kind`` (type name -> int64 indices into both)."""

    def __init__(self, shapes):
        self.shapes = list(shapes)
        self.table = build_table(self.shapes)
        kinds = np.array([SHAPE_CODES[s["type"]] for s in self.shapes])
        self.by_kind = {k: np.flatnonzero(kinds == SHAPE_CODES[k]) for k in KINDS}
        self.by_kind = {k: v for k, v in self.by_kind.items() if len(v)}


def make_pool(rng, per_kind):
    """``per_kind`` random shapes of every type (``fuzz_shape``)."""
    return Pool([fuzz_shape(rng, k) for k in KINDS for _ in range(per_kind)])


# --- pairs and poses --------------------------------------------------------------------
class Batch:
    """Pairs as the batch kernel's slots: pair k is slots (2k, 2k+1) = pool shapes
    ``ids[2k]``, ``ids[2k+1]`` at world poses ``pos`` (2n, 3), ``quat`` (2n, 4) xyzw;
    ``regime`` (n,) index into REGIMES."""

    def __init__(self, pool, ids, pos, quat, regime):
        t = pool.table
        self.pool, self.ids = pool, np.asarray(ids, np.int64)
        self.codes = np.ascontiguousarray(t.codes[self.ids])
        self.params = np.ascontiguousarray(t.params[self.ids])
        self.vrange = np.ascontiguousarray(t.vrange[self.ids])
        self.verts = np.ascontiguousarray(t.verts)
        self.pos = np.ascontiguousarray(pos, np.float64)
        self.quat = np.ascontiguousarray(quat, np.float64)
        self.regime = np.asarray(regime)
        self.n = len(self.ids) // 2
        self.pairs = np.arange(2 * self.n, dtype=np.int64).reshape(-1, 2)
        self.scale = self.params[0::2, P_RADIUS] + self.params[1::2, P_RADIUS]

    def run(self, method, pos=None):
        """(out (n, OUT_SIZE), status (n,)) of ``collide_batch`` (parallel blocks)."""
        out = np.zeros((self.n, OUT_SIZE))
        st = np.zeros(self.n, np.int64)
        collide_batch(self.codes, self.params, self.vrange, self.verts, self.pairs,
                      self.pos if pos is None else pos, self.quat, np.int64(method),
                      np.inf, out, st)
        return out, st

    def run_timed(self, method):
        """The same rows one pair at a time (the batch kernel's block loop), each call
        timed: (out, status, seconds (n,))."""
        out = np.zeros((self.n, OUT_SIZE))
        st = np.zeros(self.n, np.int64)
        dt = np.zeros(self.n)
        m = np.int64(method)
        args = (self.codes, self.params, self.vrange, self.verts, self.pairs, self.pos,
                self.quat, m, np.inf, out, st)
        clock = time.perf_counter
        # Two costs that are not the call's are kept out of its time: the process's
        # first call loads the kernel from numba's cache (~0.1 s; an empty range does
        # it here), and Python's cyclic collector, set off by an allocation between the
        # two clock reads, would be timed as the call's (a full pass here ~70 ms)
        _collide_block(*args, 0, 0)
        collecting = gc.isenabled()
        gc.disable()
        try:
            for k in range(self.n):
                t0 = clock()
                _collide_block(*args, k, k + 1)
                dt[k] = clock() - t0
        finally:
            if collecting:
                gc.enable()
        return out, st, dt

    def time_one(self, method, k):
        out = np.zeros((self.n, OUT_SIZE))
        st = np.zeros(self.n, np.int64)
        t0 = time.perf_counter()
        _collide_block(self.codes, self.params, self.vrange, self.verts, self.pairs,
                       self.pos, self.quat, np.int64(method), np.inf, out, st, k, k + 1)
        return time.perf_counter() - t0

    def shapes(self, k):
        return self.pool.shapes[self.ids[2 * k]], self.pool.shapes[self.ids[2 * k + 1]]

    def poses(self, k):
        return ((self.pos[2 * k], self.quat[2 * k]),
                (self.pos[2 * k + 1], self.quat[2 * k + 1]))

    def repro(self, k, method):
        sa, sb = self.shapes(k)
        pa, pb = self.poses(k)
        return repro_call(sa, pa, sb, pb, method)


def batch_of(cases):
    """A Batch of given pairs ``[(shape_a, pose_a, shape_b, pose_b), ...]``, poses
    ``(position (3,), quat_xyzw (4,))`` (regime "near" for all)."""
    shapes = [s for a, _, b, _ in cases for s in (a, b)]
    pos = [p[0] for _, pa, _, pb in cases for p in (pa, pb)]
    quat = np.array([p[1] for _, pa, _, pb in cases for p in (pa, pb)], np.float64)
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    return Batch(Pool(shapes), np.arange(len(shapes)), pos, quat,
                 np.full(len(cases), REGIMES.index("near")))


def draw_pairs(rng, pool, n):
    """``n`` random pairs of ``pool``'s shapes (every type pair but plane-plane, both
    orders) at poses of the five regimes; returns a Batch."""
    kinds = list(pool.by_kind)
    combos = [(a, b) for a in kinds for b in kinds if not (a == b == "plane")]
    pick = rng.integers(len(combos), size=n)
    ids = np.empty(2 * n, np.int64)
    for c, (a, b) in enumerate(combos):
        sel = np.flatnonzero(pick == c)
        ids[2 * sel] = rng.choice(pool.by_kind[a], size=len(sel))
        ids[2 * sel + 1] = rng.choice(pool.by_kind[b], size=len(sel))
    radius = pool.table.params[ids, P_RADIUS]
    ra, rb = radius[0::2], radius[1::2]
    regime = rng.choice(len(REGIMES), size=n, p=REGIME_P)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    f = np.select([regime == 0, regime == 3],
                  [rng.uniform(1.0, 3.0, n) * (ra + rb), np.zeros(n)],
                  rng.uniform(0.0, 1.0, n) * (ra + rb))
    f = np.where(regime == 2, rng.uniform(0.0, 1.0, n) * np.maximum(ra, rb), f)
    quat = random_quat(rng, 2 * n)
    same = (regime == 3) & (rng.random(n) < 1 / 3)
    quat[1::2][same] = quat[0::2][same]
    pos = np.zeros((2 * n, 3))
    base = np.maximum(ra, rb)
    pos[0::2] = rng.normal(size=(n, 3)) * base[:, None]
    far = rng.random(n) < 0.1                  # some pairs far from the world origin
    pos[0::2][far] += rng.normal(size=(int(far.sum()), 3)) * 100.0
    pos[1::2] = pos[0::2] + f[:, None] * u
    batch = Batch(pool, ids, pos, quat, regime)
    touch = np.flatnonzero(regime == 4)
    if len(touch):
        out, st = batch.run(M_AUTO)
        ok = (st[touch] != ST_FAILED) & (st[touch] != ST_NOT_RUN)
        k = touch[ok]
        batch.pos[2 * k + 1] -= out[k, OUT_DIST][:, None] * out[k, OUT_NORMAL:OUT_NORMAL + 3]
    return batch


# --- which method takes which pair ------------------------------------------------------
_CLOSED = {frozenset(p) for p in (("sphere", "sphere"), ("sphere", "box"),
                                  ("sphere", "capsule"), ("sphere", "cylinder"),
                                  ("sphere", "cone"), ("capsule", "capsule"),
                                  ("box", "capsule"))}


def runs_pair(method, shape_a, shape_b):
    """Whether ``method`` takes the pair (documented in narrowphase.py, analytic.py and
    ellipsoid.py); otherwise its status is NOT_RUN."""
    ta, tb = shape_a["type"], shape_b["type"]
    plane = "plane" in (ta, tb)
    if method in ("auto", "distance"):
        return not (ta == tb == "plane")
    if method in ("gjk_epa", "mpr"):
        return not plane
    if method == "analytic":
        if plane:
            return not (ta == tb == "plane")
        if frozenset((ta, tb)) in _CLOSED:
            return True
        other = shape_b if ta == "sphere" else shape_a
        return ({ta, tb} == {"sphere", "ellipsoid"} and not other.get("margin", 0.0))
    # ellipsoid_exact / ellipsoid_sampled
    return all(s["type"] in ("sphere", "ellipsoid") and not s.get("margin", 0.0)
               for s in (shape_a, shape_b))


# --- checks -------------------------------------------------------------------------------
class Stats:
    def __init__(self, method):
        self.method = method
        self.calls = self.failed = self.nan = self.other = self.disagree = 0
        self.api = 0
        self.slowest = 0.0
        self.slowest_repro = ""


def _touching(st):
    return (st == ST_TOUCHING) | (st == ST_PENETRATING)


def check_pairs(batch, methods, time_bound=0.05, api_every=0, report=print, stats=None,
                rng=None):
    """Run ``methods`` (names of METHODS) on every pair of ``batch`` and check each call
    (module docstring).  Failures go to ``report`` as one line each; returns
    {method: Stats} (accumulated into ``stats`` when given)."""
    stats = stats if stats is not None else {}
    n = batch.n
    scale = batch.scale
    ref_out, ref_st = batch.run(M_AUTO)
    ref_d = ref_out[:, OUT_DIST]
    ref_touch = _touching(ref_st)
    sa_sb = [batch.shapes(k) for k in range(n)]
    for name in methods:
        s = stats.setdefault(name, Stats(name))
        code = METHOD_NAMES.index("auto" if name == "distance" else name)
        runs = np.array([runs_pair(name, a, b) for a, b in sa_sb])
        problems = {}                      # pair -> list of what failed

        def flag(mask, what):
            for k in np.flatnonzero(mask):
                problems.setdefault(int(k), []).append(what)

        if name == "distance":
            out, st = ref_out, ref_st
            dt = np.zeros(n)
        else:
            out, st, dt = batch.run_timed(code)
            par_out, par_st = batch.run(code)
            same = (par_st == st) & np.all((par_out == out) | (np.isnan(par_out)
                                                               & np.isnan(out)), axis=1)
            flag(~same, "parallel batch rows differ from one-pair calls")
        s.calls += n
        d = out[:, OUT_DIST]
        nrm = out[:, OUT_NORMAL:OUT_NORMAL + 3]
        pa, pb = out[:, OUT_PA:OUT_PA + 3], out[:, OUT_PB:OUT_PB + 3]
        known = np.isin(st, (ST_SEPARATED, ST_TOUCHING, ST_PENETRATING, ST_FAILED,
                             ST_NOT_RUN))
        flag(~known, "unknown status")
        failed = st == ST_FAILED
        flag(failed, "FAILED")
        s.failed += int(failed.sum())
        flag(runs & (st == ST_NOT_RUN), "NOT_RUN on a pair the method takes")
        flag(~runs & (st != ST_NOT_RUN), "ran on a pair the method does not take")
        ran = runs & known & (st != ST_NOT_RUN)
        finite = np.all(np.isfinite(out[:, :OUT_PB + 3]), axis=1)
        flag(ran & ~finite, "NaN/Inf in the output")
        s.nan += int((ran & ~finite).sum())
        ok = ran & finite & ~failed
        touch = _touching(st)
        flag(ok & (np.abs(np.linalg.norm(nrm, axis=1) - 1.0) > SELF_TOL), "normal not unit")
        ell = name.startswith("ellipsoid")
        band = TOUCH_TOL * scale
        if not ell:
            rule = np.where(d > band, ST_SEPARATED,
                            np.where(d < -band, ST_PENETRATING, ST_TOUCHING))
            flag(ok & (st != rule), "status against the touching rule on its distance")
        witness = ok & ~((code == M_MPR) & (st == ST_SEPARATED))
        gap = np.linalg.norm(pb - pa - d[:, None] * nrm, axis=1)
        flag(witness & (gap > DEPTH_TOL * scale),
             "point_b - point_a != distance * normal")
        # moving B by the depth along the normal separates the pair (auto judges)
        sep = np.flatnonzero(ok & touch)
        if len(sep):
            moved = batch.pos.copy()
            shift = np.maximum(0.0, -d[sep]) + SELF_TOL * scale[sep]
            moved[2 * sep + 1] += shift[:, None] * nrm[sep]
            mo, ms = batch.run(M_AUTO, pos=moved)
            still = (mo[sep, OUT_DIST] < -DEPTH_TOL * scale[sep]) & (ms[sep] != ST_FAILED)
            bad = np.zeros(n, bool)
            bad[sep[still]] = True
            flag(bad, "B moved by the depth along the normal still penetrates")
        # agreement with auto
        refok = (ref_st != ST_FAILED) & (ref_st != ST_NOT_RUN) & np.isfinite(ref_d)
        cmp = ok & refok
        outside = np.abs(ref_d) > (ELL_BAND if ell else BAND) * scale
        if name == "ellipsoid_sampled":
            dis = cmp & outside & touch & ~ref_touch
        else:
            dis = cmp & outside & (touch != ref_touch)
        tol = DEPTH_TOL * scale
        if code == M_MPR:
            dis |= cmp & touch & ref_touch & (-d < -ref_d - tol)
            dis |= cmp & (st == ST_SEPARATED) & ((d < 0.0) | (d > ref_d + tol))
        else:
            dis |= cmp & (np.abs(d - ref_d) > tol)
        flag(dis, "disagrees with auto")
        s.disagree += int(dis.sum())
        # time per call
        slow = np.flatnonzero(dt > time_bound)
        for k in slow:
            if min(batch.time_one(code, k) for _ in range(2)) > time_bound:
                problems.setdefault(int(k), []).append(f"slower than {time_bound} s")
        if n and dt.max() > s.slowest:
            k = int(np.argmax(dt))
            s.slowest = float(dt[k])
            a, b = sa_sb[k]
            s.slowest_repro = f"{a['type']}-{b['type']} [{REGIMES[batch.regime[k]]}]"
        # the public API on a subset
        if api_every:
            for k in range(0, n, api_every):
                a, b = sa_sb[k]
                (pa_, qa), (pb_, qb) = batch.poses(k)
                t0 = time.perf_counter()
                r = (distance(a, (pa_, qa), b, (pb_, qb)) if name == "distance"
                     else collide(a, (pa_, qa), b, (pb_, qb), method=name))
                t_api = time.perf_counter() - t0
                s.api += 1
                if name == "distance" and t_api > s.slowest:
                    s.slowest = t_api
                    s.slowest_repro = f"{a['type']}-{b['type']} [{REGIMES[batch.regime[k]]}]"
                if int(r.status) == ST_NOT_RUN and st[k] == ST_NOT_RUN:
                    continue
                bad = not np.all(np.isfinite(np.r_[r.distance, r.normal, r.point_a,
                                                   r.point_b]))
                if abs(out[k, OUT_DIST]) > BAND * scale[k] and ok[k]:
                    bad |= _touching(np.int64(r.status)) != touch[k]
                if ok[k] and code != M_MPR:
                    bad |= abs(r.distance - out[k, OUT_DIST]) > tol[k]
                bad |= (int(r.status) == ST_FAILED) != bool(failed[k])
                if bad:
                    problems.setdefault(k, []).append(
                        f"public API answer {r.status.name} {r.distance!r} differs from "
                        f"the batch row {int(st[k])} {out[k, OUT_DIST]!r}")
        s.other += sum(1 for v in problems.values()
                       if any(w not in ("FAILED", "NaN/Inf in the output",
                                        "disagrees with auto") for w in v))
        for k, whats in sorted(problems.items()):
            report(f"FUZZ {name} [{REGIMES[batch.regime[k]]}] {'; '.join(whats)}: status "
                   f"{int(st[k])} d {out[k, OUT_DIST]!r} (auto {int(ref_st[k])} "
                   f"{ref_d[k]!r}, scale {scale[k]!r}); repro: {batch.repro(k, name)}")
    return stats


def table(stats):
    """The summary as a Markdown table."""
    rows = ["| method | calls | FAILED | NaN | other failures | disagreements | "
            "slowest call (ms) | API calls |",
            "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for s in stats.values():
        rows.append(f"| {s.method} | {s.calls:,} | {s.failed} | {s.nan} | {s.other} | "
                    f"{s.disagree} | {1e3 * s.slowest:.2f} | {s.api:,} |")
    return "\n".join(rows)
