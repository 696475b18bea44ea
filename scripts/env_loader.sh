#!/usr/bin/env bash
# roslaunch env-loader for the hosts of a multi-host launch (launch/multihost_example.launch):
# sets up this package's devel space, its venv and ROS_IP on the remote host, then runs the
# node command roslaunch passes. Override the locations with SERVER_SELECT_DIR.
dir=${SERVER_SELECT_DIR:-$HOME/server_select}
source "$dir/build/devel/setup.bash" || { echo "env_loader: no build in $dir (run make build)" >&2; exit 1; }
export PATH="$dir/.venv/bin:$PATH"
# The address other hosts reach this one at; set ROS_IP in the environment to override.
export ROS_IP=${ROS_IP:-$(hostname -I | awk '{print $1}')}
exec "$@"
