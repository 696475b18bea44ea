"""The testbed benchmarks (`make bench-routing`, `make bench-hedging`) in a tiny
configuration, so that none can rot: they run, count tasks and bytes, and print their
tables. Nothing is asserted about what they measure. Needs root and TUN."""

import json
import subprocess
import sys

import pytest

from server_select.testbed.netns import available

ok, why = available()
pytestmark = pytest.mark.skipif(not ok, reason=why)


def run(module, args, tmp_path):
    proc = subprocess.run([sys.executable, '-m', module] + args + ['--out', str(tmp_path)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    return proc.stdout


def test_bytes_per_task_broadcast_and_direct(tmp_path):
    out = run('server_select.bench.routing_bytes',
              ['--servers', '2', '--kinds', 'sort', '--seconds', '8'], tmp_path)
    rows = json.loads((tmp_path / 'routing_bytes.json').read_text())
    assert [r['routing'] for r in rows] == ['broadcast', 'direct']
    assert all(r['tasks'] > 0 and r['up_kb'] > 0 and r['down_kb'] > 0 for r in rows), rows
    assert 'kB/task' in out


def test_hedging_off_and_on(tmp_path):
    out = run('server_select.bench.hedging', ['--seconds', '4', '--runs', '1'], tmp_path)
    results = json.loads((tmp_path / 'hedging.json').read_text())
    assert set(results) == {'off', 'on'}
    assert all(r['tasks'] > 0 for runs in results.values() for r in runs), results
    assert 'p99.9 ms' in out


def test_capacity_on_cpu_limited_servers(tmp_path):
    out = run('server_select.bench.capacity',
              ['--shares', '0.2,0.2', '--robots', '2', '--loads', '1', '--variants',
               'fleet,static', '--seconds', '12'], tmp_path)
    results = json.loads((tmp_path / 'capacity_overload.json').read_text())
    runs = results['kinds']['image']['runs']
    assert [r['variant'] for r in runs] == ['fleet', 'static']
    assert all(r['tasks'] > 0 and r['work'] > 0 for r in runs), runs
    assert (tmp_path / 'capacity_overload.png').exists()
    assert 'goodput / measured capacity %' in out
