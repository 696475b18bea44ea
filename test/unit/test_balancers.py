"""The league's peers, each on its defining behaviour (core/selection/balancers.py)."""

import collections
import random

import pytest
from hypothesis import given, settings, strategies as st

from server_select.core.selection import balancers
from server_select.core.selection.balancers import PeakEwma, Prequal
from server_select.core.util.stats import percentile
from server_select.core.load.work_queue import Load
from server_select.core.flow.task_flow import TaskFlow

from support.clock import Clock


class Recorded(random.Random):
    """A random source that remembers the pairs it drew."""

    def __init__(self, seed):
        random.Random.__init__(self, seed)
        self.drawn = []

    def sample(self, population, k):
        out = random.Random.sample(self, population, k)
        self.drawn.append(list(out))
        return out


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


# -- two random choices --------------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1),
       out=st.lists(st.integers(0, 5), min_size=2, max_size=6),
       rtts=st.lists(st.floats(0.001, 2.0), min_size=6, max_size=6))
def test_two_choice_rules_never_take_the_worse_of_the_pair_they_drew(seed, out, rtts):
    servers = list(range(1, len(out) + 1))
    clock = Clock(5.0)
    p2c = balancers.make('p2c_peak_ewma', rng=Recorded(seed), clock=clock)
    lr = balancers.make('least_request', rng=Recorded(seed), clock=clock)
    for b in (p2c, lr):
        for server, n in zip(servers, out):
            b.ended(server, rtts[server - 1])     # one sample each
            for _ in range(n):
                b.started(server)
    clock.now += 1.0
    for _ in range(5):
        first = p2c.order(servers)[0]
        a, b = p2c.rng.drawn[-1]
        cost = dict((s, p2c.cost(s, clock())) for s in (a, b))
        assert first in (a, b) and cost[first] <= min(cost.values())
        first = lr.order(servers)[0]
        a, b = lr.rng.drawn[-1]
        assert first in (a, b) and lr.out[first] <= min(lr.out[a], lr.out[b])
        if lr.out[a] == lr.out[b]:
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
        b.started(b.order([1, 2, 3])[0])
    assert sorted(b.out.values()) == [10, 10, 10]


def test_attempts_that_end_are_no_longer_out():
    b = balancers.make('least_request')
    b.started(1)
    b.ended(1, None)
    b.ended(1, None)          # never below zero
    assert b.out[1] == 0


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
    picks = collections.Counter(b.order([1, 2, 3], 'sort')[0] for _ in range(300))
    assert set(picks) == {1, 2, 3} and min(picks.values()) > 60
    assert len(b.pool) == 1


def test_prequal_pool_holds_16_answers_and_spends_one_per_task():
    clock = Clock(0.0)
    b = Prequal(clock=clock)
    for i in range(20):
        b.probed(1 + i % 4, 0.01, load(i % 3))
    assert len(b.pool) == 16
    b.order([1, 2, 3, 4], 'sort')
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
    turns = [b.order([1, 2])[0] for _ in range(8)]
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
    assert published == [(task, 1), (task, 2)] and b.out == {1: 1, 2: 1}
    clock.now += 0.05
    assert f.resolve(task, 2, True).status == 'ended'
    assert f.resolve(task, 1, True).status == 'duplicate'
    assert len(reports) == 1 and reports[0].answered_by == 2 and reports[0].attempts == 2
    assert sum(b.out.values()) == 0 and f.replicated == 1


def test_every_attempt_ends_once_whatever_ends_the_task():
    clock, published, reports = Clock(0.0), [], []
    b = balancers.make('least_request', rng=random.Random(2), clock=clock)
    f = flow(b, clock, published, reports)
    ok, errs = f.send_next('a'), f.send_next('b')
    f.send_next('c')                                        # never answered
    f.resolve(ok, published[0][1], True)
    f.resolve(errs, published[1][1], False, 'bad')       # re-sent elsewhere
    assert sum(b.out.values()) == 2                        # errs' second attempt, late's
    clock.now += 2.5
    f.tick()                                               # both past the 2 s timeout
    assert sum(b.out.values()) == 0 and len(reports) == 3
    f.send_next('d')
    f.abandon('stopping')
    assert sum(b.out.values()) == 0 and len(reports) == 4


# -- the fleet's rule, hot_cold --------------------------------------------------------------

def hot_cold(clock, seed=1):
    return balancers.make('hot_cold', rng=random.Random(seed), clock=clock)


def feed(rule, clock, answers, rounds=5):
    """``answers``: {server: (rtt, rif, utilization)}, given ``rounds`` times each."""
    for _ in range(rounds):
        for server, (rtt, rif, utilization) in sorted(answers.items()):
            rule.probed(server, rtt, Load(rif, 0, 1, 0.0, {'image': 0.1}, utilization))
        clock.now += 0.1


def test_hot_cold_never_picks_a_hot_server_while_a_cold_one_exists():
    clock = Clock()
    rule = hot_cold(clock)
    feed(rule, clock, {1: (0.001, 4, 0.0), 2: (0.05, 0, 0.0), 3: (0.08, 0, 0.0)})
    # server 1 is nearest but hot (4 in flight against the others' 0): the fastest cold wins
    assert rule.order([1, 2, 3], 'image')[0] == 2


def test_hot_cold_every_answer_hot_or_equal_takes_the_fastest():
    clock = Clock()
    rule = hot_cold(clock)
    feed(rule, clock, {1: (0.030, 1, 0.0), 2: (0.010, 1, 0.0)})
    assert rule.order([1, 2], 'image')[0] == 2


def test_hot_cold_keeps_its_server_within_the_noise_and_leaves_beyond_it():
    clock = Clock()
    rule = hot_cold(clock)
    jitter = [0.0, 0.004, -0.004, 0.002, -0.002]
    for j in jitter:      # 1 ms apart under +-4 ms of noise: not a reason to move
        rule.probed(1, 0.011 + j, Load(0, 0, 1, 0.0, {'image': 0.1}, 0.0))
        rule.probed(2, 0.010 - j, Load(0, 0, 1, 0.0, {'image': 0.1}, 0.0))
        clock.now += 0.1                                 # probes at 10 Hz
    rule.current = 1
    assert [rule.order([1, 2], 'image')[0] for _ in range(20)] == [1] * 20
    for _ in range(5):    # server 2 is now 20 ms nearer: far beyond the noise
        rule.probed(1, 0.030, Load(0, 0, 1, 0.0, {'image': 0.1}, 0.0))
        rule.probed(2, 0.010, Load(0, 0, 1, 0.0, {'image': 0.1}, 0.0))
        clock.now += 0.1
    assert rule.order([1, 2], 'image')[0] == 2
    assert 'faster' in rule.why


def choice_after(answers):
    """Where a robot whose last task went to server 1 sends its next after 16 answers of
    each server, 0.1 s apart: ``answers(i)`` gives the i-th (server 1's, server 2's) Load."""
    clock = Clock()
    rule = hot_cold(clock)
    rule.current = 1
    for i in range(16):
        for server, load in zip((1, 2), answers(i)):
            rule.probed(server, 0.001, load)
        clock.now += 0.1
    return rule.order([1, 2], 'image')[0]


def test_hot_cold_counts_answers_that_saw_one_queue_as_one():
    # server 1 had another robot's task queued for the first 0.8 s of the window and
    # none since; server 2 none
    def verdict(work):
        return choice_after(lambda i: (Load(int(i < 8), 0, 1, 0.0, {'image': work}, 0.0),
                                       Load(0, 0, 1, 0.0, {'image': work}, 0.0)))
    # with 0.5 s of work a frame the queue changed once in the window: one observation
    # that server 1 is busier, not 8: the robot stays; with 20 ms of work the queue was
    # seen queued and empty many times over: server 1 is slower, the robot leaves
    assert verdict(0.5) == 1
    assert verdict(0.02) == 2


def test_hot_cold_counts_the_error_of_the_servers_reported_work():
    # two idle servers whose medians of their recent frames differ by 30 ms in 450
    def verdict(error):
        return choice_after(lambda i: (
            Load(0, 0, 1, 0.0, {'image': 0.45}, 0.0, {'image': error}),
            Load(0, 0, 1, 0.0, {'image': 0.42}, 0.0, {'image': error})))
    # medians known to 15 ms each: 30 ms is within 3 errors of their difference (64 ms):
    # the robot stays; medians reported without error: 30 ms is a reason to move
    assert verdict(0.015) == 1
    assert verdict(0.0) == 2


def test_hot_cold_ranks_by_expected_completion_with_the_work_in_flight():
    clock = Clock()
    rule = hot_cold(clock)
    # server 1 is 20 ms nearer, but another robot's 0.1 s frame is always ahead there
    feed(rule, clock, {1: (0.010, 1, 0.0), 2: (0.030, 0, 0.0)})
    assert rule.order([1, 2], 'image')[0] == 2


def test_hot_cold_leaves_out_the_robots_own_task_and_one_odd_answer():
    clock = Clock()
    rule = hot_cold(clock)
    feed(rule, clock, {1: (0.010, 0, 0.0), 2: (0.020, 0, 0.0)})
    assert rule.order([1, 2], 'image')[0] == 1
    rule.started(1)                      # its own frame is at server 1 now
    feed(rule, clock, {1: (0.010, 1, 0.0), 2: (0.020, 0, 0.0)}, rounds=3)
    rule.probed(1, 0.010, Load(2, 0, 1, 0.0, {'image': 0.1}, 0.0))   # one other caught
    assert rule.order([1, 2], 'image')[0] == 1


def test_hot_cold_without_answers_picks_at_random_and_stays():
    clock = Clock()
    picks = set()
    for seed in range(20):
        rule = hot_cold(clock, seed)
        first = rule.order([1, 2, 3], 'image')[0]
        assert rule.order([1, 2, 3], 'image')[0] == first
        picks.add(first)
    assert picks == {1, 2, 3}


def test_hot_cold_leaves_an_ejected_server_at_once():
    clock = Clock()
    rule = hot_cold(clock)
    feed(rule, clock, {1: (0.010, 0, 0.0), 2: (0.020, 0, 0.0)})
    assert rule.order([1, 2], 'image')[0] == 1
    assert rule.order([2], 'image') == [2]       # the caller left out server 1


def herd(seed, robots=20, steps=150, work=0.04):
    """20 robots on server 1 (each a task a second of ``work`` s), server 2 comes up idle
    at step 20; every 0.2 s each robot hears both servers' load as the robots' previous
    choices made it, and about one in five sends a task. The count on server 1 each step,
    and the moves by reason."""
    clock, rng = Clock(), random.Random(seed)
    rules = [hot_cold(clock, seed * 100 + i) for i in range(robots)]
    on = [1] * robots
    for rule in rules:
        rule.current = 1
    servers, counts = [1], []
    for step in range(steps):
        servers = [1, 2] if step >= 20 else [1]
        total = collections.Counter(on)
        for i, rule in enumerate(rules):
            for s in servers:
                utilization = (total[s] - (on[i] == s)) * work
                rule.probed(s, 0.010 + rng.gauss(0, 0.0005),
                            Load(int(rng.random() < utilization), 0, 1, 0.0,
                                 {'image': work}, utilization))
        for i, rule in enumerate(rules):
            if rng.random() < 0.2:
                on[i] = rule.order(servers, 'image')[0]
        clock.now += 0.2
        counts.append(on.count(1))
    return counts, sum((r.moves for r in rules), collections.Counter())


def test_hot_cold_robots_spread_to_a_new_server_without_a_herd():
    for seed in range(3):
        counts, moves = herd(seed)
        # no herd: never all (or nearly all) at once on the new server, and settled near
        # half and half, with few moves (one per robot that should move, and some)
        assert min(counts[20:]) >= 5, counts
        assert all(7 <= n <= 13 for n in counts[-10:]), counts
        assert sum(moves.values()) <= 25, moves


def overload(seed, works=(1.25, 0.833, 0.625), robots=6, rate=1.2, steps=300, lag=5):
    """6 robots streaming ``rate`` frames/s to 3 servers of unequal speed (``works``: s of
    work a frame, one worker each) at twice what they can do together, all choosing at
    once at the start; every 0.2 s each robot hears each server's load as the robots'
    choices ``lag`` steps before made it (its answers lag), and sends a frame at its rate.
    Robots per server each step, and the moves by reason."""
    clock, rng = Clock(), random.Random(seed)
    rules = [hot_cold(clock, seed * 100 + i) for i in range(robots)]
    on, counts = [None] * robots, []
    past = [list(on)] * (lag + 1)
    for step in range(steps):
        seen = past[-lag - 1]
        total = collections.Counter(seen)
        for i, rule in enumerate(rules):
            for s, work in enumerate(works, start=1):
                utilization = (total[s] - (seen[i] == s)) * rate * work
                rif = min(utilization, 2.0)
                rule.probed(s, 0.001 + rng.gauss(0, 0.0002),
                            Load(int(rif) + (rng.random() < rif - int(rif)), 0, 1, 0.0,
                                 {'image': work}, utilization))
        for i, rule in enumerate(rules):
            if on[i] is None or rng.random() < rate * 0.2:
                on[i] = rule.order([1, 2, 3], 'image')[0]
        clock.now += 0.2
        past.append(list(on))
        counts.append(tuple(on.count(s) for s in (1, 2, 3)))
    return counts, sum((r.moves for r in rules), collections.Counter())


def goodput(counts, works=(1.25, 0.833, 0.625), rate=1.2):
    """The share of the servers' capacity a split of robots ``counts`` keeps busy."""
    return sum(min(n * rate, 1 / w) for n, w in zip(counts, works)) / sum(1 / w for w in works)


def test_hot_cold_robots_that_read_alike_spread_over_unequal_servers_in_overload():
    moved = []
    for seed in range(5):
        counts, moves = overload(seed)
        # the robots all start on the fastest server (its answers were idle) and each
        # moves with the share of its like that makes the servers meet: the proportional
        # split (1:2:3) within seconds, no herd from server to server
        assert counts[0] == (0, 0, 6), counts[0]
        kept = [goodput(c) for c in counts[50:]]
        assert sum(kept) / len(kept) >= 0.97, (counts[::10], moves)
        assert counts[-1] == (1, 2, 3), counts[-10:]
        moved.append(moves['faster'] + moves['hot'])
    assert sorted(moved)[2] <= 12, moved      # median: 2 moves a minute a robot at most


def test_hot_cold_share_of_robots_alike_that_move():
    clock = Clock()
    rule = hot_cold(clock)
    rule.current = 3
    works = {1: 1.25, 2: 0.833, 3: 0.625}
    for _ in range(5):     # five others like it on server 3 (0.75 of its time each)
        for s, u in ((1, 0.0), (2, 0.0), (3, 5 * 1.2 * 0.625)):
            rule.probed(s, 0.001, Load(0, 0, 1, 0.0, {'image': works[s]}, u))
        rule.sends['image'].append(clock.now)
        clock.now += 1 / 1.2
    fresh = dict(rule.probes)
    rate = rule.rate('image', clock.now)
    share = rule.share(3, 2, 'image', fresh, rate, clock.now)
    # 6-7 alike on server 3 (its rate over the last 5 s is 0.96 frames/s): one to three
    # moving to server 2 make the two meet, not all of them; and each decides 1.44 times
    # in a window (1.5 s) before its answers show who moved
    alike = 1 + 5 * 1.2 * 0.625 / (rate * 0.625)
    assert 1 / alike / (rate * 1.5) <= share <= 3 / alike / (rate * 1.5), share
    assert rule.share(3, 2, 'image', fresh, 0.0, clock.now) == 1.0   # own load unknown


def test_hot_cold_a_task_sent_again_at_once_does_not_make_the_robot_move_for_certain():
    """A robot's second attempt right after its first (a busy answer, sent on): its rate
    is counted over the horizon, not from the gap between the two (10 ms: 100 tasks/s,
    an own load that swamped every server alike: it stayed beside two idle servers)."""
    works = {1: 1.25, 2: 0.833, 3: 0.625}
    moved = 0
    for seed in range(200):
        clock = Clock()
        rule = hot_cold(clock, seed)
        rule.current = 3
        for s, u in ((1, 0.0), (2, 0.0), (3, 5 * 1.2 * 0.625)):   # five others on 3
            rule.probed(s, 0.001, Load(0, 0, 1, 0.0, {'image': works[s]}, u))
        rule.sends['image'].append(clock.now - 0.01)
        assert rule.rate('image', clock.now) == pytest.approx(2 / 5.0)    # and this one
        moved += rule.order([1, 2, 3], 'image')[0] != 3
    # one to three of six alike make servers 2 and 3 meet: about a third of them moves
    assert 20 <= moved <= 120, moved


def test_hot_cold_counts_its_own_rate_from_the_attempts_sent_not_from_being_asked():
    clock = Clock()
    rule = hot_cold(clock)
    for s in (1, 2):
        rule.probed(s, 0.001, Load(0, 0, 1, 0.0, {'sort': 0.002}, 0.0))
    for _ in range(5):                                  # asked, nothing sent
        rule.order([1, 2], 'sort')
    assert rule.rate('sort', clock.now) == pytest.approx(1 / 5.0)   # the one it decides
    for _ in range(3):
        rule.started(rule.order([1, 2], 'sort')[0], 'sort')
        clock.now += 0.5
    assert rule.rate('sort', clock.now) == pytest.approx(4 / 5.0)
    assert rule.rate('image', clock.now) == pytest.approx(1 / 5.0)
