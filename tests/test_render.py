"""mkcollision_ros.render draws recordings to PNG without a display (rerun's headless
native viewer on Mesa's software Vulkan driver, which tools/setup.sh installs).

The scenes are three bodies of distinct colours, left / right / up in the world, seen by
a fixed camera from -y; the pictures must show each colour where its body is."""
import os
import subprocess
import sys

import numpy as np
import pytest
import rerun as rr
import rerun.blueprint as rrb
from PIL import Image

from mkcollision_ros.render import (MissingDependency, RenderError, check_requirements, free_port,
                                    parse_size, render_png)

APP = "mkcollision_render_test"
SIZE = (640, 400)
STEPS = 20
# name: (rgb, where it is at the last step)
BODIES = {
    "red": ((255, 0, 0), (-2.7, 0.0, 0.0)),
    "blue": ((0, 0, 255), (3.0, 0.0, 0.0)),
    "green": ((0, 200, 0), (0.0, 0.0, 2.5)),
}


def _blueprint():
    """One 3D view filling the window, camera at -y looking at the origin with +z up,
    the time cursor on the newest step, all panels hidden."""
    return rrb.Blueprint(
        rrb.Spatial3DView(origin="/world", name="scene", line_grid=False,
                          background=[255, 255, 255],
                          eye_controls=rrb.EyeControls3D(position=[0, -12, 0],
                                                         look_target=[0, 0, 0],
                                                         eye_up=[0, 0, 1])),
        rrb.TopPanel(state="hidden"), rrb.BlueprintPanel(state="hidden"),
        rrb.SelectionPanel(state="hidden"),
        rrb.TimePanel(state="hidden", play_state="following"))


def _log_scene(rec, steps=STEPS):
    """The red box moves from x = +3 (on top of the blue ball) to its place on the left
    at the last step, so a picture of any earlier step fails the layout checks."""
    rec.send_blueprint(_blueprint())
    for i in range(steps):
        rec.set_time("step", sequence=i)
        s = i / (steps - 1)
        for name, (rgb, (x, y, z)) in BODIES.items():
            if name == "red":
                x = 3.0 + s * (x - 3.0)
            center = [[x, y, z]]
            if name == "red":
                arch = rr.Boxes3D(centers=center, half_sizes=[[0.8, 0.8, 0.8]],
                                  colors=[rgb], fill_mode="solid")
            else:
                arch = rr.Ellipsoids3D(centers=center, half_sizes=[[0.8, 0.8, 0.8]],
                                       colors=[rgb], fill_mode="solid")
            rec.log(f"world/{name}", arch)


def _recording(path):
    rr.set_strict_mode(True)
    rec = rr.RecordingStream(APP)
    rec.set_sinks(rr.FileSink(str(path)))
    _log_scene(rec)
    rec.flush()
    return path


def _masks(png):
    """Boolean masks of the pixels whose hue is clearly each body's (shading changes
    the brightness, not which channel dominates)."""
    rgb = np.asarray(Image.open(png).convert("RGB")).astype(np.int32)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return rgb, {
        "red": (r > 90) & (r > 2 * g + 30) & (r > 2 * b + 30),
        "green": (g > 90) & (g > 2 * r + 30) & (g > 2 * b + 30),
        "blue": (b > 90) & (b > 2 * r + 30) & (b > 2 * g + 30),
    }


def _check_picture(png, size=SIZE):
    rgb, masks = _masks(png)
    assert rgb.shape[:2] == (size[1], size[0])
    # Not blank: many distinct colours, and no single colour covers nearly everything.
    flat = (rgb // 8).reshape(-1, 3)
    colours, counts = np.unique(flat, axis=0, return_counts=True)
    assert len(colours) >= 20, f"only {len(colours)} distinct colours"
    assert counts.max() < 0.99 * flat.shape[0], "one colour fills the picture"
    centroid = {}
    for name, mask in masks.items():
        n = int(mask.sum())
        assert n >= 300, f"{name} body: only {n} pixels of its colour"
        ys, xs = np.nonzero(mask)
        centroid[name] = (xs.mean(), ys.mean())
        # one compact blob: its pixels stay within a small box around the centroid
        assert xs.max() - xs.min() < 0.3 * size[0] and ys.max() - ys.min() < 0.4 * size[1], name
    (rx, ry), (bx, by), (gx, gy) = centroid["red"], centroid["blue"], centroid["green"]
    w, h = size
    assert rx < 0.45 * w < 0.55 * w < bx, centroid           # left and right of the middle
    assert rx < gx < bx, centroid                             # up is between them
    assert gy < ry - 0.1 * h and gy < by - 0.1 * h, centroid  # and above both
    assert abs(ry - by) < 0.05 * h, centroid                  # left and right at one height


def test_recording_renders_bodies_where_they_are(tmp_path):
    rrd = _recording(tmp_path / "scene.rrd")
    out = render_png(rrd, tmp_path / "scene.png", size=SIZE, timeout=60.0)
    assert out == (tmp_path / "scene.png").resolve()
    _check_picture(out)


def test_time_cursor_and_view_only(tmp_path):
    """At the first step the red box still stands in front of the blue ball (right
    of the middle); the picture of the view alone has no viewer chrome around it."""
    rrd = _recording(tmp_path / "scene.rrd")
    out = render_png(rrd, tmp_path / "first.png", size=SIZE, time_at="step=first",
                     view_only=True)
    rgb, masks = _masks(out)
    assert rgb.shape[0] < SIZE[1] and rgb.shape[1] <= SIZE[0]     # the view, not the window
    ys, xs = np.nonzero(masks["red"])
    assert len(xs) >= 300 and xs.mean() > 0.55 * rgb.shape[1]
    assert masks["blue"].sum() < 100            # the box hides the ball behind it
    _check_picture(render_png(rrd, tmp_path / "last.png", size=SIZE, time_at="step=last"))
    with pytest.raises(ValueError, match="no timeline 'nope'"):
        render_png(rrd, tmp_path / "x.png", size=SIZE, time_at="nope=3")


def test_blueprint_file_replaces_the_recordings_layout(tmp_path):
    """A recording whose own blueprint looks from +x at the first step, rendered with
    the test's blueprint as an .rbl file: camera and time are the file's."""
    rr.set_strict_mode(True)
    rbl = tmp_path / "layout.rbl"
    _blueprint().save(APP, str(rbl))
    rec = rr.RecordingStream(APP)
    rec.set_sinks(rr.FileSink(str(tmp_path / "other.rrd")))
    _log_scene(rec)
    rec.send_blueprint(rrb.Blueprint(rrb.Spatial3DView(
        origin="/world", eye_controls=rrb.EyeControls3D(position=[12, 0, 0], look_target=[0, 0, 0],
                                                        eye_up=[0, 0, 1])),
        rrb.TimePanel(play_state="paused")))
    rec.flush()
    out = render_png(tmp_path / "other.rrd", tmp_path / "other.png", size=SIZE, blueprint=rbl)
    _check_picture(out)


def test_live_source_renders_its_newest_data(tmp_path):
    """A gRPC server sink, as the node's `serve` sink runs it: the data logged before
    the render starts reaches the picture, at its newest step."""
    rr.set_strict_mode(True)
    rec = rr.RecordingStream(APP)
    port = free_port()
    rec.set_sinks(rr.GrpcServerSink(bind_ip="127.0.0.1", port=port))
    _log_scene(rec)
    rec.flush()
    out = render_png(f"rerun+http://127.0.0.1:{port}/proxy", tmp_path / "live.png",
                     size=SIZE, timeout=60.0, settle=1.0)
    _check_picture(out)
    del rec


def test_project_recording_shows_each_state_where_its_bodies_are(tmp_path):
    """A recording of the project's own logger (Pipeline(rerun="save:...")): a deep
    pair on the left, a touching pair on the right, a free body above; rendered with a
    fixed camera on world/bodies (labels off), each state's colour is where its bodies
    are."""
    from mkcollision_ros.pipeline import Pipeline
    from mkcollision_ros.rerun_log import DEEP, FREE, TOUCHING
    from mkcollision_ros.render import _stores

    bodies = [{"name": "deep_a", "shape": {"type": "sphere", "radius": 0.6}},
              {"name": "deep_b", "shape": {"type": "sphere", "radius": 0.6}},
              {"name": "touch_a", "shape": {"type": "box", "size": [1.0, 1.0, 1.0]}},
              {"name": "touch_b", "shape": {"type": "box", "size": [1.0, 1.0, 1.0]}},
              {"name": "free", "shape": {"type": "sphere", "radius": 0.6}}]
    pos = np.array([[-3.3, 0, 0], [-2.5, 0, 0], [2.5, 0, 0], [3.495, 0, 0], [0, 0, 2.5]])
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (len(bodies), 1))
    rrd = tmp_path / "pipeline.rrd"
    p = Pipeline(bodies, rerun=f"save:{rrd}")
    for k in range(3):
        res = p.step(pos, quat, 1.0 + 0.1 * k)
    p.close()
    assert sorted(res.pairs.tolist()) == [[0, 1], [2, 3]]
    no_labels = [rr.Ellipsoids3D.from_fields(show_labels=False),
                 rr.Boxes3D.from_fields(show_labels=False)]
    rbl = tmp_path / "bodies.rbl"
    rrb.Blueprint(
        rrb.Spatial3DView(origin="/world/bodies", line_grid=False, background=[255, 255, 255],
                          defaults=no_labels,
                          eye_controls=rrb.EyeControls3D(position=[0, -9, 0.5],
                                                         look_target=[0, 0, 0.5],
                                                         eye_up=[0, 0, 1])),
        rrb.TopPanel(state="hidden"), rrb.BlueprintPanel(state="hidden"),
        rrb.SelectionPanel(state="hidden"), rrb.TimePanel(state="hidden"),
    ).save(_stores(rrd)[0][0].application_id, str(rbl))
    out = render_png(rrd, tmp_path / "pipeline.png", size=SIZE, blueprint=rbl, view_only=True)
    rgb = np.asarray(Image.open(out).convert("RGB")).astype(np.float64)

    def shade_of(colour):
        """Pixels pointing the way of ``colour`` in RGB (shading scales them)."""
        c = np.asarray(colour[:3], np.float64)
        norm = np.linalg.norm(rgb, axis=2)
        cos = (rgb @ c) / np.maximum(norm * np.linalg.norm(c), 1e-9)
        return (cos > np.cos(np.radians(4))) & (norm > 0.3 * np.linalg.norm(c)) \
            & (norm < 0.95 * np.linalg.norm([255.0] * 3))

    centroid = {}
    for name, colour in (("deep", DEEP), ("touching", TOUCHING), ("free", FREE)):
        ys, xs = np.nonzero(shade_of(colour))
        assert len(xs) >= 300, f"{name}: only {len(xs)} pixels of {colour}"
        centroid[name] = (np.median(xs), np.median(ys))   # edge pixels of others aside
    (dx, dy), (tx, ty), (fx, fy) = centroid["deep"], centroid["touching"], centroid["free"]
    w = rgb.shape[1]
    assert dx < 0.45 * w < 0.55 * w < tx and dx < fx < tx, centroid
    assert fy < dy and fy < ty and abs(dy - ty) < 0.05 * rgb.shape[0], centroid


def test_cli_writes_png_and_reports_missing_vulkan(tmp_path):
    rrd = _recording(tmp_path / "scene.rrd")
    cmd = [sys.executable, "-m", "mkcollision_ros.render", str(rrd),
           "--out", str(tmp_path / "cli.png"), "--size", "640x400"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    _check_picture(tmp_path / "cli.png")
    env = dict(os.environ, VK_ICD_FILENAMES=str(tmp_path / "no_such_icd.json"))
    cmd[5] = str(tmp_path / "none.png")
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "apt-get install mesa-vulkan-drivers" in lines[0], done.stderr
    assert not (tmp_path / "none.png").exists()


def test_bad_arguments(tmp_path, monkeypatch):
    rrd = _recording(tmp_path / "scene.rrd")
    for bad in ("12", "0x400", "axb", "640x400x3", "99999x10", "32x32"):
        with pytest.raises(ValueError):
            parse_size(bad)
    assert parse_size("640X400") == (640, 400)
    with pytest.raises(ValueError, match="no recording file"):
        render_png(tmp_path / "missing.rrd", tmp_path / "x.png")
    with pytest.raises(ValueError, match="no blueprint file"):
        render_png(rrd, tmp_path / "x.png", blueprint=tmp_path / "missing.rbl")
    for bad in ("step", "=3", "step="):
        with pytest.raises(ValueError, match="TIMELINE=VALUE"):
            render_png(rrd, tmp_path / "x.png", time_at=bad)
    with pytest.raises(ValueError, match="live source"):
        render_png("rerun+http://127.0.0.1:9/proxy", tmp_path / "x.png", blueprint=rrd)
    with pytest.raises(ValueError, match="timeout"):
        render_png(rrd, tmp_path / "x.png", timeout=0)
    with pytest.raises(ValueError, match="settle"):
        render_png(rrd, tmp_path / "x.png", timeout=5, settle=5)
    monkeypatch.setenv("VK_ICD_FILENAMES", str(tmp_path / "none.json"))
    with pytest.raises(MissingDependency, match="mesa-vulkan-drivers"):
        check_requirements()


def test_silent_live_source_fails_clearly(tmp_path):
    """No server at the address: a RenderError saying no data came."""
    url = f"rerun+http://127.0.0.1:{free_port()}/proxy"      # nothing listens there
    with pytest.raises(RenderError, match="timed out waiting for data"):
        render_png(url, tmp_path / "x.png", timeout=3.0, settle=1.0)
    assert not (tmp_path / "x.png").exists()
