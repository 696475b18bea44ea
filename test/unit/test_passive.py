import math
import random

import pytest

from server_select.core.ranking.passive import TaskBaseline, TaskCost
from server_select.core.ranking.window import median, trimmed_mean, LatencyWindow


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
    w = LatencyWindow(5.0, 'trimmed')
    for t, rtt in enumerate((0.010, 0.012, 0.242, 0.011)):
        w.add(1, 1, float(t), True, rtt)
    assert w.stats(1, 1, 3.0).value == pytest.approx(0.0115)       # the spike trimmed
    assert w.stats(1, 1, 3.0).se > 0


def test_a_servers_task_cost_is_added_to_its_probes_and_fades_once_its_tasks_stop():
    cost = TaskCost(tau=5.0, keep=9, min_count=3)
    key = (1, 2)
    assert cost.probe(key, 0.0, 0.010) == pytest.approx(0.010)    # nothing known: as is
    cost.task(key, 0.1, 0.035)
    cost.task(key, 0.2, 0.035)
    assert cost.penalty(key, 0.2) == 0.0                          # fewer than min_count
    cost.task(key, 0.3, 0.035)
    assert cost.penalty(key, 0.3) == pytest.approx(0.025)         # 35 ms tasks, 10 ms probes
    assert cost.probe(key, 0.3, 0.010) == pytest.approx(0.035)
    # no task since 0.3 s: the memory fades with tau
    assert cost.penalty(key, 5.3) == pytest.approx(0.025 * math.exp(-1.0))
    assert cost.penalty(key, 30.3) < 0.0001
    assert cost.penalty((1, 3), 0.3) == 0.0                       # per pair
    cost.forget(key)
    assert cost.penalty(key, 0.3) == 0.0


def test_one_slow_task_or_tasks_faster_than_probes_make_no_penalty():
    cost = TaskCost(tau=5.0, keep=9, min_count=3)
    cost.probe('a', 0.0, 0.020)
    for t, sample in enumerate([0.020, 0.021, 0.240, 0.020, 0.019]):   # one retransmission
        cost.task('a', 0.1 * t, sample)
    assert cost.penalty('a', 0.5) == pytest.approx(0.0, abs=0.0011)
    cost.probe('b', 0.0, 0.020)
    for t in range(5):
        cost.task('b', 0.1 * t, 0.015)
    assert cost.penalty('b', 0.5) == 0.0                          # never a bonus
    cost.task('c', 0.0, 0.5)                                      # no probe to compare with
    assert cost.penalty('c', 0.0) == 0.0
    with pytest.raises(ValueError):
        TaskCost(tau=0.0)


def test_the_probe_reference_follows_the_probes():
    cost = TaskCost(tau=5.0, min_count=1, probe_tau=1.0)
    cost.probe('a', 0.0, 0.010)
    for i in range(1, 41):            # the link gets slower: 30 ms probes for 10 s
        cost.probe('a', 0.25 * i, 0.030)
    cost.task('a', 10.0, 0.030)       # a task as fast as the probes: no excess
    assert cost.penalty('a', 10.0) == pytest.approx(0.0, abs=0.0001)
