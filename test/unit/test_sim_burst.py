"""A burst in the simulator: robots that stop, robots that send their own kinds
(``suite: host_args``), and how soon the others are back (sim/recovery.py)."""

import collections

import pytest

from server_select.sim import recovery
from server_select.sim.model import Model
from server_select.sim.run import simulate
from server_select.testbed.scenario import Scenario


def burst(stop=20.0):
    """Robot 1 sends sort tasks throughout; robot 2, from 10 s to ``stop``, frames only."""
    hosts = {'manager': {'role': 'manager'}, 'server1': {'role': 'server', 'id': 1},
             'robot1': {'role': 'robot', 'id': 1},
             'robot2': {'role': 'robot', 'id': 2, 'start': 10.0, 'stop': stop}}
    return Scenario({'name': 'burst', 'duration': 40.0, 'hosts': hosts, 'links': {},
                     'default': {'delay': 2},
                     'suite': {'measure_from': 5.0, 'robot_args': {'task_rate': 5},
                               'host_args': {'robot2': {'sort_tasks': False,
                                                        'image_source': 'frames',
                                                        'frame_rate': 2}}}})


def test_a_robot_sends_its_own_kinds_and_nothing_after_it_stops():
    sim = simulate(burst(), Model.load(), 1, ['fleet'])
    kinds = collections.defaultdict(set)
    last = collections.defaultdict(float)
    for record in sim.records:
        kinds[record.robot].add(record.outcome.kind)
        last[record.robot] = max(last[record.robot], record.outcome.stamp)
    assert kinds == {1: {'sort'}, 2: {'image'}}
    assert 19.0 < last[2] <= 20.0 and last[1] > 39.0
    stray = burst()
    stray.suite['host_args']['robot9'] = {'frame_rate': 4}
    with pytest.raises(ValueError, match='host_args names no robot of it: robot9'):
        simulate(stray, Model.load(), 1, ['fleet'])


def test_the_fault_is_its_robots_that_stop_or_a_server_hang_and_the_fleet_those_up_throughout():
    event, fleet = recovery.fault_of(burst())
    assert (event['kind'], event['start'], event['end'], fleet) == ('overload', 10.0, 20.0, [1])
    hung, fleet = recovery.fault_of(Scenario.load('config/sim/mixed_kinds.yaml'))
    assert (hung['kind'], hung['start'], hung['end']) == ('server_stop', 50.0, 55.0)
    calm = burst()
    calm.hosts['robot2'] = calm.hosts['robot2']._replace(stop=None)
    with pytest.raises(ValueError, match='no robot stops and no server hangs'):
        recovery.fault_of(calm)


def test_the_fleet_is_back_at_once_after_a_burst_it_was_not_slowed_by_and_never_without_server():
    # one robot's frames beside another's sort tasks on a whole core: robot 1 is back at once
    assert recovery.recovery(burst(), Model.load(), 1, 'fleet') == 0.0
    gone = burst()      # its only server stops with the burst: every later task fails
    gone.hosts['server1'] = gone.hosts['server1']._replace(stop=20.0)
    assert recovery.recovery(gone, Model.load(), 1, 'fleet') is None


def test_each_variant_is_paired_seed_by_seed_with_the_first_and_with_a_kept_run():
    found = {'fleet': [1.0, 2.0, None], 'fleet~steps': [0.5, 2.0, 3.0]}
    lines = recovery.table(found, against={'fleet': [1.0, 1.0, 1.0]}).splitlines()
    assert lines[2].startswith('| fleet | 2.0 |') and lines[2].endswith('| | |'), lines
    # the kept run: 0, +1, +29 s (not back counts at LIMIT): 0 sooner, 2 later
    assert lines[3].startswith('| fleet minus the kept run |') and \
        lines[3].endswith('| 0 / 2 |') and '+10.00 [' in lines[3], lines[3]
    # against the first: -0.5, 0, -27: 2 sooner, 0 later; its max was never "not back"
    assert lines[4].startswith('| fleet~steps | 2.0 | ') and '| 3.0 | 0 of 3 |' in lines[4] \
        and '-9.17 [' in lines[4] and lines[4].endswith('| 2 / 0 |'), lines[4]
    assert '| 30.0+ | 1 of 3 |' in lines[2]
