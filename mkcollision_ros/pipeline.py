"""The scene pipeline: poses in, persistent contacts out.  Plain Python, no rclpy.

    from mkcollision_ros.pipeline import Pipeline, PipelineConfig
    p = Pipeline(bodies, config=PipelineConfig())
    res = p.step(positions, orientations, stamp)      # -> StepResult

One step runs, in order (each phase timed in ``StepResult.timings``, seconds):
  bounds       world AABBs of every body from its support function (kernels/broadphase)
  broadphase   a hashed uniform grid: exactly the pairs whose AABBs (grown by
               proximity / 2 each) overlap; planes against every body reaching their
               half-space
  filter       drop static-static pairs, pairs failing the group/mask test
               ``(group_i & mask_j) and (group_j & mask_i)``, and the allowed pairs
               (``config.allowed_pairs``, names, MoveIt's allowed-collision idea)
  narrowphase  kernels/narrowphase.collide_batch with ``config.method``; pairs with a
               plane always use the closed form (``auto``), as GJK/EPA and MPR do not
               take unbounded shapes.  Distance cutoff 0 (contacts only): only
               touching pairs are kept, so a pair stops as soon as it is proved apart
               (bounding spheres, a box-box separating axis, GJK's bound) instead of
               refining a distance nobody reads
  manifold     face clipping for face-on-face contacts (kernels/manifold), else one point
  arbiters     persistent contacts with stable ids and events (arbiters.py)

Frames and signs (see results.py): world frame, metres; normals unit from body_a to
body_b with body_a < body_b; depth >= 0; point_b - point_a = -depth * normal for a
penetrating contact.  Quaternions are xyzw.
"""
import contextlib
import math
import time
from dataclasses import dataclass, field, fields

import numba
import numpy as np

from .arbiters import ArbiterSet, Events
from .kernels.broadphase import filter_pairs, find_pairs, normalise_poses, world_aabbs
from .kernels.constants import M_AUTO, METHOD_NAMES, OUT_SIZE, PLANE, ST_FAILED
from .kernels.manifold import MAX_MANIFOLD, manifold_batch, split_pairs
from .kernels.narrowphase import collide_batch
from .results import ContactSet
from .shapes import build_table

# distance cutoff of the narrow phase (m): the step keeps touching pairs only
_CONTACTS_ONLY = 0.0

PIPELINE_METHODS = ("auto", "gjk_epa", "mpr")
BODY_KEYS = {"name", "shape", "static", "group", "mask"}
MAX_BITS = 0xFFFFFFFF
# narrow-phase batches at least this long run on all of numba's threads, shorter ones
# with numba.set_num_threads(1): waking a second thread costs up to milliseconds on a
# loaded machine.  256 pairs are ~0.5-2 ms of work (2-10 us a pair); on the 1,000-body
# bench scene (442 pairs) two threads took the narrow phase from 2.2 to 1.65 ms (it was
# 2048 while a pair cost 3-4x more).  Same compiled kernels, so the same numbers.
PARALLEL_MIN_ITEMS = 256
# the same for the cheap phases (bounds, broad phase, manifolds: 0.02-1 us per item).
# Measured on the shared 2-core machine (bench scenes, 10,000 bodies): two threads made
# the bounds 15-30x SLOWER (0.2 ms on one thread, 5-7 ms on two while the other core
# was busy) and the broad phase 1.5-3x slower; a parallel region only pays when the
# second core is idle and the work is many milliseconds.  Re-measured in session 3
# (bench scenes, whole step, threshold 200,000 vs 1,000): with the other core idle, two
# threads were 5-12% faster (1k bodies 1.47 -> 1.46 and 8.0 -> 7.0 ms; 10k 12.5 -> 11.0
# and 80.7 -> 71.6 ms); with a busy loop on the other core, 10k bodies at density 2
# went 128-135 -> 154 ms (broad phase 13 -> 24 ms).  A node runs beside other work, so
# the default stays on one thread; set ``Pipeline.parallel_min_cheap_items`` lower on
# a machine with idle cores.
PARALLEL_MIN_CHEAP_ITEMS = 200_000


@contextlib.contextmanager
def _threads(n_items, parallel_min):
    """Run the enclosed kernels on one thread when the batch is short."""
    before = numba.get_num_threads()
    if n_items >= parallel_min or before == 1:
        yield
        return
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


@dataclass
class PipelineConfig:
    """Settings of a Pipeline (SI units).

    method          "auto" (closed forms, else GJK/EPA), "gjk_epa" or "mpr"
    proximity       m >= 0: pairs whose AABBs are this close are candidates
    merge_distance  m > 0: a new contact this close to a stored one keeps its id
    drift_threshold m > 0: a stored contact whose points separate along the normal, or
                    slide across it, by more than this is dropped; clipped manifold
                    points up to this far outside the reference face are kept
    max_contacts    >= 1 contacts per pair (deepest plus largest area)
    stale_steps     >= 1: steps a touching pair survives without the narrow phase
                    confirming it (failed / not run) before it ends
    allowed_pairs   [[name, name], ...] pairs that never collide
    """
    method: str = "auto"
    proximity: float = 0.0
    merge_distance: float = 0.02
    drift_threshold: float = 0.01
    max_contacts: int = 4
    stale_steps: int = 3
    allowed_pairs: list = field(default_factory=list)

    @classmethod
    def from_dict(cls, d):
        """Build from a dict (YAML); unknown keys raise ValueError."""
        if not isinstance(d, dict):
            raise ValueError(f"pipeline config must be a dict, got {d!r}")
        known = {f.name for f in fields(cls)}
        unknown = set(d) - known
        if unknown:
            raise ValueError(f"pipeline config: unknown key(s) {sorted(unknown)}; "
                             f"expected {sorted(known)}")
        cfg = cls(**d)
        cfg.validate()
        return cfg

    def validate(self):
        """Raise ValueError naming the first bad setting."""
        if self.method not in PIPELINE_METHODS:
            raise ValueError(f"pipeline config: method must be one of {PIPELINE_METHODS}, "
                             f"got {self.method!r}")
        for name, lo, strict in (("proximity", 0.0, False), ("merge_distance", 0.0, True),
                                 ("drift_threshold", 0.0, True)):
            v = getattr(self, name)
            if (isinstance(v, bool) or not isinstance(v, (int, float))
                    or not math.isfinite(v) or (v <= lo if strict else v < lo)):
                raise ValueError(f"pipeline config: {name} must be a finite number "
                                 f"{'>' if strict else '>='} {lo}, got {v!r}")
        for name in ("max_contacts", "stale_steps"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"pipeline config: {name} must be an integer >= 1, got {v!r}")
        if not isinstance(self.allowed_pairs, (list, tuple)):
            raise ValueError("pipeline config: allowed_pairs must be a list of [name, name]")
        for p in self.allowed_pairs:
            if (not isinstance(p, (list, tuple)) or len(p) != 2
                    or not all(isinstance(x, str) for x in p)):
                raise ValueError(f"pipeline config: allowed_pairs entries must be "
                                 f"[name, name], got {p!r}")


@dataclass
class StepResult(ContactSet):
    """Contacts of one step, world frame, metres; C contacts over K touching pairs.
    The contact fields are those of ``results.ContactSet``; a step adds the rest.

    names list[str] (N,); stamp float (s, as given)
    pairs int64 (K, 2): touching pairs (a < b), sorted
    body_a, body_b int64 (C,); contact_id int64 (C,) stable while the contact persists;
    age int64 (C,) steps since it began (0 on its first step)
    position (C, 3) midpoint of the witness points; point_a, point_b (C, 3) on A and B;
    normal (C, 3) unit, A -> B; depth (C,) >= 0
    method int64 (C,) method code of the pair's narrow phase (constants.M_*);
    status int64 (C,) the pair's status this step (constants.ST_*)
    events arbiters.Events: arrays kind (EV_BEGAN / EV_PERSISTED / EV_ENDED), body_a,
        body_b, contact_id (-1 for pair events); iterates as tuples (kind name
        "began" / "persisted" / "ended", body_a, body_b, contact_id)
    names is the pipeline's own list (shared between steps: do not modify it)
    timings dict phase -> seconds; n_candidate_pairs: broad-phase pairs before the filter;
    n_narrowphase_pairs: pairs after the filter
    """
    stamp: float
    pairs: np.ndarray
    events: Events
    timings: dict
    n_candidate_pairs: int
    n_narrowphase_pairs: int


def _validate_bodies(bodies):
    if not isinstance(bodies, (list, tuple)) or not bodies:
        raise ValueError("bodies must be a non-empty list of dicts")
    names, shapes, static, group, mask = [], [], [], [], []
    for k, b in enumerate(bodies):
        if not isinstance(b, dict):
            raise ValueError(f"body {k}: must be a dict, got {b!r}")
        unknown = set(b) - BODY_KEYS
        if unknown:
            raise ValueError(f"body {k}: unknown key(s) {sorted(unknown)}; "
                             f"expected {sorted(BODY_KEYS)}")
        name = b.get("name")
        if not isinstance(name, str) or not name:
            raise ValueError(f"body {k}: 'name' must be a non-empty string, got {name!r}")
        if name in names:
            raise ValueError(f"body {k}: duplicate name {name!r}")
        if "shape" not in b:
            raise ValueError(f"body {name!r}: missing 'shape'")
        st = b.get("static", False)
        if not isinstance(st, (bool, np.bool_)):
            raise ValueError(f"body {name!r}: 'static' must be a bool, got {st!r}")
        bits = []
        for key, default in (("group", 1), ("mask", MAX_BITS)):
            v = b.get(key, default)
            if (isinstance(v, bool) or not isinstance(v, (int, np.integer))
                    or not 0 <= v <= MAX_BITS):
                raise ValueError(f"body {name!r}: '{key}' must be an integer in "
                                 f"[0, 0xFFFFFFFF], got {v!r}")
            bits.append(int(v))
        try:
            build_table([b["shape"]])
        except ValueError as e:
            raise ValueError(f"body {name!r}: {e}") from None
        names.append(name)
        shapes.append(b["shape"])
        static.append(bool(st))
        group.append(bits[0])
        mask.append(bits[1])
    return (names, shapes, np.array(static, bool), np.array(group, np.int64),
            np.array(mask, np.int64))


class Pipeline:
    """Bodies -> contacts, step by step.  See the module docstring for the phases.

    bodies: list of dicts {"name": str, "shape": shape dict (shapes.py),
        "static": bool = False, "group": int = 1, "mask": int = 0xFFFFFFFF}.
    config: PipelineConfig.  Invalid bodies or settings raise ValueError.
    """

    def __init__(self, bodies, config=None):
        self.config = PipelineConfig() if config is None else config
        if not isinstance(self.config, PipelineConfig):
            raise ValueError(f"config must be a PipelineConfig, got {type(self.config).__name__}")
        self.config.validate()
        self.names, shapes, self.static, self.group, self.mask = _validate_bodies(bodies)
        self.table = build_table(shapes)
        self.n = len(self.names)
        index = {nm: i for i, nm in enumerate(self.names)}
        acm = []
        for pa, pb in self.config.allowed_pairs:
            for nm in (pa, pb):
                if nm not in index:
                    raise ValueError(f"pipeline config: allowed_pairs names unknown body {nm!r}")
            i, j = sorted((index[pa], index[pb]))
            acm.append(i * self.n + j)
        self._acm = np.unique(np.array(acm, np.int64))
        self._is_plane = self.table.codes == PLANE
        self._method = METHOD_NAMES.index(self.config.method)
        self._order = np.empty(0, np.int64)
        self._axis = -1
        self._buffers = {}
        # batches this long or longer use the threaded kernels (read at each step)
        self.parallel_min_items = PARALLEL_MIN_ITEMS
        self.parallel_min_cheap_items = PARALLEL_MIN_CHEAP_ITEMS
        self.arbiters = ArbiterSet(self.config.merge_distance, self.config.drift_threshold,
                                   self.config.max_contacts, self.config.stale_steps,
                                   n_bodies=self.n)

    # ------------------------------------------------------------------------------
    def _check_poses(self, positions, orientations):
        try:
            pos = np.ascontiguousarray(positions, dtype=np.float64)
            quat = np.ascontiguousarray(orientations, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError("positions and orientations must be numeric arrays") from None
        if pos.shape != (self.n, 3) or quat.shape != (self.n, 4):
            raise ValueError(f"expected positions ({self.n}, 3) and orientations "
                             f"({self.n}, 4) quat_xyzw, got {pos.shape} and {quat.shape}")
        unit = np.empty((self.n, 4))
        i, why = normalise_poses(pos, quat, unit)
        if i >= 0:
            why = ("non-finite position", "non-finite quaternion", "zero quaternion")[why - 1]
            raise ValueError(f"body {i} ({self.names[i]!r}): {why}")
        return pos, unit

    def _buffer(self, name, shape, dtype=np.float64):
        """A scratch array reused from step to step (grown by 1.5x when too short);
        only for data that does not leave the step."""
        buf = self._buffers.get(name)
        if buf is None or buf.shape[0] < shape[0]:
            buf = np.empty((max(shape[0], int(1.5 * (0 if buf is None else buf.shape[0])), 1),)
                           + tuple(shape[1:]), dtype)
            self._buffers[name] = buf
        return buf

    def step(self, positions, orientations, stamp=0.0):
        """Run one step.

        positions float64 (N, 3) world (m); orientations float64 (N, 4) quat_xyzw (any
        non-zero norm, normalised here); stamp: time (s), passed through.
        Raises ValueError naming the body on non-finite values or zero quaternions.
        Returns a StepResult.
        """
        t = self.table
        timings = {}
        pos, quat = self._check_poses(positions, orientations)
        try:
            stamp = float(stamp)
        except (TypeError, ValueError):
            raise ValueError(f"stamp must be a number, got {stamp!r}") from None
        par = self.parallel_min_items
        cheap = self.parallel_min_cheap_items

        t0 = time.perf_counter()
        lo = self._buffer("lo", (self.n, 3))
        hi = self._buffer("hi", (self.n, 3))
        plane_w = self._buffer("plane_w", (self.n, 4))
        with _threads(self.n, cheap):
            world_aabbs(t.codes, t.params, t.vrange, t.verts, pos, quat,
                        0.5 * self.config.proximity, lo, hi, plane_w)
        t1 = time.perf_counter()
        timings["bounds"] = t1 - t0

        with _threads(self.n, cheap):
            cand, self._order, self._axis = find_pairs(lo, hi, self._is_plane, plane_w,
                                                       self._order, int(self._axis))
        t2 = time.perf_counter()
        timings["broadphase"] = t2 - t1

        pairs = filter_pairs(cand, self.static, self.group, self.mask, self._acm, self.n)
        t3 = time.perf_counter()
        timings["filter"] = t3 - t2

        npairs = len(pairs)
        out = self._buffer("out", (npairs, OUT_SIZE))[:npairs]
        status = self._buffer("status", (npairs,), np.int64)[:npairs]
        if self._method == M_AUTO:
            # pairs with a plane use the closed form (auto) whatever the method
            with _threads(npairs, par):
                collide_batch(t.codes, t.params, t.vrange, t.verts, pairs, pos, quat,
                              M_AUTO, _CONTACTS_ONLY, out, status)
        else:
            has_plane = self._is_plane[pairs[:, 0]] | self._is_plane[pairs[:, 1]]
            for sel, method in ((has_plane, M_AUTO), (~has_plane, self._method)):
                idx = np.flatnonzero(sel)
                if len(idx):
                    o = np.empty((len(idx), OUT_SIZE))
                    s = np.empty(len(idx), np.int64)
                    with _threads(len(idx), par):
                        collide_batch(t.codes, t.params, t.vrange, t.verts,
                                      np.ascontiguousarray(pairs[idx]), pos, quat, method,
                                      _CONTACTS_ONLY, o, s)
                    out[idx] = o
                    status[idx] = s
        t4 = time.perf_counter()
        timings["narrowphase"] = t4 - t3

        # touching pairs -> manifolds; failed / not-run pairs keep their arbiters a while
        rows = [self._buffer(f"split{k}", (npairs,), np.int64) for k in range(8)]
        nt, nu = split_pairs(pairs, out, status, self.n, ST_FAILED, *rows)
        cpts = self._buffer("cpts", (nt, MAX_MANIFOLD, 7))
        cnormal = self._buffer("cnormal", (nt, 3))
        ccount = self._buffer("ccount", (nt,), np.int64)
        if nt:
            with _threads(nt, cheap):
                manifold_batch(t.codes, t.params, t.vrange, t.verts, pairs, rows[0][:nt],
                               pos, quat, out, self.config.drift_threshold, cpts, cnormal,
                               ccount)
        t5 = time.perf_counter()
        timings["manifold"] = t5 - t4

        events = self.arbiters.update_arrays(
            pos, quat, rows[1][:nt], cpts, cnormal, ccount, rows[5][:nu],
            rows[2][:nt], rows[3][:nt], rows[6][:nu], rows[7][:nu])
        con = self.arbiters.contacts()
        t6 = time.perf_counter()
        timings["arbiters"] = t6 - t5

        return StepResult(
            names=self.names, stamp=stamp,
            pairs=self.arbiters.pairs(),
            body_a=con["body_a"], body_b=con["body_b"],
            position=0.5 * (con["point_a"] + con["point_b"]),
            point_a=con["point_a"], point_b=con["point_b"], normal=con["normal"],
            depth=con["depth"], contact_id=con["contact_id"], age=con["age"],
            method=con["method"], status=con["status"], events=events, timings=timings,
            n_candidate_pairs=int(len(cand)), n_narrowphase_pairs=int(npairs))

    def warm_up(self):
        """Compile (or load from the on-disk cache) every kernel on a tiny scene, so the
        first real step does not wait for the compiler.  Leaves this pipeline's state
        untouched."""
        tiny = Pipeline([
            {"name": "plane", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0},
             "static": True},
            {"name": "box", "shape": {"type": "box", "size": [1.0, 1.0, 1.0]}},
            {"name": "ball", "shape": {"type": "sphere", "radius": 0.5}},
        ], PipelineConfig(method=self.config.method))
        pos = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.49], [0.0, 0.0, 1.45]])
        quat = np.tile([0.0, 0.0, 0.0, 1.0], (3, 1))
        tiny.step(pos, quat, 0.0)
        tiny.step(pos, quat, 0.0)
