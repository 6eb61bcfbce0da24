"""Contact arrays <-> ``ContactArray`` / ``Contact`` messages.

``contacts`` arguments are any object with these attributes (the pipeline's
``StepResult`` has them): ``names`` (list of body names, indexed by body id),
``body_a``, ``body_b`` int64 (C,), ``position``, ``point_a``, ``point_b``, ``normal``
float64 (C, 3) world frame, ``depth`` float64 (C,) >= 0, ``contact_id`` int64 (C,),
``age`` int64 (C,), ``method``, ``status`` int64 (C,).  Sign conventions: see
``mkcollision_ros.results`` and ``Contact.msg``.
"""
import numpy as np
from geometry_msgs.msg import Point, Vector3
from mkcollision_msgs.msg import Contact, ContactArray, ContactEvents, ProximityArray

from mkcollision_ros.arbiters import EV_PERSISTED

from ._arrays import pack, view


def contacts_to_contact_array(contacts, stamp=None, frame_id="world", shard=(0, 1)):
    """Contacts -> ``ContactArray`` (one message, struct-of-arrays); ``shard`` (index,
    count): the shard it comes from."""
    msg = ContactArray()
    msg.shard_index, msg.shard_count = shard
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    names = contacts.names
    msg.body_a = [names[i] for i in contacts.body_a]
    msg.body_b = [names[i] for i in contacts.body_b]
    msg.positions = pack(contacts.position, "d", np.float64)
    msg.points_a = pack(contacts.point_a, "d", np.float64)
    msg.points_b = pack(contacts.point_b, "d", np.float64)
    msg.normals = pack(contacts.normal, "d", np.float64)
    msg.depths = pack(contacts.depth, "d", np.float64)
    msg.ids = pack(contacts.contact_id, "Q", np.uint64)
    msg.ages = pack(contacts.age, "I", np.uint32)
    msg.methods = pack(contacts.method, "B", np.uint8)
    msg.statuses = pack(contacts.status, "B", np.uint8)
    return msg


def contact_array_to_arrays(msg):
    """``ContactArray`` -> dict of numpy arrays (zero-copy, read-only views) and names."""
    n = len(msg.depths)
    return {
        "body_a": list(msg.body_a),
        "body_b": list(msg.body_b),
        "position": view(msg.positions).reshape(n, 3),
        "point_a": view(msg.points_a).reshape(n, 3),
        "point_b": view(msg.points_b).reshape(n, 3),
        "normal": view(msg.normals).reshape(n, 3),
        "depth": view(msg.depths),
        "contact_id": view(msg.ids, np.uint64),
        "age": view(msg.ages, np.uint32),
        "method": view(msg.methods, np.uint8),
        "status": view(msg.statuses, np.uint8),
    }


def _point(v, kind=Point):
    out = kind()
    out.x, out.y, out.z = float(v[0]), float(v[1]), float(v[2])
    return out


def contacts_to_contact_list(contacts):
    """Contacts -> list of ``Contact`` messages (for services and events)."""
    out = []
    names = contacts.names
    for k in range(len(contacts.depth)):
        c = Contact()
        c.body_a = names[contacts.body_a[k]]
        c.body_b = names[contacts.body_b[k]]
        c.position = _point(contacts.position[k])
        c.point_a = _point(contacts.point_a[k])
        c.point_b = _point(contacts.point_b[k])
        c.normal = _point(contacts.normal[k], Vector3)
        c.depth = float(contacts.depth[k])
        c.signed_distance = float(np.dot(contacts.point_b[k] - contacts.point_a[k],
                                         contacts.normal[k]))
        c.id = int(contacts.contact_id[k])
        c.age = int(contacts.age[k])
        c.method = int(contacts.method[k])
        c.status = int(contacts.status[k])
        out.append(c)
    return out


def events_to_contact_events(events, names, stamp=None, frame_id="world", shard=(0, 1)):
    """A step's ``arbiters.Events`` -> ``ContactEvents`` with its began and ended events
    (persisting ones left out); ``names`` maps body ids to names; ``shard`` as in
    contacts_to_contact_array."""
    msg = ContactEvents()
    msg.shard_index, msg.shard_count = shard
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    keep = np.asarray(events.kind) != EV_PERSISTED
    msg.kinds = pack(np.asarray(events.kind)[keep], "B", np.uint8)
    msg.body_a = [names[i] for i in np.asarray(events.body_a)[keep]]
    msg.body_b = [names[i] for i in np.asarray(events.body_b)[keep]]
    msg.ids = pack(np.asarray(events.contact_id)[keep], "q", np.int64)
    return msg


def proximity_to_proximity_array(proximity, names, stamp=None, frame_id="world",
                                 shard=(0, 1)):
    """A step's ``pipeline.ProximitySet`` -> ``ProximityArray``; ``shard`` as in
    contacts_to_contact_array."""
    msg = ProximityArray()
    msg.shard_index, msg.shard_count = shard
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.body_a = [names[i] for i in proximity.body_a]
    msg.body_b = [names[i] for i in proximity.body_b]
    msg.distances = pack(proximity.distance, "d", np.float64)
    msg.points_a = pack(proximity.point_a, "d", np.float64)
    msg.points_b = pack(proximity.point_b, "d", np.float64)
    msg.normals = pack(proximity.normal, "d", np.float64)
    return msg
