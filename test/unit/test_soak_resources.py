"""Resource slopes: a leak shows as a slope, a restart's drop does not, nor a start's rise."""

import os
import time

from server_select.soak import resources
from server_select.soak.resources import Sample


def series(node, pid, start, end, rss, leak_per_s=0.0, cpu_share=0.1):
    return [Sample(t, node, pid, rss + leak_per_s * (t - start), 20, 8, cpu_share * t)
            for t in range(start, end, 10)]


def test_a_leak_is_a_slope_per_ten_minutes_and_a_flat_node_none():
    samples = series('robot1', 10, 0, 1800, 50.0, leak_per_s=1.0 / 600) + \
        series('robot2', 11, 0, 1800, 50.0)
    found = resources.slopes(samples, 900.0, 1800.0)
    assert abs(found['robot1']['rss_mib'][0] - 1.0) < 1e-6
    assert found['robot2']['rss_mib'][0] == 0.0
    assert found['robot2']['fds'][0] == 0.0 and found['robot2']['threads'][0] == 0.0
    assert abs(found['robot2']['cpu_s'][0]) < 1e-6        # a steady 10 % of a core


def test_a_restart_is_no_slope_and_its_first_minute_is_left_out():
    before = series('server1', 20, 0, 1200, 120.0)
    after = [s._replace(rss_mib=40.0 + min(60.0, s.t - 1200)) for s in     # grows, then flat
             series('server1', 21, 1200, 1800, 0.0)]
    found = resources.slopes(before + after, 900.0, 1800.0)
    assert found['server1']['rss_mib'][0] == 0.0


def test_read_measures_this_process():
    sample = resources.read(os.getpid(), 'me', time.time())
    assert sample.rss_mib > 1 and sample.fds >= 3 and sample.threads >= 1 and sample.cpu_s > 0


def test_a_gone_or_zombie_process_is_no_sample(tmp_path, monkeypatch):
    assert resources.read(2 ** 22 + 7, 'gone', 0.0) is None
    status = tmp_path / 'status'
    status.write_text('Name:\tx\nState:\tZ (zombie)\nThreads:\t1\n')     # no VmRSS
    real_open = open
    monkeypatch.setattr('builtins.open', lambda path, *a, **k: real_open(
        status if str(path).endswith('/status') else path, *a, **k))
    assert resources.read(os.getpid(), 'zombie', 0.0) is None
