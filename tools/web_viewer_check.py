"""Check rerun's web viewer in a real browser: headless Chromium loads the viewer page,
which streams a recording (or a live source such as the node's ``serve`` sink) over
gRPC, draws it with WebGL2 (Chromium's SwiftShader, no GPU), and this script saves a
screenshot and checks it is not blank.

    . tools/env.sh
    python tools/web_viewer_check.py --out docs/web-viewer.png
        serve a small built-in scene (three bodies: red left, blue right, green up) and
        check the picture shows each colour where its body is;
    python tools/web_viewer_check.py --recording run.rrd --out shot.png
        serve a recording file;
    python tools/web_viewer_check.py --connect rerun+http://127.0.0.1:9876/proxy --out shot.png
        show a running gRPC source, e.g. the node started with ``-p rerun:=serve``, in a
        web viewer this script serves;
    python tools/web_viewer_check.py --out shot.png \
        --page 'http://127.0.0.1:9090/?url=rerun+http://127.0.0.1:9876/proxy'
        open a web viewer page served elsewhere, e.g. the node's own (``-p rerun:=serve``
        serves gRPC on 9876 and the web viewer on 9090).

With ``--recording``, ``--connect`` or ``--page`` the check is "not blank" (many colours, none
covering nearly everything) plus, for each ``--expect-color R,G,B``, at least 300
pixels of a shade of that colour (not a grey: the viewer's own UI is grey, white and
one blue).

Everything listens on 127.0.0.1 only.  The rerun server runs in its own process group
and Chromium with a fresh profile in a temporary folder; both are killed at the end.
Chromium is driven over the DevTools protocol (a minimal websocket client below, text
frames only): a plain ``chromium --screenshot`` fires before the viewer has loaded.
The script takes screenshots every few seconds until the picture is not blank (and, for
the built-in scene, shows the bodies' colours in place), for at most ``--timeout`` s.

The web viewer decodes and draws on the CPU here; on a small machine it falls behind a
busy live stream (the node's demo: tens of seconds, shown as "latency" in its top bar),
so a screenshot of a live source shows an older step than the native viewer would.
docs/web-viewer.png is this script's screenshot of the node's own web viewer page
(``-p rerun:=serve``) with the demo publisher feeding the node.

Needs Debian's ``chromium`` (``apt-get install chromium``, about 124 MB; ``--chromium``
names another binary) and the venv's rerun-sdk.  Exit codes: 0 the picture is good,
1 it stayed blank (or wrong), 2 something to install is missing.
"""
import argparse
import base64
import io
import json
import os
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.parse
import urllib.request
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from mkcollision_ros.render import (MissingDependency, free_port, parse_size,  # noqa: E402
                                    rerun_binary)
from mkcollision_ros.rerun_log import stop_group  # noqa: E402

SCENE = {  # body: (rgb, centre at the last step)
    "red": ((255, 0, 0), (-2.7, 0.0, 0.0)),
    "blue": ((0, 0, 255), (3.0, 0.0, 0.0)),
    "green": ((0, 200, 0), (0.0, 0.0, 2.5)),
}
# Flags for a headless Chromium on a closed network: without the background-networking
# ones it keeps trying to reach Google's servers; SwiftShader gives WebGL2 without a GPU.
CHROMIUM_FLAGS = [
    "--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist", "--disable-quic", "--no-first-run", "--no-default-browser-check",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-extensions", "--disable-default-apps", "--mute-audio", "--hide-scrollbars",
    "--remote-debugging-address=127.0.0.1", "--remote-debugging-port=0",
]


# ---------------------------------------------------------------- websocket + DevTools

class WebSocket:
    """A client websocket (RFC 6455) enough for the DevTools protocol: text frames out
    (masked), text frames in (unmasked, possibly fragmented), pings answered."""

    def __init__(self, url, timeout=30.0):
        parts = urllib.parse.urlsplit(url)
        self.sock = socket.create_connection((parts.hostname, parts.port), timeout=timeout)
        key = base64.b64encode(os.urandom(16)).decode()
        path = parts.path + (f"?{parts.query}" if parts.query else "")
        self.sock.sendall((f"GET {path} HTTP/1.1\r\nHost: {parts.hostname}:{parts.port}\r\n"
                           "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                           f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n")
                          .encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise ConnectionError("websocket handshake: connection closed")
            head += chunk
        status, _, rest = head.partition(b"\r\n\r\n")
        if b" 101 " not in status.split(b"\r\n")[0]:
            raise ConnectionError(f"websocket handshake refused: {status[:200]!r}")
        self.buf = rest

    def _read(self, n):
        while len(self.buf) < n:
            chunk = self.sock.recv(1 << 20)
            if not chunk:
                raise ConnectionError("websocket closed")
            self.buf += chunk
        out, self.buf = self.buf[:n], self.buf[n:]
        return out

    def _send_frame(self, opcode, payload):
        head = bytes([0x80 | opcode])
        n = len(payload)
        if n < 126:
            head += bytes([0x80 | n])
        elif n < 1 << 16:
            head += bytes([0x80 | 126]) + struct.pack(">H", n)
        else:
            head += bytes([0x80 | 127]) + struct.pack(">Q", n)
        mask = os.urandom(4)
        body = (np.frombuffer(payload, np.uint8)
                ^ np.resize(np.frombuffer(mask, np.uint8), n)).tobytes()
        self.sock.sendall(head + mask + body)

    def send(self, text):
        self._send_frame(0x1, text.encode())

    def recv(self):
        parts = []
        while True:
            b0, b1 = self._read(2)
            opcode, n = b0 & 0x0F, b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._read(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._read(8))[0]
            mask = self._read(4) if b1 & 0x80 else None
            payload = self._read(n)
            if mask:
                payload = (np.frombuffer(payload, np.uint8)
                           ^ np.resize(np.frombuffer(mask, np.uint8), n)).tobytes()
            if opcode == 0x9:                       # ping
                self._send_frame(0xA, payload)
                continue
            if opcode == 0x8:
                raise ConnectionError("websocket closed by the browser")
            if opcode in (0x1, 0x0):
                parts.append(payload)
                if b0 & 0x80:
                    return b"".join(parts).decode()

    def close(self):
        try:
            self._send_frame(0x8, b"")
        except OSError:
            pass
        self.sock.close()


class DevTools:
    """Commands to one page target; events are read and dropped."""

    def __init__(self, ws_url, timeout):
        self.ws = WebSocket(ws_url, timeout)
        self.next_id = 0

    def call(self, method, **params):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == self.next_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})


# ---------------------------------------------------------------- processes

def wait_http(url, deadline):
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(url, timeout=2) as r:
                return r.read()
        except OSError:
            time.sleep(0.2)
    raise TimeoutError(f"nothing answered at {url}")


def write_scene(path, app_id="mkcollision_web_viewer_check", steps=20):
    """The built-in scene: a fixed camera from -y, panels hidden, time on the newest
    step; the red box moves into its place on the left over the steps."""
    import rerun as rr
    import rerun.blueprint as rrb
    rec = rr.RecordingStream(app_id)
    rec.set_sinks(rr.FileSink(str(path)))
    rec.send_blueprint(rrb.Blueprint(
        rrb.Spatial3DView(origin="/world", name="scene", line_grid=False,
                          background=[255, 255, 255],
                          eye_controls=rrb.EyeControls3D(position=[0, -12, 0], look_target=[0, 0, 0],
                                                         eye_up=[0, 0, 1])),
        rrb.TopPanel(state="hidden"), rrb.BlueprintPanel(state="hidden"),
        rrb.SelectionPanel(state="hidden"), rrb.TimePanel(state="hidden", play_state="following")))
    for i in range(steps):
        rec.set_time("step", sequence=i)
        for name, (rgb, (x, y, z)) in SCENE.items():
            if name == "red":
                x = 3.0 + i / (steps - 1) * (x - 3.0)
                arch = rr.Boxes3D(centers=[[x, y, z]], half_sizes=[[0.8] * 3], colors=[rgb],
                                  fill_mode="solid")
            else:
                arch = rr.Ellipsoids3D(centers=[[x, y, z]], half_sizes=[[0.8] * 3], colors=[rgb],
                                       fill_mode="solid")
            rec.log(f"world/{name}", arch)
    rec.flush()
    return path


# ---------------------------------------------------------------- picture checks

def picture(png_bytes):
    from PIL import Image
    return np.asarray(Image.open(io.BytesIO(png_bytes)).convert("RGB")).astype(np.int32)


def not_blank(rgb):
    """Many distinct colours and no colour covering nearly the whole picture; returns
    (ok, description)."""
    flat = (rgb // 8).reshape(-1, 3)
    colours, counts = np.unique(flat, axis=0, return_counts=True)
    share = counts.max() / flat.shape[0]
    return len(colours) >= 20 and share < 0.99, f"{len(colours)} colours, largest {share:.0%}"


def shade_of(rgb, colour, min_pixels=300):
    """Pixels that are a shaded version of ``colour`` (direction in RGB within 10
    degrees, at least a third as bright): at least ``min_pixels`` of them.  Returns
    (ok, description)."""
    c = np.asarray(colour, np.float64)
    p = rgb.reshape(-1, 3).astype(np.float64)
    norm = np.linalg.norm(p, axis=1)
    cos = (p @ c) / np.maximum(norm * np.linalg.norm(c), 1e-9)
    n = int(((cos > np.cos(np.radians(10))) & (norm > np.linalg.norm(c) / 3)).sum())
    return n >= min_pixels, f"{n} pixels of {tuple(int(v) for v in colour)}"


def scene_in_place(rgb):
    """The built-in scene's bodies: each colour present and red left of green left of
    blue, green above both; returns (ok, description)."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    masks = {"red": (r > 90) & (r > 2 * g + 30) & (r > 2 * b + 30),
             "green": (g > 90) & (g > 2 * r + 30) & (g > 2 * b + 30),
             "blue": (b > 90) & (b > 2 * r + 30) & (b > 2 * g + 30)}
    cen = {}
    for name, m in masks.items():
        if m.sum() < 300:
            return False, f"{name}: {int(m.sum())} pixels"
        ys, xs = np.nonzero(m)
        cen[name] = (round(xs.mean()), round(ys.mean()))
    (rx, ry), (gx, gy), (bx, by) = cen["red"], cen["green"], cen["blue"]
    ok = rx < gx < bx and gy < ry and gy < by
    return ok, f"centroids {cen}"


# ---------------------------------------------------------------- main

def run(args):
    chromium = shutil.which(args.chromium) if args.chromium else None
    if not chromium:
        raise MissingDependency(f"no {args.chromium} browser: apt-get install chromium")
    exe = rerun_binary()
    deadline = time.monotonic() + args.timeout
    tmp = Path(tempfile.mkdtemp(prefix="mkc-webcheck-"))
    procs = []
    try:
        env = dict(os.environ, RUST_LOG="warn", XDG_RUNTIME_DIR=str(tmp))
        web_port = free_port()
        if args.page:
            serve = None
        elif args.connect:
            source, serve = args.connect, [args.connect]
        else:
            rrd = Path(args.recording) if args.recording else write_scene(tmp / "scene.rrd")
            grpc_port = free_port()
            source = f"rerun+http://127.0.0.1:{grpc_port}/proxy"
            serve = ["--port", str(grpc_port), str(rrd)]
        if serve is None:
            page = args.page
            wait_http(page, deadline)
        else:
            cmd = [str(exe), "--serve-web", "--bind", "127.0.0.1", "--web-viewer-port",
                   str(web_port), "--renderer", "webgl", *serve]
            procs.append(subprocess.Popen(cmd, env=env, stdin=subprocess.DEVNULL,
                                          start_new_session=True, stderr=subprocess.STDOUT,
                                          stdout=open(tmp / "rerun.log", "w")))
            wait_http(f"http://127.0.0.1:{web_port}/", deadline)
            page = (f"http://127.0.0.1:{web_port}/?url={urllib.parse.quote(source, safe='')}"
                    "&renderer=webgl")
        w, h = args.size
        profile = tmp / "profile"
        procs.append(subprocess.Popen(
            [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", f"--window-size={w},{h}",
             "about:blank"], stdin=subprocess.DEVNULL, start_new_session=True,
            stdout=open(tmp / "chromium.log", "w"), stderr=subprocess.STDOUT))
        port_file = profile / "DevToolsActivePort"
        while not port_file.is_file() or len(port_file.read_text().split()) < 2:
            if time.monotonic() > deadline or procs[-1].poll() is not None:
                raise RuntimeError("chromium did not open its DevTools port: "
                                   + (tmp / "chromium.log").read_text()[-500:])
            time.sleep(0.1)
        devtools_port = int(port_file.read_text().split()[0])
        targets = json.loads(wait_http(f"http://127.0.0.1:{devtools_port}/json/list", deadline))
        pages = [t for t in targets if t.get("type") == "page"]
        if not pages:
            raise RuntimeError(f"chromium lists no page to drive: {targets}")
        target = pages[0]
        # a busy browser answers slowly: wait for an answer as long as the whole check
        cdp = DevTools(target["webSocketDebuggerUrl"], timeout=args.timeout)
        cdp.call("Emulation.setDeviceMetricsOverride", width=w, height=h, deviceScaleFactor=1,
                 mobile=False)
        t0 = time.monotonic()
        cdp.call("Page.navigate", url=page)
        print(f"[web-check] {page} in {chromium}", flush=True)
        if args.connect or args.recording or args.page:
            def check(rgb):
                results = [not_blank(rgb)] + [shade_of(rgb, c) for c in args.expect_color]
                return all(ok for ok, _ in results), "; ".join(why for _, why in results)
        else:
            check = _both
        shot, ok, why = None, False, ""
        while time.monotonic() < deadline:
            time.sleep(args.interval)
            shot = base64.b64decode(cdp.call("Page.captureScreenshot", format="png")["data"])
            ok, why = check(picture(shot))
            print(f"[web-check] {time.monotonic() - t0:5.1f} s: {why}", flush=True)
            if ok and time.monotonic() - t0 >= args.min_wait:
                break
        webgl = cdp.call("Runtime.evaluate", returnByValue=True, expression=(
            "(() => { const g = document.createElement('canvas').getContext('webgl2');"
            " if (!g) return 'no webgl2'; const d = g.getExtension('WEBGL_debug_renderer_info');"
            " return d ? g.getParameter(d.UNMASKED_RENDERER_WEBGL) : 'webgl2'; })()"))
        print(f"[web-check] WebGL2 renderer: {webgl.get('result', {}).get('value')}")
        cdp.ws.close()
        if shot is not None:
            out = Path(args.out)
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_bytes(shot)
            print(f"[web-check] wrote {out} ({w}x{h}) after {time.monotonic() - t0:.1f} s")
        return ok, why
    finally:
        for p in reversed(procs):
            stop_group(p, signals=(signal.SIGKILL,))
        shutil.rmtree(tmp, ignore_errors=True)


def _both(rgb):
    ok1, why1 = not_blank(rgb)
    ok2, why2 = scene_in_place(rgb)
    return ok1 and ok2, f"{why1}; {why2}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    src = parser.add_mutually_exclusive_group()
    src.add_argument("--recording", help="an .rrd file to serve (default: a built-in scene)")
    src.add_argument("--connect", help="a running source, rerun+http://host:port/proxy")
    src.add_argument("--page", help="a web viewer page already served, e.g. the node's: "
                                    "http://127.0.0.1:9090/?url=rerun+http://127.0.0.1:9876/proxy")
    parser.add_argument("--out", default="web-viewer.png", help="screenshot PNG to write")
    parser.add_argument("--size", default="1280x800", help="browser window, pixels")
    parser.add_argument("--timeout", type=float, default=90.0, help="seconds in all (default 90)")
    parser.add_argument("--min-wait", type=float, default=0.0,
                        help="seconds to keep the page open before a good picture counts")
    parser.add_argument("--interval", type=float, default=3.0, help="seconds between screenshots")
    parser.add_argument("--expect-color", action="append", default=[], metavar="R,G,B",
                        help="with --recording/--connect: a body colour that must appear "
                             "(shaded) in at least 300 pixels; may be repeated")
    parser.add_argument("--chromium", default="chromium", help="browser binary (default chromium)")
    args = parser.parse_args(argv)
    try:
        args.size = parse_size(args.size)
    except ValueError as exc:
        parser.error(str(exc))
    try:
        args.expect_color = [tuple(int(v) for v in c.split(",")) for c in args.expect_color]
        if any(len(c) != 3 or not all(0 <= v <= 255 for v in c) or max(c) - min(c) < 60
               for c in args.expect_color):
            raise ValueError
    except ValueError:
        parser.error("--expect-color must look like 255,128,0 (0..255), a colour, not a "
                     "grey (greys are everywhere in the viewer's own UI)")
    if args.recording and not Path(args.recording).is_file():
        parser.error(f"no recording file at {args.recording}")
    try:
        ok, why = run(args)
    except MissingDependency as exc:
        print(f"web_viewer_check: missing: {exc}", file=sys.stderr)
        return 2
    except (OSError, RuntimeError) as exc:     # timeouts, refused, closed
        print(f"web_viewer_check: no picture: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
    verdict = "ok" if ok else "the picture stayed blank or wrong"
    print(f"[web-check] {verdict}: {why}", file=sys.stdout if ok else sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
