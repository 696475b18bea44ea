"""The robot's task path without a master: every task ends in exactly one report."""

import itertools

import pytest

from server_select.core.task_flow import (DUPLICATE, LATE, LOCAL, NO_SERVER, UNKNOWN,
                                          TaskFlow)
from server_select.msg import SelectionFlag, TaskReport


class Clock(object):
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


class World(object):
    """What a TaskFlow is handed: a target, a wire, a checker and a report sink."""

    def __init__(self, target=3, timeout=2.0, ids=None):
        self.clock = Clock()
        self.target = target
        self.published, self.reports, self.local_runs = [], [], []
        self.flow = TaskFlow('sort', timeout, lambda: self.target, self.make,
                             self.published.append, self.check, self.reports.append,
                             run_local=self.run_local, ids=ids, clock=self.clock)

    def make(self, task_id, server, stamp):
        return ('request', task_id, server, stamp), 'context %d' % task_id

    def check(self, result, context):
        return None if result == 'good ' + context else 'wrong result'

    def run_local(self, task_id, stamp):
        self.local_runs.append(task_id)
        return None if task_id % 2 else 'local failure'


def test_no_server_and_local_are_the_message_constants():
    assert NO_SERVER == TaskReport.NO_SERVER == SelectionFlag.NO_SERVER == -1
    assert LOCAL == TaskReport.LOCAL == -2


def test_send_then_answer_gives_one_checked_report_with_the_round_trip():
    w = World()
    task_id = w.flow.send_next('stamp-1')
    assert w.published == [('request', 1, 3, 'stamp-1')] and task_id == 1
    assert len(w.flow) == 1 and w.reports == []
    w.clock.now += 0.25
    outcome = w.flow.resolve(1, 3, True, '', 'good context 1')
    assert w.reports == [outcome]
    assert outcome == (1, 'sort', 'stamp-1', 3, 3, True, '', pytest.approx(0.25))
    assert (w.flow.sent, w.flow.ok, w.flow.failed, len(w.flow)) == (1, 1, 0, 0)
    assert list(w.flow.rtts) == [pytest.approx(0.25)]


def test_a_wrong_result_or_an_error_result_fails_the_task():
    w = World()
    w.flow.send_next('s1')
    w.flow.send_next('s2')
    wrong = w.flow.resolve(1, 3, True, '', 'garbage')
    refused = w.flow.resolve(2, 3, False, 'empty task')
    assert (wrong.ok, wrong.error) == (False, 'wrong result')
    assert (refused.ok, refused.error, refused.answered_by) == (False, 'empty task', 3)
    assert (w.flow.ok, w.flow.failed) == (0, 2) and list(w.flow.rtts) == []


def test_deadline_expires_oldest_first_and_keeps_the_send_stamp():
    w = World(timeout=2.0)
    w.flow.send_next('s1')
    w.clock.now += 1.0
    w.flow.send_next('s2')
    w.clock.now += 0.999
    assert w.flow.expire() == []
    w.clock.now += 0.001
    (first,) = w.flow.expire()
    assert (first.task_id, first.stamp, first.server_id, first.answered_by, first.ok,
            first.rtt) == (1, 's1', 3, NO_SERVER, False, None)
    assert 'task_timeout 2 s' in first.error
    w.clock.now += 1.0
    assert [o.task_id for o in w.flow.expire()] == [2]
    assert [r.task_id for r in w.reports] == [1, 2] and len(w.flow) == 0


def test_duplicate_late_and_unknown_results_are_ignored_and_counted():
    w = World(timeout=1.0)
    w.flow.send_next('s1')
    w.flow.send_next('s2')
    w.flow.resolve(1, 3, True, '', 'good context 1')
    assert w.flow.resolve(1, 3, True, '', 'good context 1') == DUPLICATE
    w.clock.now += 1.0
    w.flow.expire()
    assert w.flow.resolve(2, 3, True, '', 'good context 2') == LATE
    assert w.flow.resolve(99, 3, True, '', 'x') == UNKNOWN
    assert [(r.task_id, r.ok) for r in w.reports] == [(1, True), (2, False)]
    assert w.flow.ignored == {DUPLICATE: 1, LATE: 1, UNKNOWN: 1}


def test_no_server_selected_is_reported_at_once_and_nothing_is_published():
    w = World(target=NO_SERVER)
    w.flow.send_next('s1')
    (report,) = w.reports
    assert (report.server_id, report.answered_by, report.ok, report.error, report.stamp) == \
        (NO_SERVER, NO_SERVER, False, 'no server selected', 's1')
    assert w.published == [] and len(w.flow) == 0


def test_local_work_is_run_in_the_robot_and_reported_as_local():
    w = World(target=LOCAL)
    w.flow.send_next('s1')
    w.flow.send_next('s2')
    assert w.local_runs == [1, 2] and w.published == []
    assert [(r.server_id, r.answered_by, r.ok, r.error) for r in w.reports] == \
        [(LOCAL, LOCAL, True, ''), (LOCAL, LOCAL, False, 'local failure')]


def test_task_ids_are_shared_across_flows_of_one_robot():
    ids = itertools.count(1)
    a, b = World(ids=ids), World(ids=ids)
    assert [a.flow.send_next('s'), b.flow.send_next('s'), a.flow.send_next('s')] == [1, 2, 3]


def test_the_target_is_asked_at_send_time():
    w = World(target=1)
    w.flow.send_next('s1')
    w.target = 2
    w.flow.send_next('s2')
    assert [p[2] for p in w.published] == [1, 2]
    assert w.flow.resolve(2, 2, True, '', 'good context 2').server_id == 2


def test_remembered_ids_are_bounded():
    w = World()
    w.flow = TaskFlow('sort', 1.0, lambda: 3, w.make, w.published.append, w.check,
                      w.reports.append, clock=w.clock, remember=5, keep_rtts=3)
    for _ in range(10):
        task_id = w.flow.send_next('s')
        w.flow.resolve(task_id, 3, True, '', 'good context %d' % task_id)
    assert len(w.flow._ended) == 5 and len(w.flow.rtts) == 3
    assert w.flow.resolve(1, 3, True, '', 'x') == UNKNOWN   # forgotten: no longer a duplicate


@pytest.mark.parametrize('bad', [0, -1, float('nan')])
def test_timeout_must_be_positive(bad):
    with pytest.raises(ValueError):
        World(timeout=bad)
