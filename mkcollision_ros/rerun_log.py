"""Rerun logging of a scene's steps: bodies, contacts, events, timings and, for chosen
pairs, the Minkowski difference with the iterations of the method that answered.

    from mkcollision_ros.pipeline import Pipeline
    p = Pipeline(bodies, rerun="save:run.rrd")        # library: a keyword
    # node: the parameter ``rerun`` (same text), ``rerun_pairs`` (["a:b", ...])

Sinks (``parse_sink``; rerun is imported only when one is opened, never for "off"):
  off                         nothing
  save:<file.rrd>             stream to a file (without rerun's footer index, which
                              grows in memory with the run); every FLUSH_STEPS steps
                              the log waits
                              until the file has everything, so when the disk or
                              rerun's encoder falls behind the steps wait instead of
                              memory growing
  connect[:<url>]             stream to a running viewer (gRPC, default
                              rerun+http://127.0.0.1:9876/proxy)
  serve[:[<ip>:]<port>]       host a gRPC server (default 127.0.0.1:9876; it buffers at
                              most ``memory_limit`` for viewers that connect late, the
                              oldest data dropped first) and, when ``web_port`` > 0, a
                              web viewer on the same address (a child ``rerun`` process,
                              stopped with the logger)

Entities (world frame, metres; timelines ``step`` (sequence) and ``stamp`` (the poses'
time: a timestamp when it is a date after 1973, else a duration)):
  world/bodies/{ellipsoids,boxes,capsules,cylinders}  rerun primitives, one instance a
                              body in slot order, labelled with its name, coloured free /
                              touching / deep (FREE, TOUCHING, DEEP; deep: a contact
                              deeper than ``deep`` m); spheres are ellipsoids
  world/bodies/meshes         cones, convex hulls and planes as one mesh
                              (meshes.shape_mesh), vertex colours by state; a plane is
                              a square patch spanning the bounded bodies (sized on each
                              scene edit), always PLANE-coloured: a floor touches
                              nearly everything, and red would hide the bodies' states
  world/bodies/mesh_names     the meshes' names, as labels at their body origins
  world/contacts              contact positions labelled "a-b #id"; beside them, per
                              instance: contact_id, body_a, body_b (slots), age, depth,
                              method, status (codes: constants.M_*, ST_*; rr.AnyValues)
  world/normals               an arrow per contact along the normal, normal_length +
                              depth long
  world/witness/{a,b}         the witness points on A and on B, one per contact
  tables/contacts             the contacts as a markdown table (pair, id, age, depth,
                              normal, method, status), the deepest ``table_rows`` first
  events                      one text entry per step with events: began / ended pairs
                              and contacts
  stats                       contacts, touching pairs, candidate pairs (series)
  timing                      step latency and each phase's time, ms (series)
  minkowski/<a>-<b>/...       for each chosen pair (trace.trace_pair): the difference
                              A - B as a mesh, the origin, the answer (the point
                              point_a - point_b), and the iterations on the ``iteration``
                              timeline: mpr/portal, gjk/simplex, epa/polytope
A blueprint lays these out: the 3D view, the series, the table, the events and one
view per chosen pair.

Cost: the recorder runs in a child process of the logger (``RerunLog``), so the step
only pickles its data and hands it over.  There, what changes every step (poses,
colours, contacts, the table, events, series) is
held for up to ``batch_steps`` steps or ``batch_seconds`` and sent as columns, one
``send_columns`` call per entity and field set for the whole batch, since each call
costs ~70 us of the SDK's Python conversion besides its data; what is sent once (names,
sizes, triangles, styles, clears, the Minkowski view) is logged at once.  A viewer
sees a step at most ``batch_seconds`` late; ``close`` sends what is held.
"""
import math
import os
import pickle
import queue
import shutil
import signal
import subprocess
import sys
import threading
import time
from typing import NamedTuple

import numpy as np

from .arbiters import EV_PERSISTED, KIND_NAMES
from .kernels.constants import METHOD_NAMES, P_RADIUS
from .meshes import shape_mesh
from .results import Status
from .rotations import quat_to_matrix

STATUS_NAMES = tuple(s.name.lower() for s in sorted(Status))

FREE = (150, 150, 150, 255)
TOUCHING = (255, 150, 0, 255)
DEEP = (230, 20, 20, 255)
PLANE = (90, 100, 110, 255)
CONTACT = (30, 80, 255, 255)
NORMAL = (0, 200, 60, 255)
WITNESS_A = (255, 0, 255, 255)
WITNESS_B = (0, 220, 220, 255)
DEFAULT_CONNECT = "rerun+http://127.0.0.1:9876/proxy"
DEFAULT_SERVE = ("127.0.0.1", 9876)
SINK_FORMS = "off | save:<file.rrd> | connect[:<url>] | serve[:[<ip>:]<port>]"
_DATE = 1e8          # s: a stamp beyond this (1973) is a date, else a duration
MINKOWSKI_DIRECTIONS = 150   # support directions of the Minkowski difference's hull
FLUSH_STEPS = 50     # the file sink's bound on steps held in memory (~1 ms a flush)
BATCH_STEPS = 10     # steps held before they are sent as columns (module docstring)
BATCH_SECONDS = 0.1  # s: the longest a step is held
QUEUE_STEPS = 50     # steps waiting for the logger process before a step waits too
_SHAPE_GROUPS = {"sphere": "ellipsoids", "ellipsoid": "ellipsoids", "box": "boxes",
                 "capsule": "capsules", "cylinder": "cylinders", "cone": "meshes",
                 "convex": "meshes", "plane": "meshes"}


class Sink(NamedTuple):
    """A parsed sink: kind "off" / "save" / "connect" / "serve"; target: the file
    (save), the URL (connect) or (ip, port) (serve)."""
    kind: str
    target: object = None


def parse_sink(text):
    """The Sink that ``text`` names (SINK_FORMS); ValueError with the expected forms."""
    if not isinstance(text, str):
        raise ValueError(f"rerun sink must be a string ({SINK_FORMS}), got {text!r}")
    kind, _, rest = text.strip().partition(":")
    if kind in ("", "off") and not rest:
        return Sink("off")
    if kind == "save":
        if not rest:
            raise ValueError("rerun sink save:<file.rrd> needs a file name")
        return Sink("save", rest)
    if kind == "connect":
        url = rest or DEFAULT_CONNECT
        if not url.startswith(("rerun://", "rerun+http://", "rerun+https://")):
            raise ValueError(f"rerun sink connect:<url>: the url must start with "
                             f"rerun://, rerun+http:// or rerun+https://, got {url!r}")
        return Sink("connect", url)
    if kind == "serve":
        ip, port = DEFAULT_SERVE
        if rest:
            head, _, tail = rest.rpartition(":")
            ip = head or ip
            try:
                port = int(tail)
            except ValueError:
                raise ValueError(f"rerun sink serve:[<ip>:]<port>: bad port {tail!r}") \
                    from None
            if not 0 < port < 65536:
                raise ValueError(f"rerun sink serve: port {port} not in 1..65535")
        return Sink("serve", (ip, port))
    raise ValueError(f"unknown rerun sink {text!r}; expected {SINK_FORMS}")


def parse_pairs(items):
    """[(name_a, name_b), ...] from "a:b" strings or 2-sequences; ValueError otherwise."""
    out = []
    for item in items:
        if isinstance(item, str):
            a, sep, b = item.partition(":")
        elif isinstance(item, (list, tuple)) and len(item) == 2:
            (a, b), sep = item, ":"
        else:
            a = b = sep = ""
        if not sep or not a or not b or not isinstance(a, str) or not isinstance(b, str):
            raise ValueError(f"a rerun pair is \"name_a:name_b\", got {item!r}")
        out.append((a, b))
    return out


def _packed(rgba_):
    r, g, b, a = rgba_
    return np.uint32((r << 24) | (g << 16) | (b << 8) | a)


def _colors(depth, deep):
    """uint32 (N,) packed state colours from each body's deepest contact (-1: none)."""
    c = np.full(len(depth), _packed(FREE), np.uint32)
    c[depth >= 0.0] = _packed(TOUCHING)
    c[depth > deep] = _packed(DEEP)
    return c


class _Groups(NamedTuple):
    """The scene's bodies sorted into rerun archetypes (rebuilt on each scene edit)."""
    slots: dict          # group -> int64 slots
    names: dict          # group -> list of names
    dims: dict           # group -> arrays of the archetype's size fields
    mesh_local: np.ndarray    # float64 (M, K, 3) body-frame mesh vertices, padded
    mesh_valid: np.ndarray    # bool (M, K): the real ones (row-major: the mesh's order)
    mesh_owner: np.ndarray    # int64 (V,) index into slots["meshes"]
    mesh_tris: np.ndarray     # uint32 (F, 3)
    mesh_plane: np.ndarray    # bool (M,): the mesh is a plane's patch (drawn PLANE)


def _plane_extent(scene):
    """(centre (3,), side m) of a plane patch that spans the posed bounded bodies."""
    bounded = scene.posed & ~scene.is_plane
    if not bounded.any():
        return np.zeros(3), 2.0
    p = scene.positions[bounded]
    r = float(scene.table.params[:len(scene.names)][bounded, P_RADIUS].max())
    lo, hi = p.min(axis=0) - r, p.max(axis=0) + r
    return 0.5 * (lo + hi), max(2.0, 1.2 * float(np.max(hi - lo)))


def _groups(scene):
    slots = {g: [] for g in ("ellipsoids", "boxes", "capsules", "cylinders", "meshes")}
    names = {g: [] for g in slots}
    dims = {g: [] for g in slots}
    local, owner, tris, base, planes = [], [], [], 0, []
    table = scene.table
    centre, side = _plane_extent(scene)
    for body in scene.bodies():
        slot = scene.index[body.name]
        s = body.shape
        g = _SHAPE_GROUPS[s["type"]]
        m = float(s.get("margin", 0.0))
        slots[g].append(slot)
        names[g].append(body.name)
        if s["type"] == "sphere":
            dims[g].append(np.full(3, float(s["radius"]) + m))
        elif s["type"] == "ellipsoid":
            dims[g].append(np.asarray(s["radii"], float) + m)
        elif g == "boxes":
            dims[g].append(0.5 * np.asarray(s["size"], float) + m)
        elif g == "capsules":
            dims[g].append((float(s["radius"]) + m, float(s["length"])))
        elif g == "cylinders":
            dims[g].append((float(s["radius"]) + m, float(s["height"]) + 2.0 * m))
        else:
            first, count = table.vrange[slot]
            r = quat_to_matrix(scene.orientations[slot:slot + 1])[0]
            near = r.T @ (centre - scene.positions[slot])   # the scene's centre, body frame
            v, f = shape_mesh(s, table.verts[first:first + count], plane_size=side,
                              plane_near=near)
            planes.append(s["type"] == "plane")
            local.append(v)
            owner.append(np.full(len(v), len(slots[g]) - 1))
            tris.append(f + base)
            base += len(v)
    cat = (lambda parts, shape, dt: np.concatenate(parts).astype(dt) if parts
           else np.zeros(shape, dt))
    k = max((len(v) for v in local), default=0)
    pad = np.zeros((len(local), k, 3))
    valid = np.zeros((len(local), k), bool)
    for i, v in enumerate(local):
        pad[i, :len(v)], valid[i, :len(v)] = v, True
    return _Groups({g: np.array(v, np.int64) for g, v in slots.items()}, names,
                   {g: np.array(v, float) for g, v in dims.items()}, pad, valid,
                   cat(owner, (0,), np.int64), cat(tris, (0, 3), np.uint32),
                   np.array(planes, bool))


def blueprint(pairs=()):
    """The layout: 3D scene | series, table, events | one view per chosen pair (a list
    of (a, b)); the time panel as a bar (play, step, scrub) following the newest step,
    the side panels collapsed."""
    import rerun.blueprint as rrb
    side = rrb.Vertical(
        rrb.TimeSeriesView(origin="stats", name="contacts"),
        rrb.TimeSeriesView(origin="timing", name="time (ms)"),
        rrb.TextDocumentView(origin="tables/contacts", name="contacts"),
        rrb.TextLogView(origin="events", name="events"))
    views = [rrb.Spatial3DView(origin="world", name="scene"), side]
    views += [rrb.Spatial3DView(origin=f"minkowski/{a}-{b}", name=f"{a} - {b}")
              for a, b in pairs]
    shares = [3, 2] + [2] * len(pairs)
    return rrb.Blueprint(rrb.Horizontal(*views, column_shares=shares),
                         rrb.BlueprintPanel(state="collapsed"),
                         rrb.SelectionPanel(state="collapsed"),
                         rrb.TimePanel(state="collapsed", play_state="following"))


def _markdown_table(names, res, rows):
    """The deepest ``rows`` contacts of ``res`` as a markdown table."""
    n = len(res.depth)
    order = np.argsort(-res.depth, kind="stable")[:rows]
    head = (f"{n} contacts" + (f", the deepest {len(order)}" if len(order) < n else "")
            + "\n\n| pair | id | age | depth (m) | normal | method | status |\n"
            "|---|---|---|---|---|---|---|\n")
    lines = [f"| {names[res.body_a[i]]}-{names[res.body_b[i]]} | {res.contact_id[i]} "
             f"| {res.age[i]} | {res.depth[i]:.6g} | "
             f"({res.normal[i, 0]:.3f}, {res.normal[i, 1]:.3f}, {res.normal[i, 2]:.3f}) "
             f"| {METHOD_NAMES[res.method[i]]} | {STATUS_NAMES[res.status[i]]} |"
             for i in order]
    return head + "\n".join(lines)


class _Recorder:
    """The logging itself, in the logger's process (RerunLog starts it in a child):
    steps to one rerun sink (module docstring).

    sink: a SINK_FORMS string or a Sink; pairs: chosen pairs for the Minkowski view
    ("a:b" or (a, b)); deep (m): the depth from which a body is drawn DEEP;
    normal_length (m); point_size (m): contact point radius; table_rows: rows of the
    contacts table; memory_limit: the serve sink's buffer; web_port: the serve sink's
    web viewer (0: none); minkowski_method: the method traced for chosen pairs
    ("auto": the one the pipeline would use for a single pair); minkowski_period (s):
    a chosen pair's Minkowski view is logged at its first step and then at most once
    per period (building the hull of MINKOWSKI_DIRECTIONS support points takes tens of
    milliseconds in Python; 0: every step); batch_steps, batch_seconds: how long the
    per-step data is held before it is sent (module docstring; 1: every step)."""

    def __init__(self, sink, pairs=(), deep=0.01, normal_length=0.05, point_size=0.01,
                 table_rows=20, memory_limit="256MiB", web_port=9090,
                 application_id="mkcollision_ros", recording_id=None,
                 minkowski_method="auto", minkowski_period=0.5,
                 batch_steps=BATCH_STEPS, batch_seconds=BATCH_SECONDS):
        self.sink = sink if isinstance(sink, Sink) else parse_sink(sink)
        if self.sink.kind == "off":
            raise ValueError("RerunLog needs a sink other than off")
        self.pairs = parse_pairs(pairs)
        self.deep, self.normal_length = float(deep), float(normal_length)
        self.point_size, self.table_rows = float(point_size), int(table_rows)
        self.minkowski_method = minkowski_method
        self.minkowski_period = float(minkowski_period)
        self.batch_steps = max(1, int(batch_steps))
        self.batch_seconds = float(batch_seconds)
        self._held = {}              # (entity path, archetype) -> [(time, fields), ...]
        self._held_steps, self._held_since = 0, 0.0
        self._now = None             # this step's (step, stamp)
        import rerun as rr
        self._rr = rr
        self.rec = rr.RecordingStream(application_id, recording_id=recording_id)
        self._viewer = None
        self.where = self._open(self.sink, memory_limit, int(web_port))
        self._groups, self._version = None, None
        self._timing_names = None
        self._logged = set()         # groups with instances at the last step
        self._last = {}              # group -> (groups, posed, positions, quats, colours)
        self._label_of = {}          # contact id -> its label
        self._styled = False         # the contacts' static colours and sizes are sent
        self._since_flush = 0
        self._minkowski_at = {}      # pair -> when its Minkowski view was last logged
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self.rec.log("stats", rr.SeriesLines(names=["contacts", "touching pairs",
                                                    "candidate pairs"]), static=True)

    # -- sinks ----------------------------------------------------------------------
    def _open(self, sink, memory_limit, web_port):
        """Open the sink; returns a line saying how to look at the recording."""
        rr, bp = self._rr, self.blueprint()
        if sink.kind == "save":
            # no footer: rerun keeps the footer's index of every chunk in memory until
            # the file closes (~9 KB a step at 1,000 bodies, without bound on a long
            # run); viewers and read_recording read the file whole instead
            self.rec.set_sinks(rr.FileSink(sink.target, write_footer=False),
                               default_blueprint=bp)
            return f"recording to {sink.target}; open it with: rerun {sink.target}"
        if sink.kind == "connect":
            self.rec.connect_grpc(sink.target, default_blueprint=bp)
            return f"streaming to the viewer at {sink.target}"
        ip, port = sink.target
        server = rr.GrpcServerSink(bind_ip=ip, port=port, server_memory_limit=memory_limit)
        self.rec.set_sinks(server, default_blueprint=bp)
        where = f"serving on {server.uri} (open with: rerun --connect {server.uri})"
        if web_port > 0:
            exe = shutil.which("rerun")
            if exe is None:
                raise ValueError("rerun sink serve: the `rerun` executable (rerun-sdk) "
                                 "is not on PATH, needed for the web viewer; set "
                                 "web_port 0 to serve without it")
            self._viewer = subprocess.Popen(
                [exe, "--serve-web", "--bind", ip, "--web-viewer-port", str(web_port),
                 server.uri], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                start_new_session=True)
            where += f"; web viewer: http://{ip}:{web_port}/?url={server.uri}"
        return where

    def blueprint(self):
        """This log's layout (``blueprint(self.pairs)``)."""
        return blueprint(self.pairs)

    def close(self):
        """Send what is held, flush and close the sink; stop the web viewer."""
        self._send_held()
        self.rec.flush()
        self.rec.disconnect()
        if self._viewer is not None:
            stop_group(self._viewer)
            self._viewer = None

    # -- one step -----------------------------------------------------------------
    def log_step(self, scene, res, step, latency=None):
        """Log one step: ``scene`` (scene.Scene) after the step, its StepResult ``res``,
        the step counter and the step's latency (s; None: the sum of its phases)."""
        rec = self.rec
        rec.set_time("step", sequence=int(step))
        if res.stamp >= _DATE:
            rec.set_time("stamp", timestamp=res.stamp)
        else:
            rec.set_time("stamp", duration=res.stamp)
        self._now = (int(step), float(res.stamp))
        if self._version != (scene.version, scene.n_slots):
            self._groups = _groups(scene)
            self._version = (scene.version, scene.n_slots)
        depth = np.full(scene.n_slots, -1.0)
        if len(res.depth):
            np.maximum.at(depth, res.body_a, res.depth)
            np.maximum.at(depth, res.body_b, res.depth)
        self._log_bodies(scene, _colors(depth, self.deep))
        self._log_contacts(res)
        self._log_events(res)
        self._log_series(res, latency)
        for a, b in self.pairs:
            self._log_minkowski(scene, res, a, b)
        if self._held_steps == 0:
            self._held_since = time.perf_counter()
        self._held_steps += 1
        if (self._held_steps >= self.batch_steps
                or time.perf_counter() - self._held_since >= self.batch_seconds):
            self._send_held()
        self._since_flush += 1
        if self.sink.kind == "save" and self._since_flush >= FLUSH_STEPS:
            self._since_flush = 0
            self._send_held()
            rec.flush()

    # -- per-step data, held and sent as columns ---------------------------------
    def _hold(self, path, kind, **fields):
        """Hold this step's ``fields`` of ``path`` (an archetype's ``columns`` keywords,
        each an array or list with one entry per instance, or a string).  Arrays are
        held as they are: in the logger's child every step's scene and result arrive
        as fresh arrays (unpickled), which nothing changes afterwards."""
        rows = self._held.setdefault((path, kind), [])
        rows.append((self._now, {k: [v] if isinstance(v, str) else v
                                 for k, v in fields.items()}))

    def _send_held(self):
        """One send_columns per entity and run of steps with the same fields."""
        import pyarrow as pa
        rr, rec = self._rr, self.rec
        held, self._held, self._held_steps = self._held, {}, 0
        for (path, kind), rows in held.items():
            start = 0
            while start < len(rows):
                keys = sorted(rows[start][1])
                dated = rows[start][0][1] >= _DATE
                end = start + 1
                while (end < len(rows) and sorted(rows[end][1]) == keys
                       and (rows[end][0][1] >= _DATE) == dated):
                    end += 1
                run = rows[start:end]
                stamps = [t[1] for t, _ in run]
                indexes = [rr.TimeColumn("step", sequence=[t[0] for t, _ in run]),
                           rr.TimeColumn("stamp", timestamp=stamps) if dated
                           else rr.TimeColumn("stamp", duration=stamps)]
                columns = []
                for key in keys:
                    values = [f[key] for _, f in run]
                    if isinstance(values[0], list):
                        data = [x for v in values for x in v]
                    else:
                        data = np.concatenate(values)
                        if kind is rr.AnyValues:     # an arrow array: no per-item pass
                            data = pa.array(data)
                    columns.extend(kind.columns(**{key: data}).partition(
                        [len(v) for v in values]))
                rec.send_columns(path, indexes=indexes, columns=columns)
                start = end

    def _clear_if_empty(self, path, group, n):
        if n:
            self._logged.add(group)
        elif group in self._logged:
            self.rec.log(path, self._rr.Clear(recursive=False))
            self._logged.discard(group)
        return n

    def _log_bodies(self, scene, colors):
        """One call per group and step.  A group's sizes, labels and triangles are
        sent when its bodies change; each step sends only the poses and colours that
        changed (rerun keeps the latest of each component), nothing for a group at rest."""
        rr, rec, g = self._rr, self.rec, self._groups
        posed = scene.posed
        pos, quat = scene.positions, scene.orientations
        for name in ("ellipsoids", "boxes", "capsules", "cylinders", "meshes"):
            keep = posed[g.slots[name]]
            s = g.slots[name][keep]
            path = f"world/bodies/{name}"
            if not self._clear_if_empty(path, name, len(s)):
                self._last.pop(name, None)
                if name == "meshes":
                    self._clear_if_empty("world/bodies/mesh_names", "mesh_names", 0)
                continue
            p, q, c = pos[s], quat[s], colors[s]
            last = self._last.get(name)
            fresh = last is None or last[0] is not g or not np.array_equal(last[1], keep)
            moved = fresh or not (np.array_equal(last[2], p) and np.array_equal(last[3], q))
            recolour = fresh or not np.array_equal(last[4], c)
            if not (moved or recolour):
                continue
            self._last[name] = (g, keep, p.copy(), q.copy(), c)
            if name == "meshes":
                self._log_meshes(g, s, keep, p, q, c, fresh, moved, recolour)
                continue
            fields = {}
            if fresh:
                dims = g.dims[name][keep]
                fields = dict(labels=[n for n, k in zip(g.names[name], keep) if k],
                              fill_mode="solid")
                if name in ("ellipsoids", "boxes"):
                    fields["half_sizes"] = dims
                else:
                    fields["radii"], fields["lengths"] = dims[:, 0], dims[:, 1]
            if recolour:
                fields["colors"] = c
            if moved:
                fields["quaternions"] = q
                if name == "capsules":
                    # rerun places a capsule's end at the translation, extending along +z
                    axis = quat_to_matrix(q)[:, :, 2]
                    half = 0.5 * g.dims[name][keep][:, 1:2]
                    fields["translations"] = p - half * axis
                else:
                    fields["centers"] = p
            kind = {"ellipsoids": rr.Ellipsoids3D, "boxes": rr.Boxes3D,
                    "capsules": rr.Capsules3D, "cylinders": rr.Cylinders3D}[name]
            if fresh:
                rec.log(path, kind.from_fields(**fields))
            else:
                self._hold(path, kind, **fields)

    def _log_meshes(self, g, s, keep, p, q, c, fresh, moved, recolour):
        rr, rec = self._rr, self.rec
        on = keep[g.mesh_owner]
        owner = g.mesh_owner[on]
        fields = {}
        if fresh:
            tris = g.mesh_tris
            if not keep.all():             # drop unposed bodies' vertices and triangles
                new_index = np.cumsum(on) - 1
                tris = new_index[tris[on[tris].all(axis=1)]].astype(np.uint32)
            fields["triangle_indices"] = tris
            self._clear_if_empty("world/bodies/mesh_names", "mesh_names", 1)
            rec.log("world/bodies/mesh_names", rr.Points3D.from_fields(
                labels=[n for n, k in zip(g.names["meshes"], keep) if k], radii=0.0))
        if moved:
            r = quat_to_matrix(q)
            world = np.matmul(g.mesh_local[keep], r.transpose(0, 2, 1)) + p[:, None, :]
            fields["vertex_positions"] = world[g.mesh_valid[keep]]
            if fresh:
                rec.log("world/bodies/mesh_names", rr.Points3D.from_fields(positions=p))
            else:
                self._hold("world/bodies/mesh_names", rr.Points3D, positions=p)
        if recolour:
            c = c.copy()
            c[g.mesh_plane[keep]] = _packed(PLANE)
            fields["vertex_colors"] = c[owner]
        if fresh:
            rec.log("world/bodies/meshes", rr.Mesh3D.from_fields(**fields))
        else:
            self._hold("world/bodies/meshes", rr.Mesh3D, **fields)

    def _log_contacts(self, res):
        rr, rec = self._rr, self.rec
        n = len(res.depth)
        for path in ("world/contacts", "world/normals", "world/witness/a",
                     "world/witness/b"):
            self._clear_if_empty(path, path, n)
        if not n:
            self._hold("tables/contacts", rr.TextDocument, text="no contacts",
                       media_type="text/markdown")
            return
        if not self._styled:       # one colour and size each: static, sent once
            self._styled = True
            rec.log("world/contacts", rr.Points3D.from_fields(
                radii=self.point_size, colors=CONTACT), static=True)
            rec.log("world/normals", rr.Arrows3D.from_fields(
                radii=0.25 * self.point_size, colors=NORMAL), static=True)
            for side, colour in (("a", WITNESS_A), ("b", WITNESS_B)):
                rec.log(f"world/witness/{side}", rr.Points3D.from_fields(
                    radii=0.5 * self.point_size, colors=colour), static=True)
        names = res.names
        self._hold("world/contacts", rr.Points3D, positions=res.position,
                   labels=self._labels(names, res))
        self._hold("world/contacts", rr.AnyValues, contact_id=res.contact_id,
                   body_a=res.body_a, body_b=res.body_b, age=res.age, depth=res.depth,
                   method=res.method, status=res.status)
        self._hold("world/normals", rr.Arrows3D, origins=res.position,
                   vectors=res.normal * (self.normal_length + res.depth)[:, None])
        self._hold("world/witness/a", rr.Points3D, positions=res.point_a)
        self._hold("world/witness/b", rr.Points3D, positions=res.point_b)
        self._hold("tables/contacts", rr.TextDocument,
                   text=_markdown_table(names, res, self.table_rows),
                   media_type="text/markdown")

    def _labels(self, names, res):
        """"a-b #id" per contact, each made once for the life of its contact id."""
        cache = self._label_of
        if len(cache) > 4 * len(res.contact_id) + 1024:
            keep = set(res.contact_id.tolist())
            self._label_of = cache = {i: t for i, t in cache.items() if i in keep}
        out = []
        for i, a, b in zip(res.contact_id.tolist(), res.body_a.tolist(),
                           res.body_b.tolist()):
            text = cache.get(i)
            if text is None:
                text = cache[i] = f"{names[a]}-{names[b]} #{i}"
            out.append(text)
        return out

    def _log_events(self, res):
        ev = res.events
        changed = np.flatnonzero(ev.kind != EV_PERSISTED)
        if not len(changed):
            return
        names = res.names
        lines = []
        for kind, a, b, cid in zip(KIND_NAMES[ev.kind[changed]].tolist(),
                                   ev.body_a[changed].tolist(), ev.body_b[changed].tolist(),
                                   ev.contact_id[changed].tolist()):
            what = "pair" if cid < 0 else f"contact #{cid}"
            lines.append(f"{kind} {names[a]}-{names[b]} {what}")
        self._hold("events", self._rr.TextLog, text="\n".join(lines), level="INFO")

    def _log_series(self, res, latency):
        rr, rec = self._rr, self.rec
        self._hold("stats", rr.Scalars, scalars=np.array(
            [len(res.depth), len(res.pairs), res.n_candidate_pairs], float))
        phases = list(res.timings)
        if self._timing_names != phases:
            self._timing_names = phases
            rec.log("timing", rr.SeriesLines(names=["step"] + phases), static=True)
        total = sum(res.timings.values()) if latency is None else latency
        self._hold("timing", rr.Scalars, scalars=np.array(
            [1e3 * total] + [1e3 * res.timings[p] for p in phases]))

    def _log_minkowski(self, scene, res, a, b):
        from .trace import minkowski_difference, trace_pair
        rr, rec = self._rr, self.rec
        root = f"minkowski/{a}-{b}"
        if a not in scene or b not in scene:
            rec.log(f"{root}/note", rr.TextLog(f"{a} or {b} is not in the scene",
                                               level="WARN"))
            return
        ia, ib = scene.index[a], scene.index[b]
        if not (scene.posed[ia] and scene.posed[ib]):
            return
        ba, bb = scene.body(a), scene.body(b)
        if "plane" in (ba.shape["type"], bb.shape["type"]):
            rec.log(f"{root}/note", rr.TextLog("a plane has no support mapping: no "
                                               "Minkowski difference", level="WARN"))
            return
        now = time.monotonic()
        if now - self._minkowski_at.get((a, b), -math.inf) < self.minkowski_period:
            return
        self._minkowski_at[(a, b)] = now
        pa = (scene.positions[ia], scene.orientations[ia])
        pb = (scene.positions[ib], scene.orientations[ib])
        verts, tris = minkowski_difference(ba.shape, pa, bb.shape, pb,
                                           directions=MINKOWSKI_DIRECTIONS)
        tr = trace_pair(ba.shape, pa, bb.shape, pb, method=self.minkowski_method)
        r = tr.result
        gap = np.asarray(r.point_a) - np.asarray(r.point_b)
        rec.log(f"{root}/difference", rr.Mesh3D(vertex_positions=verts,
                                                triangle_indices=tris,
                                                albedo_factor=(120, 160, 255, 255)))
        rec.log(f"{root}/origin", rr.Points3D([[0.0, 0.0, 0.0]], radii=0.01,
                                              colors=(255, 255, 255, 255),
                                              labels=["origin"]))
        rec.log(f"{root}/answer", rr.Arrows3D(
            origins=[[0.0, 0.0, 0.0]], vectors=[gap], colors=DEEP,
            labels=[f"{r.status.name.lower()} {r.distance:+.6g} m by {tr.answered_by}; "
                    f"traced: {tr.traced}"
                    + (f" on the cores (grown by {tr.core_radius:.4g} m)"
                       if tr.traced == "gjk_epa" and tr.core_radius > 0 else "")]))
        for i, (stage, portal) in enumerate(tr.mpr_portals):
            rec.set_time("iteration", sequence=i)
            labels = [stage] + [""] * (len(portal) - 1)
            rec.log(f"{root}/mpr/portal", rr.LineStrips3D(_edges(portal)),
                    rr.Points3D(portal, radii=0.005, labels=labels))
        for i, simplex in enumerate(tr.gjk_simplices):
            rec.set_time("iteration", sequence=i)
            rec.log(f"{root}/gjk/simplex", rr.LineStrips3D(_edges(simplex)),
                    rr.Points3D(simplex, radii=0.005))
        offset = len(tr.gjk_simplices)
        for i, (pv, pf) in enumerate(tr.epa_polytopes):
            rec.set_time("iteration", sequence=offset + i)
            rec.log(f"{root}/epa/polytope", rr.Mesh3D(vertex_positions=pv,
                                                      triangle_indices=pf))
        rec.disable_timeline("iteration")


class _Posed:
    """The scene as the recorder reads it: the last scene sent (edits only), with this
    step's poses."""

    def __init__(self, scene, posed, positions, orientations):
        self._scene = scene
        self.posed, self.positions, self.orientations = posed, positions, orientations

    def __getattr__(self, name):
        return getattr(self._scene, name)

    def __contains__(self, name):
        return name in self._scene


class RerunLog:
    """Logs steps to one rerun sink (module docstring), from a child process.

    The recorder (the rerun SDK's calls and their conversions, a few milliseconds a
    step at 1,000 bodies) runs in a child process, ``python -m mkcollision_ros.rerun_log``,
    on a core of its own when there is one: ``log_step`` pickles the step's poses and
    result (and the scene after each edit) and queues them for a writer thread that
    pipes them to the child, so a step waits only for the pickling.  At most
    QUEUE_STEPS steps wait in the queue; beyond that a step waits for the child, so a
    slow sink never grows memory without bound.  This process never imports rerun.
    A failure in the child (a bad option, a sink that cannot open) is raised here: by
    the constructor while opening, by the next ``log_step`` after (every later one
    when the child is gone); ``close`` returns what was not raised yet.

    Arguments as the recorder's: sink (a SINK_FORMS string or a Sink), pairs (chosen
    pairs for the Minkowski view, "a:b" or (a, b)), and the keywords deep,
    normal_length, point_size, table_rows, memory_limit, web_port, application_id,
    recording_id, minkowski_method, minkowski_period, batch_steps, batch_seconds
    (_Recorder)."""

    def __init__(self, sink, pairs=(), **options):
        self.sink = sink if isinstance(sink, Sink) else parse_sink(sink)
        if self.sink.kind == "off":
            raise ValueError("RerunLog needs a sink other than off")
        self.pairs = parse_pairs(pairs)
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        env = dict(os.environ)
        env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"]
                                    if env.get("PYTHONPATH") else "")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "mkcollision_ros.rerun_log"], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, env=env, start_new_session=True)
        self._errors = []
        self._dead = None            # why the child can take no more steps
        self._version = None
        try:
            pickle.dump(("open", self.sink, self.pairs, options), self.process.stdin)
            self.process.stdin.flush()
            reply = pickle.load(self.process.stdout)
        except (OSError, EOFError, pickle.UnpicklingError) as err:
            stop_group(self.process)
            raise RuntimeError(f"the rerun logger process did not start: {err!r}") from err
        if reply[0] != "open":
            stop_group(self.process)
            raise (ValueError if reply[1] == "ValueError" else RuntimeError)(reply[2])
        self.where, self.viewer_pid = reply[1], reply[2]
        self._closed = False
        self._queue = queue.Queue(maxsize=QUEUE_STEPS)
        self._writer = threading.Thread(target=self._write, daemon=True)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._writer.start()
        self._reader.start()

    def blueprint(self):
        """This log's layout (``blueprint(self.pairs)``)."""
        return blueprint(self.pairs)

    def _write(self):
        # after a failed write it goes on taking items (and drops them), so a step or
        # close waiting on a full queue is never left waiting
        out = self.process.stdin
        while True:
            item = self._queue.get()
            if item is None:
                break
            if self._dead:
                continue
            try:
                out.write(item)
                out.flush()
            except (OSError, ValueError):
                self._dead = "the rerun logger process ended"
        try:
            out.close()
        except OSError:
            pass

    def _read(self):
        while True:
            try:
                reply = pickle.load(self.process.stdout)
            except (OSError, EOFError, pickle.UnpicklingError):
                if not self._closed:
                    self._dead = "the rerun logger process ended"
                return
            if reply[0] == "error":
                self._errors.append(reply[1])

    def _raise_pending(self):
        if self._dead:
            raise RuntimeError(f"rerun logging failed: {self._dead}")
        if self._errors:
            text = self._errors.pop(0)
            raise RuntimeError(f"rerun logging failed: {text}")

    def log_step(self, scene, res, step, latency=None):
        """Hand one step to the recorder: ``scene`` (scene.Scene) after the step, its
        StepResult ``res``, the step counter and the step's latency (s; None: the sum
        of its phases).  Raises RuntimeError for a failure the child reported since
        the last call."""
        if self._closed:
            raise RuntimeError("this RerunLog is closed")
        self._raise_pending()
        if self._version != (scene.version, scene.n_slots):
            self._version = (scene.version, scene.n_slots)
            self._queue.put(pickle.dumps(("scene", scene), protocol=5))
        n = scene.n_slots
        self._queue.put(pickle.dumps(
            ("step", scene.posed[:n], scene.positions[:n], scene.orientations[:n], res,
             int(step), latency), protocol=5))

    def close(self):
        """Send what is held, close the sink and the web viewer, and end the child
        (waits for it to finish writing).  Never raises for the child's failures:
        returns the messages of those no ``log_step`` raised yet."""
        if self._closed:
            return []
        self._closed = True
        self._queue.put(pickle.dumps(("close",), protocol=5))
        self._queue.put(None)
        self._writer.join()
        try:
            self.process.wait(timeout=60)
        except subprocess.TimeoutExpired:
            stop_group(self.process)
        self._reader.join(timeout=5)
        left, self._errors = self._errors, []
        return left


def _serve():
    """The child's loop (``python -m mkcollision_ros.rerun_log``): messages from stdin,
    replies (opened, errors) on the original stdout; anything else printed goes to
    stderr."""
    reply = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    source = sys.stdin.buffer

    def send(*msg):
        pickle.dump(msg, reply)
        reply.flush()

    _, sink, pairs, options = pickle.load(source)
    try:
        rec = _Recorder(sink, pairs, **options)
    except Exception as err:  # noqa: BLE001 - reported to the parent, which raises
        send("failed", type(err).__name__, str(err))
        return
    send("open", rec.where, rec._viewer.pid if rec._viewer is not None else None)
    scene = None
    try:
        while True:
            try:
                msg = pickle.load(source)
            except EOFError:          # the parent is gone: close what there is
                break
            if msg[0] == "close":
                break
            if msg[0] == "scene":
                scene = msg[1]
                continue
            _, posed, positions, orientations, res, step, latency = msg
            try:
                rec.log_step(_Posed(scene, posed, positions, orientations), res, step,
                             latency)
            except Exception as err:  # noqa: BLE001 - reported, the next step goes on
                send("error", f"{type(err).__name__}: {err}")
    finally:
        try:
            rec.close()
        except Exception as err:  # noqa: BLE001
            send("error", f"closing: {type(err).__name__}: {err}")


def stop_group(proc, signals=(signal.SIGTERM, signal.SIGKILL), timeout=5.0):
    """Stop a child started with its own session and everything in its process group
    (the ``rerun`` wrapper leaves the real viewer running otherwise): each signal in
    turn to the group, then up to ``timeout`` s for the group to be gone."""
    for sig in signals:
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            break
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            proc.poll()
            try:
                os.killpg(proc.pid, 0)
            except ProcessLookupError:
                return
            time.sleep(0.05)
    proc.poll()


def _edges(points):
    """Line strips of every edge of a simplex's points (k, 3), k <= 4."""
    k = len(points)
    return [np.stack([points[i], points[j]]) for i in range(k) for j in range(i + 1, k)] \
        or [np.stack([points[0], points[0]])]




_TIMELINES = ("step", "stamp", "iteration")


def read_recording(path):
    """A recording's data, for tests and scripts: {entity path: [row, ...]} in log
    order, each row a dict column -> value (timelines as int64: sequences, and
    nanoseconds for stamps; components as lists, one entry per instance; colours as
    packed 0xRRGGBBAA); what an entity got at the same time in several chunks (several
    archetypes, or the held columns and an immediate log) is one row.  Static rows have
    no timeline columns."""
    import warnings

    import pyarrow as pa
    from rerun.chunk import RrdReader
    out = {}
    with warnings.catch_warnings():
        # a file a viewer saved while receiving has no footer: read whole, as it is
        warnings.simplefilter("ignore")
        reader = RrdReader(str(path))
    for chunk in reader.stream().to_chunks():
        rb = chunk.to_record_batch()
        cols = {}
        for name, col in zip(rb.schema.names, rb.columns):
            if name.startswith("rerun.controls"):
                continue
            if pa.types.is_timestamp(col.type) or pa.types.is_duration(col.type):
                col = col.cast(pa.int64())
            cols[name] = col.to_pylist()
        rows = [{k: v[i] for k, v in cols.items()} for i in range(rb.num_rows)]
        out.setdefault(chunk.entity_path, []).extend(rows)
    for path, rows in out.items():
        rows.sort(key=lambda r: (r.get("step", -1), r.get("iteration", -1)))
        out[path] = merged = []
        for r in rows:
            when = tuple(r.get(k) for k in _TIMELINES)
            if merged and any(w is not None for w in when) and when == tuple(
                    merged[-1].get(k) for k in _TIMELINES):
                merged[-1].update(r)
            else:
                merged.append(r)
    return out


def read_blueprint_views(path):
    """The views of a recording's blueprint: [(kind, origin, name), ...], kind as rerun
    names it ("3D", "TimeSeries", "TextDocument", "TextLog", ...)."""
    import warnings

    from rerun.chunk import RrdReader
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")      # a file without footer: read whole
        reader = RrdReader(str(path))
    views = []
    for store in reader.blueprints():
        for chunk in reader.stream(store=store).to_chunks():
            rb = chunk.to_record_batch()
            if "ViewBlueprint:class_identifier" not in rb.schema.names:
                continue
            row = {c: rb.column(c).to_pylist() for c in (
                "ViewBlueprint:class_identifier", "ViewBlueprint:space_origin",
                "ViewBlueprint:display_name")}
            for kind, origin, name in zip(*row.values()):
                views.append((kind[0], origin[0], name[0]))
    return views


def rgba(packed):
    """A packed 0xRRGGBBAA colour as an (r, g, b, a) tuple."""
    return tuple(int(packed) >> s & 0xFF for s in (24, 16, 8, 0))


def latest_at(rows, step, column):
    """What a viewer shows of ``column`` at ``step``: its value in the last of ``rows``
    (one entity's, from read_recording) logged at or before that step that has it
    (static rows count as before every step); None when there is none, or when a Clear
    came later."""
    value = None
    for r in rows:
        if r.get("step", -1) > step:
            break
        if "Clear:is_recursive" in r:
            value = None
        elif column in r:
            value = r[column]
    return value


if __name__ == "__main__":
    # the module under its own name, so that what the parent pickled (Sink, scene
    # and result types) is of the classes the recorder checks against
    from mkcollision_ros import rerun_log
    rerun_log._serve()
