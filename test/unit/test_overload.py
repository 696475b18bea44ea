"""The robot's task path under overload: busy answers, the retry budget, the in-flight limit
with the newest frame winning, attempt deadlines that follow the load."""


import pytest

from server_select.core.flow.attempts import AttemptClock
from server_select.core.flow.budget import RetryBudget
from server_select.core.flow.task_flow import RETRIED

from support.clock import Clock
from test_task_flow import World


def busy(w, task_id, server):
    return w.flow.resolve(task_id, server, False, 'busy: would finish in 3 s', busy=True)


def busy_status(w, task_id, server):
    return busy(w, task_id, server).status


def test_each_attempt_tells_the_server_how_long_its_robot_still_waits():
    w = World(candidates=(3, 1), timeout=2.0, first=0.5)
    w.flow.send_next('s1')
    w.clock.now += 0.6                 # past the attempt deadline: re-sent to server 1
    w.flow.tick()
    assert [s for _, s in w.published] == [3, 1]
    assert w.budgets == [pytest.approx(2.0), pytest.approx(1.4)]


def test_a_fresh_deadline_is_what_each_server_is_given_within_the_timeout():
    fresh = {3: 0.9, 1: None, 2: 5.0}    # server 1: nothing known yet
    w = World(candidates=(3, 1, 2), timeout=2.0, first=0.5)
    w.flow.deadlines.fresh = fresh.get
    w.flow.send_next('s1')
    w.clock.now += 0.6
    w.flow.tick()                      # re-sent to server 1: the rest of the timeout
    w.clock.now += 0.6
    w.flow.tick()                      # and to server 2: the timeout is less than 5 s
    assert [s for _, s in w.published] == [3, 1, 2]
    assert w.budgets == [pytest.approx(0.9), pytest.approx(1.4), pytest.approx(0.8)]


def test_a_frame_is_fresh_from_its_first_send_and_goes_nowhere_once_stale():
    w = World(candidates=(3, 1, 2), timeout=5.0, first=0.5)
    w.flow.deadlines.fresh = {3: 1.4, 1: 1.4, 2: 1.4}.get
    w.flow.send_next('s1')
    w.clock.now += 0.6                 # no answer from 3: re-sent to 1 with what is left
    w.flow.tick()
    assert [s for _, s in w.published] == [3, 1]
    assert w.budgets == [pytest.approx(1.4), pytest.approx(0.8)]
    w.clock.now += 0.9                 # 1.5 s after the first send: stale, sent nowhere
    w.flow.tick()
    assert [s for _, s in w.published] == [3, 1] and w.flow.resent == 1
    assert len(w.flow) == 1            # a late answer from 1 is still taken


def test_a_busy_fresh_frame_goes_on_only_where_the_load_says_it_is_done_in_time():
    fresh = {3: 1.4, 1: 1.4, 2: 1.4, 4: None}
    w = World(candidates=(3, 1, 2))
    w.flow.deadlines.fresh = fresh.get
    w.flow.deadlines.expected = {3: 2.0, 1: 2.1, 2: 0.8}.get   # backlog + work there, s
    w.flow.send_next('s1')
    assert busy_status(w, 1, 3) == RETRIED
    assert [s for _, s in w.published] == [3, 2]        # server 1 is as far behind as 3
    outcome = busy(w, 1, 2).outcome                      # and then nobody is left in time
    assert not outcome.ok and outcome.error.startswith('server 2 busy')
    assert [s for _, s in w.published] == [3, 2] and w.flow.resent == 1
    # a server whose load is not known, or a task without a freshness deadline, goes on
    w.candidates = [3, 4]
    w.flow.send_next('s2')
    assert busy_status(w, 2, 3) == RETRIED and w.published[-1][1] == 4


def test_a_busy_answer_sends_the_task_on_and_blames_nobody():
    w = World(candidates=(3, 1))
    w.flow.send_next('s1')
    assert busy_status(w, 1, 3) == RETRIED
    assert w.failures == [] and w.flow.busy == 1
    outcome = w.answer(1, 1).outcome
    assert (outcome.ok, outcome.answered_by, outcome.attempts) == (True, 1, 2)


def test_busy_everywhere_fails_the_task_at_once_with_the_reason():
    w = World(candidates=(3,))
    w.flow.send_next('s1')
    outcome = busy(w, 1, 3).outcome
    assert not outcome.ok and outcome.error.startswith('server 3 busy (busy: would finish')
    assert w.failures == [] and len(w.flow) == 0


def test_without_budget_a_task_keeps_its_one_attempt():
    budget = RetryBudget(ratio=0.1, reserve=1, clock=Clock())
    w = World(candidates=(3, 1), budget=budget)
    for stamp in ('s1', 's2', 's3'):
        w.flow.send_next(stamp)
    assert busy_status(w, 1, 3) == RETRIED == busy_status(w, 2, 3)    # 1 + 10 % of 3 tasks: 1.3
    outcome = busy(w, 3, 3).outcome
    assert not outcome.ok and w.flow.unfunded == 1 and budget.refused == 1
    assert [s for _, s in w.published] == [3, 3, 3, 1, 1]


def test_no_hedge_without_budget():
    budget = RetryBudget(ratio=0.1, reserve=0, clock=Clock())
    w = World(candidates=(3, 1), timeout=5.0, hedge=0.5, budget=budget)
    for task in range(1, 6):                         # 5 answers: the hedge delay is known
        w.flow.send_next('s%d' % task)
        w.clock.now += 0.1
        w.answer(task, 3)
    w.flow.send_next('s6')
    assert budget.spend() and not budget.spend()     # 10 % of 6 tasks: one extra send
    w.clock.now += 0.3                   # past the p50 round trip, before the deadline
    w.flow.tick()
    assert w.flow.hedged == 0 and w.flow.unfunded == 1
    assert [s for _, s in w.published][-1] == 3


def test_at_most_max_in_flight_tasks_are_out_and_a_held_send_goes_when_one_ends():
    w = World(candidates=(3,), max_in_flight=2)
    assert w.flow.send_next('s1') == 1 and w.flow.send_next('s2') == 2
    assert w.flow.send_next('s3') is None and not w.flow.due()
    assert w.flow.send_next('s4') is None            # replaces the held one
    assert (w.flow.sent, w.flow.skipped, len(w.published)) == (2, 1, 2)
    w.answer(1, 3)
    assert w.flow.due()
    assert w.flow.send_next('s5') == 3 and not w.flow.due()


def test_a_late_frame_gives_way_to_a_newer_one_instead_of_being_sent_again():
    w = World(candidates=(3, 1), first=0.5, max_in_flight=1, newest_wins=True)
    w.flow.send_next('s1')
    w.clock.now += 0.6
    w.flow.tick()                                    # no newer frame: sent again
    assert [s for _, s in w.published] == [3, 1]
    w.flow.send_next('s2')                           # held back: task 1 is out
    w.clock.now += 0.6
    (outcome,) = w.flow.tick()
    assert not outcome.ok and 'a newer task waits' in outcome.error
    assert w.flow.superseded == 1 and w.flow.due() and len(w.flow) == 0


def test_a_busy_frame_gives_way_to_a_newer_one():
    w = World(candidates=(3, 1), max_in_flight=1, newest_wins=True)
    w.flow.send_next('s1')
    w.flow.send_next('s2')                           # held back
    outcome = busy(w, 1, 3).outcome
    assert not outcome.ok and outcome.error.endswith('a newer task waits')
    assert [s for _, s in w.published] == [3] and w.flow.due()


def test_an_attempt_deadline_follows_what_the_server_says_it_takes():
    expected = {3: 1.5}
    clock = AttemptClock(5.0, first=1.0, floor=0.25, expected=expected.get)
    assert clock.seconds(3) == pytest.approx(3.0)    # 2 x (backlog + work), not 1 s
    assert clock.seconds(1) == pytest.approx(1.0)    # no load known: as before
    expected[3] = 4.0
    assert clock.seconds(3) == 5.0                   # never past the task timeout


def test_no_hedge_for_a_delay_the_servers_load_explains():
    expected = {3: 0.5}
    clock = AttemptClock(5.0, min_samples=1, expected=expected.get)
    clock.add(3, 0.2)
    assert clock.hedge_seconds(3, 0.95) == pytest.approx(1.0)   # 2 x what the load says
    expected[3] = None
    assert clock.hedge_seconds(3, 0.95) == pytest.approx(0.4)   # else quantile + median


def test_a_hedge_waits_past_the_usual_spread_by_one_round_trip():
    clock = AttemptClock(5.0, min_samples=5)
    for rtt in [0.010] * 50 + [0.016] * 45 + [0.230] * 3:   # 3 % retransmissions
        clock.add(1, rtt)
    # median 10 ms, quartiles 10 and 16 ms: 10 + 1.645 x 6 / 1.349, then a round trip
    assert clock.hedge_seconds(1, 0.95) == pytest.approx(0.010 + 0.00732 + 0.010, abs=1e-4)
    jitter = [0.010 + 0.0001 * i for i in range(100)]        # 10-20 ms, no tail
    for rtt in jitter:
        clock.add(2, rtt)
    assert not [r for r in jitter if r > clock.hedge_seconds(2, 0.95)]   # no copy could win


def test_one_retransmission_among_few_round_trips_does_not_stop_hedging():
    clock = AttemptClock(5.0, min_samples=5)
    for rtt in [0.018] * 12 + [0.247]:           # a new server's first 13 answers
        clock.add(4, rtt)
    assert clock.hedge_seconds(4, 0.95) == pytest.approx(0.018 + 0.018)


def test_a_tail_of_lost_packets_does_not_set_the_delay_of_the_hedges_that_cut_it():
    # 1 % loss on a 3-packet task and its result: 6 % of round trips wait for a 200 ms
    # retransmission. The p95 by rank is in that tail (a hedge after 233 ms never wins);
    # the p95 of the usual spread is not, so the tail's tasks are hedged
    clock = AttemptClock(5.0, min_samples=5)
    for rtt in [0.020 + 0.0005 * (i % 7) for i in range(94)] + [0.221] * 6:
        clock.add(3, rtt)
    rtts = sorted(clock._rtts[3])
    assert rtts[int(0.95 * (len(rtts) - 1))] == 0.221
    assert 0.040 < clock.hedge_seconds(3, 0.95) < 0.050
