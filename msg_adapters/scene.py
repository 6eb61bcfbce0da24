"""Scene messages <-> the library's body dicts (``mkcollision_ros.scene``).

``Body`` carries a shape three ways (see Body.msg): this package's ``type`` and
``dimensions`` (every shape type, including the ellipsoid, capsule and plane that
shape_msgs/SolidPrimitive lacks), a SolidPrimitive (box, sphere, cylinder, cone), or a
shape_msgs/Mesh taken as the convex hull of its vertices.
"""
import numpy as np
from geometry_msgs.msg import Point
from mkcollision_msgs.msg import Body, Scene
from shape_msgs.msg import SolidPrimitive

# dimensions of each ``type``: the shape dict's keys, in order (a list value takes n)
TYPE_DIMENSIONS = {
    "sphere": (("radius", 1),), "ellipsoid": (("radii", 3),), "box": (("size", 3),),
    "capsule": (("radius", 1), ("length", 1)), "cylinder": (("radius", 1), ("height", 1)),
    "cone": (("radius", 1), ("height", 1)), "plane": (("normal", 3), ("offset", 1)),
    "convex": (),
}


def _shape_from_type(msg):
    kind = msg.type
    if kind not in TYPE_DIMENSIONS:
        raise ValueError(f"body '{msg.name}': unknown type {kind!r}; expected one of "
                         f"{', '.join(TYPE_DIMENSIONS)}")
    if kind == "convex":
        return _shape_from_mesh(msg)
    want = sum(n for _, n in TYPE_DIMENSIONS[kind])
    dims = [float(v) for v in msg.dimensions]
    if len(dims) != want:
        keys = ", ".join(k for k, _ in TYPE_DIMENSIONS[kind])
        raise ValueError(f"body '{msg.name}': type {kind} takes {want} dimensions "
                         f"({keys}), got {len(dims)}")
    shape, at = {"type": kind}, 0
    for key, n in TYPE_DIMENSIONS[kind]:
        shape[key] = dims[at] if n == 1 else dims[at:at + n]
        at += n
    return shape


def _shape_from_primitive(msg):
    p, d = msg.primitive, [float(v) for v in msg.primitive.dimensions]
    need = {SolidPrimitive.BOX: 3, SolidPrimitive.SPHERE: 1, SolidPrimitive.CYLINDER: 2,
            SolidPrimitive.CONE: 2}
    if p.type not in need:
        raise ValueError(f"body '{msg.name}': SolidPrimitive type {p.type} is not supported "
                         f"(BOX, SPHERE, CYLINDER, CONE; a prism as a Mesh)")
    if len(d) != need[p.type]:
        raise ValueError(f"body '{msg.name}': SolidPrimitive type {p.type} needs "
                         f"{need[p.type]} dimensions, got {len(d)}")
    if p.type == SolidPrimitive.BOX:
        return {"type": "box", "size": d}
    if p.type == SolidPrimitive.SPHERE:
        return {"type": "sphere", "radius": d[0]}
    kind = "cylinder" if p.type == SolidPrimitive.CYLINDER else "cone"
    return {"type": kind, "radius": d[SolidPrimitive.CYLINDER_RADIUS],
            "height": d[SolidPrimitive.CYLINDER_HEIGHT]}


def _shape_from_mesh(msg):
    pts = [[v.x, v.y, v.z] for v in msg.mesh.vertices]
    if not pts:
        raise ValueError(f"body '{msg.name}': no shape (set type, primitive or "
                         f"mesh.vertices)")
    return {"type": "convex", "points": pts}


def body_msg_to_body(msg):
    """``Body`` -> a body dict for ``Scene.add_body`` / ``replace_body`` (validated
    there).  Raises ValueError naming the body for a shape it cannot describe."""
    if msg.type:
        shape = _shape_from_type(msg)
    elif msg.primitive.type != 0:
        shape = _shape_from_primitive(msg)
    else:
        shape = _shape_from_mesh(msg)
    if msg.margin:
        shape["margin"] = float(msg.margin)
    body = {"name": msg.name, "shape": shape, "static": bool(msg.is_static)}
    if not msg.default_filter:
        body["group"], body["mask"] = int(msg.group), int(msg.mask)
    if msg.has_pose:
        p, q = msg.pose.position, msg.pose.orientation
        body["pose"] = ([p.x, p.y, p.z], [q.x, q.y, q.z, q.w])
    return body


def scene_to_scene_msg(scene, stamp=None, frame_id="world"):
    """A ``mkcollision_ros.scene.Scene`` -> ``Scene`` (every body with its shape as
    ``type`` + ``dimensions``, hulls as mesh vertices, its filter and current pose)."""
    msg = Scene()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    table = scene.table
    for body in scene.bodies():
        slot = scene.index[body.name]
        b = Body(name=body.name, type=body.shape["type"], is_static=body.static,
                 group=body.group, mask=body.mask,
                 margin=float(body.shape.get("margin", 0.0)))
        if b.type == "convex":
            first, count = table.vrange[slot]
            b.mesh.vertices = [Point(x=float(x), y=float(y), z=float(z))
                               for x, y, z in table.verts[first:first + count]]
        else:
            dims = []
            for key, n in TYPE_DIMENSIONS[b.type]:
                v = body.shape[key]
                dims += [float(x) for x in np.ravel(v)] if n > 1 else [float(v)]
            b.dimensions = dims
        b.has_pose = bool(scene.posed[slot])
        pos, q = scene.positions[slot], scene.orientations[slot]
        b.pose.position.x, b.pose.position.y, b.pose.position.z = (float(v) for v in pos)
        (b.pose.orientation.x, b.pose.orientation.y, b.pose.orientation.z,
         b.pose.orientation.w) = (float(v) for v in q)
        msg.bodies.append(b)
    msg.allowed_pairs = [n for pair in scene.allowed_pairs() for n in pair]
    return msg
