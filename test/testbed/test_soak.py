"""The short chaos soak (every fault kind once, in waves of faults at once, about 2
minutes): the keyed fleet on the testbed, its invariants over the whole history from the
bags. Asserted: every task of every robot's life reported exactly once, every restarted
node doing its job again, the keyless intruder named. Printed, not asserted: failures
outside a fault's window and bound, and recovery times. Beside make test's other streams
on 2 cores these are the machine's: a frame (0.13 CPU-s) on servers of 0.2-0.55 of a core
was answered busy just past a bound 7 times in one CI run, 0 times in three runs alone.
Needs root and TUN (elsewhere: skipped with the reason)."""

import argparse
import json

import pytest

from server_select.soak import plan
from server_select.soak.fleet import TASK_RATE
from server_select.soak.report import TASK_TIMEOUT
from server_select.soak.run import soak
from server_select.testbed.netns import available

ok, why = available()
pytestmark = pytest.mark.skipif(not ok, reason=why)


def test_a_short_soak_loses_nothing_and_every_node_comes_back(tmp_path, monkeypatch):
    # `make soak`'s folder is relative (results/soak): the key files the nodes are given
    # must not be (roslaunch starts them in ROS_HOME), as a new user's first soak found
    monkeypatch.chdir(tmp_path)
    out = tmp_path / 'soak'
    verdict = soak(argparse.Namespace(short=True, seed=2, minutes=0, out='soak'),
                   say=lambda line: print('soak:', line))
    print((out / 'report.md').read_text())
    print(json.dumps(verdict))
    lost = verdict['lost with a killed robot']
    offered = len(plan.ROBOTS) * TASK_RATE * plan.needed(1, short=True)
    assert verdict['tasks'] > offered / 2 and verdict['reports'] + lost == verdict['tasks'], \
        verdict
    # one robot_kill: at most the tasks of one task timeout are out when it dies
    assert lost <= TASK_RATE * TASK_TIMEOUT, verdict
    assert (verdict['unreported'], verdict['duplicated']) == (0, 0), verdict
    assert verdict['restarted nodes not serving'] == 0, verdict
    assert verdict['intruders not named'] == 0, verdict
    assert (out / 'timeline.png').stat().st_size > 10000
