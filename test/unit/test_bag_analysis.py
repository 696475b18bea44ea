import pytest

from server_select.testbed.bag_analysis import (Flag, Report, felt_changes, mode_summary,
                                                oracle_changes, reaction_times, switches)
from server_select.testbed.bag_tables import compare, legend, profiles, table, verdict
from server_select.testbed.scenario import Scenario


def flag(t, robot, server):
    return Flag(t, robot, server, [server], [0.001])


def test_switches_count_changes_of_the_target_server_in_task_order():
    reports = [Report(0, 1, task, True, 0.001, server, server, '')
               for task, server in [(3, 3), (1, 2), (2, 2), (4, 2), (5, -1), (6, 2)]]
    reports.append(Report(0, 2, 1, True, 0.001, 1, 1, ''))
    assert switches(reports) == {1: 2, 2: 0}


def scenario():
    return Scenario({'hosts': {'m': {'role': 'manager'}, 's1': {'role': 'server', 'id': 1},
                               's2': {'role': 'server', 'id': 2},
                               'r1': {'role': 'robot', 'id': 1}},
                     'links': {'r1 s1': [{'at': 0, 'delay': 2}, {'at': 10, 'ramp': 12, 'over': 10}],
                               'r1 s2': [{'at': 0, 'delay': 6}, {'at': 30, 'down': True}]}})


def test_oracle_changes_find_the_ramp_crossing_and_the_down_link():
    changes = oracle_changes(scenario(), [1], 0.0, 40.0, step=0.05)
    assert [(round(t, 2), r, s) for t, r, s in changes] == [(14.05, 1, 2), (30.0, 1, 1)]


def test_a_ramp_crossing_is_felt_once_the_gap_is_a_millisecond_a_step_at_once():
    changes = oracle_changes(scenario(), [1], 0.0, 40.0, step=0.05)
    felt = felt_changes(scenario(), changes)
    # s1 grows 1 ms a second one way: 1 ms of round trip slower than s2 0.5 s after the
    # crossing; s2's link going down is felt when it happens
    assert [(round(t, 2), r, s) for t, r, s in felt] == [(14.5, 1, 2), (30.0, 1, 1)]
    # a change undone before it is felt is left out
    assert [(round(t, 2), r, s) for t, r, s in felt_changes(
        scenario(), [(14.05, 1, 2), (14.3, 1, 1)])] == [(30.0, 1, 1)]


def test_reaction_times():
    changes = [(14.0, 1, 2), (30.0, 1, 1)]
    flags = [flag(5, 1, 1), flag(15, 1, 1), flag(16.5, 1, 2), flag(29, 1, 2)]
    assert reaction_times(flags, changes) == [(14.0, 1, 2, 2.5), (30.0, 1, 1, None)]
    # already on the new server before the change: no reaction needed
    assert reaction_times([flag(13, 1, 2)], [(14.0, 1, 2)]) == [(14.0, 1, 2, 0.0)]


def report(task, ok, rtt, server=1):
    return Report(0, 1, task, ok, rtt, server, server if ok else -1, '' if ok else 'timeout')


def test_mode_summary_compare_and_table():
    summaries = {
        'select': mode_summary([report(1, True, 0.010), report(2, True, 0.020, server=2)],
                               [flag(1, 1, 1), flag(2, 1, 2)], [(1.5, 1, 2)]),
        'fixed': mode_summary([report(1, True, 0.030), report(2, False, float('nan'))], []),
        'oracle': mode_summary([report(1, True, 0.010), report(2, True, 0.010)], []),
    }
    compare(summaries)
    s = summaries['select']
    assert (s['tasks'], s['failed'], s['switches']) == (2, 0, 1)
    assert s['rtt_ms']['mean'] == pytest.approx(15.0)
    # the failed task counts at the 2 s task timeout: fixed's mean is (30 + 2000) / 2 ms
    assert summaries['fixed']['rtt_ms']['mean'] == pytest.approx(1015.0)
    assert summaries['fixed']['rtt_ms']['max'] == pytest.approx(2000.0)
    assert s['vs_fixed_pct'] == pytest.approx(100.0 * (1015 - 15) / 1015)
    assert s['gap_to_oracle_pct'] == pytest.approx(50.0)
    assert s['reaction_mean_s'] == pytest.approx(0.5) and s['reaction_missed'] == 0
    assert summaries['fixed']['failed'] == 1
    text = table(summaries)
    assert '| select | 2 | 0 | 15.00 | 15.00 |' in text
    assert '+98.5 %' in text and '| fixed | 2 | 1 | 1015.00 |' in text


def test_the_verdict_says_what_selection_achieved_in_plain_words():
    summaries = {'select': {'tasks': 120, 'failed': 0, 'vs_fixed_pct': 50.8,
                            'gap_to_oracle_pct': 19.1},
                 'fixed': {'tasks': 120, 'failed': 3, 'vs_fixed_pct': 0.0,
                           'gap_to_oracle_pct': 142.0}}
    assert verdict(summaries) == (
        'select was 51 % faster than a fixed server and 19 % slower than the oracle that '
        'knows the network (mean task round trip); 0 of 120 tasks failed.')
    worse = {'select': {'tasks': 10, 'failed': 1, 'vs_fixed_pct': -5.0,
                        'gap_to_oracle_pct': None}}
    assert verdict(worse) == ('select was 5 % slower than a fixed server (mean task round '
                              'trip); 1 of 10 tasks failed.')
    alone = {'select': {'tasks': 4, 'failed': 0}}
    assert verdict(alone) == 'select: nothing to compare with; 0 of 4 tasks failed.'
    assert verdict({}) == 'no select run to judge'


def test_the_legend_says_each_column_once_and_why_a_column_is_empty():
    full = {'select': {'vs_fixed_pct': 10.0, 'gap_to_oracle_pct': 5.0, 'reactions': [0.5]},
            'fixed': {'vs_fixed_pct': 0.0, 'gap_to_oracle_pct': 20.0}}
    text = legend(full)
    for column in ('tasks, failed', 'mean ... max ms', 'vs fixed', 'gap to oracle',
                   'switches', 'reaction'):
        assert sum(line.startswith(column + ':') for line in text.splitlines()) == 1, column
    assert '(+: faster)' in text and '(+: slower)' in text
    assert '"-"' not in text
    plain = legend({'select': {'vs_fixed_pct': None, 'gap_to_oracle_pct': None}})
    assert '(left out: vs fixed, no fixed run to compare with; gap to oracle, no oracle run ' \
        'to compare with; reaction, no scenario, which says when the nearest server ' \
        'changes)' in plain
    assert not any(plain.startswith(c + ':') or '\n%s:' % c in plain
                   for c in ('vs fixed', 'gap to oracle', 'reaction'))


def test_columns_that_apply_to_no_row_are_left_out_of_the_table():
    plain = {'run': mode_summary([report(1, True, 0.010), report(2, False, float('nan'))], [])}
    header = table(plain).splitlines()[0]
    assert header == ('| mode | tasks | failed | mean ms | median ms | p95 ms | p99 ms | '
                      'max ms | switches |')
    assert table(plain).splitlines()[2].startswith('| run | 2 | 1 |')


def test_the_profiles_are_compared_on_the_same_scenario_in_one_line():
    summaries = {'select': {'rtt_ms': {'mean': 10.0}, 'failed': 2, 'tasks': 40},
                 'fleet': {'rtt_ms': {'mean': 8.0}, 'failed': 0, 'tasks': 40}}
    line = profiles(summaries)
    assert line.startswith("the fleet profile was 20 % faster than the paper's on this "
                           'scenario (8.0 ms against 10.0 ms), 0 against 2 tasks failed'), line
