#!/usr/bin/env bash
# roslaunch env-loader for the hosts of a multi-host launch (launch/multihost_example.launch):
# sources the workspace this script belongs to, then runs the node command roslaunch passes.
# Found from where the script lives: an install or devel space (<prefix>/lib/server_select/),
# this repository built with make (scripts/ -> build/devel), or a catkin workspace
# (<ws>/src/server_select/scripts/ -> <ws>/devel). SERVER_SELECT_SETUP names a setup.bash
# to use instead.
here=$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")" && pwd)
setup=${SERVER_SELECT_SETUP:-}
if [ -z "$setup" ]; then
  for candidate in "$here/../../setup.bash" "$here/../build/devel/setup.bash" \
                   "$here/../../../devel/setup.bash"; do
    [ -f "$candidate" ] && { setup=$candidate; break; }
  done
fi
[ -n "$setup" ] && source "$setup" || { echo "env_loader: no setup.bash found from $here" >&2; exit 1; }
# the Makefile's venv (pip packages), when the package is used from this repository
[ -x "$here/../.venv/bin/python3" ] && export PATH="$here/../.venv/bin:$PATH"
# The address other hosts reach this one at: set ROS_IP in the environment to override;
# else the source address of this host's route to the master (roslaunch passes
# ROS_MASTER_URI), right on a host with several interfaces (wlan0, eth0, docker0);
# else the first address of the host.
if [ -z "${ROS_IP:-}" ]; then
  master=${ROS_MASTER_URI#*://}; master=${master%%:*}; master=${master%%/*}
  master_ip=$(getent ahostsv4 "$master" 2>/dev/null | awk '{print $1; exit}')
  [ -n "$master_ip" ] && ROS_IP=$(ip -o -4 route get "$master_ip" 2>/dev/null \
                                  | sed -n 's/.* src \([0-9.]*\).*/\1/p')
  export ROS_IP=${ROS_IP:-$(hostname -I | awk '{print $1}')}
fi
exec "$@"
