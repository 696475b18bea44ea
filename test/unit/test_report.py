import pytest

from server_select.core.observe.summary import RunReport, switch_count
from server_select.core.util.stats import format_ms, summarize


def test_summarize():
    s = summarize([0.001, 0.002, 0.003, float('nan'), None])
    assert s['n'] == 3 and s['median'] == 0.002 and s['max'] == 0.003
    assert summarize([]) == {'n': 0}
    assert format_ms({'n': 0}) == 'no samples'
    assert format_ms(s, ('median',)) == 'median 2.000 ms'


def test_run_report_counts_switches_and_tasks():
    r = RunReport()
    r.add_flag(1, 2, [2, 1], [0.001, 0.002])
    r.add_flag(1, 2, [2, 1], [0.001, 0.002])
    r.add_flag(1, 1, [1, 2], [0.001, 0.002])
    r.add_task(1, True, 0.004, 2, '', 1, 2)
    r.add_task(1, False, float('nan'), -1, 'timeout', 2, 1)     # sent to 1: a switch
    r.add_probe(1, 1, True, 0.0005)
    r.add_probe(1, 2, False, 0.0)
    (s,) = r.summaries()
    assert s['switches'] == 1 and s['selected'] == 1
    assert (s['tasks'], s['ok'], s['failed']) == (2, 1, 1)
    assert s['errors'] == {'timeout': 1} and s['servers_used'] == [2]
    assert (s['probes'], s['probes_failed'], s['probe_rtt']['n']) == (2, 1, 1)
    table = r.table()
    # the failed task counts at the task timeout (2 s): median of 4 ms and 2000 ms
    assert s['rtt']['max'] == 2.0 and s['rtt']['median'] == pytest.approx(1.002)
    assert ('| R1 | S1 | S1 1.00, S2 2.00 | 1 | 2 | 1 | 1 | 1002.00 | 1900.20 | 1980.04 '
            '| 2000.00 | 2 (1) | 0.50 | 0.50 |') in table
    r.add_task(2, True, 0.003, 1, '')
    assert r.verdict() == ('2 robots sent 3 tasks, 1 failed, median task round trip 4.00 ms; '
                           'selected now: R1 -> S1, R2 -> none; switches in all: 1')
    assert RunReport().verdict() == ('0 robots sent 0 tasks, 0 failed; selected now: none; '
                                     'switches in all: 0')


def test_median_and_range_of_repeated_runs():
    from server_select.core.util.tables import median_range
    assert median_range([3.0, 1.0, 2.0]) == '2.0 (1.0-3.0)'
    assert median_range([1.0, 4.0], '%.0f') == '2 (1-4)'   # 2.5 rounds to even
    assert median_range([7], '%d') == '7'


def test_the_legend_says_what_every_column_of_the_table_means():
    header = RunReport().table().splitlines()[0]
    legend = RunReport.legend()
    for column in ('selected', 'ranking', 'switches', 'tasks', 'ok', 'failed', 'task RTT',
                   'probes (failed)', 'probe RTT'):
        assert column in header and any(line.startswith(column) or ', %s' % column in
                                        line.split(':')[0] for line in legend.splitlines()), \
            column
    assert 'counts at the task timeout' in legend


def test_one_count_of_switches_from_where_tasks_went():
    assert switch_count([1, 1, 2, -1, 2, -2, 3, 1]) == 3     # no server, local: left out
    assert switch_count([]) == 0
    # frames to 1 and sort tasks to 2, taking turns: neither kind switches
    assert switch_count([1, 2, 1, 2, 3], ['image', 'sort', 'image', 'sort', 'sort']) == 1


def test_percentiles_match_numpys_linear_interpolation():
    import numpy as np
    import random
    rng = random.Random(4)
    for n in (1, 2, 7, 100, 1001):
        values = [rng.uniform(0, 1) for _ in range(n)]
        s = summarize(values)
        for key, q in (('median', 50), ('p95', 95), ('p99', 99)):
            assert s[key] == pytest.approx(float(np.percentile(values, q)), abs=1e-12)
        assert s['sd'] == pytest.approx(float(np.std(values, ddof=1)) if n > 1 else 0.0)
