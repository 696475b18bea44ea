"""The robot's task path without a master: every task ends in exactly one report, and a
task whose server does not answer goes to the next candidate."""

import itertools

import pytest

from server_select.core.flow.attempts import AttemptClock
from server_select.core.flow.budget import RetryBudget
from server_select.core.flow.task_flow import (DUPLICATE, FOREIGN, LATE, LOCAL, NO_SERVER,
                                               OUTRUN, RETRIED, UNKNOWN, TaskFlow)

from support.clock import Clock


class World(object):
    """What a TaskFlow is handed: candidates, a wire, a checker, evidence and report sinks."""

    def __init__(self, candidates=(3,), timeout=2.0, ids=None, first=0.5, **kwargs):
        self.clock = Clock()
        self.candidates = list(candidates)
        self.published, self.reports, self.local_runs = [], [], []
        self.failures, self.successes, self.budgets = [], [], []
        self.flow = TaskFlow(
            'sort', timeout, lambda: list(self.candidates), self.make, self.publish, self.check,
            self.reports.append, run_local=self.run_local,
            on_failure=lambda server, why: self.failures.append(server),
            on_success=self.successes.append,
            deadlines=AttemptClock(timeout, first=first, floor=0.1, min_samples=1),
            ids=ids, clock=self.clock, **kwargs)

    def publish(self, request, server, budget):
        self.published.append((request, server))
        self.budgets.append(budget)

    def make(self, task_id, stamp):
        return ('request', task_id, stamp), 'context %d' % task_id

    def check(self, result, context):
        return None if result == 'good ' + context else 'wrong result'

    def run_local(self, task_id, stamp):
        self.local_runs.append(task_id)
        return None if task_id % 2 else 'local failure'

    def answer(self, task_id, server, good=True):
        return self.flow.resolve(task_id, server, True, '',
                                 'good context %d' % task_id if good else 'garbage')


def test_send_then_answer_gives_one_checked_report_with_the_round_trip():
    w = World()
    assert w.flow.send_next('stamp-1') == 1
    assert w.published == [(('request', 1, 'stamp-1'), 3)]
    w.clock.now += 0.25
    outcome = w.answer(1, 3).outcome
    assert w.reports == [outcome] and w.successes == [3]
    assert outcome == (1, 'sort', 'stamp-1', 3, 3, True, '', pytest.approx(0.25), 1)
    assert (w.flow.sent, w.flow.ok, w.flow.failed, len(w.flow)) == (1, 1, 0, 0)


def test_an_error_answer_goes_to_the_next_candidate_and_the_server_is_blamed():
    w = World(candidates=(3, 1))
    w.flow.send_next('s1')
    assert w.flow.resolve(1, 3, False, 'server overloaded').status == RETRIED
    assert w.failures == [3] and [s for _, s in w.published] == [3, 1]
    outcome = w.answer(1, 1).outcome
    assert (outcome.ok, outcome.server_id, outcome.answered_by, outcome.attempts) == \
        (True, 3, 1, 2)


def test_a_wrong_result_with_no_candidate_left_fails_the_task():
    w = World(candidates=(3,))
    w.flow.send_next('s1')
    outcome = w.answer(1, 3, good=False).outcome
    assert (outcome.ok, outcome.error, outcome.attempts) == (False, 'wrong result', 1)
    assert (w.flow.ok, w.flow.failed) == (0, 1) and w.failures == [3]


def test_a_silent_server_is_left_at_its_attempt_deadline_and_nothing_is_lost():
    w = World(candidates=(3, 1, 2), timeout=2.0, first=0.5)
    w.flow.send_next('s1')
    w.clock.now += 0.49
    assert w.flow.tick() == [] and len(w.published) == 1
    w.clock.now += 0.01
    w.flow.tick()
    assert [s for _, s in w.published] == [3, 1] and w.failures == [3]
    # the first server answers after all: first answer wins, the re-sent copy is outrun
    w.clock.now += 0.1
    outcome = w.answer(1, 3).outcome
    assert (outcome.ok, outcome.answered_by, outcome.attempts) == (True, 3, 2)
    assert outcome.rtt == pytest.approx(0.6)
    assert w.answer(1, 1).status == OUTRUN
    assert w.answer(1, 3).status == DUPLICATE             # the winner again: a fault
    assert len(w.reports) == 1


def test_deadlines_follow_each_servers_round_trips():
    clock = AttemptClock(2.0, factor=5.0, floor=0.25, first=1.0, min_samples=3)
    assert clock.seconds(1) == 1.0
    for rtt in (0.010, 0.012, 0.011):
        clock.add(1, rtt)
    assert clock.seconds(1) == 0.25                 # 5 x 12 ms is under the floor
    for rtt in (0.2, 0.3, 0.3):
        clock.add(2, rtt)
    assert clock.seconds(2) == pytest.approx(1.5)
    clock.add(2, 0.9)
    assert clock.seconds(2) == 2.0                  # never past the task timeout


def test_when_every_candidate_was_tried_the_task_fails_at_its_timeout():
    w = World(candidates=(3, 1), timeout=2.0, first=0.5)
    w.flow.send_next('s1')
    for _ in range(30):
        w.clock.now += 0.1
        w.flow.tick()
    (outcome,) = w.reports
    assert (outcome.ok, outcome.answered_by, outcome.attempts, outcome.stamp) == \
        (False, NO_SERVER, 2, 's1')
    assert outcome.error == ('no result within task_timeout 2 s (2 attempts: servers 3, 1; '
                             'not sent again: no other server to try (candidates [3, 1]))')
    assert w.failures == [3, 1]
    assert w.answer(1, 1).status == LATE


def test_a_task_the_retry_budget_keeps_from_another_server_says_so_when_it_fails():
    budget = RetryBudget(ratio=0.1, window=10.0, reserve=2, clock=Clock())
    for _ in range(9):
        budget.sent()
    assert all(budget.spend() for _ in range(3))             # tasks were late earlier
    w = World(candidates=(3, 1), timeout=2.0, first=0.5, budget=budget)
    w.flow.send_next('s1')
    for _ in range(30):
        w.clock.now += 0.1
        w.flow.tick()
    (outcome,) = w.reports
    assert [server for _, server in w.published] == [3]
    assert outcome.error.endswith('(1 attempts: servers 3; not sent again: the retry budget '
                                  '(10 % of tasks + 2 per 10 s) is spent)'), outcome.error
    assert w.flow.unfunded == 1


def test_duplicate_late_unknown_and_foreign_results_are_ignored_and_counted():
    w = World(timeout=1.0, first=1.0)
    w.flow.send_next('s1')
    w.flow.send_next('s2')
    w.flow.send_next('s3')
    w.answer(1, 3)
    assert w.answer(1, 3).status == DUPLICATE
    assert w.answer(3, 7).status == FOREIGN               # never sent to server 7
    w.clock.now += 1.0
    w.flow.tick()
    assert w.answer(2, 3).status == LATE
    assert w.answer(99, 3).status == UNKNOWN
    assert [(r.task_id, r.ok) for r in w.reports] == [(1, True), (2, False), (3, False)]
    assert w.flow.ignored == {DUPLICATE: 1, LATE: 1, UNKNOWN: 1, FOREIGN: 1}


def test_no_server_selected_is_reported_at_once_and_nothing_is_published():
    w = World(candidates=())
    w.flow.send_next('s1')
    (report,) = w.reports
    assert (report.server_id, report.answered_by, report.ok, report.error, report.stamp,
            report.attempts) == (NO_SERVER, NO_SERVER, False, 'no server selected', 's1', 0)
    assert w.published == [] and len(w.flow) == 0


def test_local_work_is_run_in_the_robot_and_reported_as_local():
    w = World(candidates=(LOCAL,))
    w.flow.send_next('s1')
    w.flow.send_next('s2')
    assert w.local_runs == [1, 2] and w.published == []
    assert [(r.server_id, r.answered_by, r.ok, r.error) for r in w.reports] == \
        [(LOCAL, LOCAL, True, ''), (LOCAL, LOCAL, False, 'local failure')]


def test_task_ids_are_shared_across_flows_of_one_robot():
    ids = itertools.count(1)
    a, b = World(ids=ids), World(ids=ids)
    assert [a.flow.send_next('s'), b.flow.send_next('s'), a.flow.send_next('s')] == [1, 2, 3]


def test_candidates_are_asked_at_send_time_and_switches_counted():
    w = World(candidates=(1,))
    w.flow.send_next('s1')
    w.candidates = [2, 1]
    w.flow.send_next('s2')
    w.flow.send_next('s3')
    assert [s for _, s in w.published] == [1, 2, 2] and w.flow.switches == 1
    assert w.answer(2, 2).outcome.server_id == 2


def test_remembered_ids_and_round_trips_are_bounded():
    w = World(remember=5, keep_rtts=3)
    for _ in range(10):
        w.answer(w.flow.send_next('s'), 3)
    assert len(w.flow._ended) == 5 and len(w.flow.rtts) == 3
    assert w.answer(1, 3).status == UNKNOWN   # forgotten: no longer a duplicate


@pytest.mark.parametrize('bad', [0, -1, float('nan')])
def test_timeout_must_be_positive(bad):
    with pytest.raises(ValueError):
        World(timeout=bad)


def test_a_task_that_cannot_be_made_is_reported_failed_and_not_sent():
    w = World()

    def broken(task_id, stamp):
        raise ValueError('frame does not decode')
    w.flow._make = broken
    w.flow.send_next('s1')
    (report,) = w.reports
    assert (report.ok, report.error, report.attempts) == \
        (False, 'cannot make the task: frame does not decode', 0)
    assert w.published == [] and len(w.flow) == 0


def _learn(w, server, rtts):
    """Give ``server`` a history of answered tasks with these round trips."""
    for rtt in rtts:
        task = w.flow.send_next('warm-up')
        w.clock.now += rtt
        w.answer(task, server)


def test_a_hedged_task_goes_to_the_next_server_a_round_trip_past_the_p95_first_wins():
    w = World(candidates=(3, 4), hedge=0.95)
    # server 3: median 10 ms, quartiles 8 and 12 ms: the p95 of that spread 14.9 ms
    _learn(w, 3, [0.006, 0.008, 0.010, 0.012, 0.014] * 4)
    del w.published[:]
    task = w.flow.send_next('s')
    w.clock.now += 0.020
    w.flow.tick()
    assert [s for _, s in w.published] == [3]     # 20 ms: past the p95, not yet
    w.clock.now += 0.010
    w.flow.tick()
    assert [s for _, s in w.published] == [3, 4]  # 30 ms: a copy to server 4
    assert (w.flow.hedged, w.flow.resent, w.failures) == (1, 0, [])   # nobody blamed
    w.clock.now += 0.001
    outcome = w.answer(task, 4).outcome                   # the copy wins
    assert outcome.ok and outcome.answered_by == 4 and outcome.attempts == 2
    assert w.answer(task, 3).status == OUTRUN            # the original, late: counted, dropped
    assert w.flow.ignored == {OUTRUN: 1}
    w.flow.tick()
    assert [s for _, s in w.published] == [3, 4]  # once per task


def test_no_hedge_without_history_or_without_another_server_or_when_off():
    w = World(candidates=(3, 4), hedge=0.95)
    w.flow.send_next('s')                         # no round trips of server 3 yet
    w.clock.now += 0.3
    w.flow.tick()
    assert w.flow.hedged == 0
    alone = World(candidates=(3,), hedge=0.95)
    _learn(alone, 3, [0.010] * 20)
    alone.flow.send_next('s')
    alone.clock.now += 0.05
    alone.flow.tick()
    assert alone.flow.hedged == 0 and alone.failures == []
    off = World(candidates=(3, 4))
    _learn(off, 3, [0.010] * 20)
    off.flow.send_next('s')
    off.clock.now += 0.05
    off.flow.tick()
    assert off.flow.hedged == 0 and len(off.published) == 21


def test_answers_of_tasks_sent_once_are_latency_samples_hedged_ones_are_not():
    answers = []
    w = World(candidates=(3, 4), hedge=0.95,
              on_answer=lambda server, rtt: answers.append((server, rtt)))
    _learn(w, 3, [0.010] * 19 + [0.020])
    assert len(answers) == 20 and answers[-1] == (3, pytest.approx(0.020))
    task = w.flow.send_next('s')
    w.clock.now += 0.035
    w.flow.tick()                                 # hedged to server 4
    w.clock.now += 0.001
    assert w.answer(task, 4).outcome.ok
    assert len(answers) == 20                     # the race's winner is not sampled


def test_a_robot_that_stops_reports_each_task_still_out_failed_once():
    w = World(candidates=(3, 4), timeout=2.0)
    for stamp in ('s1', 's2', 's3'):
        w.flow.send_next(stamp)
    w.answer(2, 3)
    w.clock.now += 0.6
    w.flow.tick()                                 # task 1 and 3 re-sent to server 4
    ended = w.flow.abandon('the robot stopped')
    assert sorted(o.task_id for o in ended) == [1, 3] and len(w.flow) == 0
    assert all(not o.ok and o.error.startswith('the robot stopped (2 attempts: servers')
               for o in ended)
    assert sorted(r.task_id for r in w.reports) == [1, 2, 3] and w.flow.failed == 2
    assert w.answer(1, 4).status == 'late' and w.flow.abandon('again') == []


def test_next_wake_is_the_earliest_deadline_timeout_or_hedge():
    w = World(timeout=2.0, hedge=0.95)
    assert w.flow.next_wake() is None
    w.flow.send_next(0)
    pending = list(w.flow._pending.values())[0]
    assert w.flow.next_wake() == min(pending.deadline, pending.started + 2.0)
    _learn(w, 3, [0.010] * 20)
    w.flow.send_next(0)
    newest = list(w.flow._pending.values())[-1]
    hedge_at = newest.hedge_at(lambda s: w.flow.deadlines.hedge_seconds(s, 0.95))
    assert hedge_at is not None and w.flow.next_wake() <= hedge_at
    w.clock.now += 3.0
    w.flow.tick()
    assert w.flow.next_wake() is None and len(w.flow) == 0


def test_at_its_next_wake_a_task_out_of_time_ends():
    """What next_wake names, tick acts on: a task sent at 11.12 s with a 5 s timeout
    ends at 16.12 s, although 16.12 - 11.12 is 4.999999999999998 in floats (a driver on a
    virtual clock, the simulator, would otherwise wake at that time for ever)."""
    w = World(candidates=[], timeout=5.0)
    w.candidates = [3]
    w.clock.now = 11.12
    w.flow.send_next(0)
    w.flow.deadlines = AttemptClock(5.0, first=5.0, floor=5.0)
    list(w.flow._pending.values())[0].deadline = 11.12 + 5.0
    w.clock.now = w.flow.next_wake()
    assert w.clock.now - 11.12 < 5.0
    ended = w.flow.tick()
    assert [o.ok for o in ended] == [False] and len(w.flow) == 0


def test_every_task_out_on_a_server_that_stops_goes_elsewhere_past_the_fixed_reserve():
    # 5 tasks/s with 1 s attempt deadlines: 5 are out on server 3 when it stops; 10 % of
    # the 10 tasks sent plus a reserve of 2 would re-send 3 of them
    budget = RetryBudget(ratio=0.1, window=10.0, reserve=2, clock=Clock())
    w = World(candidates=(3, 1), timeout=2.0, first=1.0, budget=budget)
    budget._clock = w.clock
    for task in range(1, 6):
        w.flow.send_next('s%d' % task)
        w.clock.now += 0.05
        w.answer(task, 3)
        w.clock.now += 0.15
    for task in range(6, 11):                      # server 3 stopped: no answer any more
        w.flow.send_next('s%d' % task)
        w.clock.now += 0.2
        w.flow.tick()
    w.clock.now += 0.3                             # past the last one's attempt deadline
    w.flow.tick()
    sent_to = [s for _, s in w.published]
    assert (sent_to.count(3), sent_to.count(1)) == (10, 5)
    assert (w.flow.resent, w.flow.unfunded, len(w.flow)) == (5, 0, 5)
    for task in range(6, 11):
        assert w.answer(task, 1).status == 'ended'
    assert not any(r.ok is False for r in w.reports)


def test_re_sends_of_tasks_stranded_on_a_stopped_server_leave_the_budget_to_others():
    # A fault test failed so: tasks stranded on a server that had stopped hearing them were
    # re-sent from the budget's window, and a task late once on the next server 2 s later
    # found it spent and failed.
    budget = RetryBudget(ratio=0.1, window=10.0, reserve=2, clock=Clock())
    w = World(candidates=(3, 1, 2), timeout=2.0, first=1.0, budget=budget)
    budget._clock = w.clock
    for task in range(1, 11):                      # 2 s at 5 tasks/s; server 3 answers
        w.flow.send_next('s%d' % task)
        w.clock.now += 0.05
        w.answer(task, 3)
        w.clock.now += 0.15

    def answer_re_sends():                          # server 1 answers at once
        for (_, task, _), server in w.published:
            if server == 1 and task in range(11, 21) and task not in answered:
                answered.add(task)
                w.answer(task, 1)
    answered = set()
    for task in range(11, 21):                     # server 3 stopped: 10 tasks stranded
        w.flow.send_next('s%d' % task)
        w.clock.now += 0.2
        w.flow.tick()
        answer_re_sends()
    w.candidates = [1, 2]                          # it is left
    w.clock.now += 1.0
    w.flow.tick()
    answer_re_sends()
    assert (w.flow.resent, w.flow.unfunded, len(answered)) == (10, 0, 10)
    for task in range(21, 26):                     # server 1 is slow once
        w.flow.send_next('s%d' % task)
        if task != 21:
            w.answer(task, 1)
        w.clock.now += 0.2
        w.flow.tick()
    assert [s for (_, task, _), s in w.published if task == 21] == [1, 2]
    assert (w.flow.resent, w.flow.unfunded) == (11, 0)
    assert not any(r.ok is False for r in w.reports)
