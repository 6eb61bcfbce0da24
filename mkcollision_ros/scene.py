"""The scene: the one owner of a scene's bodies, their shapes, filters and poses.
Plain Python + numpy, no ROS.

    from mkcollision_ros.scene import Scene
    scene = Scene([{"name": "ball", "shape": {"type": "sphere", "radius": 0.3}},
                   {"name": "floor", "shape": {"type": "plane", "normal": [0, 0, 1],
                                               "offset": 0.0}, "static": True}])
    scene.set_poses(["ball"], [[0, 0, 0.29]], [[0, 0, 0, 1]], stamp=1.5)
    scene.add_body({"name": "crate", "shape": {"type": "box", "size": [1, 1, 1]},
                    "pose": ([2, 0, 0.5], [0, 0, 0, 1])})
    scene.remove_body("ball")

Body ids are slots.  A body keeps its slot from ``add_body`` to ``remove_body``; a freed
slot is reused by a later add (lowest first) once the pipeline has stepped past the
removal (``take_ended``), so the events of that step still name the removed body, and
ids stay below the largest number of bodies the scene ever held at once.  ``names[slot]`` is the body's name (None for a
free slot); pair results (``Pipeline.step``) name bodies by slot.

A body is a dict (or a ``Body``):

    name    non-empty str, unique in the scene
    shape   a shape dict (mkcollision_ros.shapes)
    static  bool = False: static-static pairs are never tested
    group   int in [0, 0xFFFFFFFF] = 1, mask int in [0, 0xFFFFFFFF] = 0xFFFFFFFF:
            a pair may collide iff (group_a & mask_b) and (group_b & mask_a) (32 bits,
            as Bullet's and MuJoCo's collision filters)
    pose    optional initial pose (position [x, y, z], quaternion [x, y, z, w])

``validate_body`` is the one body validator (the params file, the Python API and the
node use it); invalid input raises ValueError naming the body and the key.

A body collides once it has a pose: an initial pose, or one from ``set_poses``; a static
body without either sits at the origin with the identity orientation.  Poses carry a
per-body stamp (s, the stamp of the update that set it; NaN before the first).

Edits (add, remove, replace, allowed pairs) apply at once to the scene's arrays and cost
what they touch: one body's shape row, its hull, its vertices appended to the shared
vertex array (compacted when half of it is garbage).  Removing a body, or replacing its
shape, ends its pairs' arbiters at the pipeline's next step, with events
(``take_ended``); every other pair keeps its arbiter and contact ids.
"""
import heapq
from dataclasses import dataclass
from typing import NamedTuple, Optional

import numpy as np

from .kernels.constants import N_PARAMS, PLANE, SPHERE
from .shapes import ShapeTable, point_count, shape_row, validate_pose

# pair keys are a * KEY_BASE + b (a < b), so a key does not depend on the scene's size
KEY_BASE = 1 << 31
MAX_BITS = 0xFFFFFFFF
BODY_KEYS = {"name", "shape", "static", "group", "mask", "pose"}
IDENTITY = (0.0, 0.0, 0.0, 1.0)
# a quaternion of norm <= this is a zero quaternion (refused); others are normalised
QUAT_MIN_NORM = 1e-9


@dataclass(frozen=True)
class Body:
    """A validated body (see the module docstring); ``pose`` is None or
    (position float64 (3,), unit quat_xyzw float64 (4,))."""
    name: str
    shape: dict
    static: bool = False
    group: int = 1
    mask: int = MAX_BITS
    pose: Optional[tuple] = None


def validate_body(body, where=None):
    """Check one body dict (or Body); return a Body.  Raises ValueError naming the body
    (or ``where``) and the key."""
    return _validate(body, where)[0]


def _validate(body, where=None):
    """validate_body, and the shape's packed row (shapes.shape_row) built on the way."""
    if isinstance(body, Body):
        body = dict(name=body.name, shape=body.shape, static=body.static,
                    group=body.group, mask=body.mask, pose=body.pose)
    label = where or "body"
    if not isinstance(body, dict):
        raise ValueError(f"{label}: must be a dict, got {body!r}")
    unknown = set(body) - BODY_KEYS
    if unknown:
        raise ValueError(f"{label}: unknown key(s) {sorted(unknown)}; "
                         f"expected {sorted(BODY_KEYS)}")
    name = body.get("name")
    if not isinstance(name, str) or not name:
        raise ValueError(f"{label}: 'name' must be a non-empty string, got {name!r}")
    label = f"body {name!r}"
    if "shape" not in body:
        raise ValueError(f"{label}: missing 'shape'")
    try:
        row = shape_row(body["shape"])
    except ValueError as e:
        raise ValueError(f"{label}: {e}") from None
    static = body.get("static", False)
    if not isinstance(static, (bool, np.bool_)):
        raise ValueError(f"{label}: 'static' must be true or false, got {static!r}")
    bits = []
    for key, default in (("group", 1), ("mask", MAX_BITS)):
        v = body.get(key, default)
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)) \
                or not 0 <= v <= MAX_BITS:
            raise ValueError(f"{label}: '{key}' must be an integer bitmask in "
                             f"[0, 0xFFFFFFFF], got {v!r}")
        bits.append(int(v))
    pose = body.get("pose")
    if pose is not None:
        pose = validate_pose(pose, f"{label}: initial pose")
    return Body(name=name, shape=body["shape"], static=bool(static), group=bits[0],
                mask=bits[1], pose=pose), row


class SceneView(NamedTuple):
    """What one step reads of a scene (views of its arrays, valid until the next edit).

    table: the ShapeTable over slots [0, S); active int64 (A,) sorted slots that
    collide (in use, posed and enabled), or None when all S do; static bool (S,), group, mask
    int64 (S,); positions float64 (S, 3) m, orientations float64 (S, 4) unit
    quat_xyzw; allowed int64 (K,) sorted pair keys that never collide."""
    table: ShapeTable
    active: Optional[np.ndarray]
    static: np.ndarray
    group: np.ndarray
    mask: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray
    allowed: np.ndarray


class Scene:
    """Bodies by stable slot, with shapes, filters, allowed pairs and stamped poses.

    bodies: body dicts (see the module docstring); allowed_pairs: [[name, name], ...]
    pairs that never collide (MoveIt's allowed-collision idea).  Invalid input raises
    ValueError and leaves the scene as it was."""

    def __init__(self, bodies=(), allowed_pairs=()):
        self.names = []                   # slot -> name, None for a free slot
        self.index = {}                   # name -> slot
        self._bodies = []                 # slot -> Body or None
        self._free = []                   # heap of free slots
        self._retired = {}                # slot -> name: removed, not yet taken
        self._cap = 0
        self._verts = np.zeros((0, 3))
        self._n_verts = 0
        self._garbage = 0
        self._allowed = set()             # frozensets of two names
        self._allowed_keys = None
        self._ended = []
        self._n_active = 0
        self.version = 0                  # +1 per edit (not per pose update)
        self._grow(max(8, len(bodies)))
        self.add_bodies(bodies)
        self.set_allowed_pairs(allowed_pairs)

    # -- storage ------------------------------------------------------------------
    def _grow(self, cap):
        """Grow the per-slot arrays to ``cap`` rows (new rows: free slots)."""
        old = self._cap
        if cap <= old:
            return
        fills = (("_codes", (), np.int64, SPHERE), ("_params", (N_PARAMS,), np.float64, 0.0),
                 ("_vrange", (2,), np.int64, 0), ("_vlen", (), np.int64, 0),
                 ("_static", (), bool, True), ("_group", (), np.int64, 0),
                 ("_mask", (), np.int64, 0), ("_pos", (3,), np.float64, 0.0),
                 ("_quat", (4,), np.float64, IDENTITY), ("_stamp", (), np.float64, np.nan),
                 ("_posed", (), bool, False), ("_used", (), bool, False),
                 ("_enabled", (), bool, True))
        for attr, tail, dtype, fill in fills:
            new = np.empty((cap,) + tail, dtype)
            if old:
                new[:old] = getattr(self, attr)[:old]
            new[old:] = fill
            setattr(self, attr, new)
        self._cap = cap

    def _put_verts(self, verts):
        """Append a shape's vertex rows; return their first row."""
        need = self._n_verts + len(verts)
        if need > len(self._verts):
            buf = np.empty((max(need, int(1.5 * len(self._verts)), 64), 3))
            buf[:self._n_verts] = self._verts[:self._n_verts]
            self._verts = buf
        first = self._n_verts
        self._verts[first:need] = verts
        self._n_verts = need
        return first

    def _compact_verts(self):
        """Drop the rows of removed or replaced shapes (when they are half the array)."""
        if self._garbage <= max(1024, self._n_verts // 2):
            return
        slots = [s for s in range(len(self.names)) if self.names[s] is not None
                 and self._vlen[s] > 0]
        total = int(self._vlen[slots].sum()) if slots else 0
        buf = np.empty((max(total, 64), 3))
        at = 0
        for s in slots:
            first, n = int(self._vrange[s, 0]), int(self._vlen[s])
            buf[at:at + n] = self._verts[first:first + n]
            self._vrange[s, 0] = at
            at += n
        self._verts, self._n_verts, self._garbage = buf, at, 0

    def _write(self, slot, body, code, prm, verts):
        if self._vlen[slot] > 0:
            self._garbage += int(self._vlen[slot])
        first = self._put_verts(verts) if len(verts) else 0
        self._codes[slot] = code
        self._params[slot] = prm
        self._vrange[slot] = (first, point_count(code, prm, verts))
        self._vlen[slot] = len(verts)
        self._static[slot] = body.static
        self._group[slot] = body.group
        self._mask[slot] = body.mask
        self._bodies[slot] = body

    # -- edits --------------------------------------------------------------------
    def add_body(self, body):
        """Add one body; returns its slot.  Raises ValueError (scene unchanged)."""
        return self.add_bodies([body])[0]

    def add_bodies(self, bodies):
        """Add several bodies, all or none; returns their slots (int list)."""
        checked = self._check_bodies(bodies, set(self.index))
        slots = [self._add(body, row) for body, row in checked]
        if slots:
            self._edited()
        return slots

    def remove_body(self, name):
        """Remove a body by name (and the allowed pairs naming it); returns its slot,
        free for reuse after the pipeline's next step, which ends its pairs."""
        slot = self._remove(self._slot(name))
        self._compact_verts()
        self._edited()
        return slot

    def replace_body(self, body):
        """Replace the body of the same name (shape, static, group, mask; a given pose
        also sets its pose).  It keeps its slot; when its shape changes its pairs end at
        the next step and begin anew.  Returns the slot."""
        new, row = _validate(body)
        slot = self._replace(self._slot(new.name), new, row)
        self._compact_verts()
        self._edited()
        return slot

    def set_allowed_pairs(self, pairs):
        """Replace the allowed-collision pairs: [[name, name], ...] of known bodies."""
        self._allowed = self._check_allowed(pairs, set(self.index))
        self._edited()

    def edit(self, remove=(), bodies=(), allowed_pairs=None):
        """Several edits at once, all or none (a bad one raises ValueError naming it and
        changes nothing): remove the bodies named in ``remove``, then add each of
        ``bodies``, or replace the body of its name, then, unless None, replace the
        allowed pairs with ``allowed_pairs``.  Returns the slots of ``bodies``."""
        remove = list(remove)
        for name in remove:
            self._slot(name)
        if len(set(remove)) != len(remove):
            raise ValueError(f"remove names a body twice: {remove}")
        left = set(self.index) - set(remove)
        checked = self._check_bodies(bodies, set())
        names = left | {body.name for body, _ in checked}
        allowed = None if allowed_pairs is None else self._check_allowed(allowed_pairs, names)
        for name in remove:
            self._remove(self.index[name])
        slots = [self._replace(self.index[body.name], body, row) if body.name in self.index
                 else self._add(body, row) for body, row in checked]
        if allowed is not None:
            self._allowed = allowed
        self._compact_verts()
        self._edited()
        return slots

    def _check_bodies(self, bodies, taken):
        """Validated (Body, shape row) pairs; names must be new to ``taken`` and to
        each other."""
        if not isinstance(bodies, (list, tuple)):
            raise ValueError(f"bodies must be a list of body dicts, got {bodies!r}")
        checked, seen = [], set()
        for k, b in enumerate(bodies):
            body, row = _validate(b, f"body {k}")
            if body.name in taken or body.name in seen:
                raise ValueError(f"body {k}: duplicate name {body.name!r}")
            seen.add(body.name)
            checked.append((body, row))
        return checked

    @staticmethod
    def _check_allowed(pairs, names):
        if not isinstance(pairs, (list, tuple)):
            raise ValueError("allowed_pairs must be a list of [name, name]")
        new = set()
        for p in pairs:
            if (not isinstance(p, (list, tuple)) or len(p) != 2
                    or not all(isinstance(x, str) for x in p)):
                raise ValueError(f"allowed_pairs entries must be [name, name], got {p!r}")
            for nm in p:
                if nm not in names:
                    raise ValueError(f"allowed_pairs names unknown body {nm!r}")
            if p[0] == p[1]:
                raise ValueError(f"allowed_pairs entry {list(p)!r} names one body twice")
            new.add(frozenset(p))
        return new

    def _add(self, body, row):
        code, prm, verts = row
        if self._free:
            slot = heapq.heappop(self._free)
        else:
            slot = len(self.names)
            if slot >= self._cap:
                self._grow(2 * self._cap)
            self.names.append(None)
            self._bodies.append(None)
        self.names[slot] = body.name
        self.index[body.name] = slot
        self._used[slot] = True
        self._enabled[slot] = True
        self._write(slot, body, code, prm, verts)
        self._stamp[slot] = np.nan
        if body.pose is not None:
            self._pos[slot], self._quat[slot] = body.pose
        else:
            self._pos[slot] = 0.0
            self._quat[slot] = IDENTITY
        self._posed[slot] = body.pose is not None or body.static
        return slot

    def _remove(self, slot):
        name = self.names[slot]
        del self.index[name]
        self._allowed = {p for p in self._allowed if name not in p}
        self.names[slot] = None
        self._used[slot] = False
        self._bodies[slot] = None
        self._garbage += int(self._vlen[slot])
        self._vlen[slot] = 0
        self._codes[slot] = SPHERE
        self._params[slot] = 0.0
        self._vrange[slot] = 0
        self._static[slot] = True
        self._group[slot] = 0
        self._mask[slot] = 0
        self._posed[slot] = False
        self._stamp[slot] = np.nan
        self._retired[slot] = name
        self._ended.append(slot)
        return slot

    def _replace(self, slot, new, row):
        code, prm, verts = row
        old = self._bodies[slot]
        first = self._vrange[slot, 0]
        shape_changed = (code != self._codes[slot] or not np.array_equal(prm, self._params[slot])
                         or len(verts) != self._vlen[slot]
                         or not np.array_equal(verts, self._verts[first:first + len(verts)]))
        if shape_changed:
            self._write(slot, new, code, prm, verts)
            self._ended.append(slot)
        else:
            self._static[slot], self._group[slot], self._mask[slot] = (
                new.static, new.group, new.mask)
            self._bodies[slot] = new
        if new.pose is not None:
            self._pos[slot], self._quat[slot] = new.pose
            self._posed[slot] = True
        elif new.static and not old.static:
            self._posed[slot] = True
        return slot

    def _edited(self):
        self.version += 1
        self._allowed_keys = None
        self._n_active = None

    def _slot(self, name):
        if name not in self.index:
            raise ValueError(f"unknown body {name!r}")
        return self.index[name]

    # -- poses --------------------------------------------------------------------
    def set_poses(self, names, positions, orientations, stamp=None, **limits):
        """Set poses by name.  Bad entries are dropped one by one and described:
        unknown names, non-finite values, zero quaternions, a body named twice (all its
        entries: no "last wins"), and what ``limits`` (``max_abs``, ``quat_tolerance``:
        see ``pose_problems``) refuse.  Returns (applied count, problems list of str)."""
        names = list(names)
        slots = np.fromiter((self.index.get(n, -1) for n in names), np.int64, len(names))
        problems = [f"{n}: unknown body" for n, s in zip(names, slots) if s < 0]
        ok = slots >= 0
        applied, bad = self.set_poses_at(slots[ok], np.asarray(positions, float)[ok],
                                         np.asarray(orientations, float)[ok], stamp, **limits)
        return applied, problems + bad

    def set_poses_at(self, slots, positions, orientations, stamp=None, max_abs=None,
                     quat_tolerance=None):
        """Set the poses of bodies ``slots`` (int64 (K,)); as ``set_poses``."""
        slots = np.asarray(slots, np.int64).reshape(-1)
        pos = np.asarray(positions, np.float64).reshape(-1, 3)
        quat = np.asarray(orientations, np.float64).reshape(-1, 4)
        if not len(pos) == len(quat) == len(slots):
            raise ValueError(f"{len(slots)} bodies, {len(pos)} positions and {len(quat)} "
                             f"orientations: the lengths must agree")
        in_use = (slots >= 0) & (slots < len(self.names))
        in_use[in_use] = self._used[slots[in_use]]
        why = pose_problems(pos, quat, max_abs, quat_tolerance)
        if len(slots) > 1:
            uniq, counts = np.unique(slots, return_counts=True)
            if counts.max() > 1:
                why[np.isin(slots, uniq[counts > 1])] = 5
        good = in_use & (why == 0)
        problems = [f"slot {slots[k]}: no such body" if not in_use[k]
                    else f"{self.names[slots[k]]}: {POSE_PROBLEMS[why[k]]}"
                    for k in np.flatnonzero(~good)]
        if len(problems) > 1:
            problems = list(dict.fromkeys(problems))     # a duplicate is said once
        good_quat = quat[good]
        self._write_poses(slots[good], pos[good],
                          good_quat / np.linalg.norm(good_quat, axis=1)[:, None], stamp)
        return int(np.count_nonzero(good)), problems

    def _write_poses(self, slots, positions, unit_quats, stamp):
        """Set checked poses (finite, unit quaternions) of bodies in use ``slots``
        (None: every slot, all in use)."""
        if slots is None:
            slots = slice(0, len(self.names))
        self._pos[slots] = positions
        self._quat[slots] = unit_quats
        if stamp is not None:
            self._stamp[slots] = float(stamp)
        if not self._posed[slots].all():
            self._posed[slots] = True
            self._n_active = None

    # -- reading ------------------------------------------------------------------
    @property
    def n_slots(self):
        """Slots in use or free below the highest used one (the arrays' length)."""
        return len(self.names)

    def __len__(self):
        return len(self.index)

    def __contains__(self, name):
        return name in self.index

    def body(self, name):
        """The Body named ``name`` (ValueError when unknown)."""
        return self._bodies[self._slot(name)]

    def bodies(self):
        """Every body, in slot order."""
        return [b for b in self._bodies if b is not None]

    @property
    def table(self):
        """The ShapeTable over slots [0, n_slots) (views; a free slot is a zero sphere)."""
        s = len(self.names)
        return ShapeTable(self._codes[:s], self._params[:s], self._vrange[:s],
                          self._verts[:self._n_verts])

    @property
    def static(self):
        return self._static[:len(self.names)]

    @property
    def group(self):
        return self._group[:len(self.names)]

    @property
    def mask(self):
        return self._mask[:len(self.names)]

    @property
    def positions(self):
        """float64 (n_slots, 3) m, world (a view: write through ``set_poses``)."""
        return self._pos[:len(self.names)]

    @property
    def orientations(self):
        """float64 (n_slots, 4) unit quat_xyzw (a view)."""
        return self._quat[:len(self.names)]

    @property
    def stamps(self):
        """float64 (n_slots,) s: each body's last pose stamp (NaN: none yet)."""
        return self._stamp[:len(self.names)]

    def set_enabled(self, enabled):
        """Which bodies may collide: bool (n_slots,); a disabled body keeps its pose and
        slot but takes no part in the broad phase (the node's stale policy)."""
        enabled = np.asarray(enabled, bool)
        if enabled.shape != (len(self.names),):
            raise ValueError(f"enabled must have {len(self.names)} entries")
        if not np.array_equal(enabled, self._enabled[:len(self.names)]):
            self._enabled[:len(self.names)] = enabled
            self._n_active = None

    @property
    def enabled(self):
        """bool (n_slots,): may collide (see set_enabled)."""
        return self._enabled[:len(self.names)]

    @property
    def used(self):
        """bool (n_slots,): the slot holds a body."""
        return self._used[:len(self.names)]

    @property
    def posed(self):
        """bool (n_slots,): in use and has a pose (collides)."""
        return self._posed[:len(self.names)]

    @property
    def is_plane(self):
        return self._codes[:len(self.names)] == PLANE

    def allowed_keys(self):
        """int64 (K,) sorted pair keys (a * KEY_BASE + b) of the allowed pairs."""
        if self._allowed_keys is None:
            keys = []
            for p in self._allowed:
                i, j = sorted(self.index[n] for n in p)
                keys.append(i * KEY_BASE + j)
            self._allowed_keys = np.unique(np.array(keys, np.int64))
        return self._allowed_keys

    def allowed_pairs(self):
        """The allowed pairs as sorted [name, name] lists."""
        return sorted(sorted(p) for p in self._allowed)

    def view(self):
        """A SceneView for one step."""
        s = len(self.names)
        if self._n_active is None:
            self._n_active = int(np.count_nonzero(self._posed[:s] & self._enabled[:s]))
        active = (None if self._n_active == s
                  else np.flatnonzero(self._posed[:s] & self._enabled[:s]))
        return SceneView(self.table, active, self.static, self.group, self.mask,
                         self.positions, self.orientations, self.allowed_keys())

    def take_ended(self):
        """Slots whose pairs must end (removed, or a new shape) since the last call,
        int64 sorted, and the names of the removed ones (dict slot -> name); their
        slots become free for reuse.  The pipeline calls it once per step."""
        out = np.unique(np.array(self._ended, np.int64))
        retired = self._retired
        for slot in retired:
            heapq.heappush(self._free, slot)
        self._ended, self._retired = [], {}
        return out, retired


POSE_PROBLEMS = ("", "non-finite value", "zero quaternion", "coordinate beyond the limit",
                 "non-unit quaternion", "duplicate body in one update")


def pose_problems(positions, orientations, max_abs=None, quat_tolerance=None):
    """What is wrong with each pose (positions (K, 3) m, quat_xyzw (K, 4)): int64 (K,)
    codes into POSE_PROBLEMS, 0 for a good pose.  ``max_abs`` (m): a coordinate beyond
    it is refused (a finite 1e308 overflows once squared); ``quat_tolerance``: a
    quaternion whose norm is farther than this from 1 is refused (closer ones are
    normalised; tf2 uses 0.01).  None: no such limit."""
    pos = np.asarray(positions, np.float64).reshape(-1, 3)
    quat = np.asarray(orientations, np.float64).reshape(-1, 4)
    finite = np.isfinite(pos).all(axis=1) & np.isfinite(quat).all(axis=1)
    with np.errstate(invalid="ignore", over="ignore"):
        norms = np.sqrt(np.sum(quat * quat, axis=1))
    code = np.zeros(len(pos), np.int64)
    if quat_tolerance is not None:
        code[finite & ~(np.abs(norms - 1.0) <= quat_tolerance)] = 4
    if max_abs is not None:
        code[finite & ~(np.abs(pos) <= max_abs).all(axis=1)] = 3
    code[finite & ~(norms > QUAT_MIN_NORM)] = 2
    code[~finite] = 1
    return code
