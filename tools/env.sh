# Source this file (bash) to use the set-up environment: the venv is the ROS prefix,
# install/ holds the built packages.   . tools/env.sh
_MK_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export VIRTUAL_ENV="$_MK_ROOT/.venv"
export PATH="$VIRTUAL_ENV/bin:$PATH"
export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
export CMAKE_PREFIX_PATH="$VIRTUAL_ENV${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
# local_setup.bash reads unset variables; relax nounset while sourcing it.
case $- in *u*) _MK_U=1; set +u;; *) _MK_U=;; esac
. "$_MK_ROOT/install/local_setup.bash"
[ -n "$_MK_U" ] && set -u
unset _MK_U
# the package's executables (what `ros2 run mkcollision_ros <name>` starts) as commands:
# collision_node, demo, demo_publisher, render_recording
export PATH="$_MK_ROOT/install/mkcollision_ros/lib/mkcollision_ros:$PATH"
# Keep DDS discovery on this machine unless the user asks for more.
export ROS_AUTOMATIC_DISCOVERY_RANGE="${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}"
