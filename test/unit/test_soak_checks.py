"""The soak's invariants on made-up histories: each catches what it is there for."""

from server_select.soak import checks
from server_select.soak.history import Report, Sent, merge

TIMEOUT = 2.0


def report(t, robot, task, ok=True, rtt=0.01, kind='sort', copies=1):
    return Report(t, robot, task, kind, ok, '' if ok else 'timeout', rtt, 1, 1, copies)


def test_every_task_once_is_clean_and_a_gap_or_a_second_report_is_counted():
    reports = [report(i * 0.2, 1, i) for i in range(1, 51)]
    assert checks.ledger(reports, [], [], TIMEOUT)['unreported'] == []
    gap = [r for r in reports if r.task != 20]
    assert checks.ledger(gap, [], [], TIMEOUT)['unreported'] == [(1, 0, 20)]
    twice = reports + [report(4.0, 1, 20, ok=False)]
    assert checks.ledger(twice, [], [], TIMEOUT)['duplicated'] == [(1, 0, 20)]
    again = [r._replace(copies=2) if r.task == 7 else r for r in reports]
    assert checks.ledger(again, [], [], TIMEOUT)['duplicated'] == [(1, 0, 7)]


def test_a_task_sent_but_never_reported_is_unreported_even_after_the_last_report():
    reports = [report(i * 0.2, 1, i) for i in range(1, 11)]
    sent = [Sent(2.2, 1, 11, 1, '/robot1')]
    assert checks.ledger(reports, sent, [], TIMEOUT)['unreported'] == [(1, 0, 11)]


def test_a_restarted_robot_counts_from_one_and_a_killed_one_loses_only_its_last_tasks():
    first = [report(i * 0.2, 1, i) for i in range(1, 41)]        # to 8 s
    stops = [('robot1', 11.0, 9.0)]        # killed at 9 s, its launch gone at 11
    sent = [Sent(8.2, 1, 41, 1, '/robot1'), Sent(8.4, 1, 42, 1, '/robot1')]    # out when it died
    second = [report(12 + i * 0.2, 1, i) for i in range(1, 21)]
    result = checks.ledger(first + second, sent, stops, TIMEOUT)
    assert (result['robot lives'], result['tasks']) == (2, 62)
    assert result['unreported'] == [] and result['lost with a killed robot'] == 2
    holed = [r for r in first if r.task != 5] + second       # long before the kill
    assert checks.ledger(holed, sent, stops, TIMEOUT)['unreported'] == [(1, 0, 5)]
    clean = [('robot1', 9.0, None)]                          # a clean stop loses nothing
    assert len(checks.ledger(first + second, sent, clean, TIMEOUT)['unreported']) == 2


def test_a_failure_counts_only_outside_every_fault_window_and_its_bound():
    events = [{'start': 100.0, 'end': 110.0, 'bound': 5.0}]
    failed = [report(t, 1, i, ok=False) for i, t in enumerate((50.0, 99.0, 114.0, 116.0))]
    stray = checks.stray_failures(failed, events, TIMEOUT, (0.0, 200.0))
    assert [r.t for r in stray] == [50.0, 116.0]
    assert checks.stray_failures(failed, events, TIMEOUT, (60.0, 200.0))[0].t == 116.0

    restarted = [dict(events[0], serving={'server4': 6.5})]     # serving at 116.5
    assert [r.t for r in checks.stray_failures(failed, restarted, TIMEOUT, (60.0, 200.0))] \
        == []
    never = [dict(events[0], serving={'server4': None})]
    assert len(checks.stray_failures(failed, never, TIMEOUT, (60.0, 200.0))) == 1


def _steady(start, end, rtt=0.010, robots=(1, 2)):
    return [report(start + i * 0.1, robot, i, rtt=rtt)
            for i in range(int((end - start) / 0.1)) for robot in robots]


def test_recovery_is_when_no_task_fails_and_round_trips_are_back_within_ten_percent():
    event = {'start': 100.0, 'end': 110.0, 'bound': 5.0}
    before = _steady(40.0, 100.0)
    slow = _steady(110.0, 113.0, rtt=0.020)          # twice the reference: not back
    after = _steady(113.0, 130.0, rtt=0.0105)        # 5 % above: back
    back, reference = checks.recovery(sorted(before + slow + after), event, [event], {1, 2},
                                      130.0)
    assert reference == 2 and abs(back - 3.0) <= checks.STEP
    failing = [report(114.0, 2, 999, ok=False)]
    back, _ = checks.recovery(sorted(before + slow + after + failing), event, [event],
                              {1, 2}, 130.0)
    assert back > 4.0
    never, _ = checks.recovery(sorted(before + _steady(110.0, 130.0, rtt=0.02)), event,
                               [event], {1, 2}, 130.0)
    assert never is None


def test_a_late_recovery_names_the_pairs_that_held_it_worst_first():
    event = {'start': 100.0, 'end': 110.0, 'bound': 5.0}
    before = _steady(40.0, 100.0)
    back = _steady(110.0, 170.0, robots=(1,))                  # robot 1 is back at once
    held = [r._replace(answered_by=2) for r in _steady(110.0, 170.0, rtt=0.034, robots=(2,))]
    history = sorted(before + back + held)
    assert checks.recovery(history, event, [event], {1, 2}, 170.0)[0] is None
    found = checks.held_back(history, event, [event], {1, 2}, 170.0)
    (robot, kind, ratio, failed, server), = found
    assert (robot, kind, failed, server) == (2, 'sort', 0, 2) and abs(ratio - 3.4) < 1e-6
    failing = [report(120.0, 1, 9999, ok=False)]
    found = checks.held_back(sorted(history + failing), event, [event], {1, 2}, 170.0)
    assert [(f[0], f[3]) for f in found] == [(1, 1), (2, 0)]   # a failure first
    assert checks.held_back(sorted(before + _steady(110.0, 170.0)), event, [event], {1, 2},
                            170.0) == []


def test_a_message_two_recorders_heard_is_one_and_two_in_one_bag_are_two():
    merged = merge([{'reports': {('a',): 1, ('b',): 2}}, {'reports': {('a',): 1}}])
    assert merged['reports'] == {('a',): 1, ('b',): 2}


def test_warnings_count_outside_faults_and_an_intruder_must_be_named():
    from server_select.soak.history import Line
    events = [{'kind': 'intruder', 'start': 100.0, 'end': 110.0, 'bound': 5.0}]
    lines = [Line(50.0, '/robot1', 4, 'server 2 is slow'),
             Line(105.0, '/server1', 4, 'dropped a task of robot 2 from /intruder_1_2'),
             Line(120.0, '/robot1', 2, 'all well')]
    assert checks.warnings_outside(lines, events, (0.0, 200.0)) == {'/robot1': 1}
    assert checks.intruders_named(lines, events) == [(100.0, 1)]
    assert checks.intruders_named(lines[:1], events) == [(100.0, 0)]


def test_a_task_under_a_robots_id_from_another_node_is_not_the_robots():
    from server_select.soak.history import own_sends
    sent = [Sent(1.0, 1, 5, 2, '/robot1'), Sent(0.5, 1, 900, 2, '/intruder_1_2'),
            Sent(0.7, 1, 3, 1, '/robot1')]
    assert [s.task for s in own_sends(sent)] == [3, 5]
    reports = [report(1.0, 1, task) for task in range(1, 6)]
    assert checks.ledger(reports, own_sends(sent), [], TIMEOUT)['unreported'] == []
    assert len(checks.ledger(reports, sent, [], TIMEOUT)['unreported']) == 895


def test_faults_at_once_are_over_together_and_recovery_counts_from_the_last():
    short = {'start': 100.0, 'end': 102.0, 'bound': 5.0}
    long_ = {'start': 100.0, 'end': 112.0, 'bound': 5.0}
    later = {'start': 130.0, 'end': 131.0, 'bound': 5.0}
    events = [short, long_, later]
    assert checks.over_with(short, events) == 112.0
    assert checks.over_with(long_, events) == 112.0 and checks.over_with(later, events) == 131.0
    before = _steady(40.0, 100.0)
    during = _steady(102.0, 112.0, rtt=0.05)            # the long fault still on
    after = _steady(112.0, 125.0)
    back, _ = checks.recovery(sorted(before + during + after), short, events, {1, 2}, 125.0)
    assert back is not None and back <= checks.STEP
