"""A node takes over servers 1 and 2's probe services while the fleet runs (ROS 1 lets any
node register any service, under another node's name: test/fault/probe_impostor.py),
answering server 1's probes 50 ms late and server 2's at once, unsigned; robot 1 starts
again meanwhile, so that it looks the services up at the master after the takeover.

With a fleet key (``fleet_key:=`` on every node): robot 1 probes each server where its
sealed announcement says and counts only answers sealed for its request, so none of the
impostor's answers becomes a sample, and robot 1 says so. Without one: robot 1's samples
of servers 1 and 2 are the impostor's, and its manager ranks on them.
"""

import json
import os
import signal
import subprocess
import sys
import threading
import time

import rosgraph
import rospy

from server_select.core.config import names
from server_select.core.util.procs import wait_until
from server_select.msg import LatencySample

from support.fleet import Fleet
from test_faults import STABLE, TASK_TIMEOUT, answered, show, warm_up

HERE = os.path.dirname(os.path.abspath(__file__))
TASKS = 25          # robot 1's answered tasks after its restart that are counted
STEADY = dict(STABLE, policy='hysteresis')


class Samples(object):
    """Robot 1's probe samples of servers 1 and 2: (server, seq, stamp ns, ok, rtt, time)."""

    def __init__(self):
        self.lock, self.got = threading.Lock(), []
        self.subs = [rospy.Subscriber(names.sample_topic(1, s), LatencySample, self.add,
                                      queue_size=1000) for s in (1, 2)]

    def add(self, msg):
        with self.lock:
            self.got.append((msg.server_id, msg.seq, msg.header.stamp.to_nsec(), msg.ok,
                             msg.rtt, time.monotonic()))

    def since(self, t0):
        with self.lock:
            return [s for s in self.got if s[5] >= t0]

    def close(self):
        for sub in self.subs:
            sub.unregister()


def impostor_run(ros, **args):
    rec, samples = ros['rec'], Samples()
    rec.clear()
    master = rosgraph.Master(rospy.get_name())
    try:
        with Fleet(ros['log'], **dict(STEADY, **args)) as fleet:
            warm_up(rec)
            real = master.lookupService(names.probe_service(1))
            impostor = subprocess.Popen(
                [sys.executable, os.path.join(HERE, 'probe_impostor.py'), '1:0.05,2:0', '120'],
                stdout=subprocess.PIPE, universal_newlines=True, start_new_session=True)
            fleet.extra.append(impostor)      # stopped with the fleet whatever happens
            assert wait_until(lambda: master.lookupService(names.probe_service(1)) != real,
                              20.0), 'the impostor did not take over the probe service'
            pid = fleet.signal('/robot1', signal.SIGKILL)
            assert wait_until(lambda: fleet.pid('/robot1') != pid, 10.0)
            t0 = time.monotonic()
            fleet.restart_robot(1)
            assert wait_until(lambda: answered(rec, 1, t0, TASKS), 60.0), rec.failures(1)
            impostor.send_signal(signal.SIGINT)
            out, _ = impostor.communicate(timeout=30)
            back = master.lookupService(names.probe_service(1))
            outcome = rec.outcomes((1,), TASK_TIMEOUT)[1]
    finally:
        samples.close()
    given = json.loads(out.strip().splitlines()[-1])['answered']
    theirs = set((s, seq, stamp) for s, robot, seq, stamp in given if robot == 1)
    ok = [s for s in samples.since(t0) if s[3]]
    counted = [s for s in ok if (s[0], s[1], s[2]) in theirs]
    tasks = [r.msg for r in rec.of(rec.reports, 1, t0) if r.msg.ok][:TASKS]
    counts = {
        "impostor's answers to robot 1": len(theirs),
        'robot 1 good samples of servers 1, 2': len(ok),
        'of them the impostor\'s': len(counted),
        'robot 1 tasks': len(tasks),
        'answered by server 3': sum(1 for m in tasks if m.answered_by == 3),
        'failed': outcome['failed'], 'never answered': outcome['never answered'],
        "robot 1's warnings": len(rec.log_lines('/robot1', 'ignored a probe answer')) +
        len(rec.log_lines('/robot1', 'sealed announcement says')),
        'service given back': back == real}
    show('a node took over the probe services of servers 1 (50 ms late) and 2 (at once), '
         '%s:' % ('fleet key' if args else 'no key'), [counts])
    assert counts['service given back'], (back, real)
    return counts


def test_with_a_fleet_key_no_impostor_answer_counts(ros, fleet_key):
    counts = impostor_run(ros, fleet_key=fleet_key)
    assert counts["of them the impostor's"] == 0, counts
    assert counts['robot 1 good samples of servers 1, 2'] >= 10, counts
    assert (counts['failed'], counts['never answered']) == (0, 0), counts
    assert counts["robot 1's warnings"] >= 1, counts


def test_without_a_key_robot_1_counts_the_impostors_answers(ros):
    counts = impostor_run(ros)
    # as documented (README, "Signed fleet messages"): the master is all ROS 1 has
    assert counts["of them the impostor's"] >= \
        counts['robot 1 good samples of servers 1, 2'] / 2, counts
