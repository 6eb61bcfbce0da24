"""Outcomes of a collision query, and the project's one sign convention.

Sign convention (the same in kernels, messages and this module):
  * ``normal`` is a unit vector pointing from A to B, in the world frame;
  * ``distance`` is signed: positive when apart, negative when penetrating;
  * ``depth`` = max(0, -distance) >= 0; moving B by ``depth`` along ``normal``
    brings the pair to touching;
  * ``point_a`` / ``point_b`` are world-frame witness points on the surfaces of A and B
    (closest points when apart, deepest points when penetrating), so that
    ``point_b - point_a == distance * normal``.
Units are SI (metres).

Touching rule (every method): contact iff distance <= TOUCH_TOL * scale, where scale is
the sum of the two shapes' bounding radii (kernels/constants.py).
"""
import enum
from dataclasses import dataclass, fields

import numpy as np

from .kernels import constants as C


class Status(enum.IntEnum):
    SEPARATED = C.ST_SEPARATED
    TOUCHING = C.ST_TOUCHING
    PENETRATING = C.ST_PENETRATING
    FAILED = C.ST_FAILED        # the iteration cap was hit or the input degenerated
    NOT_RUN = C.ST_NOT_RUN      # the pair is not supported by the method (e.g. plane-plane)


@dataclass(frozen=True)
class CollisionResult:
    touching: bool
    status: Status
    distance: float
    depth: float
    normal: np.ndarray      # (3,) unit, A -> B, world
    point_a: np.ndarray     # (3,) world
    point_b: np.ndarray     # (3,) world
    method: str
    iterations: int

    @classmethod
    def from_row(cls, status, row):
        """Build from a kernel result row (constants.OUT_*) already in the world frame."""
        d = float(row[C.OUT_DIST])
        st = Status(int(status))
        return cls(
            touching=st in (Status.TOUCHING, Status.PENETRATING),
            status=st,
            distance=d,
            depth=max(0.0, -d),
            normal=np.array(row[C.OUT_NORMAL:C.OUT_NORMAL + 3]),
            point_a=np.array(row[C.OUT_PA:C.OUT_PA + 3]),
            point_b=np.array(row[C.OUT_PB:C.OUT_PB + 3]),
            method=C.METHOD_NAMES[int(row[C.OUT_METHOD])],
            iterations=int(row[C.OUT_ITERS]),
        )


@dataclass
class ContactSet:
    """Contacts as arrays (the layout ``msg_adapters`` reads), world frame, metres.

    names list[str] (body id -> name); body_a, body_b int64 (C,) body ids (a < b);
    position, point_a, point_b, normal float64 (C, 3); depth float64 (C,) >= 0;
    contact_id, age, method, status int64 (C,).
    """
    names: list
    body_a: np.ndarray
    body_b: np.ndarray
    position: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray
    depth: np.ndarray
    contact_id: np.ndarray
    age: np.ndarray
    method: np.ndarray
    status: np.ndarray

    @classmethod
    def select(cls, contacts, keep):
        """The contacts of any object with these fields, rows where ``keep`` is true."""
        values = {f.name: getattr(contacts, f.name) for f in fields(cls)}
        return cls(**{k: (v if k == "names" else np.asarray(v)[keep])
                      for k, v in values.items()})
