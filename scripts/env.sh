# Source this file (bash) to use rm_ros2 from the virtualenv:  source scripts/env.sh
# It activates .venv, sources the colcon workspace (which chains the venv as underlay)
# and keeps DDS on this machine unless you have chosen otherwise.
_rm_root=$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)
if [ ! -f "$_rm_root/install/setup.bash" ]; then
  echo "rm_ros2: not set up yet; run scripts/setup.sh (or make test / make run) first" >&2
  unset _rm_root
  return 1 2>/dev/null || exit 1
fi
# shellcheck disable=SC1091
source "$_rm_root/.venv/bin/activate"
# shellcheck disable=SC1091
source "$_rm_root/install/setup.bash"
# Network rule: DDS discovery stays on localhost unless ROS_AUTOMATIC_DISCOVERY_RANGE is set.
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42}
# Fast DDS: participants re-announce every 0.25 s, so discovery settles fast (the file says why).
export FASTRTPS_DEFAULT_PROFILES_FILE=${FASTRTPS_DEFAULT_PROFILES_FILE:-$_rm_root/scripts/fastdds_profile.xml}
export RM_ROS2_ROOT="$_rm_root"
# The project's own executables (rmcli, bringup, rm_robot, can_bridge) live where
# `ros2 run` looks (install/<pkg>/lib/<pkg>); put them on PATH for the shell too.
for _rm_pkg in rm_bringup rm_base; do
  case ":$PATH:" in *":$_rm_root/install/$_rm_pkg/lib/$_rm_pkg:"*) ;;
    *) PATH="$_rm_root/install/$_rm_pkg/lib/$_rm_pkg:$PATH" ;; esac
done
export PATH
unset _rm_pkg
unset _rm_root
