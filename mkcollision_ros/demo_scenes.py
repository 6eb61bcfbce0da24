"""The demo's scenes: bodies as data and scripted motion (kinematics, not physics).

A scene has its bodies (the node's params format, written to ``config/demo_<name>.yaml``
by ``write_params``; static bodies marked static) and ``pose(t)``: the moving bodies'
poses at script time ``t`` (s), positions (N, 3) in metres and quat_xyzw (N, 4), in the
order of ``scene.moving``.  A script plays for ``scene.duration`` seconds, holds its
final state for ``scene.hold`` seconds and starts again (``pose`` is periodic with
period ``duration + hold``).

Scenes (``SCENES``; ``make_scene(name, bodies=None)`` builds one):

bowling   ten pins (ellipsoids 0.12 x 0.12 x 0.38 m, the collision ellipsoids of a pin)
          in their triangle, a ball (r 0.108 m) rolling into the head pin; pins hit by the
          ball or by a falling pin topple and slide away and lie on the lane.
dominoes  a row of boxes 0.03 x 0.12 x 0.24 m falling one into the next; each domino
          turns about its front bottom edge until its top edge reaches the next one
          (the tipping angle follows from the spacing and the size), then leans on it.
marbles   six marbles (r 0.03 m) rolling down two tilted planks, one after the other,
          and into a tray with walls.
stack     a tower of eight blocks hit by a thrown ball; the tower tips over about its
          far bottom edge, the blocks part and land in a row on the floor.
swarm     mixed shapes on crossing orbits (``demo_poses``); ``bodies=N`` generates N
          bodies, the orbits spread out so the density stays about the same.

Bodies at rest, rolling or lying sink ``REST`` metres into what holds them, so their
resting contacts show as contacts too.  ``scene.expects`` lists the contacts a viewer
expects (``Expect``): each counts the subjects seen touching one of their partners
(when ``moved`` is set: only while the subject is at least that far from where it
started); ``Expect.report`` turns the subjects seen into a line of the summary.
"""
import math
import os
from typing import NamedTuple

import numpy as np
import yaml

from .rotations import quat_axis_angle, quat_rotate

REST = 0.002         # m, depth of a resting contact
G = 9.81             # m/s^2
KEY_DT = 0.002       # s, spacing of a script's keyframes (pose(t) interpolates them)
SCENE_NAMES = ("bowling", "dominoes", "marbles", "stack", "swarm")
NODE_PARAMS = {"frame_id": "world", "contact_margin": 0.001, "max_contacts": 4,
               "publish_markers": True, "marker_normal_length": 0.1}


def _y_turn(angle):
    """Rotation about +y by ``angle``: a body's +z tips toward +x."""
    return quat_axis_angle(np.array([0.0, 1.0, 0.0]), angle)


def _xz_turn(angle, vec):
    """(dx, dz) vectors (..., 2) turned about +y by ``angle`` (+z toward +x)."""
    c, s = np.cos(angle), np.sin(angle)
    dx, dz = vec[..., 0], vec[..., 1]
    return np.stack([dx * c + dz * s, -dx * s + dz * c], -1)


# -- scenes ------------------------------------------------------------------------------
class Expect(NamedTuple):
    """Contacts a viewer expects: each subject touching one of its partners.

    label     what is counted ("ball-pin contacts")
    noun      what the subjects are ("pins")
    targets   {subject name: frozenset of partner names}
    moved     m or None: count a contact only while the subject is at least this far
              from its position at t = 0 (a toppled pin on the floor, not a standing one)
    wanted    how many subjects the script makes touch (None: not known in advance)
    """
    label: str
    noun: str
    targets: dict
    moved: float = None
    wanted: int = None

    def report(self, seen):
        """The summary line of the subjects ``seen`` touching."""
        line = f"{self.label}: {len(seen)} of {len(self.targets)} {self.noun}"
        if self.wanted is None:
            return line
        return line + (f" (the script makes at least {self.wanted}: "
                       f"{'seen' if len(seen) >= self.wanted else 'NOT all seen'})")


def note_contacts(scene, t, pairs, seen):
    """Add to ``seen`` ({Expect label: set of subjects}) the subjects of
    ``scene.expects`` that the touching ``pairs`` ((name, name), any order) at script time
    ``t`` show."""
    for e in scene.expects:
        got = seen.setdefault(e.label, set())
        for a, b in pairs:
            for subject, partner in ((a, b), (b, a)):
                if subject in got or partner not in e.targets.get(subject, ()):
                    continue
                if e.moved is None or scene.moved(t, subject) >= e.moved:
                    got.add(subject)
    return seen


class Scene:
    """Bodies (params-format dicts), the moving ones' names, a keyframed script."""

    def __init__(self, name, bodies, moving, times, pos, quat, hold, expects, doc,
                 poses=None):
        self.name = name
        self.bodies = bodies                 # [{"name", "shape" keys..., "static"...}]
        self.moving = list(moving)
        self.duration = float(times[-1]) if times is not None else 0.0
        self.hold = float(hold)
        self.expects = expects
        self.doc = doc
        self._times, self._pos, self._quat = times, pos, quat
        self._poses = poses                  # a function of t instead of keyframes
        self._index = {n: i for i, n in enumerate(self.moving)}
        if quat is not None:                 # neighbouring keyframes in one hemisphere
            flip = np.cumprod(np.where(np.sum(quat[1:] * quat[:-1], -1) < 0, -1.0, 1.0),
                              axis=0)
            quat[1:] *= flip[..., None]

    @property
    def period(self):
        return self.duration + self.hold

    def script_time(self, t):
        """Time into the script of wall time ``t`` (loops; holds the end state)."""
        if self._poses is not None:
            return float(t)
        return min(float(t) % self.period, self.duration)

    def pose(self, t):
        """Positions (N, 3), quat_xyzw (N, 4) of ``self.moving`` at time ``t`` (s)."""
        if self._poses is not None:
            return self._poses(float(t))
        u = self.script_time(t)
        k = min(int(u / KEY_DT), len(self._times) - 2)
        w = min(max((u - self._times[k]) / KEY_DT, 0.0), 1.0)
        pos = (1.0 - w) * self._pos[k] + w * self._pos[k + 1]
        quat = (1.0 - w) * self._quat[k] + w * self._quat[k + 1]
        return pos, quat / np.linalg.norm(quat, axis=1, keepdims=True)

    def moved(self, t, name):
        """Distance (m) of moving body ``name`` at time ``t`` from where it starts."""
        i = self._index[name]
        return float(np.linalg.norm(self.pose(t)[0][i] - self.pose(0.0)[0][i]))

    def params(self):
        """The node's params document of this scene (a dict for yaml)."""
        names = [b["name"] for b in self.bodies]
        block = {b["name"]: {k: v for k, v in b.items() if k != "name"} for b in self.bodies}
        return {"/**": {"ros__parameters": dict(NODE_PARAMS, bodies={"names": names,
                                                                     **block})}}


def _num(x):
    return round(float(x), 6)


def _vec(v):
    return [_num(x) for x in v]


def params_body(name, shape, position=None, orientation=None, static=False):
    """A body of a params file: its name, shape keys, ``static``, initial pose."""
    body = {"name": name, **shape}
    if static:
        body["static"] = True
    if position is not None:
        body["position"] = _vec(position)
    if orientation is not None:
        body["orientation"] = _vec(orientation)
    return body


def _keyframes(duration):
    n = int(math.ceil(duration / KEY_DT)) + 1
    return np.arange(n) * KEY_DT


def _smoothstep(w):
    w = np.clip(w, 0.0, 1.0)
    return w * w * (3.0 - 2.0 * w)


# -- dominoes ------------------------------------------------------------------------------
DOMINO = dict(count=14, thick=0.03, wide=0.12, tall=0.24, spacing=0.12, reach=0.003,
              start=0.5, link_s=0.3, last_s=0.5)


def domino_lean(phi, spacing, thick, tall, reach):
    """Tilt (rad) of a domino leaning ``reach`` metres into the next one, tilted
    ``phi``; both turn about their front bottom edges, ``spacing`` apart.  The first of
    two contacts to close decides: the domino's top front edge on the next one's back
    face (signed distance spacing*cos(phi) - thick - tall*sin(theta - phi)), or its
    front face on the next one's back bottom edge (which the next one lifts as it
    falls; signed distance (spacing - thick*cos(phi))*cos(theta) -
    thick*sin(phi)*sin(theta))."""
    corner = phi + np.arcsin((spacing * np.cos(phi) - thick + reach) / tall)
    bx, bz = spacing - thick * np.cos(phi), thick * np.sin(phi)
    edge = np.arccos(np.clip(-reach / np.hypot(bx, bz), -1.0, 1.0)) - np.arctan2(bz, bx)
    return np.minimum(corner, edge)


def dominoes():
    c = DOMINO
    n, th, h, s = c["count"], c["thick"], c["tall"], c["spacing"]
    if not s - th + c["reach"] < h:
        raise ValueError("dominoes: the spacing is too wide for a domino to reach the next")
    x0 = -0.5 * (n - 1) * s
    first = domino_lean(0.0, s, th, h, c["reach"])     # the tilt at the first touch
    starts = c["start"] + c["link_s"] * np.arange(n)
    times = _keyframes(starts[-1] + c["last_s"] + 0.3)
    theta = np.zeros((len(times), n))
    u_last = np.clip((times - starts[-1]) / c["last_s"], 0.0, 1.0)
    theta[:, -1] = 0.5 * math.pi * u_last ** 2          # the last one falls flat
    for i in range(n - 2, -1, -1):
        u = np.clip((times - starts[i]) / c["link_s"], 0.0, 1.0)
        free = first * u ** 2                           # tipping from rest
        theta[:, i] = np.where(times >= starts[i + 1],
                               domino_lean(theta[:, i + 1], s, th, h, c["reach"]), free)
    pivot = np.stack([x0 + s * np.arange(n) + 0.5 * th, np.full(n, -REST)], -1)
    rel = _xz_turn(theta, np.array([-0.5 * th, 0.5 * h]))
    xz = pivot + rel
    pos = np.stack([xz[..., 0], np.zeros_like(theta), xz[..., 1]], -1)
    quat = _y_turn(theta)
    names = [f"domino_{i}" for i in range(n)]
    shape = {"type": "box", "size": [th, c["wide"], h]}
    bodies = [params_body(nm, shape, pos[0, i]) for i, nm in enumerate(names)]
    bodies.append(params_body("floor", {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": 0.0},
                        static=True))
    expects = [Expect("domino-next contacts", "dominoes",
                      {names[i]: frozenset([names[i + 1]]) for i in range(n - 1)},
                      wanted=n - 1)]
    return Scene("dominoes", bodies, names, times, pos, quat, 2.0, expects,
                 f"{n} dominoes in a row fall one into the next; the last lies flat")


# -- stack ---------------------------------------------------------------------------------
STACK = dict(levels=8, size=(0.16, 0.16, 0.1), ball_r=0.11, throw_from=(-2.4, 0.0, 0.35),
             hit_height=0.62, flight_s=0.6, push_s=0.12, fall_s=1.1, gap=0.03,
             bounce=0.5)


def stack():
    c = STACK
    n, (w, d, h), r = c["levels"], c["size"], c["ball_r"]
    centre_z = (np.arange(n) + 0.5) * h - (np.arange(n) + 1) * REST
    t_hit = 0.5 + c["flight_s"]
    t_end = t_hit + c["fall_s"] + 1.2
    times = _keyframes(t_end)
    u = np.maximum(times - t_hit, 0.0)
    theta = 0.5 * math.pi * np.minimum(u / c["fall_s"], 1.0) ** 2
    pivot = np.array([0.5 * w, -REST])
    # the column's coordinate along the tower stretches as it falls: the blocks part
    part = (theta / (0.5 * math.pi)) ** 2
    rel = np.stack([np.full((len(times), n), -0.5 * w),
                    (centre_z + REST)[None, :] + c["gap"] * np.arange(n)[None, :]
                    * part[:, None]], -1)
    xz = pivot + _xz_turn(theta[:, None], rel)
    blocks = np.stack([xz[..., 0], np.zeros((len(times), n)), xz[..., 1]], -1)
    bq = np.repeat(_y_turn(theta)[:, None, :], n, axis=1)
    # the ball: thrown (ballistic) into the tower's face, carried by it while it pushes,
    # then dropped to the floor, where it rolls back and stops
    hit = np.array([-0.5 * w - r + 0.004, 0.0, c["hit_height"]])
    p0 = np.array(c["throw_from"])
    g = np.array([0.0, 0.0, -G])
    tf = c["flight_s"]
    v0 = (hit - p0 - 0.5 * g * tf * tf) / tf
    ball = np.zeros((len(times), 3))
    spin = np.zeros(len(times))
    for k, t in enumerate(times):
        if t < 0.5:
            ball[k] = p0
        elif t < t_hit:
            f = t - 0.5
            ball[k] = p0 + v0 * f + 0.5 * g * f * f
            spin[k] = v0[0] * f / r
        elif t < t_hit + c["push_s"]:
            th = theta[k]
            rel_b = np.array([hit[0] - pivot[0], hit[2] - pivot[1]])
            bx, bz = _xz_turn(th, rel_b) + pivot
            ball[k] = [bx, 0.0, bz]
            spin[k] = spin[k - 1]
        else:
            ball[k] = ball[k - 1]
            spin[k] = spin[k - 1]
    # after the push: a short bounce back, a fall, a roll back that slows to rest
    k_rel = int(np.searchsorted(times, t_hit + c["push_s"]))
    pb = ball[k_rel - 1].copy()
    vx, vz = -c["bounce"], 0.0
    z_floor = r - REST
    for k in range(k_rel, len(times)):
        if pb[2] > z_floor:
            vz -= G * KEY_DT
            pb = pb + KEY_DT * np.array([vx, 0.0, vz])
            pb[2] = max(pb[2], z_floor)
        else:
            vx *= math.exp(-KEY_DT / 0.6)
            pb = pb + KEY_DT * np.array([vx, 0.0, 0.0])
        ball[k] = pb
        spin[k] = spin[k - 1] + vx * KEY_DT / r
    names = [f"block_{i}" for i in range(n)] + ["ball"]
    pos = np.concatenate([blocks, ball[:, None, :]], axis=1)
    quat = np.concatenate([bq, _y_turn(spin)[:, None, :]], axis=1)
    bodies = [params_body(nm, {"type": "box", "size": [w, d, h]}, pos[0, i])
              for i, nm in enumerate(names[:-1])]
    bodies.append(params_body("ball", {"type": "sphere", "radius": r}, p0))
    bodies.append(params_body("floor", {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": 0.0},
                        static=True))
    expects = [Expect("ball-tower contacts", "blocks",
                      {nm: frozenset(["ball"]) for nm in names[:-1]}, wanted=1),
               Expect("blocks on the floor after the fall", "blocks",
                      {nm: frozenset(["floor"]) for nm in names[:-1]}, moved=0.1, wanted=n)]
    return Scene("stack", bodies, names, times, pos, quat, 2.0, expects,
                 f"a tower of {n} blocks hit by a thrown ball tips over; the blocks land "
                 f"in a row")


# -- marbles -------------------------------------------------------------------------------
MARBLES = dict(count=6, radius=0.03, release_every=0.6, lane=0.075,
               planks=[((-1.3, 0.0, 1.0), 15.0, 1.1), ((-0.3, 0.0, 0.62), 8.0, 1.3)],
               plank_wide=0.45, plank_thick=0.03, tray=((1.05, 2.25), 0.02, 0.08),
               tray_wide=0.5, roll_decel=0.6, wall_bounce=0.3)


def _planks():
    """(top start point, unit down-slope direction (x, z), length, centre, quat) per plank."""
    c = MARBLES
    out = []
    for top, deg, length in c["planks"]:
        a = math.radians(deg)
        down = np.array([math.cos(a), -math.sin(a)])
        normal = np.array([math.sin(a), math.cos(a)])
        top = np.array([top[0], top[2]])
        centre = top + 0.5 * length * down - 0.5 * c["plank_thick"] * normal
        out.append((top, down, normal, length, centre, _y_turn(np.array(a))))
    return out


def _marble_path(y, t_release, times, planks, tray_top, x_far_wall):
    """One marble: resting at the top of the first plank until ``t_release``, then
    rolling (acceleration 5/7 g sin a, a solid ball), flying from plank end to the next
    surface, rolling in the tray until it stops.  Returns positions (T, 3), roll angle
    about +y (T,)."""
    c = MARBLES
    r = c["radius"]
    lift = r - REST
    top, down, normal, length, _, _ = planks[0]
    p = top + 0.5 * r * down + lift * normal
    v = np.zeros(2)
    mode, plank = "plank", 0
    pos = np.zeros((len(times), 3))
    roll = np.zeros(len(times))
    angle = 0.0
    omega = 0.0
    for k, t in enumerate(times):
        if t >= t_release:
            if mode == "plank":
                top, down, normal, length, _, _ = planks[plank]
                v = v + KEY_DT * (5.0 / 7.0) * G * (-down[1]) * down
                p = p + KEY_DT * v
                s = float(np.dot(p - top, down))
                p = top + s * down + lift * normal
                v = np.dot(v, down) * down
                omega = v[0] / r
                if s > length:
                    mode = "fly"
            elif mode == "fly":
                v = v + KEY_DT * np.array([0.0, -G])
                q = p + KEY_DT * v
                landed = False
                for j in range(plank + 1, len(planks)):
                    top, down, normal, length, _, _ = planks[j]
                    s = float(np.dot(q - top, down))
                    if 0.0 <= s <= length and np.dot(q - top, normal) <= lift:
                        plank, mode, landed = j, "plank", True
                        p = top + s * down + lift * normal
                        v = np.dot(v, down) * down
                        break
                if not landed:
                    if q[1] <= tray_top + lift:
                        mode = "tray"
                        p = np.array([q[0], tray_top + lift])
                        v = np.array([v[0], 0.0])
                    else:
                        p = q
            elif mode == "tray":
                speed = abs(v[0])
                if speed > 0.0:
                    speed = max(speed - c["roll_decel"] * KEY_DT, 0.0)
                    v = np.array([math.copysign(speed, v[0]), 0.0])
                p = p + KEY_DT * v
                if p[0] + r - REST > x_far_wall:
                    p[0] = x_far_wall - r + REST
                    v = -c["wall_bounce"] * v
                omega = v[0] / r
            angle += omega * KEY_DT
        pos[k] = [p[0], y, p[1]]
        roll[k] = angle
    return pos, roll


def marbles():
    c = MARBLES
    n, r = c["count"], c["radius"]
    planks = _planks()
    (x_lo, x_hi), tray_thick, wall_h = c["tray"]
    tray_top = tray_thick
    wall = 0.02
    t_last = 0.5 + (n - 1) * c["release_every"]
    times = _keyframes(t_last + 4.0)
    ys = (np.arange(n) - 0.5 * (n - 1)) * c["lane"]
    paths = [_marble_path(ys[i], 0.5 + i * c["release_every"], times, planks, tray_top,
                          x_hi - wall) for i in range(n)]
    pos = np.stack([p for p, _ in paths], axis=1)
    quat = np.stack([_y_turn(a) for _, a in paths], axis=1)
    names = [f"marble_{i}" for i in range(n)]
    bodies = [params_body(nm, {"type": "sphere", "radius": r}, pos[0, i])
              for i, nm in enumerate(names)]
    plank_names = [f"plank_{j}" for j in range(len(planks))]
    for nm, (_, _, _, length, centre, q) in zip(plank_names, planks):
        bodies.append(params_body(nm, {"type": "box", "size": [length, c["plank_wide"],
                                                         c["plank_thick"]]},
                            [centre[0], 0.0, centre[1]], q, static=True))
    tw, xm = c["tray_wide"], 0.5 * (x_lo + x_hi)
    bodies.append(params_body("tray", {"type": "box", "size": [x_hi - x_lo, tw, tray_thick]},
                        [xm, 0.0, 0.5 * tray_thick], static=True))
    for nm, size, at in (
            ("tray_wall_far", [wall, tw, wall_h], [x_hi - 0.5 * wall, 0.0,
                                                    tray_thick + 0.5 * wall_h]),
            ("tray_wall_near", [wall, tw, wall_h], [x_lo + 0.5 * wall, 0.0,
                                                     tray_thick + 0.5 * wall_h]),
            ("tray_wall_left", [x_hi - x_lo, wall, wall_h],
             [xm, 0.5 * (tw - wall), tray_thick + 0.5 * wall_h]),
            ("tray_wall_right", [x_hi - x_lo, wall, wall_h],
             [xm, -0.5 * (tw - wall), tray_thick + 0.5 * wall_h])):
        bodies.append(params_body(nm, {"type": "box", "size": size}, at, static=True))
    bodies.append(params_body("floor", {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": 0.0},
                        static=True))
    expects = [Expect("marble-plank contacts", "marbles",
                      {nm: frozenset(plank_names) for nm in names}, wanted=n),
               Expect("marbles in the tray", "marbles",
                      {nm: frozenset(["tray"]) for nm in names}, moved=0.5, wanted=n)]
    return Scene("marbles", bodies, names, times, pos, quat, 2.0, expects,
                 f"{n} marbles roll down {len(planks)} planks into a tray")


# -- bowling -------------------------------------------------------------------------------
BOWLING = dict(pin_radii=(0.06, 0.06, 0.19), pin_spacing=0.3048, ball_r=0.108,
               ball_start=-3.5, ball_y=0.005, ball_speed=3.0, ball_stop=1.5, fall_s=0.6,
               push_s=0.1, slide_s=0.2, knock_speed=1.5, deflect_deg=45.0,
               hit_depth=0.003, samples=600, settle_speed=0.3,
               max_speed=4.5)


def _fibonacci(n):
    """n roughly even unit vectors (n, 3)."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    rho = np.sqrt(1.0 - z * z)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], -1)


def _inside_ellipsoid(points, centre, quat, radii):
    """Which points (M, 3) lie inside the ellipsoid (centre, quat_xyzw, radii)."""
    inv = quat * np.array([-1.0, -1.0, -1.0, 1.0])
    local = quat_rotate(inv[None, :], points - centre)
    return np.sum((local / radii) ** 2, axis=-1) < 1.0


def bowling():
    """Pins hit by the ball are carried by it for ``push_s`` seconds, then slide away
    from it (slowing down, time constant ``slide_s``), faster than the ball moves along
    that direction; a pin toppling for ``fall_s`` seconds whose surface enters a
    pin by ``hit_depth`` knocks it: that one slides at ``knock_speed`` (or faster than
    the knocking pin moves toward it, up to ``max_speed``) and topples, ``deflect_deg`` off the line between
    them; a toppling pin entering another that is not closing on it speeds that one
    away by ``settle_speed``.  The ball pushes again each
    pin it enters; past the last row it slows to rest in the pit.  A toppling pin keeps its
    lowest point ``REST`` below the lane: its centre height is the ellipsoid's extent
    along the vertical, sqrt(a^2 sin^2 + c^2 cos^2) of the tilt."""
    c = BOWLING
    a, _, cz = c["pin_radii"]
    radii = np.array(c["pin_radii"])
    rb = c["ball_r"]
    row = c["pin_spacing"] * math.sqrt(3.0) / 2.0
    base = np.array([[row * i, c["pin_spacing"] * (j - 0.5 * i)]
                     for i in range(4) for j in range(i + 1)])
    n = len(base)
    v_ball = c["ball_speed"]
    t_stop_start = 0.3 + (c["ball_stop"] - 0.6 - c["ball_start"]) / v_ball
    times = _keyframes(t_stop_start + 2.0)
    # the ball: still, then rolling at constant speed, then slowing to rest in the pit
    xb = np.empty(len(times))
    for k, t in enumerate(times):
        if t < 0.3:
            xb[k] = c["ball_start"]
        elif t < t_stop_start:
            xb[k] = c["ball_start"] + v_ball * (t - 0.3)
        else:
            f = min(t - t_stop_start, 0.4)
            xb[k] = c["ball_start"] + v_ball * (t_stop_start - 0.3) + v_ball * (f - f * f / 0.8)
    ball = np.stack([xb, np.full(len(times), c["ball_y"]), np.full(len(times), rb - REST)], -1)
    ball_vel = np.gradient(xb, times)
    sphere_pts = _fibonacci(c["samples"]) * (rb - c["hit_depth"])
    pin_pts = _fibonacci(c["samples"]) * radii
    shrunk = radii - c["hit_depth"]
    t_fall = np.full(n, np.inf)               # when each pin starts to topple
    fall_dir = np.tile([1.0, 0.0], (n, 1))
    push_v = np.zeros((n, 2))                 # carried by the ball until push_end
    push_end = np.full(n, -np.inf)
    slide = np.zeros((n, 2))                  # then sliding, slowing down
    slide_t0 = np.zeros(n)
    by_ball = np.zeros(n, bool)
    foot = base.copy()
    pos = np.zeros((len(times), n, 3))
    quat = np.zeros((len(times), n, 4))
    cos_d, sin_d = math.cos(math.radians(c["deflect_deg"])), math.sin(math.radians(c["deflect_deg"]))

    def pin_pose(i, t):
        th = 0.5 * math.pi * float(_smoothstep((t - t_fall[i]) / c["fall_s"]))
        d = fall_dir[i]
        h = math.sqrt((a * math.sin(th)) ** 2 + (cz * math.cos(th)) ** 2)
        xy = foot[i] + d * cz * math.sin(th)
        half = 0.5 * th                      # about z x d: the pin's top tips toward d
        return (np.array([xy[0], xy[1], h - REST]),
                np.array([-d[1] * math.sin(half), d[0] * math.sin(half), 0.0, math.cos(half)]))

    def shove(i, t, direction, speed):
        if direction[0] < 0.2:        # pins fly on into the pit, not back up the lane
            direction = np.array([0.2, math.copysign(math.sqrt(0.96), direction[1])])
        slide[i], slide_t0[i] = direction * speed, t
        if not np.isfinite(t_fall[i]):
            t_fall[i], fall_dir[i] = t, direction

    def velocity(i, t):
        if not t_fall[i] <= t:
            return np.zeros(2)
        if t <= push_end[i]:
            return push_v[i]
        return slide[i] * math.exp(-(t - slide_t0[i]) / c["slide_s"])

    for k, t in enumerate(times):
        if k > 0:
            for i in np.flatnonzero(np.isfinite(t_fall)):
                foot[i] = foot[i] + KEY_DT * velocity(i, t)
        for i in range(n):
            pos[k, i], quat[k, i] = pin_pose(i, t)
        for i in range(n):        # the ball pushes every pin it enters, again and again
            p_i = pos[k, i]
            if np.linalg.norm(ball[k, :2] - p_i[:2]) < rb + cz and \
                    _inside_ellipsoid(ball[k] + sphere_pts, p_i, quat[k, i], radii).any():
                away = p_i[:2] - ball[k, :2]
                away /= np.linalg.norm(away)
                carry = np.array([ball_vel[k], 0.0])
                if not np.isfinite(t_fall[i]):      # a standing pin: the ball knocks it
                    t_fall[i], fall_dir[i] = t, away
                    by_ball[i] = True
                push_v[i], push_end[i] = carry, t + c["push_s"]
                shove(i, t + c["push_s"], away, 1.3 * float(np.dot(carry, away)) + 0.3)
        for i in range(n):        # a toppling pin knocks the pins it enters
            p_i = pos[k, i]
            for j in np.flatnonzero(t_fall < t):
                if j == i or np.linalg.norm(pos[k, j, :2] - p_i[:2]) > cz + 2.0 * a:
                    continue
                line = p_i[:2] - pos[k, j, :2]
                line /= np.linalg.norm(line)
                closing = float(np.dot(velocity(j, t) - velocity(i, t), line))
                pts = pos[k, j] + quat_rotate(quat[k, j][None, :], pin_pts)
                if not _inside_ellipsoid(pts, p_i, quat[k, i], shrunk).any():
                    continue
                if np.isfinite(t_fall[i]) and closing <= 0.0:
                    slide[i] = velocity(i, t) + c["settle_speed"] * line   # they part
                    slide_t0[i] = t
                    continue
                if True:
                    side = math.copysign(sin_d, fall_dir[j][0] * line[1] - fall_dir[j][1] * line[0])
                    d = np.array([cos_d * line[0] - side * line[1],
                                  side * line[0] + cos_d * line[1]])
                    speed = min(max(c["knock_speed"],
                                    1.3 * float(np.dot(velocity(j, t), line)) + 0.3),
                                c["max_speed"])
                    shove(i, t, d, speed)
                    break
    names = [f"pin_{i}" for i in range(n)]
    spin = (xb - xb[0]) / rb
    all_pos = np.concatenate([pos, ball[:, None, :]], axis=1)
    all_quat = np.concatenate([quat, _y_turn(spin)[:, None, :]], axis=1)
    bodies = [params_body(nm, {"type": "ellipsoid", "radii": list(c["pin_radii"])}, pos[0, i])
              for i, nm in enumerate(names)]
    bodies.append(params_body("ball", {"type": "sphere", "radius": rb}, ball[0]))
    bodies.append(params_body("floor", {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": 0.0},
                        static=True))
    hit = [nm for nm, h in zip(names, by_ball) if h]
    toppled = [nm for nm, tf in zip(names, t_fall) if np.isfinite(tf)]
    expects = [Expect("ball-pin contacts", "pins", {nm: frozenset(["ball"]) for nm in names},
                      wanted=len(hit)),
               Expect("toppled pins on the floor", "pins",
                      {nm: frozenset(["floor"]) for nm in names}, moved=0.15,
                      wanted=len(toppled))]
    scene = Scene("bowling", bodies, names + ["ball"], times, all_pos, all_quat, 2.0,
                  expects, "a ball rolls into ten pins; pins hit by the ball or by a "
                  "falling pin topple")
    scene.hit_by_ball, scene.toppled = hit, toppled
    return scene


# -- swarm ---------------------------------------------------------------------------------
SWARM_SHAPES = (
    ("ball", lambda g: {"type": "sphere", "radius": _num(g.uniform(0.12, 0.3))}),
    ("egg", lambda g: {"type": "ellipsoid", "radii": _vec(g.uniform(0.1, 0.35, 3))}),
    ("crate", lambda g: {"type": "box", "size": _vec(g.uniform(0.2, 0.5, 3))}),
    ("pill", lambda g: {"type": "capsule", "radius": _num(g.uniform(0.08, 0.15)),
                        "length": _num(g.uniform(0.2, 0.5))}),
    ("can", lambda g: {"type": "cylinder", "radius": _num(g.uniform(0.08, 0.2)),
                       "height": _num(g.uniform(0.2, 0.5))}),
)


def demo_poses(n_bodies, t):
    """Poses of ``n_bodies`` at time ``t`` (s): bodies circle on two rings of radius 0.9
    and 1.3 m at different angular speeds, so they meet every few seconds, and bob
    through z = 0.15..0.55 m over a floor at z = 0.  More than 12 bodies spread over
    more rings (spaced 0.4 m, about 12 bodies per metre of radius), each ring's bodies
    keeping ~0.7 m/s.  Returns positions (N, 3), quat_xyzw (N, 4)."""
    i = np.arange(n_bodies, dtype=np.float64)
    omega = 0.6 + 0.25 * (i % 3) * np.where(i % 4 < 2, 1.0, -1.0)
    if n_bodies <= 12:
        ring = np.where(i % 2 == 0, 0.9, 1.3)
    else:
        # ring k (radius 0.9 + 0.4 k) holds bodies in proportion to its radius
        radii = 0.9 + 0.4 * np.arange(n_bodies)
        cum = np.cumsum(radii / 1.1 * 6.0)
        ring = radii[np.searchsorted(cum, i, side="right")]
        omega = omega * 1.1 / ring
    phase = 2.0 * np.pi * i / max(n_bodies, 1) if n_bodies <= 12 else 2.39996 * i
    angle = omega * t + phase
    pos = np.stack([ring * np.cos(angle), ring * np.sin(angle),
                    0.35 + 0.2 * np.sin(1.3 * t + 1.7 * i)], axis=1)
    half = 0.5 * (0.8 + 0.3 * (i if n_bodies <= 12 else i % 7)) * t   # spin, tilted axis
    axis = np.stack([np.sin(i), np.cos(i), np.ones_like(i)], axis=1)
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    quat = np.concatenate([axis * np.sin(half)[:, None], np.cos(half)[:, None]], axis=1)
    return pos, quat


def swarm_bodies(n, seed=0):
    """``n`` moving bodies of mixed shapes (seeded) and a floor, as body dicts."""
    if int(n) != n or n < 1:
        raise ValueError(f"swarm: the number of bodies must be a positive integer, got {n!r}")
    g = np.random.default_rng(seed)
    bodies = []
    for i in range(int(n)):
        kind, make = SWARM_SHAPES[i % len(SWARM_SHAPES)]
        bodies.append(params_body(f"{kind}_{i}", make(g)))
    bodies.append(params_body("floor", {"type": "plane", "normal": [0.0, 0.0, 1.0], "offset": 0.0},
                        static=True))
    return bodies


def shipped_swarm_bodies():
    """The bodies of the package's config/collision_node.yaml (the swarm's default)."""
    from .config import bodies_from_params, load_params_file
    path = os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "config",
                        "collision_node.yaml")
    return [params_body(b["name"], b["shape"], static=b["static"])
            for b in bodies_from_params(load_params_file(path))]


def swarm(n=None, bodies=None):
    """The orbiting swarm: ``bodies`` (body dicts, params style) or ``n`` generated ones
    (default: the bodies of config/collision_node.yaml)."""
    if bodies is None:
        bodies = shipped_swarm_bodies() if n is None else swarm_bodies(n)
    moving = [b["name"] for b in bodies if not b.get("static")]
    everyone = frozenset(moving)
    expects = [Expect("moving bodies touching another", "moving bodies",
                      dict.fromkeys(moving, everyone))]
    return Scene("swarm", bodies, moving, None, None, None, 0.0, expects,
                 f"{len(moving)} bodies of mixed shapes on crossing orbits",
                 poses=lambda t: demo_poses(len(moving), t))


SCENES = {"bowling": bowling, "dominoes": dominoes, "marbles": marbles, "stack": stack,
          "swarm": swarm}


def make_scene(name, bodies=None):
    """The scene ``name`` (one of SCENE_NAMES); ``bodies`` (an int) only for swarm."""
    if name not in SCENES:
        raise ValueError(f"unknown scene {name!r}; expected one of {', '.join(SCENE_NAMES)}")
    if bodies is not None:
        if name != "swarm":
            raise ValueError(f"--bodies applies to the swarm scene only, not {name!r}")
        return swarm(n=bodies)
    return SCENES[name]()


def params_yaml(scene):
    """The params file text of ``scene``: the node's parameters, then one line per
    body."""
    def flow(value):
        text = yaml.safe_dump([value], default_flow_style=True, sort_keys=False,
                              width=1 << 20).strip()
        return text[1:-1]

    params = scene.params()["/**"]["ros__parameters"]
    lines = [f"# Demo scene '{scene.name}': {scene.doc}.",
             "# Written by mkcollision_ros.demo_scenes (python -m mkcollision_ros.demo_scenes"
             " config),",
             "# where the scripted motion lives; lengths in metres.",
             f"# Run it with:  demo --scene {scene.name}",
             "/**:", "  ros__parameters:"]
    lines += [f"    {key}: {flow(value)}" for key, value in params.items() if key != "bodies"]
    lines += ["    bodies:"]
    lines += [f"      {key}: {flow(value)}" for key, value in params["bodies"].items()]
    return "\n".join(lines) + "\n"


def write_params(scene, path):
    """Write ``scene``'s params file to ``path``."""
    with open(path, "w", encoding="utf-8") as f:
        f.write(params_yaml(scene))


if __name__ == "__main__":
    import sys
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(__file__), "..", "config")
    for scene_name in SCENE_NAMES:
        write_params(make_scene(scene_name), os.path.join(out, f"demo_{scene_name}.yaml"))
