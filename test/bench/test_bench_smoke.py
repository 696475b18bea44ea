"""Runs every benchmark of `make bench` once in its tiny configuration, so none can rot.

Checks that each produced figures (counts > 0, finite values) and the report sections;
asserts nothing about how fast anything is.
"""
import json
import math
import subprocess
import sys


def finite(value):
    return isinstance(value, (int, float)) and math.isfinite(value)


def test_the_master_call_benchmark_counts_calls(tmp_path):
    """`make bench-master` in a tiny configuration: the proxy sees the fleet's calls."""
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.master_calls',
                           '--robots', '2', '--servers', '2', '--warmup', '1', '--seconds', '4',
                           '--profiles', 'fleet', '--out', str(tmp_path)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    (run,) = json.loads((tmp_path / 'master_calls.json').read_text())
    assert run['nodes'] == ['/manager', '/server1', '/server2', '/robot1', '/robot2']
    # the manager, at least, checks the master's pid every second
    assert any(c['method'] == 'getPid' and c['caller'] == '/manager' and c['count'] > 0
               for c in run['calls']), run['calls']
    assert 'per node' in proc.stdout


def test_the_fleet_of_real_nodes_benchmark_measures_each_role(tmp_path):
    """`make bench-fleet` in a tiny configuration: both layouts, every role measured."""
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.fleet_nodes',
                           '--sizes', '2x2', '--seconds', '3', '--out', str(tmp_path)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    rows = json.loads((tmp_path / 'fleet_nodes.json').read_text())
    assert [r['layout'] for r in rows] == ['samples', 'views']
    for row in rows:
        assert row['all_flagged'] and (row['manager_processes'], row['robot_processes'],
                                       row['server_processes']) == (1, 2, 2), row
        assert row['manager_in_msgs_s'] > 0 and row['flag_bytes_per_robot_s'] > 0, row
        assert all(finite(row[k]) for k in ('manager_cpu', 'robot_rss', 'flag_size')), row
    assert 'at 1,000 robots' in proc.stdout


def test_the_seal_benchmark_runs_and_reports(tmp_path):
    """`make bench-seal` in a tiny configuration: every message sealed and checked."""
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.seal_cost', '--count',
                           '20', '--repeats', '2', '--out', str(tmp_path)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    rows = json.loads((tmp_path / 'seal_cost.json').read_text())
    assert len(rows) == 8 and all(len(r['seal_us']) == 2 and all(
        finite(v) and v > 0 for v in r['seal_us'] + r['check_us']) for r in rows), rows
    assert '(seal + check) / serialize' in proc.stdout


def test_the_fleet_key_benchmark_measures_both_fleets(tmp_path):
    """`make bench-seal`'s second part, tiny: two fleets side by side, with a key and without."""
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.seal_fleet', '--servers',
                           '2', '--repeats', '1', '--warmup', '3', '--seconds', '4', '--out',
                           str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    run, = json.loads((tmp_path / 'seal_fleet.json').read_text())
    for keyed in ('key', 'nokey'):
        counts = dict((role, len(run[keyed][role])) for role in ('robot', 'manager', 'server'))
        assert counts == {'robot': 1, 'manager': 1, 'server': 2}, (keyed, counts)
        assert all(finite(u['cpu_percent']) and u['rss_mb'] > 10
                   for used in run[keyed].values() for u in used), run
    assert 'robot CPU with the key / without, per run' in proc.stdout


def test_the_top_benchmark_measures_top_beside_a_fleet(tmp_path):
    """`make bench-top`, tiny: top in a pseudo-terminal beside 2 robots x 2 servers."""
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.top_cost', '--robots',
                           '2', '--servers', '2', '--repeats', '1', '--warmup', '3',
                           '--seconds', '3', '--out', str(tmp_path)], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    run, = json.loads((tmp_path / 'top_cost.json').read_text())
    # CPU time comes in 10 ms ticks: top's 0.3-0.7 % over 3 s is 0-2 of them, so 0 is a
    # measurement; its resident memory says the process measured is top's
    assert all(finite(run[k]) and run[k] >= 0 for k in ('top_cpu', 'robot_cpu')), run
    assert run['top_rss'] > 10, run
    assert 'top beside a fleet of 2 robots x 2 servers' in proc.stdout


def test_the_probe_cost_benchmark_counts_probes(tmp_path):
    """`make bench-probes` in a tiny configuration: the servers count the robot's probes."""
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.probe_cost',
                           '--servers', '6', '--repeats', '1', '--warmup', '3', '--seconds', '4',
                           '--out', str(tmp_path)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    runs = json.loads((tmp_path / 'probe_cost.json').read_text())
    assert [r['variant'] for r in runs] == ['uniform', 'adaptive']
    # uniform: every server at 4 Hz; adaptive: the nearest two at up to 10 Hz each, the
    # others less often, on a quiet host (there: 20-22.5 of 22-24.5 probes a second to
    # the two, with or without three busy loops beside at nice 0). In make test this runs
    # at nice 19 beside the other streams, and twice in CI every server stayed a
    # contender (6.5 of 19.5 a second, uniform's third): answers late by milliseconds now
    # and then widen each server's band of 3 standard errors past the 2.0-5.5 ms spread,
    # and all six share the probe budget. So the smoke run checks the shares, not the
    # rates: the two nearest never get less than their uniform share.
    assert all(r['probes'] > 0 and r['cpu'] is not None for r in runs), runs
    uniform, adaptive = (r['near'] / r['probes'] for r in runs)
    assert adaptive > uniform - 0.05, runs
    assert 'target probes/s' in proc.stdout


def test_the_loopback_demo_benchmark_counts_switches_and_work_reports(tmp_path):
    """`make bench-loopback` in a tiny configuration: one short run of the fleet demo gives
    each robot's switches and the work each server reported to the observer's probes."""
    proc = subprocess.run([sys.executable, '-m', 'server_select.bench.loopback_demo',
                           '--runs', '1', '--seconds', '15', '--out', str(tmp_path)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    (run,) = json.loads((tmp_path / 'loopback_demo.json').read_text())['runs']
    # both robots heard by the demo's report (one of three runs had lost robot 2's reports)
    assert run['unheard'] == [] and len(run['switches_per_min']) == 2 and run['tasks'] > 0, run
    # the robots send sort tasks from the start: some server did some and reported them
    assert any(finite(w) and w > 0 for w in run['work_ms'].values()), run['work_ms']
    assert 'switches a minute per robot' in proc.stdout
    assert run['settled_per_min'] == [] and 'settled (from 15 s)' in proc.stdout  # 15 s: none
