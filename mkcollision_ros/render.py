"""Render a rerun recording, or a live rerun source, to a PNG image without a display.

``python -m mkcollision_ros.render <recording.rrd | rerun+http://host:port/proxy>
--out shot.png [--size 1280x800] [--timeout 60] [--blueprint layout.rbl]``
(console script ``render_recording``) runs rerun's native viewer headless on a software
Vulkan driver and saves one screenshot of the whole viewer window.

What it needs: the ``rerun`` binary of the ``rerun-sdk`` package and a Vulkan driver
(on Debian: ``apt-get install mesa-vulkan-drivers``, which brings Mesa's lavapipe and
the Vulkan loader).  When one is missing the command prints one line saying what to
install and exits with code 2.  It exits with code 1 when the viewer writes no PNG
within the timeout.

A live source (a ``rerun+http://`` URL, e.g. the node's ``serve`` sink) is first
recorded for ``--settle`` seconds into a temporary .rrd, which is then rendered: the
headless viewer takes its screenshot as soon as it has painted once, before a stream
has delivered anything.

What is shown: the views are laid out by the recording's own blueprint, or by
``--blueprint`` (an ``.rbl`` file written by ``rerun.blueprint.Blueprint.save`` with
the recording's application id), which replaces it.  A blueprint fixes

- the time shown: ``TimePanel(play_state="following")`` shows the last time of the
  timeline, ``"paused"`` the first; without either the viewer starts playing the
  recording and the picture shows whatever time it reached;
- the 3D camera: ``Spatial3DView(eye_controls=EyeControls3D(position=...,
  look_target=..., eye_up=...))``;
- the side panels: ``Blueprint(..., collapse_panels=True)``.

The viewer's command line has no option to place the time cursor at another time.

``--size`` is the PNG's size in pixels.  The headless viewer draws two pixels per
logical point, so the window is opened at half that size in points.
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

PIXELS_PER_POINT = 2
VULKAN_PACKAGE = "mesa-vulkan-drivers"
_ICD_DIRS = ("/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d", "/usr/local/share/vulkan/icd.d")
_LOADER_DIRS = ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64",
                "/usr/lib", "/lib/x86_64-linux-gnu")


class MissingDependency(RuntimeError):
    """Something the headless viewer needs is not installed; the message says what."""


class RenderError(RuntimeError):
    """The viewer ran but wrote no image."""


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
    if w < 2 * PIXELS_PER_POINT or h < 2 * PIXELS_PER_POINT or w > 8192 or h > 8192:
        raise ValueError(f"size {w}x{h} is out of range (4..8192 pixels each way)")
    return w, h


def _is_url(source):
    return "://" in str(source)


def _stop_group(proc):
    """Kill the viewer's whole process group (a wrapper may leave its child running)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


def render_png(source, out_path, size=(1280, 800), timeout=60.0, blueprint=None,
               settle=3.0):
    """Render ``source`` (an .rrd path or a ``rerun+http://`` URL) to the PNG
    ``out_path`` of ``size`` = (width, height) pixels with the headless native viewer.
    ``blueprint`` is an optional .rbl file; a live source is recorded for ``settle``
    seconds first.  Takes at most ``timeout`` seconds in all.
    Returns the PNG's Path.  Raises MissingDependency when the rerun binary or a Vulkan
    driver is missing, ValueError for bad arguments, RenderError when no PNG appears."""
    width, height = (int(v) for v in size)
    parse_size(f"{width}x{height}")
    if not timeout > 0:
        raise ValueError(f"timeout must be positive seconds, got {timeout!r}")
    if not 0 <= settle < timeout:
        raise ValueError(f"settle must be in [0, timeout) seconds, got {settle!r}")
    if not _is_url(source) and not Path(source).is_file():
        raise ValueError(f"no recording file at {source}")
    if blueprint is not None and not Path(blueprint).is_file():
        raise ValueError(f"no blueprint file at {blueprint}")
    exe = check_requirements()
    out = Path(out_path).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    if out.exists():
        out.unlink()

    points = f"{max(1, width // PIXELS_PER_POINT)}x{max(1, height // PIXELS_PER_POINT)}"
    deadline = time.monotonic() + timeout
    with tempfile.TemporaryDirectory(prefix="mkc-render-") as tmp:
        env = dict(os.environ)
        env.setdefault("XDG_RUNTIME_DIR", tmp)
        env["RUST_LOG"] = "error"   # info/warn log lines would be drawn as notifications
        if _is_url(source):
            source = _record_stream(exe, source, Path(tmp) / "live.rrd", settle, deadline, env)
        cmd = [str(exe), "--headless", "--renderer", "vulkan", "--window-size", points,
               "--screenshot-to", str(out), "--bind", "127.0.0.1", "--port", "auto",
               str(source)]
        if blueprint is not None:
            cmd.append(str(blueprint))
        code, tail = _run_until(cmd, env, deadline, Path(tmp) / "viewer.log",
                                done=lambda: False)
    if not out.is_file() or out.stat().st_size == 0:
        why = "timed out" if code is None else f"exit code {code}"
        raise RenderError(f"rerun wrote no PNG ({why}, timeout {timeout:g} s)"
                          + (": " + " | ".join(tail) if tail else ""))
    _fit(out, width, height)
    return out


def _run_until(cmd, env, deadline, log_path, done):
    """Run ``cmd`` in its own process group until it exits, ``done()`` is true or the
    deadline passes; then kill the group.  Returns (exit code or None if it was still
    running, the last lines of its output)."""
    with open(log_path, "w") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env,
                                stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            while time.monotonic() < deadline and proc.poll() is None and not done():
                time.sleep(0.05)
            code = proc.poll()
        finally:
            _stop_group(proc)
    return code, log_path.read_text(errors="replace").strip().splitlines()[-5:]


def _record_stream(exe, url, path, settle, deadline, env):
    """Save what the live source ``url`` sends during ``settle`` seconds (after its
    first bytes) to the .rrd ``path``; RenderError if nothing arrives by the deadline."""
    first = []

    def done():
        if not first and path.is_file() and path.stat().st_size > 0:
            first.append(time.monotonic())
        return bool(first) and time.monotonic() - first[0] >= settle

    code, tail = _run_until([str(exe), "--save", str(path), str(url)], env, deadline,
                            path.with_suffix(".log"), done)
    if not first:
        raise RenderError(f"no data from {url} before the timeout"
                          + (f" (rerun exited with code {code})" if code is not None else "")
                          + (": " + " | ".join(tail) if tail else ""))
    return path


def _fit(path, width, height):
    """Resize the PNG to exactly width x height when the viewer's scale differed."""
    from PIL import Image
    with Image.open(path) as im:
        if im.size == (width, height):
            return
        fitted = im.convert("RGBA").resize((width, height), Image.LANCZOS)
    fitted.save(path)


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
                        help="seconds of a live source to collect before rendering (default 3)")
    args = parser.parse_args(argv)
    try:
        size = parse_size(args.size)
        t0 = time.monotonic()
        out = render_png(args.source, args.out, size=size, timeout=args.timeout,
                         blueprint=args.blueprint, settle=args.settle)
    except MissingDependency as exc:
        print(f"render_recording: missing: {exc}", file=sys.stderr)
        return 2
    except (ValueError, RenderError) as exc:
        print(f"render_recording: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {out} ({size[0]}x{size[1]}) in {time.monotonic() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
