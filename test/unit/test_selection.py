import math

import pytest

from server_select.core.health import ServerHealth
from server_select.core.policy import Policy
from server_select.core.selection import Selection
from server_select.core.task_flow import LOCAL, NO_SERVER

from fake_clock import Clock


def select(**kwargs):
    clock = Clock()
    health = ServerHealth([1, 2, 3], clock=clock, probation_probes=1)
    kwargs.setdefault('manager_timeout', 3.0)
    return Selection(1, [1, 2, 3], 'select', health=health, clock=clock, **kwargs), clock


def test_a_fresh_flag_orders_the_candidates_with_its_selected_server_first():
    s, clock = select()
    assert s.on_flag(2, 3, [3]) is None and s.candidates() == []   # another robot's flag
    assert s.on_flag(1, 2, [3, 2, 1]) is None     # hysteresis kept 2 although 3 ranks first
    assert s.candidates() == [2, 3, 1] and s.target() == 2 and not s.deciding_locally()


def test_flags_naming_unknown_servers_or_inconsistent_are_refused():
    s, clock = select()
    s.on_flag(1, 2, [2, 1])
    assert 'not in this robot' in s.on_flag(1, 99, [99])
    assert 'lacks' in s.on_flag(1, 3, [2, 1])
    assert s.candidates() == [2, 1]


def test_the_robots_own_evidence_skips_ejected_servers():
    s, clock = select()
    s.on_flag(1, 2, [2, 3, 1])
    s.health.failure(2, 'task timeout')
    assert s.candidates() == [3, 1]


def test_a_stale_or_empty_flag_hands_the_decision_to_the_robots_own_probes():
    s, clock = select(manager_timeout=3.0)
    for server, rtt in ((1, 0.009), (2, 0.004), (3, 0.007)):
        s.on_sample(server, True, rtt)
    s.on_flag(1, 1, [1, 2, 3])
    clock.now += 3.0
    assert s.candidates() == [1, 2, 3]
    clock.now += 0.01
    assert s.deciding_locally() and s.candidates() == [2, 3, 1]
    s.on_flag(1, NO_SERVER, [])                   # e.g. a manager restarted with no samples
    assert s.deciding_locally() and s.candidates() == [2, 3, 1]
    s.on_flag(1, 3, [3, 1])
    assert not s.deciding_locally() and s.candidates() == [3, 1]


def test_own_ranking_uses_the_managers_policy_with_hysteresis():
    s, clock = select(policy=Policy('mean', margin=0.002))
    s.on_sample(1, True, 0.005)
    s.on_sample(2, True, 0.006)
    assert s.candidates()[0] == 1
    s.on_sample(2, True, 0.002)    # mean of 2 now 4 ms: within 2 ms of 1's 5 ms, 1 is kept
    assert s.candidates() == [1, 2]


@pytest.mark.parametrize('rtt', [math.nan, -0.001, math.inf, -math.inf])
def test_impossible_round_trips_are_refused(rtt):
    s, clock = select()
    with pytest.raises(ValueError):
        s.on_sample(1, True, rtt)
    assert s.candidates() == []


def test_fixed_mode_ignores_flags_and_waits_for_its_server_to_answer():
    s = Selection(1, [1, 2, 3], 'fixed', fixed_server=2)
    s.on_flag(1, 3, [3])
    assert s.candidates() == [2]
    assert not s.ready({1, 3}) and s.ready({2})


def test_local_mode_is_always_ready():
    s = Selection(1, [1], 'local')
    assert s.candidates() == [LOCAL] and s.ready(set())
