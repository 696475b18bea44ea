#!/usr/bin/env bash
# Runs every test/*.test with rostest (each brings up its own roscore on a free port) and
# prints one closing line "N passed, N failed". Needs the devel space sourced (make test).
# rostest --text does not fail on a failed test, so rostest runs without it: its exit code
# counts, and the JUnit XML of a failed test is printed.
set -u
cd "$(dirname "$0")"
results=${ROS_HOME:-$HOME/.ros}/test_results/server_select
passed=0; failed=0; failures=()
tests=("$@"); [ ${#tests[@]} -gt 0 ] || tests=(*.test)
for t in "${tests[@]}"; do
  echo "=== rostest $t"
  rm -rf "$results"
  start=$(date +%s)
  if rostest server_select "$t"; then
    passed=$((passed + 1)); echo "=== $t: ok ($(( $(date +%s) - start )) s)"
  else
    failed=$((failed + 1)); failures+=("$t")
    echo "=== $t: FAILED ($(( $(date +%s) - start )) s); results:"
    for x in "$results"/*.xml; do [ -f "$x" ] && { echo "--- $x"; cat "$x"; echo; }; done
  fi
done
[ $failed -eq 0 ] || echo "failed rostests: ${failures[*]}"
echo "rostest: $passed passed, $failed failed"
[ $failed -eq 0 ]
