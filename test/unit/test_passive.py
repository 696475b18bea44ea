import random

import pytest

from server_select.core.passive import TaskBaseline
from server_select.core.window import median, trimmed_mean, LatencyWindow


def test_a_task_sample_is_its_round_trip_less_the_fastest_servers_overhead():
    b = TaskBaseline(keep=50, min_count=5)
    # server 1, idle: a task takes its probe latency + 3 ms of work
    learned = [b.sample('sort', 1, probe + 0.003, probe) for probe in
               (0.010, 0.020, 0.004, 0.010, 0.012)]
    assert learned[:4] == [None] * 4               # still learning
    assert learned[4] == pytest.approx(0.012)      # = its probe latency
    # server 2 is loaded: 25 ms of queueing above the same work
    for _ in range(10):
        sample = b.sample('sort', 2, 0.010 + 0.003 + 0.025, 0.010)
    assert sample == pytest.approx(0.035)          # probe latency + the load
    assert b.overhead('sort', 2) == pytest.approx(0.028)
    assert b.baseline('sort') == pytest.approx(0.003)   # the fastest server's
    assert b.sample('image', 1, 0.5, 0.010) is None     # per kind


def test_jitter_does_not_bias_the_samples_of_the_fastest_server():
    rng = random.Random(1)
    b = TaskBaseline(keep=200)
    samples = []
    for _ in range(400):
        probe = 0.010 + rng.uniform(-0.002, 0.002)          # the window's probe mean
        samples.append(b.sample('sort', 1, 0.010 + 0.002 + rng.uniform(-0.004, 0.004),
                                probe))
    samples = [s for s in samples if s is not None]
    assert sum(samples) / len(samples) == pytest.approx(0.010, abs=0.0005)


def test_unknown_probe_latency_or_bad_rtt_give_no_sample():
    b = TaskBaseline(min_count=1)
    assert b.sample('sort', 1, 0.01, None) is None
    assert b.sample('sort', 1, float('nan'), 0.01) is None
    assert b.baseline('sort') is None
    with pytest.raises(ValueError):
        TaskBaseline(keep=0)


def test_statistics():
    assert median([3, 1, 2]) == 2 and median([4, 1, 2, 3]) == 2.5
    assert trimmed_mean([0.02, 0.02, 0.242, 0.02, 0.02]) == pytest.approx(0.02)
    assert trimmed_mean([1.0, 3.0]) == 2.0
    w = LatencyWindow(5.0, 'peak_ewma', tau=1.0)
    w.add(1, 1, 0.0, True, 0.010)
    assert w.add(1, 1, 1.0, True, 0.100)[1].value == 0.100          # a peak at once
    decayed = w.add(1, 1, 2.0, True, 0.010)[1].value
    assert 0.010 < decayed < 0.100 and decayed == pytest.approx(0.010 + 0.090 * 0.3679, 1e-3)
    assert w.stats(1, 1, 2.0).se > 0
