"""Every probe a robot makes ends once (core/robot/robot.py): one its transport fails to
send ends failed, and the server is probed again next round; the others of the round go."""

import random

import pytest

from server_select.core.robot.robot import Robot
from server_select.core.robot.world import Transport
from server_select.core.settings import default
from test_least_latency import Clock
from test_robot_joining import Sort


class Failing(Transport):
    """Sends every probe but those to ``broken``, for which it raises (a bug of its own)."""

    def __init__(self, broken):
        self.broken, self.sent = broken, []

    def probe(self, server, seq, kinds, rates):
        if server == self.broken:
            raise TypeError('no probe to server %d' % server)
        self.sent.append((server, seq))


def test_a_probe_its_transport_cannot_send_ends_failed_and_the_others_go():
    clock, transport = Clock(), Failing(broken=2)
    get = lambda name: {'mode': 'select'}.get(name, default(name, 'fleet'))  # noqa: E731
    robot = Robot(1, [1, 2, 3], 'select', get, [(Sort(), 2.0)], transport=transport,
                  clock=clock, random=lambda purpose: random.Random(1))
    robot.start()
    clock.now = robot.next_probe_time()
    with pytest.raises(TypeError, match='no probe to server 2'):
        robot.probe_round()
    assert sorted(server for server, _ in transport.sent) == [1, 3]
    transport.broken, again = None, []
    for _ in range(20):           # its failed probe ended: server 2 is probed again
        for server, seq in transport.sent:
            robot.probe_answered(server, seq, 0.001)
        again += [server for server, _ in transport.sent if server == 2]
        del transport.sent[:]
        clock.now = robot.next_probe_time()
        robot.probe_round()
    assert again, 'server 2 never probed again'
