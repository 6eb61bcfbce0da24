"""Render a rerun recording, or a live rerun source, to a PNG image without a display.

``python -m mkcollision_ros.render <recording.rrd | rerun+http://host:port/proxy>
--out shot.png [--size 1280x800] [--time step=last] [--blueprint layout.rbl]
[--view] [--timeout 60] [--settle 3]`` (console script ``render_recording``) runs
rerun's native viewer headless on a software Vulkan driver, drives it through its
control API (``rerun.experimental.ViewerClient``): waits until the data has loaded,
places the time cursor, and saves one screenshot of the whole viewer (``--view``: of
the first view only).

What it needs: the ``rerun`` binary of the ``rerun-sdk`` package and a Vulkan driver
(on Debian: ``apt-get install mesa-vulkan-drivers``, which brings Mesa's lavapipe and
the Vulkan loader).  When one is missing the command prints one line saying what to
install and exits with code 2.  It exits with code 1 when no picture could be taken
within the timeout (no data arrived, the viewer failed), with the reason.

The time shown: ``--time TIMELINE=VALUE`` places the cursor there and pauses (VALUE is
a sequence number, or seconds for a duration or timestamp timeline, or ``first`` /
``last``).  By default a recording file is shown at the last time of the timeline the
viewer picked, and a live source (a ``rerun+http://`` URL, e.g. the node's ``serve``
sink) follows the newest data for ``--settle`` seconds after its first data arrived.

The layout is the recording's own blueprint, or ``--blueprint`` (an ``.rbl`` file
written by ``rerun.blueprint.Blueprint.save`` with the recording's application id),
which replaces it: the file is then rendered from a copy of its first recording store
merged with that blueprint.  A blueprint fixes the 3D camera
(``Spatial3DView(eye_controls=EyeControls3D(position=..., look_target=...,
eye_up=...))``) and the panels (``Blueprint(..., collapse_panels=True)``, or
``TopPanel/TimePanel/...(state="hidden")``).

``--size`` is the viewer window's size, in pixels of the PNG.
"""
import argparse
import importlib.util
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .rerun_log import stop_group

VULKAN_PACKAGE = "mesa-vulkan-drivers"
_ICD_DIRS = ("/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d", "/usr/local/share/vulkan/icd.d")
_LOADER_DIRS = ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64",
                "/usr/lib", "/lib/x86_64-linux-gnu")


class MissingDependency(RuntimeError):
    """Something the headless viewer needs is not installed; the message says what."""


class RenderError(RuntimeError):
    """No picture could be taken: no data came, the viewer failed, or time ran out."""


def rerun_binary():
    """Path of the real rerun viewer binary (the one inside ``rerun_cli``, not the
    Python wrapper script), else a ``rerun`` on PATH.  Raises MissingDependency."""
    spec = importlib.util.find_spec("rerun_cli")
    if spec is not None and spec.origin:
        exe = Path(spec.origin).parent / "rerun"
        if exe.is_file() and os.access(exe, os.X_OK):
            return exe
    found = shutil.which("rerun")
    if found:
        return Path(found)
    raise MissingDependency(
        "no rerun binary: install the pinned rerun-sdk (bash tools/setup.sh, or "
        "pip install -c requirements/lock.txt rerun-sdk)")


def vulkan_icds():
    """Vulkan driver manifests (ICD json files) the Vulkan loader would find."""
    env = os.environ.get("VK_ICD_FILENAMES") or os.environ.get("VK_DRIVER_FILES")
    if env:
        return [Path(p) for p in env.split(os.pathsep) if Path(p).is_file()]
    icds = []
    for folder in _ICD_DIRS:
        if os.path.isdir(folder):
            icds += sorted(Path(folder).glob("*.json"))
    return icds


def vulkan_loader_present():
    """True when ``libvulkan.so.1`` (the Vulkan loader) is installed."""
    return any(os.path.exists(os.path.join(d, "libvulkan.so.1")) for d in _LOADER_DIRS)


def check_requirements():
    """Return the rerun binary's path; raise MissingDependency naming what to install."""
    exe = rerun_binary()
    if not vulkan_loader_present() or not vulkan_icds():
        raise MissingDependency(
            "no Vulkan driver: install Mesa's software driver with "
            f"`apt-get install {VULKAN_PACKAGE}` (or run bash tools/setup.sh as root)")
    return exe


def parse_size(text):
    """``"1280x800"`` -> (1280, 800); ValueError for anything else."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise ValueError(f"size must look like 1280x800, got {text!r}") from None
    if not (64 <= w <= 8192 and 64 <= h <= 8192):
        raise ValueError(f"size {w}x{h} is out of range (64..8192 pixels each way)")
    return w, h


def _is_url(source):
    return "://" in str(source)


def parse_time(text):
    """``"step=12"`` -> ("step", "12"); the value is read against the timeline's type
    once the recording has loaded.  ValueError for anything without ``=``."""
    name, sep, value = str(text).partition("=")
    if not sep or not name.strip() or not value.strip():
        raise ValueError(f"time must look like TIMELINE=VALUE (e.g. step=12, step=last), got {text!r}")
    return name.strip(), value.strip()


def render_png(source, out_path, size=(1280, 800), timeout=60.0, blueprint=None,
               settle=3.0, time_at=None, view_only=False):
    """Render ``source`` (an .rrd path or a ``rerun+http://`` URL) to the PNG
    ``out_path`` with the headless native viewer in a window of ``size`` = (width,
    height) pixels.  ``blueprint``: an optional .rbl file replacing the recording's
    layout.  ``time_at``: ``"TIMELINE=VALUE"`` (see the module text), else a file shows
    its last time and a live source follows its newest data for ``settle`` seconds.
    ``view_only``: the first view's pixels, not the whole window.  Takes at most
    ``timeout`` seconds in all.  Returns the PNG's Path.  Raises MissingDependency when
    the rerun binary or a Vulkan driver is missing, ValueError for bad arguments,
    RenderError when no picture could be taken."""
    width, height = (int(v) for v in size)
    parse_size(f"{width}x{height}")
    if not timeout > 0:
        raise ValueError(f"timeout must be positive seconds, got {timeout!r}")
    if not 0 <= settle < timeout:
        raise ValueError(f"settle must be in [0, timeout) seconds, got {settle!r}")
    live = _is_url(source)
    if not live and not Path(source).is_file():
        raise ValueError(f"no recording file at {source}")
    if blueprint is not None and not Path(blueprint).is_file():
        raise ValueError(f"no blueprint file at {blueprint}")
    if blueprint is not None and live:
        raise ValueError("a blueprint file can replace a recording file's layout only, "
                         "not a live source's")
    at = parse_time(time_at) if time_at is not None else None
    exe = check_requirements()
    out = Path(out_path).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    deadline = time.monotonic() + timeout
    with tempfile.TemporaryDirectory(prefix="mkc-render-") as tmp:
        env = dict(os.environ)
        env.setdefault("XDG_RUNTIME_DIR", tmp)
        env["RUST_LOG"] = "error"   # info/warn log lines would be drawn as notifications
        if blueprint is not None:
            source = _with_blueprint(exe, source, blueprint, Path(tmp), deadline)
        port = free_port()
        cmd = [str(exe), "--headless", "--renderer", "vulkan", "--window-size",
               f"{width}x{height}", "--bind", "127.0.0.1", "--port", str(port),
               "--hide-welcome-screen", str(source)]
        log_path = Path(tmp) / "viewer.log"
        with open(log_path, "w") as log:
            proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env,
                                    stdin=subprocess.DEVNULL, start_new_session=True)
            try:
                png = _drive(proc, f"rerun+http://127.0.0.1:{port}/proxy", live, at,
                             settle, view_only, deadline)
            except RenderError as exc:
                tail = log_path.read_text(errors="replace").strip().splitlines()[-3:]
                raise RenderError(f"{exc} (source {source})"
                                  + (": " + " | ".join(tail) if tail else "")) from None
            finally:
                stop_group(proc, signals=(signal.SIGKILL,))
    out.write_bytes(png)
    return out


def _drive(proc, url, live, at, settle, view_only, deadline):
    """Connect to the viewer, wait for the data, place the time, return PNG bytes."""
    import warnings

    from rerun.experimental import ViewerClient

    def alive(waiting_for="the viewer"):
        if proc.poll() is not None:
            raise RenderError(f"the viewer exited with code {proc.returncode}")
        if time.monotonic() > deadline:
            raise RenderError(f"timed out waiting for {waiting_for}")

    client, state = None, None
    while state is None:
        alive()
        try:
            client = client or ViewerClient.connect(url)
            state = client.get_state()
        except Exception:       # noqa: BLE001 (not listening yet)
            client = None
            time.sleep(0.1)
    first_data = None
    while True:
        alive("data" if first_data is None else "the data to finish loading")
        state = client.get_state()
        recording = next((r for r in state.recordings
                          if r.store_id == state.active_recording), None)
        has_data = recording is not None and any(t.end is not None for t in recording.timelines)
        if has_data and first_data is None:
            first_data = time.monotonic()
        if has_data and (live or not state.loading) and state.views:
            if not live or time.monotonic() - first_data >= settle:
                break
        time.sleep(0.05)
    timelines = {t.name: t for t in recording.timelines if t.end is not None}
    if at is not None:
        name, value = at
        if name not in timelines:
            raise ValueError(f"no timeline {name!r} in the recording (it has "
                             f"{', '.join(sorted(timelines))})")
        _seek(client, timelines[name], value)
    elif live:
        client.set_time(play_state="following")
    else:
        name = recording.current_timeline if recording.current_timeline in timelines else \
            next(iter(timelines))
        _seek(client, timelines[name], "last")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        view = state.views[0].view_id if view_only else None
        try:
            png = client.take_screenshot(view)
        except Exception as exc:        # noqa: BLE001 (the viewer's own error text)
            raise RenderError(f"the viewer took no screenshot: {exc}") from None
    if not png.startswith(b"\x89PNG"):
        raise RenderError("the viewer returned no PNG")
    return png


def _seek(client, timeline, value):
    """Pause with the cursor at ``value`` ("first", "last", a number) on ``timeline``."""
    import numpy as np
    if value in ("first", "last"):
        raw = timeline.start if value == "first" else timeline.end
        kind = {"sequence": "sequence", "duration": "duration", "timestamp": "timestamp"}
        arg = {"sequence": raw, "duration": np.timedelta64(raw, "ns"),
               "timestamp": np.datetime64(raw, "ns")}[timeline.time_type]
        client.set_time(timeline.name, play_state="paused", **{kind[timeline.time_type]: arg})
        return
    try:
        number = int(value) if timeline.time_type == "sequence" else float(value)
    except ValueError:
        raise ValueError(f"time {value!r} on the {timeline.time_type} timeline "
                         f"{timeline.name!r}: want first, last or a number") from None
    client.set_time(timeline.name, play_state="paused", **{timeline.time_type: number})


def free_port():
    """A TCP port on 127.0.0.1 that was free a moment ago."""
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _stores(path):
    """(recording stores, blueprint stores) of an .rrd file; ([], []) if unreadable."""
    import warnings
    from rerun.chunk import RrdReader
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # a streamed file has no footer; that is fine
        try:
            reader = RrdReader(str(path))
            return reader.recordings(), reader.blueprints()
        except Exception:       # noqa: BLE001 (any decoding failure means: no data)
            return [], []


def _with_blueprint(exe, path, blueprint, tmp, deadline):
    """One .rrd holding the first recording of ``path`` and the blueprint file, which
    the viewer then applies every time (given as two files on its command line, the
    recording's own or the default blueprint wins when the recording loads last)."""
    out = tmp / "with-blueprint.rrd"
    cmd = [str(exe), "rrd", "merge", str(_without_blueprint(path, tmp / "data.rrd")),
           str(blueprint), "-o", str(out)]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True,
                              timeout=max(1.0, deadline - time.monotonic()))
    except subprocess.TimeoutExpired:
        raise RenderError("merging the blueprint into the recording timed out") from None
    if done.returncode != 0 or not out.is_file():
        raise RenderError(f"rerun rrd merge failed: {done.stderr.strip()[-300:]}")
    return out


def _without_blueprint(path, out):
    """The first recording of ``path`` without the blueprints stored beside it.
    Returns ``path`` itself when it has none."""
    import warnings
    from rerun.chunk import RrdReader
    recordings, blueprints = _stores(path)
    if not blueprints or not recordings:
        return path
    first = recordings[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        RrdReader(str(path)).stream(store=first).write_rrd(
            str(out), application_id=first.application_id, recording_id=first.recording_id)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="render_recording", description=__doc__.splitlines()[0])
    parser.add_argument("source", help="an .rrd file or a rerun+http://host:port/proxy URL")
    parser.add_argument("--out", required=True, help="PNG file to write")
    parser.add_argument("--size", default="1280x800", help="PNG size in pixels (default 1280x800)")
    parser.add_argument("--timeout", type=float, default=60.0,
                        help="seconds to wait for the image (default 60)")
    parser.add_argument("--blueprint", help="an .rbl blueprint file to lay out the views")
    parser.add_argument("--settle", type=float, default=3.0,
                        help="seconds a live source streams before the picture (default 3)")
    parser.add_argument("--time", dest="time_at", metavar="TIMELINE=VALUE",
                        help="time cursor, e.g. step=12, step=first, step=last "
                             "(default: a file's last time, a live source's newest data)")
    parser.add_argument("--view", action="store_true",
                        help="save the first view only, not the whole viewer window")
    args = parser.parse_args(argv)
    try:
        size = parse_size(args.size)
        t0 = time.monotonic()
        out = render_png(args.source, args.out, size=size, timeout=args.timeout,
                         blueprint=args.blueprint, settle=args.settle,
                         time_at=args.time_at, view_only=args.view)
    except MissingDependency as exc:
        print(f"render_recording: missing: {exc}", file=sys.stderr)
        return 2
    except (ValueError, RenderError) as exc:
        print(f"render_recording: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {out} in {time.monotonic() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
