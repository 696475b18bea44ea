"""The scenario suite (`make evaluate-suite`) in a tiny configuration: one short scenario
with a hung and a slowed server, five variants side by side (two of them the league's
peers: the league's smoke run), one run. Checks that every variant's tasks arrive and are
reported, that the hang and the work change really happen, and that the report and plots
are written. Needs root and TUN."""

import glob
import json
import os
import subprocess
import sys

import pytest

from server_select.testbed.netns import available

ok, why = available()
pytestmark = pytest.mark.skipif(not ok, reason=why)

HERE = os.path.dirname(os.path.abspath(__file__))


def test_suite_runs_variants_side_by_side(tmp_path):
    proc = subprocess.run(
        [sys.executable, os.path.join(HERE, '..', '..', 'scripts', 'evaluate'), '--suite',
         '--scenarios', os.path.join(HERE, 'suite_smoke.yaml'), '--variants',
         'oracle,paper,fleet,prequal,replicate', '--repeats', '1', '--out', str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
        timeout=300)
    print(proc.stdout[-4000:])
    assert proc.returncode == 0
    results = json.loads((tmp_path / 'summary.json').read_text())['suite_smoke'][0]
    assert set(results) == {'oracle', 'paper', 'fleet', 'prequal', 'replicate'}
    for variant, figures in results.items():
        assert figures['tasks'] >= 25, (variant, figures)      # 2 Hz over 17 s measured
    # the league's peers choose per task beside the others: replication sends a task twice
    # while both servers are usable (once to server 2 while the hung server 1 is ejected:
    # 6 s of the 17 measured; 65-70 % extra sends seen), Prequal once but for re-sends
    assert 0.45 <= results['replicate']['extra'] <= 1.10, results['replicate']
    assert results['prequal']['extra'] < 0.30, results['prequal']
    # the fleet profile's robot ejects the hung server and fails over: nothing is lost
    assert results['fleet']['failed'] == 0, results['fleet']
    logs = glob.glob(str(tmp_path / 'suite_smoke' / 'run1' / 'ros_home' / 'server2' / 'log'
                         / '**' / '*.log'), recursive=True)
    assert any('each task now takes 0.02 s more' in open(p).read() for p in logs), logs
    events = tmp_path / 'suite_smoke' / 'run1' / 'events.log'
    assert 'server1: SIGSTOP' in events.read_text() and 'server1: SIGCONT' in events.read_text()
    report = (tmp_path / 'report.md').read_text()
    assert '| fleet |' in report and 'mean / oracle' in report
    assert (tmp_path / 'suite_smoke' / 'time_run1.png').exists()
    assert (tmp_path / 'suite_smoke' / 'cdf_run1.png').exists()
