"""The capacity benchmark's pure parts: the static assignment it compares with, and the
figures it computes from task reports."""

import collections

import pytest

from server_select.bench.capacity_report import figures, overloaded, placed, static_assignment
from server_select.testbed.bag_analysis import Report, Run


def test_robots_go_to_servers_in_proportion_to_their_shares():
    counts = collections.Counter(static_assignment([0.4, 0.3, 0.2, 0.1], 10).values())
    assert counts == {1: 4, 2: 3, 3: 2, 4: 1}
    assert static_assignment([0.25, 0.25, 0.25], 6) == {1: 1, 2: 2, 3: 3, 4: 1, 5: 2, 6: 3}


def report(t, server, ok=True, rtt=0.5, robot=1, task=1, attempts=1):
    return Report(t, robot, task, ok, rtt if ok else float('nan'), server, server if ok
                  else -1, '', attempts)


def test_a_server_sent_more_than_it_can_do_is_overloaded_for_as_long_as_that_lasts():
    # server 1 does 2 tasks/s; it is sent 4/s from t=10 to t=16, then 1/s
    reports = [report(10.5 + 0.25 * i, 1) for i in range(24)] + \
        [report(16.5 + i, 1) for i in range(10)]
    longest = overloaded(reports, {1: 2.0, 2: 2.0}, 5.0, 10.0, 26.0)
    assert 6.0 <= longest <= 8.0          # 6 s, measured in windows of 2 s
    assert overloaded(reports[24:], {1: 2.0}, 5.0, 10.0, 26.0) == 0.0


def test_robots_are_placed_once_the_last_one_has_its_first_task_reported():
    reports = [report(14.0, 1, robot=1), report(16.5, 2, robot=2), report(15.0, 1, robot=1),
               report(17.0, 3, robot=3), report(18.0, 3, robot=2)]
    assert placed(Run({}, [], reports, [], [])) == 17.0
    assert placed(Run({}, [], [], [], [])) == 0.0


def test_failed_tasks_count_at_the_timeout_and_extra_sends_per_task():
    reports = [report(20.0, 1, rtt=1.0, task=1), report(21.0, 1, ok=False, task=2),
               report(22.0, 2, rtt=2.0, task=3, attempts=3), report(40.0, 1, task=4)]
    row = figures(Run({}, [], reports, [], []), None, 1.0, 10.0, 30.0, 5.0, {1: 1.0, 2: 1.0})
    assert (row['tasks'], row['failed'], row['goodput']) == (3, 1, pytest.approx(2 / 20.0))
    assert row['mean'] == pytest.approx((1.0 + 5.0 + 2.0) / 3)
    assert row['oldest'] == 2.0 and row['extra'] == pytest.approx(2 / 3.0)
    assert row['switches'] == pytest.approx(60.0 / 20.0 / 1)   # 1 -> 2 for robot 1
    assert 'work' not in row and 'settled' not in row
    # from 21 s on: tasks 2 (server 1) and 3 (server 2) of robot 1: one switch in 9 s
    row = figures(Run({}, [], reports, [], []), None, 1.0, 10.0, 30.0, 5.0, settled=21.0)
    assert row['settled'] == pytest.approx(60.0 / 9.0) and 'settled_overload' not in row


def test_the_overload_after_settling_leaves_out_what_came_before():
    # server 1 sent 4 tasks/s (capacity 1) from 10 to 16 s, then 1 a second
    reports = [report(10.0 + i / 4.0, 1, rtt=0.1, task=i) for i in range(24)] + [
        report(16.0 + i, 1, rtt=0.1, task=24 + i) for i in range(14)]
    row = figures(Run({}, [], reports, [], []), None, 1.0, 10.0, 30.0, 5.0, {1: 1.0},
                  settled=20.0)
    assert row['overloaded'] >= 6.0 and row['settled_overload'] == 0.0
