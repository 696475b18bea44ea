"""What a load-aware robot's probes announce and what it makes of the answers."""

import pytest

from server_select.srv import LatencyProbeResponse
from server_select.core.robot.robot_load import RobotLoad
from server_select.core.load.work_queue import Load
from server_select.ros.load import load_of

from support.clock import Clock


def test_a_probe_announces_the_robots_send_rate_only_to_where_its_tasks_go():
    """The rate announced is the robot's one count of its sends (its rule's: attempts in
    the last 5 s), told of each attempt as the robot's streams tell it."""
    clock = Clock(0.0)
    heading = {'server': 2}
    load = RobotLoad({'image': 0.5, 'sort': 4.0}, lambda kind: heading['server'],
                     clock=clock)
    # nothing sent yet: the streams' rates, to the server its first task goes to
    assert load.announcement(2) == (['image', 'sort'], [0.5, 4.0])
    assert load.announcement(1) == (['image', 'sort'], [0.0, 0.0])
    for t in (0.0, 4.0, 8.0):          # frames go out every 4 s (slower than asked)
        clock.now = t
        load.sends.started(2, 'image')
    clock.now = 9.0
    kinds, rates = load.announcement(2)
    assert rates == [pytest.approx(2 / 5.0), 4.0]    # no sort task sent yet: as asked
    heading['server'] = 1                            # the flag moved the robot
    assert load.announcement(2)[1] == [0.0, 0.0]
    assert load.announcement(1)[1] == [pytest.approx(2 / 5.0), 4.0]
    clock.now = 12.5        # only the last frame is left in the 5 s
    assert load.announcement(1)[1] == [pytest.approx(1 / 5.0), 4.0]
    clock.now = 13.5        # none left: none announced
    assert load.announcement(1)[1] == [0.0, 4.0]


def test_each_kind_is_announced_to_where_that_kind_goes():
    """Frames to server 1, sort tasks to server 2: each server counts the robot's tasks
    that go there, and only those."""
    load = RobotLoad({'image': 0.5, 'sort': 4.0}, {'image': 1, 'sort': 2}.get, clock=Clock(0.0))
    assert load.announcement(1) == (['image', 'sort'], [0.5, 0.0])
    assert load.announcement(2) == (['image', 'sort'], [0.0, 4.0])
    assert load.announcement(3) == (['image', 'sort'], [0.0, 0.0])


def test_the_wait_and_the_deadlines_come_from_the_answers_tasks_in_flight():
    """An answer's tasks in flight (the other robots') and work per task: the samples' wait
    and what the deadlines follow are the rule's one estimate, not its backlog."""
    load = RobotLoad({'image': 1.0}, lambda kind: 1)
    answer = LatencyProbeResponse(server_id=1, queued=2, in_service=1, workers=1, backlog=3.0,
                                  utilization=0.5, kinds=['image'], service_time=[0.6],
                                  service_error=[0.0])
    assert load.on_answer(1, load_of(answer), 0.05) == pytest.approx(3 * 0.6 + 0.6)
    assert load.expected('image')(1) == pytest.approx(0.05 + 3 * 0.6 + 0.6)


def test_a_frame_is_fresh_until_the_next_one_is_due_and_for_twice_its_best_answer():
    load = RobotLoad({'image': 1.0}, lambda kind: 1)
    answer = LatencyProbeResponse(server_id=1, workers=1, backlog=3.0, utilization=0.5,
                                  kinds=['image'], service_time=[0.6], service_error=[0.0])
    fresh = load.fresh_for('image', 2.0, lambda: 1.0 / 0.5)        # a frame every 2 s
    assert fresh(1) is None                                 # nothing heard of server 1
    load.on_answer(1, load_of(answer), 0.05)
    assert fresh(1) == pytest.approx(2.0)                   # the next frame is due first
    fast = load.fresh_for('image', 2.0, lambda: 1.0 / 5.0)          # 5 frames/s: past capacity
    assert fast(1) == pytest.approx(2.0 * (0.05 + 0.6))     # the queue (3 s) left out


@pytest.mark.parametrize('fields, why', [
    (dict(kinds=['image'], service_time=[0.6], service_error=[]), '1 kinds with 1 work times'),
    (dict(kinds=['image', 'image'], service_time=[0.6, 0.6], service_error=[0.0, 0.0]),
     '2 kinds \\(1 different'),
    (dict(kinds=['k%d' % i for i in range(40)], service_time=[0.1] * 40,
          service_error=[0.0] * 40), '40 kinds'),
    (dict(utilization=float('nan')), 'utilization is nan'),
    (dict(backlog=-1.0), 'backlog is -1.0'),
    (dict(kinds=['image'], service_time=[float('inf')], service_error=[0.0]),
     'work of image is inf'),
])
def test_a_load_report_that_makes_no_sense_is_refused_saying_why(fields, why):
    with pytest.raises(ValueError, match=why):
        load_of(LatencyProbeResponse(server_id=1, workers=1, **fields))


def test_a_load_report_is_read_whole():
    answer = LatencyProbeResponse(server_id=1, queued=2, in_service=1, workers=2, backlog=0.4,
                                  utilization=0.5, kinds=['image', 'sort'],
                                  service_time=[0.3, 0.002], service_error=[0.01, 0.0])
    assert load_of(answer) == Load(2, 1, 2, 0.4, {'image': 0.3, 'sort': 0.002}, 0.5,
                                   {'image': 0.01, 'sort': 0.0})
