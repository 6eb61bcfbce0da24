"""Thin, batch-first conversions between ROS messages and numpy arrays.

Nothing here computes collisions; every function turns one message into arrays or
arrays into one message.  Float arrays of the struct-of-arrays messages are read
zero-copy (``np.frombuffer`` on the ``array.array`` field) and written with one
``frombytes`` call, so a 1,000-body message costs microseconds.
"""
from .contacts import (contact_array_to_arrays, contacts_to_contact_array,
                       contacts_to_contact_list, events_to_contact_events,
                       proximity_to_proximity_array)
from .markers import MarkerPainter, contacts_to_marker_array
from .poses import (arrays_to_body_pose_array, body_pose_array_to_arrays,
                    pose_array_from_cdr, pose_array_to_arrays)
from .scene import body_msg_to_body, scene_to_scene_msg

__all__ = [
    "arrays_to_body_pose_array", "body_pose_array_to_arrays", "pose_array_to_arrays",
    "pose_array_from_cdr",
    "contacts_to_contact_array", "contact_array_to_arrays", "contacts_to_contact_list",
    "contacts_to_marker_array", "events_to_contact_events", "proximity_to_proximity_array",
    "body_msg_to_body", "scene_to_scene_msg", "MarkerPainter",
]
