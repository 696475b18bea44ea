#!/usr/bin/env bash
# alongside.sh [--nice N] BACKGROUND COMMAND...: the shell command line BACKGROUND in the
# background, its output held back, while COMMAND runs in the foreground; then BACKGROUND's
# output. Exit status non-zero if either failed. `make test` runs the catkin workspace stage
# and the benchmarks' smoke runs so, and (nested, --nice 0) the fault tests: they mostly
# wait (for nodes, for messages, for windows to pass), as pytest's testbed runs do, and the
# streams overlap on 2 cores. BACKGROUND runs at nice N (19). Ctrl-C (or any exit) stops it
# with its whole process group.
set -u
nice=19
if [ "$1" = --nice ]; then nice=$2; shift 2; fi
background_cmd=$1
shift
held=$(mktemp /tmp/server_select_alongside.XXXXXX)
# at the lowest CPU priority (by default): what waits in the foreground (testbed scenarios, fault
# tests, deadlines) gets the CPU first; the background takes what is left. A new session
# is a scheduling group of its own where the kernel groups by session (autogroup): there
# nice counts only inside the group, so the group's own nice is set too.
setsid bash -c 'if [ -w /proc/self/autogroup ]; then echo $2 > /proc/self/autogroup; fi;
  nice -n $2 bash -c "$1"; status=$?; echo "=== background: done after $SECONDS s"; exit $status' \
  alongside "$background_cmd" "$nice" > "$held" 2>&1 &
background=$!
trap 'kill -INT -- -$background 2>/dev/null; wait $background 2>/dev/null; rm -f "$held"' EXIT
trap 'exit 130' INT TERM
started=$SECONDS
"$@"
foreground=$?
echo "=== foreground: done after $((SECONDS - started)) s"
echo "=== in the background since the start: $background_cmd"
wait $background
status=$?
cat "$held"
echo "=== background: exit status $status, $((SECONDS - started)) s since both started"
[ $foreground -eq 0 ] && [ $status -eq 0 ]
