#!/usr/bin/env bash
# Run the whole test suite (sets up whatever is missing first).  Extra arguments go to
# pytest, e.g.  bash tools/test.sh -k narrowphase
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/tools/setup.sh"
cd "$ROOT"
. tools/env.sh
exec python -m pytest tests -q -p no:cacheprovider --timeout=900 "$@"
