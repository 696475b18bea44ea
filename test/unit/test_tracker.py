import math

import pytest

from server_select.tracker import NONE, TaskTracker


def test_result_resolves_once_with_round_trip():
    t = TaskTracker(timeout=2.0)
    t.sent(1, 10.0, 3, context='ctx')
    assert t.context(1) == 'ctx'
    outcome = t.resolve(1, 10.25, 3, True)
    assert outcome.ok and outcome.answered_by == 3 and outcome.server_id == 3
    assert outcome.rtt == pytest.approx(0.25)
    assert len(t) == 0


def test_duplicate_and_unknown_results_are_counted_not_resolved():
    t = TaskTracker(timeout=2.0)
    t.sent(1, 0.0, 1)
    assert t.resolve(1, 0.1, 1, True) is not None
    assert t.resolve(1, 0.2, 2, True) is None
    assert t.resolve(99, 0.2, 2, True) is None
    assert (t.duplicates, t.unknown) == (1, 1)


def test_expiry_reports_each_timed_out_task_once():
    t = TaskTracker(timeout=1.0)
    t.sent(1, 0.0, 1)
    t.sent(2, 0.5, 1)
    assert t.expire(0.9) == []
    expired = t.expire(1.0)
    assert [o.task_id for o in expired] == [1]
    assert not expired[0].ok and 'task_timeout' in expired[0].error
    assert expired[0].answered_by == NONE and math.isnan(expired[0].rtt)
    assert [o.task_id for o in t.expire(5.0)] == [2]
    assert t.expire(10.0) == []
    # a late result for an expired task is a duplicate, not a second outcome
    assert t.resolve(1, 6.0, 1, True) is None and t.duplicates == 1


def test_error_result_is_a_failed_outcome():
    t = TaskTracker(timeout=1.0)
    t.sent(5, 0.0, 2)
    outcome = t.resolve(5, 0.1, 2, False, 'empty task')
    assert not outcome.ok and outcome.error == 'empty task'


def test_fail_unsent_task():
    t = TaskTracker(timeout=1.0)
    outcome = t.fail(7, 3.0, NONE, 'no server selected')
    assert not outcome.ok and outcome.server_id == NONE
    with pytest.raises(ValueError):
        t.sent(7, 4.0, 1)


def test_reusing_a_pending_id_is_an_error():
    t = TaskTracker(timeout=1.0)
    t.sent(1, 0.0, 1)
    with pytest.raises(ValueError):
        t.sent(1, 0.1, 1)


def test_memory_of_done_tasks_is_bounded():
    t = TaskTracker(timeout=1.0, remember=10)
    for i in range(100):
        t.sent(i, 0.0, 1)
        t.resolve(i, 0.1, 1, True)
    assert len(t._done) == 10
