# Source this file (bash) to use rm_ros2 from the virtualenv:  source scripts/env.sh
# It activates .venv, sources the colcon workspace (which chains the venv as underlay)
# and keeps DDS on this machine unless you have chosen otherwise.
_rm_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
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
export RM_ROS2_ROOT="$_rm_root"
unset _rm_root
