"""Servers that join a robot's fleet (core/robot/robot.py): probed at once, task candidates
only once the transport reaches them (a task published before a server's connection is up
reaches nobody)."""

import random

from server_select.core.robot.robot import Robot
from server_select.core.robot.world import Transport
from server_select.core.settings import default
from test_least_latency import Clock


class Reaching(Transport):
    def __init__(self):
        self.reaches, self.connected = set(), []

    def connect(self, server):
        self.connected.append(server)

    def wired(self, server):
        return server in self.reaches


class Sort(object):
    kind, newest_wins, run_local, input = 'sort', False, None, 'a test'

    def make(self, task_id, stamp):
        return task_id, None

    def check(self, result, context):
        return None

    def ready(self):
        return True


def robot():
    transport = Reaching()
    get = lambda name: {'mode': 'select'}.get(name, default(name, 'fleet'))  # noqa: E731
    made = Robot(1, [], 'select', get, [(Sort(), 2.0)], transport=transport, clock=Clock(),
                 random=lambda purpose: random.Random(1))
    made.start()
    return made, transport


def test_a_joined_server_is_probed_at_once_and_a_candidate_once_reached():
    made, transport = robot()
    made.add_server(3)
    made.add_server(4)
    assert transport.connected == [3, 4] and made.servers == [3, 4]
    assert made.selection.candidates('sort') == []
    transport.reaches.add(4)
    assert made.admit_joined() == [4]
    assert made.selection.candidates('sort') == [4]
    transport.reaches.add(3)
    assert made.admit_joined() == [3] and made.admit_joined() == []     # each once
    assert sorted(made.selection.candidates('sort')) == [3, 4]


def test_a_server_that_leaves_before_it_is_reached_is_never_a_candidate():
    made, transport = robot()
    made.add_server(5)
    made.remove_server(5)
    transport.reaches.add(5)
    assert made.admit_joined() == [] and made.selection.candidates('sort') == []
    assert made.servers == []


def test_a_server_already_reached_is_a_candidate_at_once():
    made, transport = robot()
    transport.reaches.add(2)
    made.add_server(2)
    made.add_server(2)                 # a second announcement changes nothing
    assert made.selection.candidates('sort') == [2] and transport.connected == [2]
