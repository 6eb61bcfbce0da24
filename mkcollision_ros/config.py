"""Body definitions from ROS parameters or a params YAML file, as plain Python.

A params file describes bodies under ``bodies``::

    collision_node:
      ros__parameters:
        bodies:
          names: [ball, floor]
          ball: {type: sphere, radius: 0.3}
          floor: {type: plane, normal: [0.0, 0.0, 1.0], offset: 0.0, static: true}

Per body: the shape keys of ``mkcollision_ros.shapes`` (``points`` may be given flat,
``[x, y, z, x, y, z, ...]``, since ROS parameters cannot nest lists) plus ``static``
(bool), ``group`` and ``mask`` (int bitmasks), and an initial pose ``position``
[x, y, z] / ``orientation`` [x, y, z, w] (default: origin, identity; static bodies keep
it until a pose message moves them).  ROS flattens the nesting into dotted
names (``bodies.ball.radius``); ``bodies_from_flat`` reads that form, so the node and
plain Python read the same file the same way.  ``pose_topic`` (a
geometry_msgs/PoseStamped topic that moves that body, as motion-capture drivers publish
one topic per rigid body) is read by ``pose_topics_from_params``.
"""
import os

import yaml

from .scene import validate_body

BODY_KEYS = {"static", "group", "mask", "position", "orientation", "pose_topic"}
SHAPE_KEYS = {"type", "radius", "radii", "size", "length", "height", "points", "mesh",
              "normal", "offset", "margin"}


def bodies_from_flat(flat, base_dir=None):
    """``{"names": [...], "<name>.<key>": value, ...}`` -> list of body dicts
    ``{"name", "shape", "static", "group", "mask"}`` (and ``pose`` when given), checked
    by ``scene.validate_body``.  Raises ValueError naming the body and the key for
    anything missing, unknown or invalid."""
    names = flat.get("names")
    if not isinstance(names, (list, tuple)) or not names:
        raise ValueError("bodies.names must be a non-empty list of body names")
    names = [str(n) for n in names]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise ValueError(f"bodies.names has duplicates: {dup}")
    per_body = {n: {} for n in names}
    for key, value in flat.items():
        if key == "names":
            continue
        body, _, field = key.partition(".")
        if body not in per_body:
            raise ValueError(f"bodies.{key}: '{body}' is not listed in bodies.names")
        if field not in SHAPE_KEYS | BODY_KEYS:
            raise ValueError(f"bodies.{key}: unknown key '{field}'; expected one of "
                             f"{sorted(SHAPE_KEYS | BODY_KEYS)}")
        per_body[body][field] = value
    bodies = []
    for name in names:
        fields = per_body[name]
        if "type" not in fields:
            raise ValueError(f"body '{name}': missing 'type'")
        shape = {k: v for k, v in fields.items() if k in SHAPE_KEYS}
        if "points" in shape:
            pts = list(shape["points"])
            if pts and not isinstance(pts[0], (list, tuple)):
                if len(pts) % 3:
                    raise ValueError(f"body '{name}': flat 'points' needs a multiple of 3 "
                                     f"values, got {len(pts)}")
                pts = [pts[i:i + 3] for i in range(0, len(pts), 3)]
            shape["points"] = pts
        if "mesh" in shape and base_dir is not None and not os.path.isabs(shape["mesh"]):
            shape["mesh"] = os.path.join(base_dir, shape["mesh"])
        entry = {"name": name, "shape": shape}
        entry.update({k: fields[k] for k in ("static", "group", "mask") if k in fields})
        if "position" in fields or "orientation" in fields:
            entry["pose"] = (fields.get("position", [0.0, 0.0, 0.0]),
                             fields.get("orientation", [0.0, 0.0, 0.0, 1.0]))
        body = validate_body(entry)
        out = {"name": body.name, "shape": body.shape, "static": body.static,
               "group": body.group, "mask": body.mask}
        if body.pose is not None:
            out["pose"] = body.pose
        bodies.append(out)
    return bodies


def flatten(tree, prefix=""):
    """Nested dict -> dotted keys, as ROS flattens a params file."""
    out = {}
    for key, value in tree.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten(value, dotted + "."))
        else:
            out[dotted] = value
    return out


def load_params_file(path, node_name="collision_node"):
    """Read a ROS params YAML file without ROS: returns the flat parameter dict of
    ``node_name`` (blocks for ``/**`` and the node both apply, the later one winning,
    as in ROS)."""
    with open(path, encoding="utf-8") as f:
        doc = yaml.safe_load(f)
    if not isinstance(doc, dict):
        raise ValueError(f"{path}: not a ROS params file (expected a mapping of node names)")
    params = {}
    for key, block in doc.items():
        if key.lstrip("/") in ("**", node_name) and isinstance(block, dict):
            params.update(flatten(block.get("ros__parameters", {})))
    if not params:
        raise ValueError(f"{path}: no ros__parameters for node '{node_name}'")
    return params


def pose_topics_from_params(params):
    """``{body name: PoseStamped topic}`` of the bodies given a ``pose_topic``."""
    out = {}
    for key, value in params.items():
        parts = key.split(".")
        if len(parts) == 3 and parts[0] == "bodies" and parts[2] == "pose_topic":
            if not isinstance(value, str) or not value:
                raise ValueError(f"{key} must be a topic name, got {value!r}")
            out[parts[1]] = value
    return out


def bodies_from_params(params, base_dir=None):
    """Body dicts from a flat parameter dict (keys ``bodies.*``)."""
    flat = {k[len("bodies."):]: v for k, v in params.items() if k.startswith("bodies.")}
    return bodies_from_flat(flat, base_dir)
