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
        self.take(next(self.durations), task)
        return Result(True)

    def take(self, left, task):
        """``left`` s of the fake clock pass, the ticker beating unless ``task`` is stopped."""
        while left > 1e-9:
            step = min(0.1, left)
            self.clock[0] += step
            left -= step
            if task.task_id not in self.stopped:
                self.tick()

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


class Rehearsing(Endpoint):
    """An endpoint whose task type rehearses a task in ``rehearsals`` s each (False: it
    does not rehearse)."""

    def __init__(self, clock, durations, rehearsals):
        Endpoint.__init__(self, clock, durations)
        self.rehearsals, self.rehearsed, self.asked = iter(rehearsals), [], 0

    def rehearse(self, task):
        self.asked += 1
        seconds = next(self.rehearsals)
        if seconds is False:
            return False
        if isinstance(seconds, Exception):
            raise seconds
        self.take(seconds, task)
        self.rehearsed.append(task.task_id)
        return True


def checked(rehearsals, checks):
    """A server's one worker after frames of 6 s (not timed) and 0.1 s, then ``checks``
    offers of a check 5 s apart once no robot sends (10 s on): the endpoint, the work."""
    clock = [0.0]
    endpoint = Rehearsing(clock, [6.0, 0.1], rehearsals)
    work = server_work.ServerWork(1, 1, 10, clock=lambda: clock[0])
    endpoint.tick = work.pauses.tick
    worker = threading.Thread(target=work._run, daemon=True)
    worker.start()
    for task_id in (1, 2):
        work.submit(endpoint, Task(1, task_id, 0.0), True)
    assert wait_until(lambda: len(endpoint.replies) == 2, 10.0)
    idle = Task(None, 0, 0.0)
    endpoint.take(10.0, idle)             # (the pause ticker beats meanwhile)
    for _ in range(checks):
        endpoint.take(5.0, idle)
        work.check(5.0)
        # none queued, none in service
        assert wait_until(lambda: work.queue.load()[:2] == (0, 0), 10.0)
    work.queue.close()
    worker.join(10.0)
    return endpoint, work


def test_an_idle_kinds_check_rehearses_its_last_task_and_answers_nobody():
    endpoint, work = checked([0.2, 0.2], checks=2)
    assert endpoint.rehearsed == [2, 2] and len(endpoint.replies) == 2
    assert work.load().service == pytest.approx({'image': 0.2})   # 0.1, 0.2, 0.2
    assert (work.checks, work.queue.finished) == (2, 2)
    assert work.summary().endswith(', 2 checks of an idle kind')


@pytest.mark.parametrize('rehearsal', [False, RuntimeError('a defect')])
def test_a_kind_whose_type_does_not_rehearse_is_not_checked_again(rehearsal, monkeypatch):
    lines = []
    monkeypatch.setattr(server_work.rospy, 'logerr', lambda *args: lines.append(args))
    endpoint, work = checked([rehearsal], checks=3)
    assert (endpoint.asked, endpoint.rehearsed, work.checks) == (1, [], 0)
    assert work.load().service == pytest.approx({'image': 0.1})
    assert len(lines) == (rehearsal is not False)     # a defect: one line


def test_a_frames_rehearsal_shares_nothing_found(monkeypatch):
    """The image type's rehearsal makes the result, and publishes no detections."""
    import numpy
    from server_select.msg import ImageResult, ImageTask
    from server_select.tasks.image import Frames
    from server_select.vision.detection import Box

    frames = Frames(None, {})
    shared = []
    frames.detections_pub = collections.namedtuple('Pub', 'publish')(shared.append)
    monkeypatch.setattr(frames, '_search', lambda raw, packed: (
        [Box(1, 2, 3, 4, 'face', 0.9)], numpy.zeros((4, 4, 3), numpy.uint8)))
    task = ImageTask(robot_id=3, task_id=7)
    for act in (frames.rehearse, frames.handle):
        result = ImageResult()
        act(task, result)
        assert result.detection_count == 1 and result.image.width == 4
    assert [(d.robot_id, d.task_id, len(d.detections)) for d in shared] == [(3, 7, 1)]
