"""Rerun logging (mkcollision_ros.rerun_log): the recordings read back and checked
against the steps that produced them."""
import os
import socket
import subprocess
import sys
import time
import urllib.request

import numpy as np
import pytest

from mkcollision_ros.rotations import quat_to_matrix
from mkcollision_ros.meshes import shape_mesh
from mkcollision_ros.pipeline import Pipeline
from mkcollision_ros.render import free_port
from mkcollision_ros.rerun_log import (DEEP, FREE, PLANE, TOUCHING, RerunLog, Sink,
                                       latest_at, parse_pairs, parse_sink,
                                       read_blueprint_views, read_recording, rgba,
                                       stop_group)
from oracles import quat_axis

ROCK = np.random.default_rng(3).normal(size=(12, 3)) * 0.3
BODIES = [
    {"name": "floor", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0},
     "static": True},
    {"name": "ball", "shape": {"type": "sphere", "radius": 0.5}},
    {"name": "egg", "shape": {"type": "ellipsoid", "radii": [0.3, 0.4, 0.6]}},
    {"name": "crate", "shape": {"type": "box", "size": [1.0, 1.0, 1.0]}},
    {"name": "pill", "shape": {"type": "capsule", "radius": 0.2, "length": 0.8}},
    {"name": "can", "shape": {"type": "cylinder", "radius": 0.3, "height": 0.8,
                              "margin": 0.01}},
    {"name": "cone", "shape": {"type": "cone", "radius": 0.4, "height": 0.8}},
    {"name": "rock", "shape": {"type": "convex", "points": ROCK.tolist()}},
]
NAMES = [b["name"] for b in BODIES]


def poses(k, rng):
    """Step k's poses: everything floats above the floor, the ball sinks into the crate
    on steps 1-2 and leaves it on step 3."""
    pos = np.array([[0, 0, 0], [0, 0, 3.0], [-2, 0, 3], [1.2, 0, 3], [3.5, 0, 3],
                    [5, 0, 3], [6.5, 0, 3], [8.5, 0, 3]], float)
    if k == 3:
        pos[1, 1] = -3.0
    quat = np.array([quat_axis(rng.normal(size=3), rng.uniform(0, np.pi))
                     for _ in BODIES])
    quat[:2] = [0, 0, 0, 1]
    quat[3] = [0, 0, 0, 1]
    return pos, quat


def test_sink_forms_and_their_errors():
    assert parse_sink("off") == Sink("off") and parse_sink("") == Sink("off")
    assert parse_sink("save:/tmp/x.rrd") == Sink("save", "/tmp/x.rrd")
    assert parse_sink("connect").target.startswith("rerun+http://127.0.0.1:")
    assert parse_sink("connect:rerun+http://10.0.0.2:9876/proxy").target \
        == "rerun+http://10.0.0.2:9876/proxy"
    assert parse_sink("serve") == Sink("serve", ("127.0.0.1", 9876))
    assert parse_sink("serve:9000") == Sink("serve", ("127.0.0.1", 9000))
    assert parse_sink("serve:0.0.0.0:9001") == Sink("serve", ("0.0.0.0", 9001))
    for bad, why in [("save:", "file"), ("connect:http://x", "must start with"),
                     ("serve:abc", "bad port"), ("serve:70000", "port"),
                     ("file:x", "unknown rerun sink"), (3, "string")]:
        with pytest.raises(ValueError, match=why):
            parse_sink(bad)
    assert parse_pairs(["a:b", ("c", "d")]) == [("a", "b"), ("c", "d")]
    for bad in ["ab", ":b", ("a",), 5]:
        with pytest.raises(ValueError, match="name_a:name_b"):
            parse_pairs([bad])


def _rerun_modules_after_steps(rerun, steps):
    """Run ``steps`` steps of two spheres in a fresh process with ``rerun=`` the given
    sink; returns the rerun modules that process imported."""
    code = ("import sys, numpy as np\n"
            "from mkcollision_ros.pipeline import Pipeline\n"
            "p = Pipeline([{'name': 'a', 'shape': {'type': 'sphere', 'radius': 1.0}},"
            " {'name': 'b', 'shape': {'type': 'sphere', 'radius': 1.0}}],"
            f" rerun={rerun!r})\n"
            f"for k in range({steps}):\n"
            "    p.step(np.array([[0.0, 0, 0], [1.5 + 0.01 * k, 0, 0]]),"
            " np.tile([0.0, 0, 0, 1], (2, 1)), float(k))\n"
            "p.close()\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('rerun', 'rerun_bindings')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def test_off_never_imports_rerun():
    assert _rerun_modules_after_steps("off", 1) == "[]"


def test_logging_runs_in_a_child_and_reports_its_failures(tmp_path):
    """With a sink open the steps are recorded by the logger's child process: this
    process still never imports rerun, and the file holds every step.  A sink the
    child cannot open is a clear error here, and a child that dies makes the next step
    raise instead of hanging."""
    path = tmp_path / "child.rrd"
    assert _rerun_modules_after_steps(f"save:{path}", 25) == "[]"
    steps = {r["step"] for r in read_recording(path)["/world/contacts"] if "step" in r}
    assert steps == set(range(1, 26))
    with pytest.raises(RuntimeError):
        RerunLog(f"save:{tmp_path / 'no' / 'such' / 'folder' / 'x.rrd'}")
    p = Pipeline(BODIES, rerun=f"save:{tmp_path / 'killed.rrd'}")
    p.rerun.process.kill()
    p.rerun.process.wait()
    rng = np.random.default_rng(3)
    with pytest.raises(RuntimeError, match="rerun"):
        for k in range(200):
            p.step(*poses(k % 4, rng))
            time.sleep(0.005)
    for k in range(60):       # and every later step too, never waiting on a full queue
        with pytest.raises(RuntimeError, match="ended"):
            p.step(*poses(k % 4, rng))
    p.close()


@pytest.fixture(scope="module")
def recording_path(tmp_path_factory):
    return tmp_path_factory.mktemp("rerun") / "steps.rrd"


@pytest.fixture(scope="module")
def recorded(recording_path):
    """Four steps of BODIES logged to a file, with their StepResults."""
    path = recording_path
    p = Pipeline(BODIES, rerun=f"save:{path}")
    rng = np.random.default_rng(11)
    steps = []
    for k in range(4):
        pos, quat = poses(k, rng)
        if k == 1:
            pos[1, 0] = 0.55           # ball 0.35 m into the crate: deep
        if k == 2:
            pos[1, 0] = 0.205          # 5 mm into it: touching, not deep
        res = p.step(pos, quat, 100.0 + 0.5 * k)
        steps.append((pos, quat, res))
    p.close()
    return read_recording(path), steps


def shown(rows, k):
    """Every column of one entity as a viewer shows it at step k (latest-at)."""
    cols = {c for r in rows for c in r if ":" in c}
    return {c: latest_at(rows, k, c) for c in cols}


def at_step(rows, k):
    got = [r for r in rows if r.get("step") == k]
    assert got, f"nothing logged at step {k}"
    return got[-1]


def test_every_body_is_its_shape_in_slot_order(recorded):
    rec, steps = recorded
    pos, quat, _ = steps[0]
    ell = shown(rec["/world/bodies/ellipsoids"], 1)
    assert ell["Ellipsoids3D:labels"] == ["ball", "egg"]
    np.testing.assert_allclose(ell["Ellipsoids3D:half_sizes"], [[0.5] * 3, [0.3, 0.4, 0.6]])
    np.testing.assert_allclose(ell["Ellipsoids3D:centers"], pos[1:3], atol=1e-6)
    np.testing.assert_allclose(np.abs(ell["Ellipsoids3D:quaternions"]),
                               np.abs(quat[1:3]), atol=1e-6)
    box = shown(rec["/world/bodies/boxes"], 1)
    assert box["Boxes3D:labels"] == ["crate"]
    np.testing.assert_allclose(box["Boxes3D:half_sizes"], [[0.5] * 3])
    # a capsule's end at its translation, the capsule along +z of its rotation
    cap = shown(rec["/world/bodies/capsules"], 1)
    axis = quat_to_matrix(quat[4:5])[0, :, 2]
    np.testing.assert_allclose(np.array(cap["Capsules3D:translations"][0]) + 0.4 * axis,
                               pos[4], atol=1e-6)
    assert cap["Capsules3D:lengths"] == [pytest.approx(0.8)]
    cyl = shown(rec["/world/bodies/cylinders"], 1)    # grown by its 1 cm margin
    assert cyl["Cylinders3D:radii"] == [pytest.approx(0.31)]
    assert cyl["Cylinders3D:lengths"] == [pytest.approx(0.82)]
    # cone, rock and floor as one mesh: each body's mesh moved to its pose
    mesh = shown(rec["/world/bodies/meshes"], 1)
    names = shown(rec["/world/bodies/mesh_names"], 1)
    assert names["Points3D:labels"] == ["floor", "cone", "rock"]
    v = np.array(mesh["Mesh3D:vertex_positions"])
    want = []
    for i in (6, 7):
        s = BODIES[i]["shape"]
        local, _ = shape_mesh(s, ROCK if s["type"] == "convex" else None)
        want.append(local @ quat_to_matrix(quat[i:i + 1])[0].T + pos[i])
    want = np.concatenate(want)
    assert v.shape == (4 + len(want), 3)
    np.testing.assert_allclose(v[4:], want, atol=1e-5 * max(1.0, np.abs(want).max()))
    # the floor: a square patch on z = 0 under every bounded body, in its own colour
    floor = v[:4]
    assert np.all(floor[:, 2] == 0.0)
    assert floor[:, 0].min() < pos[1:, 0].min() and floor[:, 0].max() > pos[1:, 0].max()
    assert floor[:, 1].min() < pos[1:, 1].min() and floor[:, 1].max() > pos[1:, 1].max()
    colours = [rgba(c) for c in mesh["Mesh3D:vertex_colors"]]
    assert colours[:4] == [PLANE] * 4 and colours[4] == FREE
    tris = np.array(mesh["Mesh3D:triangle_indices"])
    assert tris.min() == 0 and tris.max() == len(v) - 1


def test_colours_follow_the_contact_state(recorded):
    rec, steps = recorded
    colour = {}
    for k in range(1, 5):
        ell = shown(rec["/world/bodies/ellipsoids"], k)
        box = shown(rec["/world/bodies/boxes"], k)
        colour[k] = (rgba(ell["Ellipsoids3D:colors"][0]), rgba(box["Boxes3D:colors"][0]),
                     rgba(ell["Ellipsoids3D:colors"][1]))
    assert colour[1] == (FREE, FREE, FREE)
    assert colour[2] == (DEEP, DEEP, FREE)          # 0.35 m deep
    assert colour[3] == (TOUCHING, TOUCHING, FREE)  # 5 mm: below the 1 cm of "deep"
    assert colour[4] == (FREE, FREE, FREE)


def test_contacts_keep_their_ids_and_depths(recorded):
    rec, steps = recorded
    for k, (_, _, res) in enumerate(steps, start=1):
        rows = [r for r in rec["/world/contacts"] if r.get("step") == k]
        if not len(res.depth):
            assert rows and "Clear:is_recursive" in rows[-1] or not rows
            continue
        row = rows[-1]
        assert row["contact_id"] == res.contact_id.tolist()
        assert row["depth"] == res.depth.tolist()
        assert row["age"] == res.age.tolist()
        names = [res.names[a] + "-" + res.names[b] for a, b in zip(res.body_a, res.body_b)]
        assert row["Points3D:labels"] == [f"{n} #{i}" for n, i in zip(names, res.contact_id)]
        np.testing.assert_allclose(row["Points3D:positions"], res.position, atol=1e-6)
        arrows = at_step(rec["/world/normals"], k)
        lengths = np.linalg.norm(arrows["Arrows3D:vectors"], axis=1)
        np.testing.assert_allclose(lengths, 0.05 + res.depth, rtol=1e-5)
        for side, want in (("a", res.point_a), ("b", res.point_b)):
            witness = at_step(rec[f"/world/witness/{side}"], k)
            np.testing.assert_allclose(witness["Points3D:positions"], want, atol=1e-6)
    deep = steps[1][2]
    i = [n for n, (a, b) in enumerate(zip(deep.body_a, deep.body_b))
         if {deep.names[a], deep.names[b]} == {"ball", "crate"}]
    assert len(i) == 1 and deep.depth[i[0]] == pytest.approx(0.35)
    # the same contact at the next step keeps its id (a persistent arbiter)
    nxt = steps[2][2]
    assert deep.contact_id[i[0]] in nxt.contact_id
    table = at_step(rec["/tables/contacts"], 2)["TextDocument:text"][0]
    assert f"| ball-crate | {deep.contact_id[i[0]]} | 0 | 0.35" in table


def test_events_and_series(recorded):
    rec, steps = recorded
    text = {r["step"]: r["TextLog:text"][0] for r in rec["/events"]}
    assert "began ball-crate pair" in text[2]
    assert "ended ball-crate pair" in text[4]
    for k, (_, _, res) in enumerate(steps, start=1):
        stats = at_step(rec["/stats"], k)["Scalars:scalars"]
        assert stats == [len(res.depth), len(res.pairs), res.n_candidate_pairs]
        timing = at_step(rec["/timing"], k)["Scalars:scalars"]
        assert timing[1:] == pytest.approx([1e3 * t for t in res.timings.values()])
        assert timing[0] == pytest.approx(1e3 * sum(res.timings.values()))
    names = [r for r in rec["/timing"] if "SeriesLines:names" in r][0]
    assert names["SeriesLines:names"] == ["step"] + list(steps[0][2].timings)
    stamps = [at_step(rec["/stats"], k)["stamp"] for k in range(1, 5)]
    assert stamps == [int(round(1e9 * (100.0 + 0.5 * k))) for k in range(4)]


def test_the_blueprint_lays_out_every_view(recorded, recording_path):
    views = {(kind, origin) for kind, origin, _ in read_blueprint_views(recording_path)}
    assert views == {("3D", "world"), ("TimeSeries", "stats"), ("TimeSeries", "timing"),
                     ("TextDocument", "tables/contacts"), ("TextLog", "events")}


def test_scene_edits_change_what_is_drawn(tmp_path):
    path = tmp_path / "edits.rrd"
    p = Pipeline(BODIES[1:4], rerun=f"save:{path}")
    q = np.tile([0.0, 0, 0, 1], (3, 1))
    p.step(np.array([[0.0, 0, 0], [5, 0, 0], [10, 0, 0]]), q)
    p.scene.remove_body("egg")
    p.scene.add_body({"name": "rod", "shape": {"type": "capsule", "radius": 0.1,
                                               "length": 1.0},
                      "pose": ([0.0, 3.0, 0.0], [0, 0, 0, 1])})
    p.step()
    p.close()
    rec = read_recording(path)
    assert latest_at(rec["/world/bodies/ellipsoids"], 1, "Ellipsoids3D:labels") \
        == ["ball", "egg"]
    assert latest_at(rec["/world/bodies/ellipsoids"], 2, "Ellipsoids3D:labels") == ["ball"]
    assert latest_at(rec["/world/bodies/capsules"], 2, "Capsules3D:labels") == ["rod"]


def _listening(port):
    """Local addresses listening on TCP ``port`` (from /proc/net/tcp)."""
    found = []
    with open("/proc/net/tcp") as f:
        for line in f.readlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            ip_hex, port_hex = local.split(":")
            if state == "0A" and int(port_hex, 16) == port:
                found.append(socket.inet_ntoa(bytes.fromhex(ip_hex)[::-1]))
    return found


def test_serve_binds_loopback_with_a_web_viewer():
    grpc_port, web_port = free_port(), free_port()
    log = RerunLog(f"serve:{grpc_port}", web_port=web_port, memory_limit="16MiB")
    try:
        assert _listening(grpc_port) == ["127.0.0.1"]
        page = None
        end = time.monotonic() + 30
        while page is None and time.monotonic() < end:
            try:
                page = urllib.request.urlopen(f"http://127.0.0.1:{web_port}/",
                                              timeout=2).read()
            except OSError:
                time.sleep(0.2)
        assert page is not None and b"<html" in page.lower()
        assert _listening(web_port) == ["127.0.0.1"]
        assert f"127.0.0.1:{web_port}" in log.where
        viewer_pid = log.viewer_pid
        assert viewer_pid is not None
    finally:
        log.close()
    assert log.process.poll() is not None       # the logger's process ended
    with pytest.raises(ProcessLookupError):     # and the web viewer's group with it
        os.killpg(viewer_pid, 0)


def test_connect_streams_to_a_running_viewer(tmp_path):
    """A `rerun` process listening on loopback saves what it receives; the steps logged
    through connect:<url> arrive in it."""
    port, received = free_port(), tmp_path / "received.rrd"
    server = subprocess.Popen(["rerun", "--bind", "127.0.0.1", "--port", str(port),
                               "--save", str(received)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        end = time.monotonic() + 30
        while not _listening(port) and time.monotonic() < end:
            time.sleep(0.1)
        assert _listening(port) == ["127.0.0.1"]
        p = Pipeline(BODIES[1:4], rerun=f"connect:rerun+http://127.0.0.1:{port}/proxy")
        q = np.tile([0.0, 0, 0, 1], (3, 1))
        for k in range(3):
            p.step(np.array([[0.0, 0, 0], [5, 0, 0], [0.9, 0, 0]]), q, float(k))
        p.close()
        rows = []
        while len(rows) < 3 and time.monotonic() < end:
            time.sleep(0.2)
            if received.exists():
                rows = [r for r in read_recording(received).get("/world/contacts", [])
                        if "depth" in r]
        assert [r["step"] for r in rows] == [1, 2, 3]
        assert all(r["depth"] == [pytest.approx(0.1)] for r in rows)
    finally:
        stop_group(server)


def test_a_group_at_rest_is_sent_once(tmp_path):
    path = tmp_path / "rest.rrd"
    bodies = [{"name": "shelf", "shape": {"type": "box", "size": [2.0, 0.5, 0.1]},
               "static": True},
              {"name": "bin", "shape": {"type": "box", "size": [0.4, 0.4, 0.4]}},
              {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}}]
    p = Pipeline(bodies, rerun=f"save:{path}")
    pos = np.array([[0.0, 0, 0], [0, 0, 0.5], [3.0, 0, 0]])
    q = np.tile([0.0, 0, 0, 1], (3, 1))
    for k in range(4):
        pos[2, 0] = 3.0 + 0.1 * k              # only the ball moves
        p.step(pos, q, float(k))
    p.close()
    rec = read_recording(path)
    assert [r["step"] for r in rec["/world/bodies/boxes"]] == [1]
    assert [r["step"] for r in rec["/world/bodies/ellipsoids"]] == [1, 2, 3, 4]
    moved = [r for r in rec["/world/bodies/ellipsoids"] if r["step"] > 1]
    assert all(set(r) - {"step", "stamp", "log_time"}
               == {"Ellipsoids3D:centers", "Ellipsoids3D:quaternions"} for r in moved)


def test_a_chosen_pair_shows_its_minkowski_difference_and_iterations(tmp_path):
    from mkcollision_ros import collide
    from mkcollision_ros.trace import trace_pair
    path = tmp_path / "pair.rrd"
    bodies = [{"name": "egg", "shape": {"type": "ellipsoid", "radii": [0.5, 0.3, 0.2]}},
              {"name": "rock", "shape": {"type": "convex", "points": ROCK.tolist()}}]
    p = Pipeline(bodies, rerun=RerunLog(f"save:{path}", pairs=["egg:rock", "egg:gone"],
                                        minkowski_period=0.0))
    q = np.array([[0.0, 0, 0, 1], quat_axis([1, 2, 3], 0.7)])
    pos = np.array([[0.0, 0, 0], [0.45, 0.1, 0.0]])
    p.step(pos, q, 0.0)
    p.close()
    rec = read_recording(path)
    root = "/minkowski/egg-rock"
    shape_a, shape_b = bodies[0]["shape"], bodies[1]["shape"]
    want = collide(shape_a, (pos[0], q[0]), shape_b, (pos[1], q[1]))
    assert want.touching
    # the difference contains the origin (they touch) and the answer's point a - b
    verts = np.array(rec[f"{root}/difference"][0]["Mesh3D:vertex_positions"])
    tris = np.array(rec[f"{root}/difference"][0]["Mesh3D:triangle_indices"])
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    n = np.cross(b - a, c - a)
    assert np.all(np.einsum("ij,ij->i", n, -a) < 0)          # origin behind every face
    arrow = rec[f"{root}/answer"][0]
    np.testing.assert_allclose(arrow["Arrows3D:vectors"][0], want.point_a - want.point_b,
                               atol=1e-6)
    # every iteration the trace recorded, one per index of the iteration timeline
    tr = trace_pair(shape_a, (pos[0], q[0]), shape_b, (pos[1], q[1]))
    logged = (rec.get(f"{root}/gjk/simplex", []) + rec.get(f"{root}/epa/polytope", [])
              + rec.get(f"{root}/mpr/portal", []))
    n_iter = len(tr.gjk_simplices) + len(tr.epa_polytopes) + len(tr.mpr_portals)
    assert n_iter > 0 and len(logged) == n_iter
    assert sorted(r["iteration"] for r in logged) == list(range(n_iter))
    if tr.epa_polytopes:
        last = [r for r in logged if "Mesh3D:vertex_positions" in r][-1]
        np.testing.assert_allclose(last["Mesh3D:vertex_positions"], tr.epa_polytopes[-1][0],
                                   atol=1e-6)
    note = rec["/minkowski/egg-gone/note"][0]["TextLog:text"][0]
    assert "not in the scene" in note
    views = {(k, o) for k, o, _ in read_blueprint_views(path)}
    assert ("3D", "minkowski/egg-rock") in views and ("3D", "world") in views
