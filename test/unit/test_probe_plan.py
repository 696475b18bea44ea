"""Adaptive probing: probe rates, a far server that comes near (contenders by the rule),
and the window with uneven sampling (core/robot/probe_plan.py, core/ranking/window.py)."""

import collections
import random

import pytest

from server_select.core.rule.least_latency import LeastLatency
from server_select.core.robot.probe_plan import ProbePlan, from_params
from server_select.core.manager.sample_rankings import SampleRankings
from server_select.core.ranking.window import EMPTY, LatencyWindow, PairStats

from support.clock import Clock

MS = 1e-3


def pair(value, se, n=10):
    return PairStats(value, n, 0, value, se, 0)


# -- probe plans --------------------------------------------------------------------------

def run(plan, seconds, start=0.0, contenders=None, task_rate=None):
    """Tick ``plan`` for ``seconds``; counts of probes per server."""
    counts = collections.Counter()
    ticks = int(round(seconds / plan.tick))
    for i in range(ticks):
        now = start + i * plan.tick
        if contenders is not None:
            plan.update(contenders, now, task_rate)
        counts.update(plan.due(now))
    return counts


def test_a_uniform_plan_probes_every_server_every_tick_as_the_paper():
    plan = ProbePlan(rate=1.0)
    for server in (1, 2, 3):
        plan.add(server, 0.0)
    assert plan.tick == 1.0 and not plan.adaptive
    assert run(plan, 10.0) == {1: 10, 2: 10, 3: 10}
    assert plan.rate() == 3.0 and plan.contenders == [1, 2, 3]


def test_contenders_at_their_rate_the_others_at_the_background_rate():
    plan = ProbePlan(contender_rate=10.0, background_rate=0.5, budget=20.0, hold=1.5)
    for server in range(1, 11):
        plan.add(server, 0.0)
    counts = run(plan, 20.0, contenders={1, 2})
    steady = run(plan, 20.0, start=20.0, contenders={1, 2})
    assert steady[1] == steady[2] == 200
    assert all(9 <= steady[s] <= 11 for s in range(3, 11)), steady
    assert plan.rate() == pytest.approx(20 + 0.5 * 8)
    assert counts[1] >= 185 and counts[3] >= 10   # at first every server is learnt, at 2 Hz


def test_contenders_are_probed_together_at_most_four_times_per_task_the_robot_sends():
    plan = ProbePlan(contender_rate=4.0, background_rate=0.5, budget=20.0, hold=2.0)
    for server in range(1, 5):
        plan.add(server, 0.0)
    run(plan, 10.0, contenders={1}, task_rate=2.0)
    assert run(plan, 20.0, start=10.0, contenders={1}, task_rate=2.0)[1] == 80   # 4 Hz
    every = run(plan, 20.0, start=30.0, contenders={1, 2, 3, 4}, task_rate=2.0)
    steady = run(plan, 20.0, start=50.0, contenders={1, 2, 3, 4}, task_rate=2.0)
    assert sum(every.values()) < 4 * 80 and steady == {1: 40, 2: 40, 3: 40, 4: 40}   # 2 Hz
    slow = run(plan, 20.0, start=70.0, contenders={1}, task_rate=0.1)   # a frame each 10 s
    assert slow[1] == pytest.approx(10, abs=1) and slow[2] == pytest.approx(10, abs=1)
    assert run(plan, 20.0, start=90.0, contenders={1}, task_rate=None)[1] == 80   # unknown


def test_many_contenders_share_the_budget_but_never_fall_below_the_background_rate():
    plan = ProbePlan(contender_rate=10.0, background_rate=0.5, budget=20.0, hold=1.5)
    for server in range(1, 6):
        plan.add(server, 0.0)
    counts = run(plan, 10.0, start=0.0, contenders=set(range(1, 6)))
    assert all(38 <= counts[s] <= 42 for s in range(1, 6)), counts     # 4 Hz each
    many = ProbePlan(contender_rate=10.0, background_rate=0.5, budget=20.0)
    for server in range(1, 101):
        many.add(server, 0.0)
    assert many.interval(1) == 2.0 and many.rate() == pytest.approx(50.0)


def test_contenders_are_probed_together_in_one_round_a_beat():
    """Whenever they were promoted, contenders come due together: one round of all of them
    each beat (their round trips compared under one load), none between."""
    plan = ProbePlan(contender_rate=10.0, background_rate=0.5, budget=20.0, hold=1.5)
    for server in range(1, 7):
        plan.add(server, 0.0)
    run(plan, 3.0, contenders={1})
    rounds = []
    for i in range(60):
        now = 3.0 + i * plan.tick
        plan.update({1, 2, 3, 4} | ({5} if i > 7 else set()) if i >= 3 else {1, 2}, now)
        if i == 7:
            plan.promote(5, now)                 # a fast re-check: at once, then on the beat
        rounds.append(set(plan.due(now)))
    assert 5 in rounds[7]
    steady = [r for r in rounds[10:] if r & {1, 2, 3, 4, 5}]
    assert all(r == {1, 2, 3, 4, 5} for r in steady), steady
    assert 19 <= len(steady) <= 21, len(steady)     # 20 probes a second over 5: 4 Hz each


def test_probes_per_second_stay_within_20_plus_half_the_servers():
    for servers in (10, 30, 50, 100):
        plan = ProbePlan(contender_rate=10.0, background_rate=0.5, budget=20.0, hold=1.5)
        for server in range(1, servers + 1):
            plan.add(server, 0.0)
        run(plan, 5.0, contenders={1, 2, 3})
        counts = run(plan, 20.0, start=5.0, contenders={1, 2, 3})
        assert sum(counts.values()) / 20.0 <= 20 + 0.5 * servers + 1, (servers, counts)


def test_servers_demoted_together_are_not_probed_together():
    plan = ProbePlan(contender_rate=10.0, background_rate=0.5, budget=20.0, hold=1.0)
    for server in range(1, 101):
        plan.add(server, 0.0)
    run(plan, 1.0, contenders=set())
    per_tick = []
    for i in range(40):                          # two background periods
        now = 1.0 + i * plan.tick
        plan.update(set(), now)
        per_tick.append(len(plan.due(now)))
    assert 195 <= sum(per_tick) <= 200 and max(per_tick) <= 6, per_tick


def test_a_promoted_server_is_probed_at_the_next_tick_and_demoted_after_its_hold():
    plan = ProbePlan(contender_rate=10.0, background_rate=0.5, budget=20.0, hold=1.5)
    for server in (1, 2):
        plan.add(server, 0.0)
    run(plan, 3.0, contenders={1})
    assert plan.contenders == [1] and plan.interval(2) == 2.0
    plan.promote(2, 3.0)
    assert plan.due(3.0) == [1, 2] and plan.contenders == [1, 2]
    counts = run(plan, 1.4, start=3.1, contenders={1})
    assert counts[2] == 14                       # held for 1.5 s at 10 Hz
    run(plan, 0.5, start=4.5, contenders={1})
    assert plan.contenders == [1]


def test_plans_from_parameters():
    table = {'probe_rate': 4.0, 'contender_rate': 0.0, 'background_rate': 0.5,
             'contender_budget': 20.0, 'window': 1.5}
    plan = from_params(table.get)
    assert not plan.adaptive and plan.tick == 0.25
    table['contender_rate'] = 10.0
    plan = from_params(table.get)
    assert plan.adaptive and plan.tick == 0.1 and plan.hold == 1.5
    with pytest.raises(ValueError):
        ProbePlan(contender_rate=0.2, background_rate=0.5)


# -- a far server that comes near, end to end in the pure parts ---------------------------

def test_a_far_server_that_comes_near_is_noticed_within_two_background_periods():
    """Server 3 is 40 ms away and comes to 2 ms (better than the selected 5 ms) at t = 20 s:
    its next background probe puts it near the best by the rule's estimates, it becomes a
    contender, and is then probed at the contender rate."""
    rng, clock = random.Random(3), Clock(0.0)
    truth = {1: 5.0 * MS, 2: 9.0 * MS, 3: 40.0 * MS, 4: 60.0 * MS}
    rule = LeastLatency(window=1.5, clock=clock, rng=random.Random(1))
    plan = ProbePlan(contender_rate=4.0, background_rate=1.0, budget=20.0, hold=1.5)
    for server in truth:
        plan.add(server, 0.0)
    noticed, samples_after = None, 0
    while clock.now < 30.0:
        now = clock.now
        if now >= 20.0:
            truth[3] = 2.0 * MS
        plan.update(rule.contenders(list(truth)), now)
        for server in plan.due(now):
            rule.probed(server, truth[server] + rng.gauss(0, 0.2 * MS))
            if server == 3 and now >= 20.0:
                samples_after += 1
        if now >= 20.0 and noticed is None and 3 in plan.contenders:
            noticed = now - 20.0
        if now > 2.0 and not rule.chosen:
            rule.started(rule.order(list(truth))[0])
        if 19.0 <= now < 20.0:
            assert plan.contenders == [1], (now, plan.contenders)   # 3 in the background
        clock.now = round(now + plan.tick, 6)
    assert noticed is not None and noticed <= 2 * 1.0, noticed
    assert samples_after >= 4 * (10.0 - noticed - 2.0), samples_after


# -- windows with uneven sampling ---------------------------------------------------------

def test_a_rarely_probed_pair_keeps_its_newest_samples_up_to_the_horizon():
    w = LatencyWindow(1.5, keep=3, horizon=8.0)
    for t in (0.0, 2.0, 4.0, 6.0):                        # every 2 s: background
        w.add(1, 9, t, True, 0.040)
    for i in range(60):                                   # 10 Hz: a contender
        w.add(1, 1, i * 0.1, True, 0.005 + 0.001 * (i % 2))
    sparse, dense = w.stats(1, 9, 6.0), w.stats(1, 1, 5.9)
    assert sparse.ok_count == 3 and dense.ok_count == 15   # 3 newest vs 1.5 s of samples
    assert w.stats(1, 9, 13.9).ok_count == 1              # 2 s and 4 s are past 8 s
    assert w.stats(1, 9, 14.1) == EMPTY                    # all past the horizon


def test_a_sparse_pair_has_the_wider_standard_error_of_its_few_samples():
    w = LatencyWindow(1.5, keep=3, horizon=8.0)
    values = [0.005, 0.007, 0.006, 0.008, 0.004]
    for i in range(15):
        w.add(1, 1, 10.0 + i * 0.1, True, values[i % 5])
    for i, t in enumerate((7.0, 9.0, 11.0)):
        w.add(1, 2, t, True, values[i])
    assert w.stats(1, 2, 11.4).se > 1.5 * w.stats(1, 1, 11.4).se


def test_failed_samples_push_the_good_ones_out_of_a_sparse_window():
    w = LatencyWindow(1.5, keep=2, horizon=8.0)
    w.add(1, 2, 0.0, True, 0.010)
    w.add(1, 2, 2.0, False, None)
    assert w.stats(1, 2, 2.0).ok_count == 1
    w.add(1, 2, 4.0, False, None)
    assert w.stats(1, 2, 4.0).ok_count == 0 and w.stats(1, 2, 4.0).failed_count == 2


def test_without_keep_the_window_is_the_papers_time_window():
    w = LatencyWindow(1.5, keep=0, horizon=8.0)
    assert w.horizon == 1.5
    w.add(1, 2, 0.0, True, 0.010)
    assert w.stats(1, 2, 1.6) == EMPTY
    assert LatencyWindow(10.0, keep=3, horizon=8.0).horizon == 10.0   # never below the window
    with pytest.raises(ValueError):
        LatencyWindow(1.5, keep=-1, horizon=8.0)


def test_the_manager_ranks_a_rarely_probed_server_until_its_horizon():
    r = SampleRankings(1.5, keep=3, horizon=8.0)
    r.add(1, 1, 0.0, True, 0.005)
    r.add(1, 2, 0.0, True, 0.040)
    for i in range(1, 60):
        r.add(1, 1, i * 0.1, True, 0.005)
    assert r.rank(1, 5.9).ranking == [1, 2]
    assert r.departures(5.9) == []
    assert r.departures(8.1) == [1] and r.rank(1, 8.1).ranking == [1]


def test_a_probe_round_completes_with_its_last_server_and_keeps_every_sample():
    from server_select.core.robot.probe_plan import ProbeRound
    batch = ProbeRound(7, 1.5, [1, 2, 3])
    assert not batch.record(2, True, 0.002, None)
    assert not batch.record(1, False, 0.5, 0.1)       # a failed probe: no round trip
    assert batch.record(3, True, 0.004, 0.001)
    assert batch.samples == [(2, True, 0.002, 0.0), (1, False, 0.0, 0.1),
                             (3, True, 0.004, 0.001)]
