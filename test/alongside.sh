#!/usr/bin/env bash
# alongside.sh SCRIPT COMMAND...: SCRIPT (a bash script) in the background, its output held
# back, while COMMAND runs in the foreground; then SCRIPT's output. Exit status non-zero if
# either failed. `make test` runs the catkin workspace stage so: its build and rostests
# mostly wait (for nodes, for messages), as pytest's testbed and benchmark runs do, and the
# two overlap on 2 cores. Ctrl-C (or any exit) stops SCRIPT with its whole process group.
set -u
script=$1
shift
held=$(mktemp /tmp/server_select_alongside.XXXXXX)
setsid bash "$script" > "$held" 2>&1 &
background=$!
trap 'kill -INT -- -$background 2>/dev/null; wait $background 2>/dev/null; rm -f "$held"' EXIT
trap 'exit 130' INT TERM
started=$SECONDS
"$@"
foreground=$?
echo "=== $script (started with the above): waiting for it"
wait $background
status=$?
cat "$held"
echo "=== $script: exit status $status, $((SECONDS - started)) s since both started"
[ $foreground -eq 0 ] && [ $status -eq 0 ]
