"""A server's work queue (admission by deadline, shedding, backlog), what a load-aware
robot's deadlines read of its rule's estimates, and the retry budget, without a master."""

import math
import random
import statistics
import threading

import pytest

from server_select.core.flow.budget import RetryBudget
from server_select.core.load.demand import Arrivals, Demand
from server_select.core.load.service_times import ServiceTimes
from server_select.core.load.work_queue import Load, WorkQueue
from server_select.core.robot.robot_load import RobotLoad
from server_select.core.rule.least_latency import LeastLatency
from server_select.core.util.stats import median_error

from support.clock import Clock


def queue_with(work, workers=1, max_queue=10, kind='image'):
    """A queue whose ``kind`` tasks are known to take ``work`` s."""
    clock = Clock()
    times = ServiceTimes()
    times.add(kind, work)
    return WorkQueue(workers, max_queue, times, clock), clock


def test_service_times_are_the_median_of_the_recent_ones():
    times = ServiceTimes(keep=3)
    assert times.get('sort') == 0.0           # none yet: optimistic
    for seconds in (0.1, 0.9, 0.2, 0.3):      # the first one is forgotten
        times.add('sort', seconds)
    assert times.get('sort') == pytest.approx(0.3)
    assert times.snapshot() == {'sort': pytest.approx(0.3)}
    # the median's standard error: sqrt(pi / 2) x their standard deviation / sqrt(3)
    spread = statistics.stdev([0.9, 0.2, 0.3])
    assert times.errors() == {'sort': pytest.approx(1.2533 * spread / 3 ** 0.5)}
    times.add('image', 0.5)
    assert times.errors()['image'] == 0.0     # one task: no spread known


def test_service_times_follow_a_step_in_the_work_within_the_last_second():
    clock = Clock()
    times = ServiceTimes(clock=clock)
    for _ in range(20):                      # 4 tasks a second of 1 ms each
        times.add('sort', 0.001)
        clock.now += 0.25
    tasks = 0
    while times.get('sort') < 0.026:         # each now 25 ms longer (a busy machine)
        times.add('sort', 0.026)
        clock.now += 0.25
        tasks += 1
    # the median of the last second's five: the third slow task shows it (0.75 s; of the
    # last 20 tasks, the eleventh would: 2.75 s)
    assert tasks == 3
    for _ in range(3):                       # rare tasks: the newest three still count
        clock.now += 9.0
        times.add('image', 0.5)
    times.add('image', 0.8)
    assert times.get('image') == pytest.approx(0.5) and times.errors()['image'] > 0


def test_a_kind_left_idle_reports_its_typical_work_until_a_task_measures_it():
    clock = Clock()
    times = ServiceTimes(idle=10.0, clock=clock)
    calm = [0.25, 0.26, 0.24] * 4
    for seconds in calm + [0.8] * 6:         # calm, then a burst's frames
        times.add('image', seconds)
        clock.now += 0.5
    assert times.get('image') == pytest.approx(0.8)
    clock.now += 9.0                          # the robots left: what it did, for a while
    assert times.snapshot() == {'image': pytest.approx(0.8)}
    clock.now += 1.0                          # then what it typically took, not the burst
    typical, error = median_error(calm + [0.8] * 6)
    assert 0.24 <= typical <= 0.26 and 0 < error < 0.01     # the calm, not the burst
    assert times.get('image') == pytest.approx(typical)
    assert times.snapshot() == {'image': pytest.approx(typical)}
    assert times.errors() == {'image': pytest.approx(error)}
    times.add('image', 0.3)                   # the next task is measured alone
    assert times.get('image') == pytest.approx(0.3) and times.errors() == {'image': 0.0}
    assert times.get('sort', None) is None    # a kind never done: the caller's default


def test_a_server_left_idle_looks_no_faster_than_one_still_in_use():
    """Identical servers on a shared CPU: the work of each second's tasks varies. A server
    the robots just left must not report the luck of its best second out of many (its
    least median was 20 % under its typical work here, and robots moved to it for
    nothing), but what it typically took, within that median's error."""
    rng, clock = random.Random(5), Clock()
    times = ServiceTimes(idle=10.0, clock=clock)
    draws = [0.4 * math.exp(rng.gauss(0.0, 0.2)) for _ in range(300)]
    for seconds in draws:                     # 2 tasks a second for 150 s
        times.add('sort', seconds)
        clock.now += 0.5
    clock.now += 10.5
    _, error = median_error(draws[-60:])
    assert abs(times.get('sort') - statistics.median(draws)) < 3 * error


def frames_alone(q, clock, seconds, count):
    """``count`` frames of ``seconds`` each, one at a time, 0.5 s apart."""
    for _ in range(count):
        q.offer('image', 'x')
        q.done(q.take(), seconds)
        clock.now += 0.5


def test_a_server_left_after_a_long_burst_reports_what_its_tasks_took_alone():
    """Robots fled a server whose frames ran side by side for long (more of them than
    its history holds) and slowly: left idle, it says what a frame took alone, as its
    next one will run, not what the burst's took."""
    clock = Clock()
    q = WorkQueue(2, 10, clock=clock)
    frames_alone(q, clock, 0.25, 10)
    for _ in range(40):                       # two at a time, each twice as slow
        q.offer('image', 'a')
        q.offer('image', 'b')
        first, second = q.take(), q.take()
        q.done(first, 0.5)
        q.done(second, 0.5)
        clock.now += 0.5
    assert q.load().service == {'image': pytest.approx(0.5)}
    clock.now += 10.5
    assert q.load().service == {'image': pytest.approx(0.25)}


def test_a_one_worker_server_left_after_a_queue_reports_its_alone_work_a_second_on():
    """One worker, a burst that kept tasks waiting (their data received and decoded on the
    same CPU made each slower): those did not run alone, so a second after the last one
    the server reports what a frame took alone, not the burst's for 10 s; a kind whose
    last tasks ran alone keeps saying what they took."""
    clock = Clock()
    q = WorkQueue(1, 10, clock=clock)
    frames_alone(q, clock, 0.25, 10)
    q.offer('image', 'a')
    for _ in range(20):                       # a queue: each taken with another waiting
        q.offer('image', 'b')
        q.done(q.take(), 0.6)
        clock.now += 0.5
    q.done(q.take(), 0.6)                     # the last, alone
    assert q.load().service == {'image': pytest.approx(0.6)}
    clock.now += 0.6
    assert q.load().service == {'image': pytest.approx(0.6)}     # not yet a second
    clock.now += 0.5
    assert q.load().service == {'image': pytest.approx(0.25)}
    frames_alone(q, clock, 0.6, 4)            # slow frames, each alone: a slowed server
    clock.now += 5.0
    assert q.load().service == {'image': pytest.approx(0.6)}


def test_a_queue_admits_by_what_an_idle_kind_typically_took():
    clock = Clock()
    q = WorkQueue(1, 10, clock=clock)
    for seconds in (0.2,) * 6 + (1.0,) * 3:   # a burst ends its last three
        assert q.offer('image', 'x') is None
        q.done(q.take(), seconds)
        clock.now += 0.3
    assert q.offer('image', 'a', deadline=clock.now + 0.5).startswith('busy')
    clock.now += 11.0
    assert q.offer('image', 'b', deadline=clock.now + 0.5) is None
    assert q.load().service == {'image': pytest.approx(0.2)}


def test_an_idle_server_takes_what_it_can_finish_in_time_and_refuses_the_rest():
    q, clock = queue_with(0.5)
    assert q.offer('image', 'a', deadline=clock.now + 0.6) is None
    assert q.load().backlog == pytest.approx(0.5)          # one worker, one task of 0.5 s
    why = q.offer('image', 'b', deadline=clock.now + 0.9)  # would finish at 1.0 s
    assert why.startswith('busy: would finish in 1 s') and q.refused == 1
    assert q.offer('image', 'c', deadline=None) is None    # no deadline: queued
    assert (q.load().queued, q.load().in_service) == (2, 0)


def test_the_backlog_counts_the_work_left_of_tasks_in_service_over_the_workers():
    q, clock = queue_with(1.0, workers=2)
    for item in 'abc':
        assert q.offer('image', item) is None
    assert q.load().backlog == pytest.approx(1.5)   # 3 s of work, 2 workers
    first, second = q.take(), q.take()
    clock.now += 0.4                                 # both 0.4 s into their 1 s of work
    # (three arrivals at one instant: three per 10 s horizon, 1 s of work each, 2 workers)
    assert q.load() == Load(1, 2, 2, pytest.approx((1.0 + 0.6 + 0.6) / 2), {'image': 1.0},
                            pytest.approx(0.3 * 1.0 / 2), {'image': 0.0})
    q.done(first, 1.0)
    q.done(second, 1.0)
    assert q.load().backlog == 0.0                   # one queued, a worker free: no wait


def test_a_robot_is_told_the_backlog_of_the_others_tasks_not_of_its_own():
    q, clock = queue_with(1.0)
    assert q.offer('image', 'mine', owner=7) is None
    mine = q.take()
    clock.now += 0.25
    # one worker busy with robot 7's task: another robot waits for it, robot 7 does not
    # (it keeps one task out: its next comes when this one is done)
    assert q.load().backlog == pytest.approx(0.75)
    assert q.load(excluding=7).backlog == 0.0
    assert q.load(excluding=3).backlog == pytest.approx(0.75)
    assert q.offer('image', 'theirs', owner=3) is None
    assert q.load(excluding=7).backlog == pytest.approx(1.0)     # robot 3's task waits
    assert q.load(excluding=3).backlog == pytest.approx(0.75)
    assert q.load(excluding=7).queued == 1            # the counts are of every task
    q.done(mine, 1.0)
    assert q.load(excluding=3).backlog == 0.0


def test_a_full_queue_answers_busy_at_once():
    q, _ = queue_with(0.0, max_queue=2)
    assert q.offer('sort', 1) is None and q.offer('sort', 2) is None
    assert q.offer('sort', 3) == 'busy: 2 tasks queued already'


def test_a_task_whose_deadline_passed_in_the_queue_is_shed_not_done():
    q, clock = queue_with(0.5)
    q.offer('image', 'old', deadline=clock.now + 0.6)
    clock.now += 0.2                     # its work no longer fits: 0.2 + 0.5 > 0.6
    job = q.take()
    assert q.stale(job).startswith('busy: waited 0.2 s') and q.shed == 1
    assert q.load().in_service == 0
    q.offer('image', 'fresh', deadline=clock.now + 5.0)
    job = q.take()
    assert q.stale(job) is None and job.item == 'fresh'


def test_a_kind_not_timed_yet_needs_as_long_as_its_task_in_service_has_taken():
    """Six robots' first frames at one idle server: while none has been timed, the one in
    service says how long a frame takes at least; the others wait behind that, frames
    that cannot make their deadline behind it are refused, and the report says so."""
    clock = Clock()
    q = WorkQueue(1, 10, ServiceTimes(), clock)
    for robot in range(6):
        assert q.offer('image', robot, deadline=clock.now + 2.5, owner=robot) is None
    first = q.take()
    assert q.load().service == {'image': 0.0} and q.load().backlog == 0.0
    clock.now += 0.8                                  # the first frame still in service
    load = q.load()
    assert load.service == {'image': pytest.approx(0.8)}
    assert load.backlog == pytest.approx(5 * 0.8)     # five frames of at least 0.8 s
    assert q.offer('image', 'late', deadline=clock.now + 1.0).startswith('busy: would')
    q.done(first, None)                               # not timed (the kind's first)
    second = q.take()
    assert q.stale(second) is None
    clock.now += 1.0
    assert q.load().service == {'image': pytest.approx(1.0)}
    q.done(second, 1.0)                               # timed: the median from now on
    assert q.load().service == {'image': 1.0}
    third = q.take()                                  # at 1.8 s: done at 2.8, too late
    assert q.stale(third).startswith('busy: waited 1.8 s') and q.shed == 1


def test_close_wakes_the_workers_and_returns_what_was_queued():
    q, _ = queue_with(0.1)
    taken = []
    worker = threading.Thread(target=lambda: taken.append(q.take()))
    worker.start()
    q.close()
    worker.join(5.0)
    assert taken == [None] and not worker.is_alive()
    assert q.offer('image', 'late') == 'the server is shutting down'


def test_the_utilization_is_the_others_tasks_at_their_rates_over_the_workers():
    q, clock = queue_with(0.6, workers=2)
    for t in (0.0, 2.0, 4.0, 6.0):               # robot 1: a frame every 2 s
        clock.now = t
        assert q.offer('image', 'a', owner=1) is None
        if t in (0.0, 4.0):                      # robot 2: every 4 s
            assert q.offer('image', 'b', owner=2) is None
    clock.now = 7.0
    # robot 1: 0.5 frames/s, robot 2: 0.25 frames/s, 0.6 s of work each, on 2 workers
    assert q.load().utilization == pytest.approx((0.5 + 0.25) * 0.6 / 2)
    assert q.load(excluding=1).utilization == pytest.approx(0.25 * 0.6 / 2)
    assert q.load(excluding=2).utilization == pytest.approx(0.5 * 0.6 / 2)


def test_others_send_while_another_robot_announces_a_rate_or_its_tasks_still_arrive():
    demand = Demand(horizon=10.0, announce_age=3.0)
    demand.arrived(None, 'sort', 0.0)
    assert not demand.others(0.1, None)             # alone (a sender of no id too)
    assert demand.others(0.1, 1)
    demand.arrived(1, 'sort', 0.2)
    assert demand.others(0.3, None)
    demand.announce(2, [('image', 0.0)], 0.4)       # robot 2 announces nothing here
    assert not demand.others(11.0, 1) and not demand.others(11.0, None)   # past the horizon
    demand.announce(2, [('image', 4.0)], 11.0)
    assert demand.others(11.5, 1) and not demand.others(14.5, 1)   # expired after 3 s


def test_announced_rates_count_at_once_and_replace_the_announcers_arrivals():
    q, clock = queue_with(0.5)
    for t in (0.0, 2.0, 4.0):                    # robot 1 sent a frame every 2 s, robot 2
        clock.now = t                            # one frame every 4 s
        assert q.offer('image', 'a', owner=1) is None
        if t != 2.0:
            assert q.offer('image', 'b', owner=2) is None
    clock.now = 4.5
    assert q.load(excluding=3).utilization == pytest.approx((0.5 + 0.25) * 0.5)
    q.announce(4, [('image', 1.0)])              # robot 4 moved here: counts at once
    q.announce(1, [('image', 0.0)])              # robot 1 moved away: counts no more
    assert q.load(excluding=3).utilization == pytest.approx((0.25 + 1.0) * 0.5)
    assert q.load(excluding=4).utilization == pytest.approx(0.25 * 0.5)
    clock.now = 7.0                              # robot 4's announcement is 2.5 s old ...
    assert q.load(excluding=3).utilization == pytest.approx((0.25 + 1.0) * 0.5)
    clock.now = 7.6                  # ... 3.1 s: it stopped probing; robot 1's did too: it
    # counts by its arrivals again (its last one 3.6 s ago, within two of its gaps)
    assert q.load(excluding=3).utilization == pytest.approx((0.25 + 0.5) * 0.5)
    clock.now = 8.1                  # none from robot 1 for more than two of its gaps
    assert q.load(excluding=3).utilization == pytest.approx(0.25 * 0.5)


def test_a_sender_that_stopped_counts_as_none_after_two_of_its_gaps():
    arrivals = Arrivals(horizon=10.0)
    for t in (0.0, 2.0, 4.0):
        arrivals.add(7, 'image', t)
    assert arrivals.rates(5.0) == {(7, 'image'): pytest.approx(0.5)}
    assert arrivals.rates(8.0) == {(7, 'image'): pytest.approx(0.5)}   # 4 s: two gaps
    assert arrivals.rates(8.5) == {}                      # it went elsewhere
    arrivals.add(7, 'image', 9.0)                         # back: one arrival in 10 s of
    assert arrivals.rates(15.0) == {(7, 'image'): pytest.approx(0.1)}  # history counts
    assert arrivals.rates(19.5) == {}                     # nothing left in the horizon
    arrivals.add(3, 'sort', 20.0)
    assert arrivals.rates(20.0) == {(3, 'sort'): pytest.approx(0.1)}
    with pytest.raises(ValueError):
        Arrivals(horizon=0.0)


def test_attempt_deadlines_read_the_rules_own_estimate():
    """One load model: what an attempt's deadline follows is the estimate the rule ranks
    by (round trip + the others' work in flight per worker + the work), not a figure of
    its own, for one attempt; an answer older than the window counts as none."""
    clock = Clock()
    rule = LeastLatency(window=2.0, clock=clock)
    load = RobotLoad({'image': 1.0}, balancer=rule, clock=clock)
    assert load.expected('image')(1) is None
    for rtt in (0.002, 0.004, 0.003):
        load.on_answer(1, Load(1, 1, 2, 0.9, {'image': 0.4}, 0.5), rtt)
    estimate = rule.estimate(1, 'image', clock())
    assert load.expected('image')(1) == pytest.approx(estimate.latency)
    assert estimate.latency == pytest.approx(0.003 + 2 * 0.4 / 2 + 0.4)
    # asked for more than it can do, a server is ranked by the tries a task needs there;
    # one attempt still takes the round trip + the wait + the work
    load.on_answer(2, Load(1, 1, 2, 0.9, {'image': 0.4}, 1.5), 0.003)
    overloaded = rule.estimate(2, 'image', clock())
    assert overloaded.latency > 1.4 * load.expected('image')(2)
    assert load.expected('image')(2) == pytest.approx(0.003 + 2 * 0.4 / 2 + 0.4)
    clock.now += 2.5
    assert load.expected('image')(1) is None


def test_a_robot_ranking_its_samples_keeps_a_rules_estimates_for_its_deadlines():
    """A load-aware robot with no rule per task (its ranking chooses) has the same
    estimates: its samples' wait is their queue + work for its mix of kinds."""
    clock = Clock()
    load = RobotLoad({'image': 1.0, 'sort': 3.0}, clock=clock)
    with pytest.raises(ValueError):
        RobotLoad({'image': 0.0}, clock=clock)
    wait = load.on_answer(1, Load(2, 1, 1, 0.8, {'image': 0.4, 'sort': 0.02}, 0.5), 0.002)
    mix = 0.25 * (3 * 0.4 + 0.4) + 0.75 * (3 * 0.02 + 0.02)
    assert wait == pytest.approx(mix)
    assert load.expected('sort')(1) == pytest.approx(0.002 + 3 * 0.02 + 0.02)
    load.set_rate('image', 0.0)                   # one kind still sent: a mix
    with pytest.raises(ValueError):
        load.set_rate('sort', 0.0)                # none: no mix to weigh waits by
    assert load.mix == {'image': 0.0, 'sort': 3.0}


def test_a_server_new_to_a_kind_needs_the_least_work_any_server_reported():
    """One default for a kind a server has not done: the least any server reported, for
    the rule and the deadlines alike (not nothing: no rush of every robot to a new
    server)."""
    clock = Clock()
    rule = LeastLatency(window=2.0, clock=clock)
    load = RobotLoad({'image': 1.0}, balancer=rule, clock=clock)
    load.on_answer(1, Load(0, 0, 1, 0.0, {'image': 0.3}), 0.001)
    load.on_answer(2, Load(0, 0, 1, 0.0, {'image': 0.5}), 0.001)
    load.on_answer(3, Load(0, 0, 1, 0.0, {}), 0.001)        # just came up
    assert load.expected('image')(3) == pytest.approx(0.001 + 0.3)
    assert rule.estimate(3, 'image', clock()).latency == load.expected('image')(3)


def test_a_frame_is_fresh_for_its_round_trip_and_work_with_no_queue():
    """A frame is worth waiting for until the next is due, and at least ``factor`` x
    what it takes there with no queue: the median round trip + the work."""
    clock = Clock()
    load = RobotLoad({'image': 1.0}, clock=clock)
    fresh = load.fresh_for('image', 2.0, lambda: 0.25)
    load.on_answer(1, Load(3, 1, 1, 2.4, {}), 0.002)
    assert fresh(1) is None                          # nobody has done a frame yet
    for rtt in (0.090, 0.004):                       # a probe waited for a quota period
        load.on_answer(1, Load(3, 1, 1, 2.4, {'image': 0.6}), rtt)
    assert fresh(1) == pytest.approx(2.0 * (0.004 + 0.6))     # the queue left out
    load.on_answer(2, Load(0, 0, 1, 0.0, {'image': 0.05}), 0.001)
    assert fresh(2) == 0.25                          # the next frame is due first
    clock.now += 2.5
    assert fresh(1) is None                          # no answer in the window


def test_the_retry_budget_is_a_share_of_recent_tasks_plus_a_reserve():
    clock = Clock()
    budget = RetryBudget(ratio=0.1, window=10.0, reserve=2, clock=clock)
    for _ in range(30):
        budget.sent()
    spent = sum(budget.spend() for _ in range(10))
    assert spent == 5 and budget.refused == 5         # 2 + 10 % of 30
    clock.now += 10.5                                 # all of it out of the window
    assert [budget.spend() for _ in range(3)] == [True, True, False]


def test_hedges_do_not_draw_on_the_reserve():
    clock = Clock()
    budget = RetryBudget(ratio=0.1, window=10.0, reserve=2, clock=clock)
    for _ in range(10):
        budget.sent()
    assert budget.spend(reserve=False) and not budget.spend(reserve=False)   # 10 % of 10
    assert budget.spend() and budget.spend() and not budget.spend()          # + 2 for re-sends


def test_the_reserve_covers_every_task_stranded_on_a_server_that_stopped():
    clock = Clock()
    budget = RetryBudget(ratio=0.1, window=10.0, reserve=2, clock=clock)
    for _ in range(10):
        budget.sent()
    assert all(budget.spend(stranded=5) for _ in range(20))      # a stopped server's: free
    assert [budget.spend(stranded=2) for _ in range(4)] == [True] * 3 + [False]   # 1 + 2
    assert not budget.spend(reserve=False, stranded=5)       # a hedge has no reserve


def test_a_zero_retry_budget_means_no_limit():
    budget = RetryBudget(ratio=0.0, reserve=0)
    assert all(budget.spend() for _ in range(100)) and budget.describe() == 'no limit'


def test_demand_keeps_running_sums_and_forgets_robots_that_stopped_probing():
    demand = Demand(horizon=10.0, announce_age=3.0)
    for robot in range(1, 1001):        # a thousand robots probe; 10 send here
        demand.announce(robot, [('image', 0.25 if robot <= 10 else 0.0)], 0.0)
    assert demand.rates(0.5) == {'image': pytest.approx(2.5)}
    assert demand.rates(0.5, excluding=3) == {'image': pytest.approx(2.25)}
    demand.announce(3, [('image', 0.0), ('sort', 4.0)], 1.0)   # robot 3 changed its mind
    assert demand.rates(1.0) == {'image': pytest.approx(2.25), 'sort': pytest.approx(4.0)}
    demand.arrived(3, 'image', 1.5)     # an announcer's arrivals do not count twice
    demand.arrived(None, 'image', 1.5)  # a task of nobody's does: one per horizon
    assert demand.rates(1.5)['image'] == pytest.approx(2.25 + 0.1)
    assert demand.rates(3.5) == {'image': pytest.approx(0.1), 'sort': pytest.approx(4.0)}
    assert demand.rates(4.5) == {'image': pytest.approx(0.1)}   # robot 3's, 3.5 s old
    with pytest.raises(ValueError):
        Demand(announce_age=0.0)
