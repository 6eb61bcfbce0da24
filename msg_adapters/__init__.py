"""Thin, batch-first conversions between ROS messages and numpy arrays.

Nothing here computes collisions; every function turns one message into arrays or
arrays into one message.  Float arrays of the struct-of-arrays messages are read
zero-copy (``np.frombuffer`` on the ``array.array`` field) and written with one
``frombytes`` call, so a 1,000-body message costs microseconds.
"""
from .contacts import contact_array_to_arrays, contacts_to_contact_array, contacts_to_contact_list
from .markers import contacts_to_marker_array
from .poses import (arrays_to_body_pose_array, body_pose_array_to_arrays,
                    pose_array_to_arrays)

__all__ = [
    "arrays_to_body_pose_array", "body_pose_array_to_arrays", "pose_array_to_arrays",
    "contacts_to_contact_array", "contact_array_to_arrays", "contacts_to_contact_list",
    "contacts_to_marker_array",
]
