"""A keyed server's binding of robot ids to nodes (ros/robot_admission.py): a task counts
when its connection goes to the URI the robot's sealed probe named, a lease ends by the
clock at every check, and a flood of made-up senders keeps a bounded table."""

import types

import pytest

from server_select.ros import robot_admission
from server_select.ros.robot_admission import ROBOT_LEASE, RobotAdmission

from support.clock import Clock


ROBOT1_URI = 'http://robot1:40001/'


def task(robot_id, sender, connected_to=ROBOT1_URI):
    """A task as rospy hands it over: the callerid its publisher claims, and the URI this
    node connected to for it (what the master listed)."""
    return types.SimpleNamespace(robot_id=robot_id, _connection_header={
        'callerid': sender, robot_admission.PUBLISHER_URI: connected_to})


@pytest.fixture(autouse=True)
def keyed(monkeypatch):
    """A fleet key is set (the probes that bind are checked with it elsewhere)."""
    monkeypatch.setattr(robot_admission.seal, 'enabled', lambda: True)


def bind(gate, clock, robot, node, uri):
    """What a valid sealed probe of ``robot`` from ``node`` naming ``uri`` binds."""
    gate.leases.renew(robot, node, clock(), ROBOT_LEASE)
    gate._uris[robot] = robot_admission.binding(node, uri)


def sealed_probe(robot, node, uri):
    return types.SimpleNamespace(robot_id=robot, node_uri=uri, seal=types.SimpleNamespace(
        mac=b'sealed'), _connection_header={'callerid': node})


def test_a_robot_restarted_under_its_name_is_bound_at_its_new_uri_at_once(monkeypatch):
    monkeypatch.setattr(robot_admission.seal, 'request_refusal', lambda request, _: None)
    clock = Clock()
    gate = admission(clock)
    assert gate.probe(sealed_probe(1, '/robot1', ROBOT1_URI))
    assert gate.admits(task(1, '/robot1'))
    assert gate.probe(sealed_probe(1, '/robot1', 'http://robot1:40002/'))   # restarted
    assert gate.admits(task(1, '/robot1', connected_to='http://robot1:40002/'))
    assert not gate.admits(task(1, '/robot1'))                    # (the old copy's)
    assert not gate.probe(sealed_probe(1, '/robot1_other', 'http://x:1/'))  # another node


def test_a_restarted_robots_task_before_its_sealed_probe_counts_where_the_master_lists_it(
        monkeypatch):
    class Master(object):
        def __init__(self, _caller):
            pass

        def lookupNode(self, node):
            return {'/robot1': 'http://robot1:40002/'}[node]
    monkeypatch.setattr(robot_admission.rosgraph, 'Master', Master)
    clock = Clock()
    gate = admission(clock)
    bind(gate, clock, 1, '/robot1', ROBOT1_URI)
    assert gate.admits(task(1, '/robot1', connected_to='http://robot1:40002/'))
    assert not gate.admits(task(1, '/robot1', connected_to='http://attacker:40666/'))
    assert not gate.admits(task(1, '/robot2', connected_to='http://robot1:40002/'))


def admission(clock):
    return RobotAdmission('server 1', '/latency_S1', clock=clock)


def test_a_robots_tasks_count_until_its_lease_ends_and_not_after():
    clock = Clock()
    gate = admission(clock)
    bind(gate, clock, 1, '/robot1', ROBOT1_URI)
    assert gate.admits(task(1, '/robot1'))
    assert not gate.admits(task(1, '/robot1_impostor'))
    # a publisher elsewhere that claims robot 1's callerid in its header is not robot 1
    assert not gate.admits(task(1, '/robot1', connected_to='http://attacker:40666/'))
    clock.now += ROBOT_LEASE + 0.1      # no signed probe since: the binding is over
    assert not gate.admits(task(1, '/robot1'))


def test_made_up_senders_keep_a_bounded_table():
    clock = Clock()
    gate = admission(clock)
    for n in range(1000):
        assert not gate.admits(task(1, '/x%d' % n + 'y' * 100000))
    assert gate.refused.total == 1000 and len(gate.refused) <= gate.refused.most
