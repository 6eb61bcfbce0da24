#!/usr/bin/env bash
# Set up everything (first run: a few minutes), then run the demo: the real collision
# node with config/collision_node.yaml and a publisher of moving bodies for 10 s, then a
# summary.  Extra arguments go to the demo, e.g.  bash tools/demo.sh --seconds 60
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/tools/setup.sh"
cd "$ROOT"
. tools/env.sh
exec "$ROOT/install/mkcollision_ros/lib/mkcollision_ros/demo" "$@"
