"""Contacts -> ``visualization_msgs/MarkerArray``: one SPHERE_LIST of all contact points
and one ARROW per contact along its normal (A -> B), capped in number, after a DELETEALL
so arrows of contacts that ended disappear."""
from geometry_msgs.msg import Point
from visualization_msgs.msg import Marker, MarkerArray

NAMESPACE = "mkcollision_contacts"


def _pt(v):
    p = Point()
    p.x, p.y, p.z = float(v[0]), float(v[1]), float(v[2])
    return p


def contacts_to_marker_array(contacts, stamp=None, frame_id="world", normal_length=0.2,
                             max_arrows=500, point_size=0.04):
    """Contacts (see ``contacts.py``) -> ``MarkerArray``.

    Marker 0 (DELETEALL) clears the namespace, marker 1 is the SPHERE_LIST of contact
    positions, markers 2.. are arrows from each contact position along the normal
    (``normal_length`` metres), at most ``max_arrows``.
    """
    out = MarkerArray()
    clear = Marker()
    clear.action = Marker.DELETEALL
    clear.ns = NAMESPACE
    out.markers.append(clear)

    def base(marker_id, kind):
        m = Marker()
        if stamp is not None:
            m.header.stamp = stamp
        m.header.frame_id = frame_id
        m.ns = NAMESPACE
        m.id = marker_id
        m.type = kind
        m.action = Marker.ADD
        m.pose.orientation.w = 1.0
        m.color.a = 1.0
        return m

    points = base(1, Marker.SPHERE_LIST)
    points.scale.x = points.scale.y = points.scale.z = point_size
    points.color.r, points.color.g, points.color.b = 1.0, 0.2, 0.1
    points.points = [_pt(p) for p in contacts.position]
    out.markers.append(points)
    for k in range(min(len(contacts.depth), max_arrows)):
        arrow = base(2 + k, Marker.ARROW)
        p = contacts.position[k]
        arrow.points = [_pt(p), _pt(p + normal_length * contacts.normal[k])]
        arrow.scale.x = 0.2 * point_size   # shaft diameter
        arrow.scale.y = 0.5 * point_size   # head diameter
        arrow.scale.z = 0.0                # default head length
        arrow.color.r, arrow.color.g, arrow.color.b = 0.1, 0.6, 1.0
        out.markers.append(arrow)
    return out
