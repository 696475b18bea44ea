"""How many of the package's modules one fleet decision crosses (bench.decision_path): the
count is held where it is, so that a decision does not spread over more of the package
unnoticed, and the path is the robot object's alone (no rospy, no simulator)."""

from server_select.bench.decision_path import traced_modules

MOST = 14       # modules crossed now: stream, flow (5), selection, health, rule (2), load (3)


def test_a_fleet_decision_crosses_the_robot_objects_modules_only():
    modules = traced_modules()
    print('%d modules: %s' % (len(modules), ', '.join(modules)))
    assert modules[0] == 'core/robot/stream.py'
    assert 'core/rule/least_latency.py' in modules
    assert all(m.startswith('core/') for m in modules), modules
    assert len(modules) <= MOST, modules
