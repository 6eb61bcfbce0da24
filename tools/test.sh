#!/usr/bin/env bash
# Run the whole test suite (sets up whatever is missing first, the kernels' compile
# included, so the workers start with a filled cache).  Two pytest-xdist workers, one per
# core, each taking whole test files (module fixtures such as a running node start once).
# Extra arguments go to pytest, e.g.  bash tools/test.sh -k narrowphase  (or -n 0: one
# process)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/tools/setup.sh"
cd "$ROOT"
. tools/env.sh
exec python -m pytest tests -q -p no:cacheprovider --timeout=900 -n 2 --dist loadfile "$@"
