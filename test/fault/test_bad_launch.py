"""A demo launched with an invalid robot parameter ends as a whole: no manager or server
left running without the robots, the FATAL line naming the parameter in its output."""

import subprocess
import time

from server_select.core.trust.keys import make_key
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


def launched(argv, tmp_path, name):
    """``rosrun server_select launch ARGV`` to its end: (exit status, its output)."""
    log = str(tmp_path / ('%s.log' % name))
    with open(log, 'w') as stream:
        proc = subprocess.Popen(['rosrun', 'server_select', 'launch'] + argv,
                                stdout=stream, stderr=subprocess.STDOUT,
                                start_new_session=True)
    try:
        assert wait_until(lambda: proc.poll() is not None, 30.0), open(log).read()[-3000:]
    finally:
        stop_group(proc)
    return proc.returncode, open(log, errors='replace').read()


def test_the_launch_command_exits_non_zero_when_a_node_ends_it_for_a_parameter(ros, tmp_path):
    """(roslaunch itself exits 0 then, so a script or a systemd unit cannot tell.)"""
    code, text = launched(['demo.launch', 'probe_rate:=abc', 'output:=screen'], tmp_path,
                          'bad_value')
    said = [line for line in text.splitlines()
            if line.startswith('launch: ended for an invalid parameter: /robot')]
    print('launch demo.launch probe_rate:=abc: exit status %d, %s' % (code, said))
    assert code == 2 and said and '~probe_rate' in said[0], text[-3000:]
    assert wait_until(lambda: not any(Fleet.pid(n) for n in NODES), 10.0)


def test_the_launch_command_refuses_a_misspelled_argument_before_starting(ros, tmp_path):
    """(roslaunch ignores it: ``duraton:=10`` ran the demo with no duration, for ever.)"""
    code, text = launched(['demo.launch', 'duraton:=10'], tmp_path, 'misspelled')
    print('launch demo.launch duraton:=10: exit status %d, %s' % (code, text.strip()))
    assert code == 2
    assert 'launch argument duraton:= is declared by no launch file of this launch; did ' \
        'you mean duration:=?' in text, text
    assert not any(Fleet.pid(n) for n in NODES)


def test_a_fleet_key_cut_short_ends_the_launch_with_the_key_named(ros, tmp_path):
    """A fleet key of 40 hex characters (cut when copied): the first node to read it ends
    the launch with one FATAL line naming the file and its length. (Before: the nodes
    started, and every peer then logged "wrong signature".)"""
    key = str(tmp_path / 'fleet.key')
    make_key(key)
    with open(key) as stream:
        cut = stream.read().strip()[:40]
    with open(key, 'w') as stream:
        stream.write(cut + '\n')
    code, text = launched(['demo.launch', 'profile:=fleet', 'fleet_key:=%s' % key,
                           'output:=screen'], tmp_path, 'short_key')
    fatal = [line for line in text.splitlines() if 'has 20 bytes (40 hex characters), not 32'
             in line and key in line]
    print('launch demo.launch with a fleet key of 40 hex characters: exit status %d, %d '
          'lines naming it, e.g. %s' % (code, len(fatal), fatal[:1]))
    assert code == 2 and fatal, text[-3000:]
    assert not [line for line in text.splitlines() if 'wrong signature' in line]
    assert wait_until(lambda: not any(Fleet.pid(n) for n in NODES), 10.0)
