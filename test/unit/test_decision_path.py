"""How many of the package's modules one fleet decision crosses (bench.decision_path): the
count is held where it is, so that a decision does not spread over more of the package
unnoticed, and the path is the robot object's alone (no rospy, no simulator)."""

import pytest

from server_select.bench.decision_path import traced_modules

# modules crossed now: stream, flow (2), selection, health, rule (3), stats
MOST = 9


@pytest.mark.parametrize('kind', ['sort', 'image'])
def test_a_fleet_decision_crosses_the_robot_objects_modules_only(kind):
    modules = traced_modules(kind)
    print('%d modules: %s' % (len(modules), ', '.join(modules)))
    assert modules[0] == 'core/robot/stream.py'
    assert 'core/rule/least_latency.py' in modules
    assert all(m.startswith('core/') for m in modules), modules
    assert len(modules) <= MOST, modules
