import pytest

from server_select.core.passive import TaskBaseline
from server_select.core.window import median, trimmed_mean, LatencyWindow


def test_a_task_sample_is_its_round_trip_less_the_kinds_baseline():
    b = TaskBaseline(keep=50, quantile=0.1, min_count=5)
    # idle servers: a task takes its probe latency + 3 ms of work
    learned = [b.sample('sort', probe + 0.003, probe) for probe in
               (0.010, 0.020, 0.004, 0.010, 0.012)]
    assert learned[:4] == [None] * 4               # still learning
    assert learned[4] == pytest.approx(0.012)      # = its probe latency
    # a loaded server: 25 ms of queueing above the work
    assert b.sample('sort', 0.010 + 0.003 + 0.025, 0.010) == pytest.approx(0.035)
    # the baseline is per kind
    assert b.sample('image', 0.5, 0.010) is None
    assert b.baseline('sort') == pytest.approx(0.003)


def test_unknown_probe_latency_or_bad_rtt_give_no_sample():
    b = TaskBaseline(min_count=1)
    assert b.sample('sort', 0.01, None) is None
    assert b.sample('sort', float('nan'), 0.01) is None
    assert b.baseline('sort') is None
    with pytest.raises(ValueError):
        TaskBaseline(quantile=1.0)


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
