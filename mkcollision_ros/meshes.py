"""Triangle meshes of shapes, for drawing (RViz markers, rerun); ROS- and rerun-free.

Every mesh is in the body frame, metres, with outward-wound triangles:
  cone        its base rim (``RIM`` points), the tip and the base centre: exact up to
              the rim's polygon
  cylinder    two rims and two cap centres
  plane       a square patch (``PLANE_SIZE`` m wide unless the caller sizes it) on the
              plane, centred on its point nearest the body origin (or a chosen point),
              both sides wound (visible from either side)
  others      support points along the directions of a subdivided icosahedron with
              the icosahedron's triangles (a convex hull, capsule, sphere, ellipsoid
              or box: a picture, coarse where the shape has edges)
A margin grows the mesh by that radius along each support direction (exact for the
support-point meshes, along the rim's outward direction for cones and cylinders).
"""
import functools
import math

import numpy as np

PLANE_SIZE = 20.0       # m, the side of a plane's patch
RIM = 24                # points on a cone's or cylinder's rim


@functools.lru_cache(maxsize=None)
def _icosphere(levels):
    """icosphere's arrays, computed once per level (read-only)."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    v = [np.array(x, float) / np.linalg.norm(x) for x in v]
    for _ in range(levels):
        mid, nf = {}, []

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                m = v[a] + v[b]
                v.append(m / np.linalg.norm(m))
                mid[key] = len(v) - 1
            return mid[key]
        for a, b, c in f:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            nf += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        f = nf
    v, f = np.array(v), np.array(f, dtype=np.int64)
    v.flags.writeable = f.flags.writeable = False
    return v, f


def icosphere(levels=1):
    """Unit vertices float64 (V, 3) and outward triangles int64 (F, 3) of an icosahedron
    subdivided ``levels`` times (12, 42, 162 ... vertices); read-only arrays."""
    return _icosphere(int(levels))


def support_points(shape, verts, dirs):
    """Support points (D, 3), body frame, of a ``shape`` dict along unit directions
    ``dirs`` (D, 3), margin included; ``verts`` (M, 3): a convex shape's stored points
    (unused for the other types).  Planes have none (ValueError)."""
    kind, u = shape["type"], np.asarray(dirs, float)
    if kind == "sphere":
        p = float(shape["radius"]) * u
    elif kind == "ellipsoid":
        r = np.asarray(shape["radii"], float)
        g = u * r
        p = g * r / np.linalg.norm(g, axis=1)[:, None]
    elif kind == "box":
        p = 0.5 * np.asarray(shape["size"], float) * np.where(u >= 0, 1.0, -1.0)
    elif kind == "capsule":
        h = 0.5 * float(shape["length"])
        p = float(shape["radius"]) * u + np.outer(np.where(u[:, 2] >= 0, h, -h), [0, 0, 1])
    elif kind in ("cone", "cylinder"):
        r, h = float(shape["radius"]), 0.5 * float(shape["height"])
        s = np.linalg.norm(u[:, :2], axis=1)
        rim = np.zeros_like(u)
        rim[:, :2] = r * u[:, :2] / np.where(s > 0, s, 1.0)[:, None]
        if kind == "cylinder":
            rim[:, 2] = np.where(u[:, 2] >= 0, h, -h)
            p = rim
        else:
            rim[:, 2] = -h
            tip = np.array([0.0, 0.0, h])
            p = np.where((np.sum(rim * u, axis=1) >= u @ tip)[:, None], rim, tip)
    elif kind == "convex":
        p = verts[np.argmax(u @ verts.T, axis=1)]
    else:
        raise ValueError(f"a {kind} shape has no support points")
    return p + float(shape.get("margin", 0.0)) * u


def _ring(r, z, n=RIM):
    a = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    return np.stack([r * np.cos(a), r * np.sin(a), np.full(n, z)], axis=1)


def _fan(centre, first, n, flip):
    """Triangles from vertex ``centre`` to the rim ``first .. first + n - 1``."""
    i = first + np.arange(n)
    j = first + (np.arange(n) + 1) % n
    c = np.full(n, centre)
    return np.stack([c, j, i] if flip else [c, i, j], axis=1)


def _band(lo, hi, n):
    """Triangles of the side between rims ``lo`` and ``hi`` (both n points)."""
    i = np.arange(n)
    j = (i + 1) % n
    return np.concatenate([np.stack([lo + i, lo + j, hi + j], axis=1),
                           np.stack([lo + i, hi + j, hi + i], axis=1)])


def plane_patch(normal, offset, size=PLANE_SIZE, near=(0.0, 0.0, 0.0)):
    """Vertices (4, 3) and triangles (4, 3), both sides, of a square patch ``size`` m
    wide of the plane n.x = offset (n need not be unit), centred on its point nearest
    ``near`` (body frame)."""
    n = np.asarray(normal, float)
    length = np.linalg.norm(n)
    n = n / length
    p = np.asarray(near, float)
    c = p + (float(offset) / length - p @ n) * n
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(n, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    h = 0.5 * size
    v = np.array([c + h * (sx * e1 + sy * e2) for sx, sy in ((-1, -1), (1, -1), (1, 1),
                                                            (-1, 1))])
    f = np.array([[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]], dtype=np.int64)
    return v, f


def shape_mesh(shape, verts=None, levels=1, plane_size=PLANE_SIZE,
               plane_near=(0.0, 0.0, 0.0)):
    """(vertices float64 (V, 3), triangles int64 (F, 3)) of a ``shape`` dict in its body
    frame (module docstring); ``verts``: a convex shape's stored points (M, 3);
    ``levels``: the icosahedron's subdivisions for the support-point meshes; a plane's
    patch is ``plane_size`` wide around its point nearest ``plane_near`` (body frame)."""
    kind = shape["type"]
    m = float(shape.get("margin", 0.0))
    if kind == "plane":
        return plane_patch(shape["normal"], shape["offset"], plane_size, plane_near)
    if kind in ("cone", "cylinder"):
        r, h = float(shape["radius"]) + m, 0.5 * float(shape["height"]) + m
        if kind == "cone":
            v = np.concatenate([_ring(r, -h), [[0.0, 0.0, h], [0.0, 0.0, -h]]])
            f = np.concatenate([_fan(RIM, 0, RIM, False), _fan(RIM + 1, 0, RIM, True)])
        else:
            v = np.concatenate([_ring(r, -h), _ring(r, h), [[0.0, 0.0, h], [0.0, 0.0, -h]]])
            f = np.concatenate([_band(0, RIM, RIM), _fan(2 * RIM, RIM, RIM, False),
                                _fan(2 * RIM + 1, 0, RIM, True)])
        return v, f.astype(np.int64)
    dirs, tris = icosphere(levels)
    pts = np.asarray(verts, float) if verts is not None else None
    return support_points(shape, pts, dirs), tris
