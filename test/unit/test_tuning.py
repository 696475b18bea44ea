"""Settings a running robot takes (core/robot/tuning.py): each reaches the parts that read
it, a request is taken whole or not at all, and what is read once says so."""

import pytest

from server_select.core.robot.tuning import Tuning, live_names, why_not_live
from server_select.core.settings import default
from test_robot_joining import Reaching, Sort
from test_least_latency import Clock

from server_select.core.robot.robot import Robot


def robot(profile='fleet', **settings):
    get = lambda name: dict({'mode': 'select'}, **settings).get(  # noqa: E731
        name, default(name, profile))
    made = Robot(1, [1, 2], 'select', get, [(Sort(), 2.0)], transport=Reaching(),
                 clock=Clock())
    made.start()
    return made, Tuning(made, get)


def test_a_fleet_robot_takes_its_rule_window_stream_rate_and_probe_rates_live():
    made, tuning = robot()
    assert 'window' in tuning.names and 'task_rate' in tuning.names
    assert 'contender_rate' in tuning.names and 'probe_rate' not in tuning.names  # adaptive
    assert tuning.names == ['window', 'task_rate', 'hedge', 'retry_budget', 'contender_rate']
    assert 'frame_rate' not in tuning.names        # no camera stream
    assert 'seed' not in tuning.names and 'restart' in why_not_live('seed')


def test_a_new_window_reaches_the_rule_the_probe_plan_and_the_load_view():
    made, tuning = robot()
    made.balancer.probed(1, 0.002)
    made.clock.now += 2.5                       # older than the fleet's 2 s window
    assert made.balancer.estimate(1, 'sort', made.clock()) is None
    assert tuning.set('window', 3.0) == 2.0
    assert made.balancer.estimate(1, 'sort', made.clock()).latency == pytest.approx(0.002)
    assert made.plan.hold == 3.0 and made.load.balancer.window == 3.0


def test_a_faster_task_rate_brings_the_next_send_forward():
    made, tuning = robot()
    stream = made.streams[0]
    made.clock.now += 0.01
    before = stream.next_send
    tuning.set('task_rate', 20.0)
    assert stream.period == pytest.approx(0.05)
    assert stream.next_send <= made.clock() + 0.05 < before
    assert made.load.mix == {'sort': 20.0}


def test_hedging_and_the_retry_budget_change_for_every_stream():
    made, tuning = robot()
    assert made.streams[0].flow.hedge is not None
    tuning.set_all({'hedge': False, 'retry_budget': 0.5})
    assert made.streams[0].flow.hedge is None and made.budget.ratio == 0.5


def test_a_request_is_taken_whole_or_not_at_all():
    made, tuning = robot()
    with pytest.raises(ValueError, match='below ~background_rate 1'):
        tuning.set_all({'window': 3.0, 'contender_rate': 0.5})
    assert tuning.values['window'] == 2.0 and made.balancer.window == 2.0
    assert made.plan.contender_rate == 4.0


def test_what_the_fleets_rule_fixes_is_not_tuned_either():
    made, tuning = robot()
    assert 'eject_time' not in tuning.names and 'background_rate' not in tuning.names
    with pytest.raises(ValueError, match='fixed by least_latency'):
        tuning.set('eject_time', 5.0)
    assert made.health.base == 1.0


def test_probing_chosen_at_start_stays_so():
    made, tuning = robot()
    with pytest.raises(ValueError, match='adaptive probing off'):
        tuning.set('contender_rate', 0.0)
    with pytest.raises(ValueError, match='below ~background_rate'):
        tuning.set('contender_rate', 0.5)
    tuning.set('contender_rate', 8.0)
    assert made.plan.tick == pytest.approx(1 / 8.0)


def test_a_paper_robot_following_its_manager_has_no_rule_window_to_tune():
    made, tuning = robot('paper')
    assert 'window' not in live_names(made, default) and 'probe_rate' in tuning.names
    with pytest.raises(ValueError, match="the manager's window"):
        tuning.set('window', 3.0)
    tuning.set('probe_rate', 2.0)
    assert made.plan.tick == pytest.approx(0.5)
    with pytest.raises(ValueError, match='eject_time 100 would be longer than ~eject_max 30'):
        tuning.set('eject_time', 100.0)
    tuning.set_all({'eject_time': 100.0, 'eject_max': 200.0})
    assert (made.health.base, made.health.longest) == (100.0, 200.0)
