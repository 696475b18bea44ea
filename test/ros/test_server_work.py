"""A server's workers (ros/server_work.py): what they report as a kind's work."""

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
