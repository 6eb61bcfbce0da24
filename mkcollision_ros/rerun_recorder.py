"""The recorder of rerun_log.RerunLog, in its child process: builds the recording's
entities (the layout the rerun_log module docstring gives) from the scene and each
step's results, holds what changes every step for up to ``batch_steps`` steps or
``batch_seconds`` and sends it as columns, and writes it to the sink (a file, a viewer
it connects to or one it serves).  rerun is imported inside its methods only, so that
the library without a sink never imports it.
"""
import math
import shutil
import subprocess
import time
from typing import NamedTuple

import numpy as np

from .arbiters import EV_PERSISTED, KIND_NAMES
from .kernels.constants import METHOD_NAMES, P_RADIUS
from .meshes import shape_mesh
from .rerun_log import (BATCH_SECONDS, BATCH_STEPS, CONTACT, DEEP, FLUSH_STEPS, FREE,
                        MINKOWSKI_DIRECTIONS, NORMAL, PLANE, STATUS_NAMES, TOUCHING, WITNESS_A,
                        WITNESS_B, Sink, blueprint, parse_pairs, parse_sink, stop_group)
from .rotations import quat_to_matrix

_DATE = 1e8          # s: a stamp beyond this (1973) is a date, else a duration

_SHAPE_GROUPS = {"sphere": "ellipsoids", "ellipsoid": "ellipsoids", "box": "boxes",
                 "capsule": "capsules", "cylinder": "cylinders", "cone": "meshes",
                 "convex": "meshes", "plane": "meshes"}


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


class Recorder:
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


def _edges(points):
    """Line strips of every edge of a simplex's points (k, 3), k <= 4."""
    k = len(points)
    return [np.stack([points[i], points[j]]) for i in range(k) for j in range(i + 1, k)] \
        or [np.stack([points[0], points[0]])]
