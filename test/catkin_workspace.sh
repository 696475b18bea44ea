#!/usr/bin/env bash
# The ROS way, tested: this package and the example task type of examples/ (a package of
# its own, with its own messages) copied into the src/ of a fresh catkin workspace and
# built there with Debian's packages only (no venv, no pip: PATH is the system's), then
#   catkin_make run_tests as the first command (it must build what the tests need): every
#   launch-level rostest, once, and catkin_test_results;
#   catkin_make (the README's order);
#   the timed demo launched from the workspace's devel space, recorded with plain
#   rosbag record -a, and analyze on that bag;
#   the example task type in a keyed fleet (the README's recipe with a key).
# Prints "catkin: N passed, N failed" last; exit status non-zero on any failure.
set -u
repo=$(cd "$(dirname "$0")/.." && pwd)
ws=$(mktemp -d /tmp/server_select_ws.XXXXXX)
trap '[ -n "${KEEP_WS:-}" ] || rm -rf "$ws"' EXIT
trap 'exit 130' INT TERM         # stopped: the EXIT trap still removes the workspace
mkdir -p "$ws/src/server_select"
tar -C "$repo" --exclude=./build --exclude=./.venv --exclude=./results --exclude=./.git \
  -cf - . | tar -C "$ws/src/server_select" -xf -
cp -r "$repo/examples/wordcount_task" "$ws/src/"   # a task type from outside, as a user's
# within SECONDS COMMAND: until COMMAND succeeds (checked every 0.2 s), at most SECONDS
within() { timeout "$1" bash -c "until $2 > /dev/null 2>&1; do sleep 0.2; done"; }
run() {  # a clean environment: Debian's python3 and ROS, nothing of the caller's
  env -i HOME="$HOME" PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 \
    ROS_HOME="$ws/ros_home" ROS_MASTER_URI="http://localhost:${port:-11311}" \
    bash -c "$(declare -f within); cd '$ws' && $1"
}
passed=0; failed=0
step() {
  local name=$1 began=$SECONDS; shift
  echo "=== catkin workspace: $name"
  if run "$*" > "$ws/$name.log" 2>&1; then
    passed=$((passed + 1)); echo "=== $name: ok after $((SECONDS - began)) s"
    grep -a '^Summary:' "$ws/$name.log" || true      # catkin_test_results: every test counted
  else
    failed=$((failed + 1)); echo "=== $name: FAILED; last lines:"; tail -150 "$ws/$name.log"
    # the workspace goes with this script: what its robots warned of and waited for, kept
    echo "=== $name: the robots' warnings, errors and waits (last 120):"
    grep -a -H -E '\[(WARN|ERROR)\]|wait for' "$ws"/ros_home/log/*/robot*-stdout.log 2>/dev/null \
      | sed "s|$ws/ros_home/log/||" | tail -120
  fi
}
step run_tests "catkin_make run_tests -j1 && catkin_test_results --verbose build/test_results"
step catkin_make "catkin_make"
port=$(( 20000 + RANDOM % 12000 ))   # below the kernel's ephemeral ports (32768-)
step demo "source devel/setup.bash && (roscore -p $port > roscore.out 2>&1 &) \
  && within 30 'rosnode list' \
  && (rosbag record -a -O plain.bag __name:=recorder > rosbag.out 2>&1 &) \
  && within 30 'rosnode list | grep -q /recorder' \
  && roslaunch server_select demo.launch duration:=10 output:=log | tee demo.out; \
  rosnode kill /recorder; within 30 '[ -f plain.bag ]'; pkill -INT -f 'roscore -p $port'; \
  grep -q '| R1 | S' demo.out && grep -q '| R2 | S' demo.out \
  && rosrun server_select analyze plain.bag | tee analyze.out && grep -q '^| plain | [1-9]' analyze.out"
# the example task type, as the README has it, in a keyed fleet (its results carry seals),
# until the robot's first summary says tasks were answered (10 s after it starts: on a
# loaded host its start alone took longer than the fixed 15 s this run once had); Ctrl-C
step keyed_task "source devel/setup.bash && (roscore -p $port > roscore2.out 2>&1 &) \
  && within 30 'rosnode list' && rosrun server_select make_key $ws/fleet.key \
  && { PYTHONUNBUFFERED=1 roslaunch wordcount_task wordcount.launch fleet_key:=$ws/fleet.key \
         > keyed.out 2>&1 &
       launched=\$!; within 120 \"grep -q 'wordcount: [0-9]* sent, [1-9][0-9]* ok' keyed.out\";
       kill -INT \$launched; wait \$launched; }; pkill -INT -f 'roscore -p $port'; cat keyed.out \
  && grep -q 'wordcount: [1-9][0-9]* sent, [1-9][0-9]* ok, 0 failed' keyed.out \
  && grep -q 'fleet key on' keyed.out && ! grep -q 'ignored' keyed.out"
# what failed, last (CI shows the end of the output): each failed test case, its first line,
# and what the nodes launched beside that test logged (its launch's log directory)
/usr/bin/python3 - "$ws/build/test_results" "$ws/ros_home/log" <<'PY'
import glob, os, re, sys, xml.etree.ElementTree as ET
failed, summary, ROSOUT = set(), [], re.compile(r'\[rosout\]\[(\w+)\] (\S+ \S+): (.*)')
for path in sorted(glob.glob(sys.argv[1] + '/*/*.xml')):
    for case in ET.parse(path).getroot().iter('testcase'):
        for bad in list(case.iter('failure')) + list(case.iter('error')):
            text = (bad.get('message') or bad.text or '').strip().splitlines() or ['']
            summary.append('catkin: FAILED %s %s: %s' % (
                path.rsplit('/', 1)[-1], case.get('name'),
                ' ... '.join(dict.fromkeys((text[0][:300], text[-1][:300])))))
            print(summary[-1])
            failed.add(re.sub(r'^rosunit-|\.xml$', '', os.path.basename(path)))
for name in sorted(failed):   # rospy's own log of each node: every rosout line, by time
    for run in set(os.path.dirname(p) for p in glob.glob(
            '%s/*/%s-*.log' % (sys.argv[2], glob.escape(name)))):
        lines = []
        for log in glob.glob(os.path.join(run, '*.log')):
            node = re.sub(r'-[0-9]+$', '', os.path.basename(log)[:-4])
            if not node.endswith(('-stdout', '-stderr')) and not node.startswith('ros'):
                with open(log, errors='replace') as f:
                    lines += [m.group(2, 1, 3) + (node,) for m in map(ROSOUT.match, f) if m]
        print('catkin: %s, the nodes launched with it logged (%d lines, the first 80):'
              % (name, len(lines)))
        print('\n'.join('%s %s %s: %s' % (when, level, node, text)
                        for when, level, text, node in sorted(lines)[:80]))
for line in summary:    # again, last: a long log above must not hide which case failed
    print(line)
PY
echo "catkin: $passed passed, $failed failed"
[ $failed -eq 0 ]
