import math

import pytest

from server_select.core.robot.health import ServerHealth
from server_select.core.ranking.policy import Policy
from server_select.core.robot.selection import Selection
from server_select.core.flow.task_flow import LOCAL, NO_SERVER

from support.clock import Clock


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


def test_deciding_alone_starts_from_the_server_the_manager_selected():
    """The manager's server is kept while the robot's own margin allows (no switch on the
    manager's loss alone); a clearly better server still wins."""
    s, clock = select(policy=Policy('mean', margin=0.002))
    for server, rtt in ((1, 0.0050), (2, 0.0049), (3, 0.0051)):
        s.on_sample(server, True, rtt)
    s.on_flag(1, 3, [3, 1, 2])
    clock.now += 3.01
    assert s.deciding_locally() and s.target() == 3       # within 2 ms of the best
    s.on_sample(1, True, 0.0001)                         # 1 now clearly nearest
    s.on_sample(1, True, 0.0001)
    assert s.target() == 1
    s.on_sample(3, True, 0.0001)
    assert s.target() == 1            # its own decision stands: the stale flag is not taken again


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


def test_deciding_alone_a_robot_ranks_by_its_task_samples_and_remembers_their_cost():
    s, clock = select(window=1.5, passive=True, task_memory=5.0)

    def probes():
        s.on_sample(1, True, 0.010)       # server 1: nearer by probes...
        s.on_sample(2, True, 0.012)
    for _ in range(8):
        probes()
        clock.now += 0.25
    assert s.own_ranking()[0] == 1 and s.probe_latency(1) == pytest.approx(0.010)
    for _ in range(8):                    # ...but its tasks take 25 ms more
        probes()
        for _ in range(3):
            s.on_sample(1, True, 0.035, probe=False)
        clock.now += 0.25
    assert s.own_ranking()[0] == 2
    for _ in range(12):                   # the robot has left it: probes only, 3 s
        probes()
        clock.now += 0.25
    assert s.own_ranking()[0] == 2        # still ranked by what its tasks cost
    assert s.probe_latency(1) == pytest.approx(0.010)     # the probes themselves: as is
    for _ in range(100):                  # 25 s later the memory has faded: tried again
        probes()
        clock.now += 0.25
    assert s.own_ranking()[0] == 1


def test_without_task_memory_the_cost_leaves_with_the_window():
    s, clock = select(window=1.5, passive=True)
    for _ in range(8):
        s.on_sample(1, True, 0.010)
        s.on_sample(2, True, 0.012)
        for _ in range(3):
            s.on_sample(1, True, 0.035, probe=False)
        clock.now += 0.25
    assert s.own_ranking()[0] == 2
    for _ in range(8):
        s.on_sample(1, True, 0.010)
        s.on_sample(2, True, 0.012)
        clock.now += 0.25
    assert s.own_ranking()[0] == 1


def test_heading_names_where_the_next_task_goes_without_deciding_anew():
    s, clock = select(manager_timeout=3.0)
    assert s.heading() == NO_SERVER                    # nothing decided yet
    s.on_flag(1, 2, [3, 2, 1])
    assert s.heading() == 2
    s.health.probe_ok(2)
    s.health.failure(2, 'task timeout')               # ejected: the next candidate
    assert s.heading() == 3
    s.health.started(3)                               # a task went there
    clock.now += 3.5                                  # the flag is stale: the robot's own
    for server, rtt in ((1, 0.004), (3, 0.009)):      # choice, once it has made one;
        s.on_sample(server, True, rtt)                # until then the last one's
    assert s.heading() == 3
    assert s.target() == 1 and s.heading() == 1
    s.on_sample(3, True, 0.001)                       # no new decision until it sends
    assert s.heading() == 1


def test_heading_in_fixed_mode_is_the_fixed_server():
    s = Selection(1, [1, 2], 'fixed', fixed_server=2)
    assert s.heading() == 2


def test_an_empty_window_keeps_the_server_tasks_went_to_while_nothing_speaks_against_it():
    s, clock = select(manager_timeout=3.0)
    assert s.candidates() == []                       # nothing known yet
    s.on_sample(2, True, 0.004)
    s.health.probe_ok(2)
    s.on_flag(1, 2, [2])
    assert s.candidates() == [2]
    s.health.started(2)                               # a task went there
    clock.now += 6.0            # the robot stalled: its window and the flag are empty, old
    s.on_flag(1, NO_SERVER, [])
    assert s.candidates() == [2] and s.heading() == 2
    s.health.failure(2, 'probe timeout', probe=True)  # evidence against it: no candidate
    assert s.candidates() == [] and s.heading() == NO_SERVER
    s.health.probe_ok(2)                              # answers again: on probation, until
    assert s.candidates() == [2]                      # (1 probe here) it may have tasks
    s.remove_server(2)                                # gone from the fleet: forgotten
    assert s.candidates() == []


def test_asking_whether_a_per_task_rule_is_ready_or_where_it_heads_decides_nothing():
    """A robot's summary line and its start-up check ask where tasks go; with the fleet's
    rule that must not be a decision (one made for no kind of task moved robots on a
    loaded server to a near one between two tasks) nor count as a send."""
    clock = Clock()
    health = ServerHealth([1, 2], clock=clock, probation_probes=1)
    s = Selection(1, [1, 2], 'select', health=health, clock=clock, policy=Policy('least_latency'))
    rule = s.balancer
    assert not s.ready(set())                         # no server has answered a probe
    assert s.ready({2}) and s.heading() == NO_SERVER
    assert rule.chosen is None and not rule.sends.kinds()
    first = s.candidates('sort')[0]                   # a send asks with its kind
    assert rule.chosen is None and s.heading() == NO_SERVER    # asking is not sending
    rule.started(first, 'sort')
    assert rule.chosen == first and s.heading() == first
    for _ in range(3):
        assert s.ready({2}) and s.heading() == first and s.candidates('sort')[0] == first
    assert rule.sends.count('sort', clock.now) == 1


def test_whether_the_ranking_changed_is_worked_out_only_for_a_watcher():
    """A store nobody watches (a simulated robot) records its samples all the same: the
    view is the watched one's, and only the watched store says when it may have changed."""
    quiet, _ = select()
    watched, _ = select()
    heard = []
    watched.on_change = lambda: heard.append(1)
    for server, rtt in ((1, 0.009), (2, 0.004), (3, 0.007), (2, 0.005), (1, 0.001)):
        assert quiet.on_sample(server, True, rtt) is None
        assert watched.on_sample(server, True, rtt) in (True, False)
    assert quiet.view() == watched.view() and quiet.view().ranking == [2, 1, 3]
    assert len(heard) == 5        # (no server selected yet: every sample may change it)


def test_a_rule_with_a_view_of_its_own_keeps_no_paper_store():
    """The fleet's rule ranks by its own estimates: no manager's store is built or fed for
    it, and its view, samples and servers leaving work without one."""
    s, clock = select(policy=Policy('least_latency'))
    assert s.rankings is None and s.window is None
    for server in (1, 2, 3):
        assert s.on_sample(server, True, 0.001 * server) is True
    s.remove_server(3)
    s.viewed(1)
    assert 3 not in s.view().ranking and s.candidates()
    p, _ = select(policy=Policy('prequal'))
    assert p.rankings is not None       # a peer's view is the manager's ranking of it
