"""A server's workers (ros/server_work.py): what they report as a kind's work, and the
lines that name the robots they answer busy."""

import collections
import threading

import pytest

from server_select.core.util.procs import wait_until
from server_select.ros import server_work

Task = collections.namedtuple('Task', 'robot_id task_id budget')
Result = collections.namedtuple('Result', 'ok')


class Endpoint(object):
    """Frames whose handling takes ``durations`` s of a fake clock, in turn, while the
    server's pause ticker beats every 0.1 s (``tick``), but for the tasks numbered in
    ``stopped``, throughout which the process stands still."""
    kind_name = 'image'

    def __init__(self, clock, durations, stopped=()):
        self.clock, self.durations, self.replies = clock, iter(durations), []
        self.stopped, self.tick = set(stopped), lambda: None

    def handle(self, task):
        left = next(self.durations)
        while left > 1e-9:
            step = min(0.1, left)
            self.clock[0] += step
            left -= step
            if task.task_id not in self.stopped:
                self.tick()
        return Result(True)

    def held_bytes(self, task):
        return 0

    def reply(self, task, direct, result):
        self.replies.append(result)

    @staticmethod
    def error_result(task, why, busy):
        return Result(False)


def reported(durations, stopped=()):
    """The work the server reports after frames of ``durations`` s (one worker)."""
    clock = [0.0]
    endpoint = Endpoint(clock, durations, stopped)
    work = server_work.ServerWork(1, 1, 10, clock=lambda: clock[0])
    endpoint.tick = work.pauses.tick
    worker = threading.Thread(target=work._run, daemon=True)
    worker.start()
    for task_id in range(1, len(durations) + 1):
        work.submit(endpoint, Task(1, task_id, 0.0), True)
    assert wait_until(lambda: len(endpoint.replies) == len(durations), 10.0)
    work.queue.close()
    worker.join(10.0)
    return work.load().service


def test_a_workers_first_task_of_a_kind_is_not_a_measure_of_its_work():
    # the 6 s of the first frame would have made the median of 4 frames 0.6 s, and of
    # the first two 3.25 s: what robots read as this server's work while they chose
    assert reported([6.0, 0.5, 0.5, 0.7]) == pytest.approx({'image': 0.5})


def test_a_task_timed_across_a_stop_of_the_process_is_not_a_measure_of_its_work():
    # frame 3 took 0.6 s of work and a 5 s SIGSTOP: counted, the median of the last
    # three would be 5.6 s, what robots would have read for 10 s
    assert reported([6.0, 0.5, 5.6, 0.7, 0.5], stopped=[3]) == pytest.approx({'image': 0.5})
    assert reported([6.0, 0.5, 5.6, 0.7, 0.5]) == pytest.approx({'image': 0.7})


def test_a_robot_answered_busy_is_named_though_another_was_a_moment_before(monkeypatch):
    # one line a period for every robot answered busy would let robot 1's shed task hide
    # the robot flooding the server; a line per robot, 4 a period in all, names both
    lines = []
    monkeypatch.setattr(server_work.rospy, 'logwarn', lines.append)
    clock = [0.0]
    work = server_work.ServerWork(1, 1, 2, clock=lambda: clock[0])
    endpoint = Endpoint(clock, [])
    # (task 4 of robot 9 pushes out task 2 of robot 1, which holds more of the queue)
    for robot, task_id in [(1, 1), (1, 2), (1, 3), (9, 4), (9, 5), (9, 6)]:
        work.submit(endpoint, Task(robot, task_id, 0.0), True)   # 2 places, no worker
    clock[0] += 5.0
    work.submit(endpoint, Task(9, 7, 0.0), True)
    assert [r.ok for r in endpoint.replies] == [False] * 5
    assert [line.split(':')[1] for line in lines] == [
        ' answered image task 3 of robot 1 busy', ' answered image task 5 of robot 9 busy',
        ' answered image task 7 of robot 9 busy']
    assert lines[-1].endswith('(5 busy answers so far; 1 more to robot 9 before)'), lines
