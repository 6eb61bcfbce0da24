"""A scene and its contacts -> ``visualization_msgs/MarkerArray``, in namespaces a user
can toggle in RViz:

  bodies    one marker per body, id = the body's slot: spheres and ellipsoids as
            SPHERE, boxes as CUBE, cylinders as CYLINDER, capsules, cones and convex
            hulls as a TRIANGLE_LIST through their support points (an icosahedron's
            directions mapped by the support function: a coarse picture), planes as a thin 20 m CUBE;
            coloured by contact state (free grey, touching orange, deep red)
  contacts  one SPHERE_LIST of every contact position (id 0)
  normals   one LINE_LIST, a line per contact from its position along the normal, of
            length ``normal_length`` + depth (id 0)

Ids are stable: a body keeps its marker while it is in the scene and a removed body's
marker is deleted; the contact and normal markers are replaced each time (and deleted
when there is no contact), so nothing stale is left.  Body markers are built once per
shape and only their pose and colour change from one call to the next.
"""
import math

import numpy as np
from geometry_msgs.msg import Point
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from mkcollision_ros.meshes import PLANE_SIZE, icosphere, support_points
from mkcollision_ros.rotations import quat_from_z, quat_mul, quat_rotate

FREE = ColorRGBA(r=0.6, g=0.6, b=0.6, a=0.5)
TOUCHING = ColorRGBA(r=1.0, g=0.6, b=0.0, a=0.7)
DEEP = ColorRGBA(r=1.0, g=0.0, b=0.0, a=0.8)
CONTACT = ColorRGBA(r=0.1, g=0.3, b=1.0, a=1.0)
NORMAL = ColorRGBA(r=0.0, g=0.8, b=0.2, a=1.0)
PLANE_THICKNESS = 0.002


# 12 directions and 20 triangles a mesh: 60 points, so a MarkerArray of 1,000 bodies
# stays near a megabyte (the next subdivision, 240 points a mesh, makes it 2.7 MB and
# 130 ms to serialise in rclpy)
DIRS, TRIS = icosphere(0)


def _points(rows):
    return [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in rows]


class MarkerPainter:
    """Keeps the body markers of a scene and builds each MarkerArray from them."""

    def __init__(self):
        self._bodies = {}          # slot -> (Body, Marker)
        self._cursor = 0           # where the next window of bodies starts

    def _body_marker(self, scene, slot, body):
        shape, m = body.shape, Marker()
        m.ns, m.id, m.action = "bodies", int(slot), Marker.ADD
        m.pose.orientation.w = 1.0
        grow = 2.0 * float(shape.get("margin", 0.0))
        kind = shape["type"]
        if kind in ("sphere", "ellipsoid"):
            m.type = Marker.SPHERE
            d = (2.0 * np.asarray(shape["radii"], float) if kind == "ellipsoid"
                 else np.full(3, 2.0 * float(shape["radius"]))) + grow
            m.scale.x, m.scale.y, m.scale.z = (float(x) for x in d)
        elif kind == "box":
            m.type = Marker.CUBE
            m.scale.x, m.scale.y, m.scale.z = (float(x) + grow for x in shape["size"])
        elif kind == "cylinder" and not grow:
            m.type = Marker.CYLINDER
            m.scale.x = m.scale.y = 2.0 * float(shape["radius"])
            m.scale.z = float(shape["height"])
        elif kind == "plane":
            m.type = Marker.CUBE
            m.scale.x = m.scale.y = PLANE_SIZE
            m.scale.z = PLANE_THICKNESS
        else:
            m.type = Marker.TRIANGLE_LIST
            m.scale.x = m.scale.y = m.scale.z = 1.0
            if kind == "cylinder":
                shape = dict(shape, type="convex")
                r, h = float(body.shape["radius"]), 0.5 * float(body.shape["height"])
                a = np.linspace(0, 2 * math.pi, 24, endpoint=False)
                ring = np.stack([r * np.cos(a), r * np.sin(a), np.zeros(24)], axis=1)
                verts = np.concatenate([ring + [0, 0, h], ring - [0, 0, h]])
            else:
                first, count = scene.table.vrange[slot]
                verts = scene.table.verts[first:first + count]
            pts = support_points(shape, verts, DIRS)
            m.points = _points(pts[TRIS.reshape(-1)])
        return m

    def _place(self, m, body, pos, quat):
        if body.shape["type"] == "plane":
            n = np.asarray(body.shape["normal"], float)
            n /= np.linalg.norm(n)
            # the patch's centre on the plane, its z along the normal (body frame)
            c = (float(body.shape["offset"]) / np.linalg.norm(body.shape["normal"])
                 - 0.5 * PLANE_THICKNESS) * n
            q_n = quat_from_z(n)
            q = quat_mul(quat, q_n)
            c = pos + quat_rotate(quat, c)
        else:
            c, q = pos, quat
        m.pose.position.x, m.pose.position.y, m.pose.position.z = (float(x) for x in c)
        (m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z,
         m.pose.orientation.w) = (float(x) for x in q)

    def marker_array(self, scene, contacts, stamp=None, frame_id="world",
                     normal_length=0.2, deep=0.01, point_size=0.04, bodies=True,
                     max_bodies=None, contact_marker_id=0):
        """The MarkerArray of ``scene``'s bodies (``bodies``) and of ``contacts`` (any
        object with ``body_a``, ``body_b``, ``position``, ``normal``, ``depth``); a body
        with a contact deeper than ``deep`` (m) is drawn red.  ``max_bodies``: at most
        this many body markers per array, the next ones in slot order each call (a
        marker stays in RViz until replaced), so one array's cost stays bounded.
        ``contact_marker_id``: the id of the contact points' and normals' markers (one
        per shard of a scene, so the shards' markers do not replace each other)."""
        out = MarkerArray()
        if bodies:
            depth = np.full(scene.n_slots, -1.0)
            if len(contacts.depth):
                np.maximum.at(depth, contacts.body_a, contacts.depth)
                np.maximum.at(depth, contacts.body_b, contacts.depth)
            every = scene.bodies()
            shown = every
            if max_bodies is not None and len(every) > max_bodies:
                start = self._cursor % len(every)
                shown = (every + every)[start:start + max_bodies]
                self._cursor = start + max_bodies
            live = {scene.index[b.name]: self._bodies.get(scene.index[b.name])
                    for b in every}
            for body in shown:
                slot = scene.index[body.name]
                kept = live[slot]
                m = kept[1] if kept is not None and kept[0] is body else \
                    self._body_marker(scene, slot, body)
                live[slot] = (body, m)
                self._place(m, body, scene.positions[slot], scene.orientations[slot])
                m.color = (FREE if depth[slot] < 0 else DEEP if depth[slot] > deep
                           else TOUCHING)
                m.header.frame_id = frame_id
                if stamp is not None:
                    m.header.stamp = stamp
                out.markers.append(m)
            for slot in set(self._bodies) - set(live):
                gone = Marker(ns="bodies", id=int(slot), action=Marker.DELETE)
                gone.header.frame_id = frame_id
                out.markers.append(gone)
            self._bodies = {slot: kept for slot, kept in live.items() if kept is not None}
        pos = np.asarray(contacts.position, float)
        for ns, kind in (("contacts", Marker.SPHERE_LIST), ("normals", Marker.LINE_LIST)):
            m = Marker(ns=ns, id=int(contact_marker_id), type=kind)
            m.header.frame_id = frame_id
            if stamp is not None:
                m.header.stamp = stamp
            m.pose.orientation.w = 1.0
            if not len(pos):
                m.action = Marker.DELETE
                out.markers.append(m)
                continue
            m.action = Marker.ADD
            if kind == Marker.SPHERE_LIST:
                m.scale.x = m.scale.y = m.scale.z = point_size
                m.color = CONTACT
                m.points = _points(pos)
            else:
                m.scale.x = 0.2 * point_size
                m.color = NORMAL
                length = normal_length + np.asarray(contacts.depth, float)
                ends = pos + np.asarray(contacts.normal, float) * length[:, None]
                m.points = _points(np.stack([pos, ends], axis=1).reshape(-1, 3))
            out.markers.append(m)
        return out


def contacts_to_marker_array(contacts, stamp=None, frame_id="world", normal_length=0.2,
                             point_size=0.04):
    """Contacts alone (no scene) -> the ``contacts`` and ``normals`` markers."""
    class _NoBodies:
        n_slots = 0
    return MarkerPainter().marker_array(_NoBodies(), contacts, stamp, frame_id,
                                        normal_length, point_size=point_size, bodies=False)
