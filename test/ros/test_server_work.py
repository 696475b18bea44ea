"""A server's workers (ros/server_work.py): what they report as a kind's work."""

import collections
import threading

from server_select.core.util.procs import wait_until
from server_select.ros import server_work

Task = collections.namedtuple('Task', 'robot_id task_id budget')
Result = collections.namedtuple('Result', 'ok')


class Endpoint(object):
    """Frames whose handling takes ``durations`` s of a fake clock, in turn."""
    kind_name = 'image'

    def __init__(self, clock, durations):
        self.clock, self.durations, self.replies = clock, iter(durations), []

    def handle(self, task):
        self.clock[0] += next(self.durations)
        return Result(True)

    def held_bytes(self, task):
        return 0

    def reply(self, task, direct, result):
        self.replies.append(result)


def test_a_workers_first_task_of_a_kind_is_not_a_measure_of_its_work(monkeypatch):
    clock = [0.0]
    monkeypatch.setattr(server_work.time, 'perf_counter', lambda: clock[0])
    endpoint = Endpoint(clock, [6.0, 0.5, 0.5, 0.7])   # the first imports OpenCV: 6 s
    work = server_work.ServerWork(1, 1, 10)
    worker = threading.Thread(target=work._run, daemon=True)
    worker.start()
    for task_id in range(1, 5):
        work.submit(endpoint, Task(1, task_id, 0.0), True)
    assert wait_until(lambda: len(endpoint.replies) == 4, 10.0)
    work.queue.close()
    worker.join(10.0)
    # the 6 s of the first frame would have made the median of 4 frames 0.6 s, and of
    # the first two 3.25 s: what robots read as this server's work while they chose
    assert work.load().service == {'image': 0.5}
