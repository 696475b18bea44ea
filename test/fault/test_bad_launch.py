"""A demo launched with an invalid robot parameter ends as a whole: no manager or server
left running without the robots, the FATAL line naming the parameter in its output."""

import subprocess
import time

from server_select.core.util.procs import stop_group, wait_until

from support.fleet import NODES, Fleet


def test_an_invalid_parameter_of_one_node_ends_the_whole_launch(ros, tmp_path):
    log = str(tmp_path / 'launch.log')
    with open(log, 'w') as stream:
        launch = subprocess.Popen(['roslaunch', 'server_select', 'demo.launch',
                                   'probe_rate:=abc', 'output:=screen'],
                                  stdout=stream, stderr=subprocess.STDOUT,
                                  start_new_session=True)
    start = time.monotonic()
    try:
        ended = wait_until(lambda: launch.poll() is not None, 30.0)
        took = time.monotonic() - start
    finally:
        stop_group(launch)
    text = open(log, errors='replace').read()
    fatal = [line for line in text.splitlines() if 'invalid parameter: ~probe_rate' in line]
    left = [n for n in NODES if Fleet.pid(n)]
    print('demo.launch probe_rate:=abc: ended %s after %.1f s, %d FATAL lines, nodes left %s'
          % (ended, took, len(fatal), left))
    assert ended, text[-3000:]
    assert fatal, text[-3000:]      # a robot (the first to read it ends the launch)
    assert wait_until(lambda: not any(Fleet.pid(n) for n in NODES), 10.0), left
