"""The two longest smoke runs of the benchmarks (`make bench` and `make bench-scale`, tiny),
kept apart from test_bench_smoke.py so that `make test` runs them after the fault tests
rather than after the catkin stage (whose stream was the longest).

Checks that each produced figures (counts > 0, finite values) and the report sections;
asserts nothing about how fast anything is.
"""
import json
import subprocess
import sys

from test_bench_smoke import finite


def test_every_benchmark_runs_and_reports(tmp_path):
    out = tmp_path / 'bench'
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.run', '--tiny',
                           '--out', str(out)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:]
    report = (out / 'REPORT.md').read_text()
    for section in ('## Table 2', '## LatencyProbe round trip', '## Table 1',
                    '## Sort-task throughput', '## Image throughput', '## Where a sort task'):
        assert section in report, section
    table2 = json.loads((out / 'table2.json').read_text())
    assert all(r['ros_us']['n'] == r['count'] == r['socket_us']['n'] for r in table2)
    assert all(finite(r['ros_us']['mean']) and finite(r['socket_us']['mean']) for r in table2)
    probe = json.loads((out / 'probe_vs_echo.json').read_text())
    assert probe['probe_us']['n'] > 0 and probe['socket_echo_us']['n'] > 0
    table1 = json.loads((out / 'table1.json').read_text())
    for label in ('local', 'offload'):
        assert all(finite(v) for v in table1[label].values())
    for name, unit in (('sort_throughput', 'hz'), ('image_throughput', 'fps')):
        rows = json.loads((out / ('%s.json' % name)).read_text())
        assert rows and all(r['achieved_' + unit] > 0 for r in rows), rows
    breakdown = json.loads((out / 'sort_breakdown.json').read_text())
    assert all(r['tasks'] > 0 and finite(r['rtt_ms']) for r in breakdown), breakdown


def test_the_scale_benchmark_runs_and_reports(tmp_path):
    """`make bench-scale` in a tiny configuration: flat per robot and grouped. (--limit is
    how long a cell may wait to be ranked: about 2 s alone, over 6 s once beside the other
    test streams; a cell ranked sooner goes on at once.)"""
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.scale', '--sizes', '3x4',
                           '--layouts', 'robot,pair,view', '--grouped-sizes', '4x4:2', '--limit',
                           '20', '--measure', '2', '--signed', 'on', '--out', str(tmp_path)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    rows = json.loads((tmp_path / 'scale.json').read_text())
    assert [r['layout'] for r in rows] == ['robot', 'pair', 'view', 'grouped']
    assert all(r['signed'] for r in rows)
    # signed samples (a fleet key): every robot ranked, flags moved by the slow samples
    for row in rows:
        assert finite(row['ranked_s']) and row['changes'] > 0, row
        assert finite(row['manager_cpu']) and row['threads'] > 0, row
