"""The scene pipeline: a scene's poses in, persistent contacts and proximity pairs out.
Plain Python + numba, no rclpy.

    from mkcollision_ros.pipeline import Pipeline, PipelineConfig
    p = Pipeline(bodies, config=PipelineConfig())      # or Pipeline(scene)
    res = p.step(positions, orientations, stamp)       # -> StepResult
    p.scene.add_body({...}); p.scene.remove_body("crate")   # edits between steps
    p.configure(contact_margin=0.002, method="mpr")          # settings between steps
    res = p.step()                                     # the scene's own poses
    p = Pipeline(bodies, rerun="save:run.rrd")         # log each step (rerun_log.py)

One step runs, in order (each phase timed in ``StepResult.timings``, seconds):
  edits        arbiters of bodies removed or given a new shape since the last step end,
               with events (scene.take_ended, ArbiterSet.end_bodies)
  bounds       world AABBs of every body from its support function (kernels/broadphase),
               grown by half the reach, reach = max(contact_margin, proximity)
  broadphase   a hashed uniform grid: exactly the pairs whose grown AABBs overlap;
               planes against every body reaching their half-space; only bodies that
               have a pose take part.  Static-heavy scenes (STATIC_GRID_MIN): the static
               bodies' grid is kept from step to step and queried with the other
               bodies' boxes, which alone are boxed each step, so a step costs
               O(moving bodies) and finds no static-static pair
  filter       drop static-static pairs, pairs failing the group/mask test
               ``(group_i & mask_j) and (group_j & mask_i)``, and the scene's allowed
               pairs (MoveIt's allowed-collision idea)
  narrowphase  kernels/narrowphase.collide_batch with ``config.method``, exact up to the
               reach (farther pairs stop at a certified lower bound); pairs with a plane
               always use the closed form (``auto``), as GJK/EPA and MPR do not take
               unbounded shapes (query.collide_pairs, shared with check_collision)
  classify     touching pairs (the narrow phase's touching rule, the same as
               ``collide``'s, or an existing arbiter within ``contact_margin``: the
               hysteresis below), proximity pairs, and undecided pairs (failed, not run)
  manifold     face clipping for face-on-face contacts (kernels/manifold), else one point
  arbiters     persistent contacts with stable ids and events (arbiters.py)

Contact margin (Bullet's contact breaking threshold): a pair begins touching when the
narrow phase finds it touching or penetrating (signed distance <= TOUCH_TOL x scale,
the rule ``collide`` uses, so a fresh pair touches in the pipeline iff ``collide`` says
so), and keeps touching, with its contacts and ids, while its distance stays within
``contact_margin``; it ends beyond.  The default, 1 mm, is above the jitter of a
resting body in a simulator or under motion capture (micrometres to a fraction of a
millimetre a frame), so a pair at rest does not end and begin again every frame, and
well below the size of the parts a robot handles, so a pair that lifts off ends within
a millimetre.  A held pair's contacts have depth 0, status TOUCHING and
``point_b - point_a`` the (positive) gap along the normal.

Proximity: pairs within ``proximity`` (m) that are not touching come back in
``StepResult.proximity`` with their signed distance, closest points and normal (the
narrow phase's exact distance); they have no arbiters.

Frames and signs (see results.py): world frame, metres; normals unit from body_a to
body_b with body_a < body_b (scene slots); depth >= 0; point_b - point_a = -depth *
normal for a penetrating contact.  Quaternions are xyzw.
"""
import contextlib
import dataclasses
import math
import time
from dataclasses import dataclass, fields
from typing import NamedTuple

import numba
import numpy as np

from .arbiters import ArbiterSet, Events, body_hashes
from .kernels.broadphase import (filter_pairs, find_pairs, normalise_poses, poses_unchanged,
                                 static_grid, static_pairs, world_aabbs)
from .kernels.constants import (M_AUTO, METHOD_NAMES, OUT_DIST, OUT_METHOD, OUT_NORMAL,
                                OUT_PA, OUT_PB, OUT_SIZE, ST_FAILED, ST_NOT_RUN,
                                ST_SEPARATED, ST_TOUCHING)
from .kernels.manifold import MAX_MANIFOLD, manifold_batch, split_pairs
from .kernels.persistence import pair_shards
from .query import collide_pairs
from .results import ContactSet
from .scene import KEY_BASE, Scene

PIPELINE_METHODS = ("auto", "gjk_epa", "mpr")
# narrow-phase batches at least this long run on all of numba's threads, shorter ones
# on one: waking a second thread costs up to milliseconds on a loaded machine, and 256
# pairs are ~0.5-2 ms of work (2-10 us a pair)
PARALLEL_MIN_ITEMS = 256
# the same for the cheap phases (bounds, broad phase, manifolds: 0.02-1 us per item):
# they gain from a second thread only when it is idle and the work is many
# milliseconds, and lose several times over when the other core is busy, as beside
# other work in a robot; ``Pipeline.parallel_min_cheap_items`` lowers it
PARALLEL_MIN_CHEAP_ITEMS = 200_000


# The broad phase keeps a grid of the static bodies (kernels/broadphase.static_grid)
# and queries it with the others' boxes (static_pairs) when at least this many bodies
# are static and they outnumber the others, so that a step costs O(moving bodies):
# static bodies are never boxed or gridded again while they keep their poses, and
# static-static pairs are never found (bench/static_heavy.py).  Below it the one grid of
# every body costs about the same.
STATIC_GRID_MIN = 1000


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


def _number_ok(v, lo, strict):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer,
                                                             np.floating)):
        return False
    return math.isfinite(v) and (v > lo if strict else v >= lo)


@dataclass
class PipelineConfig:
    """Settings of a Pipeline (SI units); ``Pipeline.configure`` changes them between
    steps.

    method          "auto" (closed forms, else GJK/EPA), "gjk_epa" or "mpr"
    contact_margin  m >= 0: a touching pair keeps touching while its distance is within
                    this (the hysteresis in the module docstring)
    proximity       m >= 0: pairs this close but not touching are proximity pairs
    merge_distance  m > 0: a new contact this close to a stored one keeps its id
    drift_threshold m > 0: a stored contact whose points separate along the normal, or
                    slide across it, by more than this is dropped; clipped manifold
                    points up to this far outside the reference face are kept
    max_contacts    >= 1 contacts per pair (deepest plus largest area)
    stale_steps     >= 1: steps a touching pair survives without the narrow phase
                    confirming it (failed / not run) before it ends
    max_pairs       >= 0: narrow-phase pairs per step, 0 for no cap; beyond it the
                    step runs the first max_pairs pairs (in key order), the rest are
                    NOT_RUN (their arbiters live on for stale_steps) and
                    ``StepResult.n_truncated_pairs`` counts them
    shard_index, shard_count  0 <= shard_index < shard_count: this pipeline answers
                    only the pairs of its shard (kernels/persistence.pair_shards); 0, 1:
                    every pair
    """
    method: str = "auto"
    contact_margin: float = 0.001
    proximity: float = 0.0
    merge_distance: float = 0.02
    drift_threshold: float = 0.01
    max_contacts: int = 4
    stale_steps: int = 3
    max_pairs: int = 0
    shard_index: int = 0
    shard_count: int = 1

    @classmethod
    def from_dict(cls, d):
        """Build from a dict (YAML); unknown keys raise ValueError."""
        if not isinstance(d, dict):
            raise ValueError(f"pipeline config must be a dict, got {d!r}")
        cfg = cls()
        return cfg.replace(**d)

    def replace(self, **changes):
        """A validated copy with ``changes``; ValueError naming the setting and the
        reason, for an unknown name or a bad value."""
        known = {f.name for f in fields(self)}
        unknown = set(changes) - known
        if unknown:
            raise ValueError(f"pipeline config: unknown setting(s) {sorted(unknown)}; "
                             f"expected {sorted(known)}")
        new = dataclasses.replace(self, **changes)
        new.validate()
        return new

    def validate(self):
        """Raise ValueError naming the first bad setting and why."""
        if self.method not in PIPELINE_METHODS:
            raise ValueError(f"pipeline config: method must be one of {PIPELINE_METHODS}, "
                             f"got {self.method!r}")
        for name, strict in (("contact_margin", False), ("proximity", False),
                             ("merge_distance", True), ("drift_threshold", True)):
            v = getattr(self, name)
            if not _number_ok(v, 0.0, strict):
                raise ValueError(f"pipeline config: {name} must be a finite number "
                                 f"{'>' if strict else '>='} 0 (m), got {v!r}")
        for name, lo in (("max_contacts", 1), ("stale_steps", 1), ("max_pairs", 0),
                         ("shard_count", 1), ("shard_index", 0)):
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) \
                    or v < lo:
                raise ValueError(f"pipeline config: {name} must be an integer >= {lo}, "
                                 f"got {v!r}")
        if self.shard_index >= self.shard_count:
            raise ValueError(f"pipeline config: shard_index must be below shard_count "
                             f"({self.shard_count}), got {self.shard_index}")


@dataclass
class ProximitySet:
    """Pairs within the proximity distance that do not touch, world frame, metres.

    body_a, body_b int64 (P,) slots (a < b), sorted; distance float64 (P,) > 0;
    point_a, point_b float64 (P, 3) closest points on A and B; normal float64 (P, 3)
    unit, A -> B, with point_b - point_a = distance * normal."""
    body_a: np.ndarray
    body_b: np.ndarray
    distance: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray

    def __len__(self):
        return len(self.body_a)


@dataclass
class StepResult(ContactSet):
    """Contacts of one step, world frame, metres; C contacts over K touching pairs.
    The contact fields are those of ``results.ContactSet``; a step adds the rest.

    names list[str | None] (S,) slot -> name (None: a free slot; a body removed before
    this step keeps its name here, for its ended events); stamp float (s)
    pairs int64 (K, 2): touching pairs (a < b), sorted
    body_a, body_b int64 (C,) slots; contact_id int64 (C,) stable while the contact
    persists; age int64 (C,) steps since it began (0 on its first step)
    position (C, 3) midpoint of the witness points; point_a, point_b (C, 3) on A and B;
    normal (C, 3) unit, A -> B; depth (C,) >= 0
    method int64 (C,) method code of the pair's narrow phase (constants.M_*);
    status int64 (C,) the pair's status this step (constants.ST_*)
    proximity ProximitySet: near pairs that do not touch (empty when proximity is 0)
    events arbiters.Events: arrays kind (EV_BEGAN / EV_PERSISTED / EV_ENDED), body_a,
        body_b, contact_id (-1 for pair events); iterates as tuples (kind name
        "began" / "persisted" / "ended", body_a, body_b, contact_id).  The pairs ended
        by edits (a removed body) come first.
    names is the scene's own list, unless bodies were removed (do not modify it)
    timings dict phase -> seconds; n_candidate_pairs: broad-phase pairs before the
    filter; n_narrowphase_pairs: pairs after the filter; n_failed_pairs: pairs whose
    narrow phase failed (status FAILED: an iteration cap, a degenerate input or a
    non-finite result); their arbiters live on for ``stale_steps``; failed_pairs
    int64 (F, 2) those pairs; n_truncated_pairs: pairs not run for ``max_pairs``
    """
    stamp: float
    pairs: np.ndarray
    proximity: ProximitySet
    events: Events
    timings: dict
    n_candidate_pairs: int
    n_narrowphase_pairs: int
    n_failed_pairs: int
    failed_pairs: np.ndarray
    n_truncated_pairs: int


class Bounds(NamedTuple):
    """World AABBs lo, hi float64 (R, 3) m and planes' grown half-spaces plane_w (R, 4)
    of the slots ``slots`` int64 (R,) increasing, or of every slot (None)."""
    lo: np.ndarray
    hi: np.ndarray
    plane_w: np.ndarray
    slots: np.ndarray = None


class StaticIndex(NamedTuple):
    """The static bodies' grid (kernels/broadphase.static_grid), kept from step to step
    while the scene, the reach and the static bodies' poses stay the same."""
    key: tuple           # (scene version, reach)
    slots: np.ndarray    # int64 (S,) the static non-plane slots that take part
    pos: np.ndarray      # their positions and orientations when it was built
    quat: np.ndarray
    lo: np.ndarray       # their grown world AABBs
    hi: np.ndarray
    grid: tuple          # static_grid's (frame, keys, members, start, big)


class NarrowPhase(NamedTuple):
    """pairs int64 (P, 2); out float64 (P, OUT_SIZE) world rows; status int64 (P,)."""
    pairs: np.ndarray
    out: np.ndarray
    status: np.ndarray


class Classified(NamedTuple):
    """The narrow phase's pairs sorted out: rows into NarrowPhase and sorted pair keys
    (a * KEY_BASE + b) with the status and method codes, int64 each.
    touching_*: touching or held by the margin (T,); undecided_*: failed or not run
    (U,); proximity_rows: within the proximity distance, not touching (Q,)."""
    touching_rows: np.ndarray
    touching_keys: np.ndarray
    touching_status: np.ndarray
    touching_method: np.ndarray
    undecided_keys: np.ndarray
    undecided_status: np.ndarray
    undecided_method: np.ndarray
    proximity_rows: np.ndarray


class Manifolds(NamedTuple):
    """Per touching pair: points float64 (>= T, MAX_MANIFOLD, 7), normal (>= T, 3),
    count int64 (>= T,) (kernels.manifold.manifold_batch)."""
    points: np.ndarray
    normal: np.ndarray
    count: np.ndarray


class Pipeline:
    """A scene -> contacts, step by step.  See the module docstring for the phases.

    scene: a Scene, or a list of body dicts (scene.py) to build one from.
    config: PipelineConfig.  allowed_pairs: [[name, name], ...] when ``scene`` is a
    list.  Invalid bodies or settings raise ValueError.
    """

    def __init__(self, scene, config=None, allowed_pairs=(), rerun=None, rerun_pairs=()):
        config = PipelineConfig() if config is None else config
        if not isinstance(config, PipelineConfig):
            raise ValueError(f"config must be a PipelineConfig, got {type(config).__name__}")
        config.validate()
        if isinstance(scene, Scene):
            if allowed_pairs:
                raise ValueError("allowed_pairs belong to the scene: use "
                                 "scene.set_allowed_pairs")
            self.scene = scene
        else:
            if not isinstance(scene, (list, tuple)) or not scene:
                raise ValueError("bodies must be a non-empty list of dicts")
            self.scene = Scene(scene, allowed_pairs)
        self.config = config
        self._method = METHOD_NAMES.index(config.method)
        self._order = np.empty(0, np.int64)
        self._static = None
        self._buffers = {}
        # batches this long or longer use the threaded kernels (read at each step)
        self.parallel_min_items = PARALLEL_MIN_ITEMS
        self.parallel_min_cheap_items = PARALLEL_MIN_CHEAP_ITEMS
        # at least this many static bodies, and more than the others: static grid
        self.static_grid_min = STATIC_GRID_MIN
        self.arbiters = ArbiterSet(config.merge_distance, config.drift_threshold,
                                   config.max_contacts, config.stale_steps)
        self._pending = Events.empty()
        self._hashes = np.zeros(0, np.uint64)
        self._hashes_version = -1
        self.steps = 0
        self.rerun = None
        self.set_rerun(rerun, rerun_pairs)

    def set_rerun(self, sink, pairs=(), **options):
        """Log each step to rerun (rerun_log.RerunLog: ``sink`` a rerun_log.SINK_FORMS
        string, or a RerunLog; ``pairs`` the Minkowski view's pairs; ``options`` go to
        RerunLog), or stop logging (None / "off": rerun is not imported).  The previous
        sink is closed."""
        from . import rerun_log
        if isinstance(sink, rerun_log.RerunLog):
            new = sink
        elif sink is None or rerun_log.parse_sink(sink).kind == "off":
            new = None
        else:
            new = rerun_log.RerunLog(sink, pairs, **options)
        if self.rerun is not None and self.rerun is not new:
            self.rerun.close()
        self.rerun = new

    def close(self):
        """Flush and close the rerun sink, if any."""
        self.set_rerun(None)

    def end_contacts(self):
        """End every pair's contacts now (a time reset, as when a bag loops); their
        ``ended`` events come first in the next step's result.  Contact ids keep
        counting up."""
        self._pending = Events.concat(self._pending, self.arbiters.end_all())

    @property
    def names(self):
        """Slot -> body name (None for a free slot)."""
        return self.scene.names

    def configure(self, **changes):
        """Change settings (PipelineConfig's names) before the next step, all or none:
        a bad value raises ValueError with the reason and changes nothing.  Arbiters and
        contact ids survive."""
        new = self.config.replace(**changes)
        self.config = new
        self._method = METHOD_NAMES.index(new.method)
        a = self.arbiters
        a.merge_distance, a.drift_threshold = new.merge_distance, new.drift_threshold
        a.max_contacts, a.stale_steps = new.max_contacts, new.stale_steps
        return new

    # ------------------------------------------------------------------------------
    def _buffer(self, name, shape, dtype=np.float64):
        """A scratch array reused from step to step (grown by 1.5x when too short);
        only for data that does not leave the step."""
        buf = self._buffers.get(name)
        if buf is None or buf.shape[0] < shape[0]:
            buf = np.empty((max(shape[0], int(1.5 * (0 if buf is None else buf.shape[0])), 1),)
                           + tuple(shape[1:]), dtype)
            self._buffers[name] = buf
        return buf

    def _set_all_poses(self, positions, orientations, stamp):
        """Every slot's pose at once; ValueError naming the body on bad values."""
        sc = self.scene
        n = sc.n_slots
        try:
            pos = np.ascontiguousarray(positions, dtype=np.float64)
            quat = np.ascontiguousarray(orientations, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError("positions and orientations must be numeric arrays") from None
        if pos.shape != (n, 3) or quat.shape != (n, 4):
            raise ValueError(f"expected positions ({n}, 3) and orientations "
                             f"({n}, 4) quat_xyzw, got {pos.shape} and {quat.shape}")
        slots = None if len(sc) == n else np.flatnonzero(sc.used)
        if slots is not None:
            pos, quat = np.ascontiguousarray(pos[slots]), np.ascontiguousarray(quat[slots])
        unit = self._buffer("unit", quat.shape)[:len(quat)]
        i, why = normalise_poses(pos, quat, unit)
        if i >= 0:
            slot = i if slots is None else slots[i]
            why = ("non-finite position", "non-finite quaternion", "zero quaternion")[why - 1]
            raise ValueError(f"body {slot} ({sc.names[slot]!r}): {why}")
        sc._write_poses(slots, pos, unit, stamp)

    def step(self, positions=None, orientations=None, stamp=0.0):
        """Run one step.

        positions float64 (S, 3) world (m), orientations float64 (S, 4) quat_xyzw (any
        non-zero norm), one row per slot (rows of free slots are ignored): set every
        body's pose first, raising ValueError naming the body on non-finite values or
        zero quaternions.  Without them the step uses the scene's poses.
        stamp: time (s), passed through.  Returns a StepResult.
        """
        try:
            stamp = float(stamp)
        except (TypeError, ValueError):
            raise ValueError(f"stamp must be a number, got {stamp!r}") from None
        if positions is not None or orientations is not None:
            self._set_all_poses(positions, orientations, stamp)
        timings = {}
        clock = [time.perf_counter()]

        def lap(phase):
            clock.append(time.perf_counter())
            timings[phase] = clock[-1] - clock[-2]

        ended, retired = self.scene.take_ended()
        edit_events = Events.concat(self._pending, self.arbiters.end_bodies(ended))
        self._pending = Events.empty()
        view = self.scene.view()
        lap("edits")
        bounds = self._bounds(view)
        lap("bounds")
        candidates = self._broad_phase(view, bounds)
        lap("broadphase")
        pairs = filter_pairs(candidates, view.static, view.group, view.mask, view.allowed,
                             KEY_BASE)
        if self.config.shard_count > 1:
            shard = np.empty(len(pairs), np.int64)
            pair_shards(self._body_hashes(), pairs, np.int64(self.config.shard_count), shard)
            pairs = pairs[shard == self.config.shard_index]
        lap("filter")
        narrow = self._narrow_phase(view, pairs)
        lap("narrowphase")
        classified = self._classify(narrow)
        lap("classify")
        manifolds = self._manifolds(view, narrow, classified)
        lap("manifold")
        events = self._arbiters(view, classified, manifolds, stamp)
        lap("arbiters")
        if len(edit_events):
            events = Events.concat(edit_events, events)
        names = self.scene.names
        if retired:              # this step's events still name the removed bodies
            names = list(names)
            for slot, name in retired.items():
                names[slot] = name
        result = self._result(names, stamp, narrow, classified, events, timings,
                              len(candidates))
        self.steps += 1
        if self.rerun is not None:
            self.rerun.log_step(self.scene, result, self.steps)
        return result

    # -- the phases ---------------------------------------------------------------
    def _reach(self):
        """m: the distance up to which pairs are found and measured exactly."""
        return max(self.config.contact_margin, self.config.proximity)

    def _bounds(self, view):
        t = view.table
        moving = self._moving_slots(view)
        if moving is not None:
            codes, params, vrange = t.codes[moving], t.params[moving], t.vrange[moving]
            pos, quat = view.positions[moving], view.orientations[moving]
        else:
            codes, params, vrange = t.codes, t.params, t.vrange
            pos, quat = view.positions, view.orientations
        n = len(codes)
        lo = self._buffer("lo", (n, 3))[:n]
        hi = self._buffer("hi", (n, 3))[:n]
        plane_w = self._buffer("plane_w", (n, 4))[:n]
        with _threads(n, self.parallel_min_cheap_items):
            world_aabbs(codes, params, vrange, t.verts, pos, quat, 0.5 * self._reach(), lo,
                        hi, plane_w)
        return Bounds(lo, hi, plane_w, moving)

    def _moving_slots(self, view):
        """The slots boxed every step when the static grid is used (the bodies with a
        pose that are not static, and every plane), after bringing the static grid up
        to date; None when it is not used (every slot is boxed)."""
        slots = view.active if view.active is not None else np.arange(len(view.static))
        fixed = view.static[slots] & ~self.scene.is_plane[slots]
        n_fixed = int(np.count_nonzero(fixed))
        if n_fixed < max(self.static_grid_min, 1) or 2 * n_fixed <= len(slots):
            self._static = None
            return None
        self._static_grid(view, slots[fixed])
        return slots[~fixed]

    def _static_grid(self, view, slots):
        key = (self.scene.version, self._reach())
        old = self._static
        if (old is not None and old.key == key and np.array_equal(old.slots, slots)
                and poses_unchanged(slots, view.positions, view.orientations, old.pos,
                                    old.quat)):
            return
        pos, quat = view.positions[slots], view.orientations[slots]
        t = view.table
        n = len(slots)
        lo, hi, plane_w = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 4))
        world_aabbs(t.codes[slots], t.params[slots], t.vrange[slots], t.verts, pos, quat,
                    0.5 * self._reach(), lo, hi, plane_w)
        self._static = StaticIndex(key, slots, pos, quat, lo, hi, static_grid(lo, hi))

    def _broad_phase(self, view, bounds):
        """Candidate pairs int64 (P, 2) of slots, sorted, among the bodies with a pose
        (with the static grid: without static-static pairs, which the filter drops)."""
        lo, hi, plane_w, slots = bounds
        if slots is None:
            slots = view.active
            if slots is not None:
                lo, hi, plane_w = lo[slots], hi[slots], plane_w[slots]
        is_plane = self.scene.is_plane if slots is None else self.scene.is_plane[slots]
        cand = np.zeros((0, 2), np.int64)
        if len(lo) >= 2:
            with _threads(len(lo), self.parallel_min_cheap_items):
                cand, self._order, _ = find_pairs(lo, hi, is_plane, plane_w, self._order, -1)
            if slots is not None:
                cand = slots[cand]      # increasing, so the rows stay sorted
        if bounds.slots is None:
            return cand
        st = self._static
        rows = np.flatnonzero(~is_plane)
        found = static_pairs(np.ascontiguousarray(lo[rows]), np.ascontiguousarray(hi[rows]),
                             st.lo, st.hi, *st.grid)
        a, b = slots[rows[found[:, 0]]], st.slots[found[:, 1]]
        cand = np.concatenate([cand, np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1)])
        return cand[np.lexsort((cand[:, 1], cand[:, 0]))]

    def _narrow_phase(self, view, pairs):
        t = view.table
        pos, quat = view.positions, view.orientations
        npairs = len(pairs)
        out = self._buffer("out", (npairs, OUT_SIZE))[:npairs]
        status = self._buffer("status", (npairs,), np.int64)[:npairs]
        cap = self.config.max_pairs
        if cap and npairs > cap:
            # the pairs past the cap are not run this step (finite rows, NOT_RUN)
            out[cap:] = 0.0
            out[cap:, OUT_METHOD] = M_AUTO
            status[cap:] = ST_NOT_RUN
            self._run_narrow_phase(t, pairs[:cap], pos, quat, out[:cap], status[:cap])
        else:
            self._run_narrow_phase(t, pairs, pos, quat, out, status)
        return NarrowPhase(pairs, out, status)

    def _run_narrow_phase(self, t, pairs, pos, quat, out, status):
        par = self.parallel_min_items
        collide_pairs(t, pairs, pos, quat, self._method, self._reach(), out, status,
                      threads=lambda n: _threads(n, par))

    def _classify(self, narrow):
        pairs, out, status = narrow
        npairs = len(pairs)
        dist = out[:, OUT_DIST]
        margin = self.config.contact_margin
        if margin > 0.0 and len(self.arbiters):
            # hysteresis: a pair with an arbiter keeps touching within the margin
            near = np.flatnonzero((status == ST_SEPARATED) & (dist <= margin))
            if len(near):
                keys = pairs[near, 0] * KEY_BASE + pairs[near, 1]
                arb = self.arbiters.keys
                at = np.minimum(np.searchsorted(arb, keys), len(arb) - 1)
                status[near[arb[at] == keys]] = ST_TOUCHING
        rows = [self._buffer(f"split{k}", (npairs,), np.int64)[:npairs] for k in range(8)]
        nt, nu = split_pairs(pairs, out, status, KEY_BASE, ST_FAILED, *rows)
        proximity_rows = np.zeros(0, np.int64)
        if self.config.proximity > 0.0:
            proximity_rows = np.flatnonzero((status == ST_SEPARATED)
                                            & (dist <= self.config.proximity))
        return Classified(rows[0][:nt], rows[1][:nt], rows[2][:nt], rows[3][:nt],
                          rows[5][:nu], rows[6][:nu], rows[7][:nu], proximity_rows)

    def _manifolds(self, view, narrow, classified):
        t = view.table
        nt = len(classified.touching_rows)
        points = self._buffer("cpts", (nt, MAX_MANIFOLD, 7))
        normal = self._buffer("cnormal", (nt, 3))
        count = self._buffer("ccount", (nt,), np.int64)
        if nt:
            with _threads(nt, self.parallel_min_cheap_items):
                manifold_batch(t.codes, t.params, t.vrange, t.verts, narrow.pairs,
                               classified.touching_rows, view.positions, view.orientations,
                               narrow.out, self.config.drift_threshold, points, normal, count)
        return Manifolds(points, normal, count)

    def _body_hashes(self):
        """uint64 (S,): arbiters.body_hashes of the slots' names, kept per scene version."""
        if self._hashes_version != self.scene.version or \
                len(self._hashes) != len(self.scene.names):
            self._hashes = body_hashes(self.scene.names)
            self._hashes_version = self.scene.version
        return self._hashes

    def _arbiters(self, view, c, manifolds, stamp):
        return self.arbiters.update_arrays(
            view.positions, view.orientations, c.touching_keys, manifolds.points,
            manifolds.normal, manifolds.count, c.undecided_keys, c.touching_status,
            c.touching_method, c.undecided_status, c.undecided_method, stamp=stamp,
            body_hash=self._body_hashes())

    def _result(self, names, stamp, narrow, classified, events, timings, n_candidates):
        con = self.arbiters.contacts()
        failed = narrow.pairs[narrow.status == ST_FAILED]
        rows = classified.proximity_rows
        o = narrow.out[rows]
        proximity = ProximitySet(
            body_a=narrow.pairs[rows, 0], body_b=narrow.pairs[rows, 1],
            distance=o[:, OUT_DIST], point_a=o[:, OUT_PA:OUT_PA + 3],
            point_b=o[:, OUT_PB:OUT_PB + 3], normal=o[:, OUT_NORMAL:OUT_NORMAL + 3])
        return StepResult(
            names=names, stamp=stamp, pairs=self.arbiters.pairs(),
            body_a=con["body_a"], body_b=con["body_b"],
            position=0.5 * (con["point_a"] + con["point_b"]),
            point_a=con["point_a"], point_b=con["point_b"], normal=con["normal"],
            depth=con["depth"], contact_id=con["contact_id"], age=con["age"],
            method=con["method"], status=con["status"], proximity=proximity,
            events=events, timings=timings, n_candidate_pairs=int(n_candidates),
            n_narrowphase_pairs=int(len(narrow.pairs)),
            n_failed_pairs=len(failed), failed_pairs=failed,
            n_truncated_pairs=max(0, len(narrow.pairs) - self.config.max_pairs)
            if self.config.max_pairs else 0)

    def warm_up(self):
        """Compile (or load from the on-disk cache) every kernel a step can reach, so
        the first real step does not wait for the compiler, whatever the scene: a tiny
        scene (a plane, a box, a sphere), then a cluster of bodies of every shape
        type, a convex hull among them, overlapping at once so that the threaded
        paths (the narrow phase's and the manifolds' blocks, run whenever numba has
        more than one thread) compile too.  Leaves this pipeline's state untouched."""
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
        shapes = [{"type": "sphere", "radius": 0.5}, {"type": "box", "size": [0.8, 0.8, 0.8]},
                  {"type": "capsule", "radius": 0.3, "length": 0.6},
                  {"type": "cylinder", "radius": 0.4, "height": 0.8},
                  {"type": "cone", "radius": 0.4, "height": 0.8},
                  {"type": "ellipsoid", "radii": [0.5, 0.4, 0.3]},
                  {"type": "convex", "points": [[0.5, 0, 0], [-0.5, 0, 0], [0, 0.5, 0],
                                                [0, -0.5, 0], [0, 0, 0.5], [0, 0, -0.5]]}]
        n = 4 * len(shapes)     # 28 bodies: 378 pairs, more than two blocks of NP_CHUNK
        cluster = Pipeline([{"name": f"b{k}", "shape": shapes[k % len(shapes)]}
                            for k in range(n)], PipelineConfig(method=self.config.method))
        cluster.parallel_min_items = cluster.parallel_min_cheap_items = 0
        k = np.arange(n, dtype=float)
        pos = 0.05 * np.stack([np.cos(k), np.sin(k), 0.1 * k], axis=1)
        quat = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        cluster.step(pos, quat, 0.0)
        cluster.step(pos, quat, 0.0)
        pair_shards(body_hashes(["a", "b"]), np.array([[0, 1]]), np.int64(2),
                    np.empty(1, np.int64))
        # a static-heavy scene: the static grid's kernels
        shelf = {"type": "box", "size": [1.0, 1.0, 1.0]}
        store = Pipeline([{"name": f"s{k}", "shape": shelf, "static": True} for k in range(3)]
                         + [{"name": "bot", "shape": {"type": "sphere", "radius": 0.5}}],
                         PipelineConfig(method=self.config.method))
        store.static_grid_min = 1
        pos = np.array([[0.0, 0.0, 0.0], [1.2, 0.0, 0.0], [0.0, 1.2, 0.0], [0.6, 0.0, 0.9]])
        quat = np.tile([0.0, 0.0, 0.0, 1.0], (4, 1))
        store.step(pos, quat, 0.0)
        store.step(pos, quat, 0.0)
