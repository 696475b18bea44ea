"""The robot's task path under overload: busy answers, the retry budget, the in-flight limit
with the newest frame winning, attempt deadlines that follow the load, and the spread that
keeps robots from moving as a herd."""

import random

import pytest

from server_select.core.attempts import AttemptClock
from server_select.core.budget import RetryBudget
from server_select.core.policy import Chooser, Policy, Settling
from server_select.core.ranking import Ranking
from server_select.core.task_flow import RETRIED

from fake_clock import Clock
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
    assert clock.hedge_seconds(3, 0.95) == pytest.approx(0.2)   # else the quantile


def ranking(means, waits=None):
    """A Ranking of ``{server: statistic}`` (and ``{server: its wait part}``)."""
    order = sorted(means, key=means.get)
    return Ranking(order[0], order, [means[s] for s in order], [10] * len(order), [],
                   waits=[waits.get(s) for s in order] if waits else None)


def test_spread_takes_a_warranted_move_with_probability_half_the_relative_gap():
    policy = Policy('mean', dwell=0.0, spread=True)
    moved = 0
    for seed in range(2000):
        chooser = Chooser(policy, random.Random(seed))
        chooser.choose(ranking({1: 0.10, 2: 0.20}), 0.0)        # starts on 1
        moved += chooser.choose(ranking({1: 0.25, 2: 0.20}), 5.0) == 2
    assert moved / 2000.0 == pytest.approx((1 - 0.20 / 0.25) / 2, abs=0.03)


def test_spread_draws_once_per_dwell_and_leaves_an_unranked_server_at_once():
    chooser = Chooser(Policy('mean', dwell=3.0, spread=True), random.Random(1))
    chooser.choose(ranking({1: 0.1, 2: 0.2}), 0.0)
    draws = [chooser.choose(ranking({1: 0.4, 2: 0.2}), t) for t in (1.0, 1.5, 2.0, 3.9)]
    assert len(set(draws)) == 1                  # one draw at 1.0, then none until 4.0
    chooser = Chooser(Policy('mean', spread=True), random.Random(1))
    chooser.choose(ranking({1: 0.1, 2: 0.2}), 0.0)
    assert chooser.choose(ranking({2: 0.2}), 0.1) == 2


def test_spread_does_not_hold_back_a_move_its_wait_cannot_erase():
    """A server 7 ms nearer with 1 ms of work: taken at once, not drawn for."""
    chooser = Chooser(Policy('mean', dwell=3.0, spread=True), random.Random(1))
    chooser.choose(ranking({1: 0.0097}), 0.0)
    assert chooser.choose(ranking({1: 0.0097, 3: 0.0026}, {1: 0.001, 3: 0.001}), 5.0) == 3
    # a server better by 1.4 s of queue (idle, but 0.7 s a task): drawn for, though its
    # gain is twice its wait: robots that follow add to that wait
    moves = 0
    for seed in range(200):
        chooser = Chooser(Policy('mean', dwell=3.0, spread=True), random.Random(seed))
        chooser.choose(ranking({1: 2.1}), 0.0)
        moves += chooser.choose(ranking({1: 2.1, 2: 0.7}, {1: 2.1, 2: 0.7}), 5.0) == 2
    assert 55 < moves < 80          # (1 - 0.7 / 2.1) / 2 = a third of 200
    # a server whose load just fell: its statistic (the window's) still high, the newest
    # sample's wait low; by the window's own wait it is no nearer, and it is drawn for
    moves = 0
    for seed in range(200):
        chooser = Chooser(Policy('mean', dwell=3.0, spread=True), random.Random(seed))
        chooser.choose(ranking({1: 5.5}), 0.0)
        moves += chooser.choose(ranking({1: 5.5, 2: 0.76}, {1: 5.499, 2: 0.759}), 5.0) == 2
    assert moves < 110              # (1 - 0.76 / 5.5) / 2 = 43 % of 200, not all


def test_a_herd_is_spread_over_equal_servers():
    """20 robots on server 1, whose completion time grows with its robots; server 2 comes
    up idle. Without spread all 20 move at once and back; with it the load evens out."""
    def run(spread):
        choosers = [Chooser(Policy('mean', dwell=3.0, spread=spread), random.Random(r))
                    for r in range(20)]
        for chooser in choosers:                 # all on server 1 before server 2 came
            chooser.choose(ranking({1: 0.05}), -10.0)
        on = dict((r, 1) for r in range(20))
        history = []
        for step in range(40):                   # decisions every 0.5 s for 20 s
            load = dict((s, 0.05 * (1 + sum(1 for v in on.values() if v == s)))
                        for s in (1, 2))
            for r, chooser in enumerate(choosers):
                on[r] = chooser.choose(ranking(load), step * 0.5)
            history.append(sum(1 for v in on.values() if v == 2))
        return history
    herd, spread = run(False), run(True)
    assert max(herd) == 20                           # everyone moved together
    assert all(9 <= n <= 11 for n in spread[-10:]), spread   # settled near 10 / 10
    assert max(spread) <= 13, spread                          # never a herd


def test_robots_that_see_moves_late_move_less_with_a_shared_settling():
    """12 robots, 6 on server 1 and 6 on server 2, whose completion time grows with their
    robots; server 3 comes up idle. A move shows in the loads the others see only 1.5 s
    later (its probes announce it, the window fills), so robots that draw meanwhile draw
    on old loads. With the manager's Settling a server takes one newcomer a window:
    about half the moves for the same 4 / 4 / 4 (30 seeded runs of 60 s each)."""
    def run(settling, seed):
        shared = Settling(1.5) if settling else None
        choosers = [Chooser(Policy('mean', dwell=3.0, spread=True),
                            random.Random(seed * 100 + r), settling=shared) for r in range(12)]
        on = dict((r, 1 + r % 2) for r in range(12))
        for r, chooser in enumerate(choosers):
            chooser.choose(ranking({on[r]: 0.05}), -10.0)
        seen, moves = [], 0
        for step in range(120):                  # decisions every 0.5 s
            seen.append(dict((s, 0.05 * (1 + sum(1 for v in on.values() if v == s)))
                             for s in (1, 2, 3)))
            load = seen[max(0, len(seen) - 4)]  # what the window says: 1.5 s old
            for r, chooser in enumerate(choosers):
                before, on[r] = on[r], chooser.choose(ranking(load), step * 0.5)
                moves += on[r] != before
        return moves, max(sum(1 for v in on.values() if v == s) for s in (1, 2, 3))
    late = [run(False, seed) for seed in range(30)]
    settled = [run(True, seed) for seed in range(30)]
    assert all(most <= 5 for _, most in settled), settled       # spread out at the end
    late_moves, moves = sum(m for m, _ in late), sum(m for m, _ in settled)
    assert moves < 0.75 * late_moves, (moves, late_moves)       # 4 is the fewest a run
    assert moves < 10 * 30, moves                               # can do


def test_robots_with_no_server_go_round_the_servers_the_policy_would_keep():
    shared = Settling(1.5)
    policy = Policy('hysteresis', margin=0.0003, z=3.0, dwell=3.0, spread=True)

    def first_choice(servers, now, seed):
        return Chooser(policy, random.Random(seed), settling=shared).choose(servers, now)
    # three servers alike but for noise, one far: robots starting together go round the
    # three, never to the far one
    servers = Ranking(1, [1, 2, 3, 4], [0.0101, 0.0102, 0.0103, 0.050], [10] * 4, [],
                      [0.002] * 4, [0.001] * 4)
    chosen = [first_choice(servers, 0.1 * i, i) for i in range(6)]
    assert chosen == [1, 2, 3, 1, 2, 3], chosen
    assert first_choice(servers, 5.0, 7) == 1          # all settled again: the best
    # without spread no settling is kept
    assert Chooser(Policy('mean'), settling=shared).settling is None
