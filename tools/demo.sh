#!/usr/bin/env bash
# Set up everything (first run: a few minutes), then run the demo: the real collision
# node playing the bowling scene (config/demo_bowling.yaml, scripted motion in
# mkcollision_ros/demo_scenes.py) for 10 s, recording every step to demo.rrd in the
# repository root, then a summary and how to open the recording.  Extra arguments go to
# the demo, e.g.  bash tools/demo.sh --scene dominoes --seconds 30
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/tools/setup.sh"
cd "$ROOT"
. tools/env.sh
"$ROOT/install/mkcollision_ros/lib/mkcollision_ros/demo" --record "$ROOT/demo.rrd" "$@"
echo "(rerun is installed in the venv: in a new shell, first  cd $ROOT && . tools/env.sh)"
