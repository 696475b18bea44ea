"""Which of the package's modules one fleet decision touches (``python3 -m
server_select.bench.decision_path``): a fleet robot (the package's
:class:`~server_select.core.robot.robot.Robot`, fed probe answers of 4 servers) lets a
task fall due, and every function called from the stream's ``act`` until the transport's
``send_task`` is traced, for a sort task and for a camera frame (newest wins, fresh for a
while). Prints the modules in the order first entered and their count; the task's own
content (``make``) and the transport are stubs, so what is counted is the robot's decision
and send, not a message's encoding, nor what the flow does after the send.
"""

import os
import random
import sys
import types

from server_select.core.load.work_queue import Load
from server_select.core.robot.robot import Robot
from server_select.core.robot.world import Transport
from server_select.core.settings import default

SERVERS = (1, 2, 3, 4)
PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class _Clock(object):
    now = 0.0

    def __call__(self):
        return self.now


class _Sort(object):
    kind, newest_wins, run_local, input = 'sort', False, None, 'a stub'

    def make(self, task_id, stamp):
        return types.SimpleNamespace(task_id=task_id), None

    def check(self, result, context):
        return None

    def ready(self):
        return True


class _Frame(_Sort):
    kind, newest_wins = 'image', True


class _Wire(Transport):
    def __init__(self):
        self.sent = []

    def send_task(self, kind, request, server, budget=None):
        self.sent.append((request.task_id, server))


def fleet_robot(seed=1):
    """A fleet robot with 4 servers, each answering its probes, a few tasks of each of its
    streams (sort tasks, frames) sent and answered."""
    clock, wire = _Clock(), _Wire()
    get = lambda name: {'mode': 'select', 'start_delay': 0.0}.get(  # noqa: E731
        name, default(name, 'fleet'))
    robot = Robot(1, list(SERVERS), 'select', get, [(_Sort(), 2.0), (_Frame(), 2.0)],
                  transport=wire, clock=clock,
                  random=lambda purpose: random.Random('%s/%d' % (purpose, seed)))
    robot.start()
    for _ in range(20):
        clock.now += 0.25
        robot.probe_round()
        for server in SERVERS:
            for seq in range(1, 200):
                robot.probe_answered(server, seq, 0.001 * server, Load(
                    0, 0, 1, 0.0, {'sort': 0.002, 'image': 0.02}, 0.2))
        for stream in robot.streams:
            stream.act()
        for task_id, server in wire.sent:      # each answered at once
            for stream in robot.streams:
                stream.resolve(task_id, server, True)
        del wire.sent[:]
    return robot, clock, wire


def traced_modules(kind='sort'):
    """The package's modules (paths from its root) entered by one ``kind`` task's decision,
    from its falling due to its send, in the order first entered."""
    robot, clock, wire = fleet_robot()
    stream = robot.stream(kind)
    clock.now = max(clock.now, stream.next_send)
    entered = []
    sent = len(wire.sent)
    send = _Wire.send_task.__code__

    def profile(frame, event, _arg):
        if event == 'call' and len(wire.sent) == sent and frame.f_code is not send:
            path = os.path.abspath(frame.f_code.co_filename)
            if path.startswith(PACKAGE) and path not in entered:
                entered.append(path)
    sys.setprofile(profile)
    try:
        stream.act()
    finally:
        sys.setprofile(None)
    assert len(wire.sent) == sent + 1, 'no task was sent'
    own = os.path.abspath(__file__)
    return [os.path.relpath(p, PACKAGE) for p in entered if p != own]


def main():
    every = []
    for kind in ('sort', 'image'):
        modules = traced_modules(kind)
        print('%s: %d modules from a task falling due to its send' % (kind, len(modules)))
        for module in modules:
            print('  ' + module)
        every += [m for m in modules if m not in every]
    print('%d modules in all' % len(every))
    return 0


if __name__ == '__main__':
    sys.exit(main())
