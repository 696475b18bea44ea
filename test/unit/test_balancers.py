"""The league's peers, each on its defining behaviour (core/peers/balancers.py)."""

import collections
import random

import pytest
from hypothesis import given, settings, strategies as st

from server_select.core.peers import balancers
from server_select.core.peers.balancers import PeakEwma, Prequal
from server_select.core.util.stats import percentile
from server_select.core.load.work_queue import Load
from server_select.core.flow.task_flow import TaskFlow

from support.clock import Clock


def load(rif, work=0.01, workers=1):
    return Load(rif, 0, workers, 0.0, {'sort': work}, 0.0)


# -- peak-EWMA ---------------------------------------------------------------------------

def test_peak_ewma_takes_a_peak_at_once_and_decays_towards_lower_samples():
    e = PeakEwma(0.0, tau=10.0, initial=1.0)
    e.observe(0.02, 0.0)              # below the 1 s start, no time passed: stays high
    assert e.estimate == pytest.approx(1.0)
    e.observe(0.02, 10.0)             # one tau later: 1/e of the old estimate is left
    assert e.estimate == pytest.approx(1.0 / 2.718281828 + 0.02 * (1 - 1 / 2.718281828),
                                       rel=1e-6)
    e.observe(3.0, 10.5)              # a peak replaces it
    assert e.estimate == 3.0


def test_peak_ewma_decays_towards_zero_while_nothing_is_observed():
    e = PeakEwma(0.0, tau=10.0, initial=1.0)
    assert e.get(0.0) == pytest.approx(1.0)
    assert e.get(20.0) == pytest.approx(1.0 * 2.718281828 ** -2, rel=1e-6)
    assert e.get(100.0) < 0.001       # a server left alone is tried again


def send(balancer, servers, kind=None):
    """Ask where a task goes and send it there (what the rule changes, it changes here)."""
    order = balancer.order(servers, kind)
    balancer.started(order[0], kind, order=order)
    return order[0]


# -- two random choices --------------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1),
       out=st.lists(st.integers(0, 5), min_size=2, max_size=6),
       rtts=st.lists(st.floats(0.001, 2.0), min_size=6, max_size=6))
def test_two_choice_rules_never_take_the_worse_of_the_pair_they_drew(seed, out, rtts):
    servers = list(range(1, len(out) + 1))
    clock = Clock(5.0)
    p2c = balancers.make('p2c_peak_ewma', rng=random.Random(seed), clock=clock)
    lr = balancers.make('least_request', rng=random.Random(seed), clock=clock)
    for b in (p2c, lr):
        for server, n in zip(servers, out):
            b.ended(server, rtts[server - 1])     # one sample each
            for _ in range(n):
                b.started(server)
    clock.now += 1.0
    for _ in range(5):
        a, b = p2c._two(servers)                  # the pair its next decision draws
        cost = dict((s, p2c.cost(s, clock())) for s in (a, b))
        first = send(p2c, servers)
        assert a != b and first in (a, b) and cost[first] <= min(cost.values())
        a, b = lr._two(servers)
        out = dict(lr.attempts_out)
        first = send(lr, servers)
        assert a != b and first in (a, b) and out.get(first, 0) <= min(out.get(a, 0),
                                                                       out.get(b, 0))
        if out.get(a, 0) == out.get(b, 0):
            assert first == a                     # Envoy: a tie keeps the first drawn


def test_p2c_cost_counts_the_attempts_out():
    clock = Clock(0.0)
    b = balancers.make('p2c_peak_ewma', clock=clock)
    b.ended(1, 0.1)
    b.ended(2, 0.1)
    b.started(1)
    b.started(1)
    assert b.cost(1, clock()) == pytest.approx(3 * b.cost(2, clock()))
    assert b.order([1, 2])[0] == 2        # the only pair there is: the cheaper wins


def test_least_request_spreads_one_robots_tasks_over_every_server():
    b = balancers.make('least_request', rng=random.Random(3))
    for _ in range(30):
        send(b, [1, 2, 3])
    out = b.attempts_out.values()
    assert max(out) - min(out) <= 2 and sum(out) == 30


def test_attempts_that_end_are_no_longer_out():
    b = balancers.make('least_request')
    b.started(1)
    b.ended(1, None)
    b.ended(1, None)          # never below zero
    assert b.attempts_out[1] == 0


# -- Prequal ------------------------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(answers=st.lists(st.tuples(st.integers(1, 5), st.integers(0, 20),
                                  st.floats(0.001, 0.5)), min_size=2, max_size=24),
       seed=st.integers(0, 1000))
def test_prequal_never_picks_a_hot_server_while_a_cold_one_exists(answers, seed):
    clock = Clock(0.0)
    b = Prequal(rng=random.Random(seed), clock=clock)
    for server, rif, rtt in answers:
        b.probed(server, rtt, load(rif))
    pool = [e[0] for e in b.pool]
    limit = percentile(sorted(a.rif for a in pool), 100 * b.q)
    cold = [a for a in pool if a.rif <= limit]
    first = b.order([1, 2, 3, 4, 5], 'sort')[0]
    best_cold = min(cold, key=lambda a: (b.latency(a, 'sort'), a.rif))
    assert first == best_cold.server                   # there is always a cold answer
    assert b.latency(best_cold, 'sort') <= min(b.latency(a, 'sort') for a in cold)


def test_prequal_takes_the_lowest_latency_among_the_cold_and_avoids_the_hot():
    clock = Clock(0.0)
    b = Prequal(clock=clock)
    b.probed(1, 0.001, load(9))       # nearest, but 9 in flight: hot
    b.probed(2, 0.010, load(1))
    b.probed(3, 0.005, load(1))
    b.probed(4, 0.020, load(0))
    assert b.order([1, 2, 3, 4], 'sort') == [3, 2, 4, 1]


def test_prequal_with_fewer_than_two_fresh_answers_picks_at_random():
    clock = Clock(0.0)
    b = Prequal(rng=random.Random(1), clock=clock)
    b.probed(1, 0.001, load(0))
    b.probed(2, 0.001, load(0))
    clock.now += 1.5                # older than the pool's 1 s: gone
    b.probed(3, 0.001, load(0))
    picks = collections.Counter(send(b, [1, 2, 3], 'sort') for _ in range(300))
    assert set(picks) == {1, 2, 3} and min(picks.values()) > 60
    assert len(b.pool) == 1


def test_prequal_pool_holds_16_answers_and_spends_one_per_task():
    clock = Clock(0.0)
    b = Prequal(clock=clock)
    for i in range(20):
        b.probed(1 + i % 4, 0.01, load(i % 3))
    assert len(b.pool) == 16
    b.order([1, 2, 3, 4], 'sort')
    assert len(b.pool) == 16          # asking spends nothing
    send(b, [1, 2, 3, 4], 'sort')
    assert len(b.pool) == 15          # each task uses one up, or removes the oldest or worst


def test_prequal_latency_adds_the_servers_work_for_the_kind():
    clock = Clock(0.0)
    b = Prequal(clock=clock)
    b.probed(1, 0.001, Load(0, 0, 1, 0.0, {'image': 0.5}, 0.0))     # near, slow at images
    b.probed(2, 0.020, Load(0, 0, 1, 0.0, {'image': 0.1}, 0.0))
    assert b.order([1, 2], 'image')[0] == 2


# -- weighted round robin, replication --------------------------------------------------------

def test_round_robin_follows_the_workers_weights_smoothly():
    b = balancers.make('round_robin')
    b.probed(1, 0.01, load(0, workers=3))
    b.probed(2, 0.01, load(0, workers=1))
    turns = [send(b, [1, 2]) for _ in range(8)]
    assert turns.count(1) == 6 and turns.count(2) == 2
    assert 'x'.join(map(str, turns)).count('1x1x1x1') == 0      # never 4 in a row


def test_replicate_sends_two_copies_to_the_two_nearest_by_probes():
    b = balancers.make('replicate')
    for rtt1, rtt2, rtt3 in ((0.03, 0.01, 0.02), (0.03, 0.01, 0.02)):
        b.probed(1, rtt1)
        b.probed(2, rtt2)
        b.probed(3, rtt3)
    assert b.copies == 2 and b.order([1, 2, 3])[:2] == [2, 3]


def test_unknown_balancer_is_refused():
    with pytest.raises(ValueError):
        balancers.make('fastest')


# -- with the task flow: copies, and every attempt ends once --------------------------------

def flow(balancer, clock, published, reports, copies=1):
    return TaskFlow('sort', 2.0, lambda: balancer.order([1, 2, 3]),
                    make=lambda task_id, stamp: (task_id, None),
                    publish=lambda request, server, budget: published.append((request, server)),
                    check=lambda result, context: None, report=reports.append,
                    clock=clock, attempts=balancer, copies=copies)


def test_replicated_task_goes_to_two_servers_and_the_first_answer_wins():
    clock, published, reports = Clock(0.0), [], []
    b = balancers.make('replicate', clock=clock)
    b.probed(1, 0.01)
    b.probed(2, 0.02)
    b.probed(3, 0.03)
    f = flow(b, clock, published, reports, copies=b.copies)
    task = f.send_next('s')
    assert published == [(task, 1), (task, 2)] and b.attempts_out == {1: 1, 2: 1}
    clock.now += 0.05
    assert f.resolve(task, 2, True).status == 'ended'
    assert f.resolve(task, 1, True).status == 'outrun'
    assert len(reports) == 1 and reports[0].answered_by == 2 and reports[0].attempts == 2
    assert sum(b.attempts_out.values()) == 0 and f.replicated == 1


def test_every_attempt_ends_once_whatever_ends_the_task():
    clock, published, reports = Clock(0.0), [], []
    b = balancers.make('least_request', rng=random.Random(2), clock=clock)
    f = flow(b, clock, published, reports)
    ok, errs = f.send_next('a'), f.send_next('b')
    f.send_next('c')                                        # never answered
    f.resolve(ok, published[0][1], True)
    f.resolve(errs, published[1][1], False, 'bad')       # re-sent elsewhere
    assert sum(b.attempts_out.values()) == 2                        # errs' second attempt, late's
    clock.now += 2.5
    f.tick()                                               # both past the 2 s timeout
    assert sum(b.attempts_out.values()) == 0 and len(reports) == 3
    f.send_next('d')
    f.abandon('stopping')
    assert sum(b.attempts_out.values()) == 0 and len(reports) == 4
