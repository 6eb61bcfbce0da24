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

Cost: the recorder (rerun_recorder.py) runs in a child process of the logger
(``RerunLog``, this module; the child's loop is ``_serve``), so the step
only pickles its data and hands it over.  There, what changes every step (poses,
colours, contacts, the table, events, series) is
held for up to ``batch_steps`` steps or ``batch_seconds`` and sent as columns, one
``send_columns`` call per entity and field set for the whole batch, since each call
costs ~70 us of the SDK's Python conversion besides its data; what is sent once (names,
sizes, triangles, styles, clears, the Minkowski view) is logged at once.  A viewer
sees a step at most ``batch_seconds`` late; ``close`` sends what is held.
"""
import os
import pickle
import queue
import signal
import subprocess
import sys
import threading
import time
from typing import NamedTuple

from .results import Status

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
MINKOWSKI_DIRECTIONS = 150   # support directions of the Minkowski difference's hull
FLUSH_STEPS = 50     # the file sink's bound on steps held in memory (~1 ms a flush)
BATCH_STEPS = 10     # steps held before they are sent as columns (module docstring)
BATCH_SECONDS = 0.1  # s: the longest a step is held
QUEUE_STEPS = 50     # steps waiting for the logger process before a step waits too


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
    (rerun_recorder.Recorder)."""

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
        from .rerun_recorder import Recorder
        rec = Recorder(sink, pairs, **options)
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
