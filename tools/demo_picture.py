"""The README's picture: the demo's recording at the first step where the ball touches
a pin, rendered without a display by mkcollision_ros.render in the recording's own
layout.

    . tools/env.sh && bash tools/demo.sh && python tools/demo_picture.py [demo.rrd] [docs/demo.png]
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from mkcollision_ros.render import render_png  # noqa: E402
from mkcollision_ros.rerun_log import read_recording  # noqa: E402


def first_ball_pin_step(path):
    for row in read_recording(path).get("/world/contacts", []):
        labels = row.get("Points3D:labels") or []
        if any("ball" in t and "pin" in t for t in labels):
            return row["step"]
    raise SystemExit(f"{path}: no ball-pin contact recorded")


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else "demo.rrd"
    out = sys.argv[2] if len(sys.argv) > 2 else os.path.join("docs", "demo.png")
    step = first_ball_pin_step(src)
    render_png(src, out, size=(1280, 800), time_at=f"step={step}")
    print(f"wrote {out} (step {step} of {src})")


if __name__ == "__main__":
    main()
