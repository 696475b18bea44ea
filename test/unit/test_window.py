import pytest

from server_select.core.ranking.window import LatencyWindow


def test_mean_of_successful_samples_in_window():
    w = LatencyWindow(5.0)
    for t, rtt in [(0.0, 0.010), (1.0, 0.020), (2.0, 0.030)]:
        w.add(1, 1, t, True, rtt)
    stats = w.stats(1, 1, 2.0)
    assert stats.ok_count == 3
    assert stats.mean == pytest.approx(0.020)


def test_samples_older_than_window_are_dropped():
    w = LatencyWindow(5.0)
    w.add(1, 1, 0.0, True, 1.0)
    w.add(1, 1, 4.0, True, 0.002)
    assert w.stats(1, 1, 4.9).mean == pytest.approx(0.501)
    # the first sample is exactly `window` old at t=5.0: gone
    assert w.stats(1, 1, 5.0).mean == pytest.approx(0.002)
    assert w.stats(1, 1, 9.0)[:3] == (None, 0, 0)


def test_failed_samples_count_but_do_not_enter_the_mean():
    w = LatencyWindow(5.0)
    w.add(1, 2, 0.0, True, 0.004)
    w.add(1, 2, 1.0, False, 123.0)
    stats = w.stats(1, 2, 1.0)
    assert stats.mean == pytest.approx(0.004)
    assert (stats.ok_count, stats.failed_count) == (1, 1)


def test_only_failed_samples_give_no_mean():
    w = LatencyWindow(5.0)
    w.add(1, 2, 0.0, False, 0.0)
    assert w.stats(1, 2, 0.5)[:3] == (None, 0, 1)


def test_pairs_are_independent_and_unknown_pairs_are_empty():
    w = LatencyWindow(5.0)
    w.add(1, 1, 0.0, True, 0.001)
    w.add(2, 1, 0.0, True, 0.009)
    assert w.stats(1, 1, 0.0).mean == pytest.approx(0.001)
    assert w.stats(2, 1, 0.0).mean == pytest.approx(0.009)
    assert w.stats(3, 3, 0.0)[:3] == (None, 0, 0)
    stats = w.robot_stats(1, [1, 2], 0.0)
    assert stats[1].ok_count == 1 and stats[2].mean is None


@pytest.mark.parametrize('bad', [0, -1.0, float('nan')])
def test_window_must_be_positive(bad):
    with pytest.raises(ValueError):
        LatencyWindow(bad)


def test_failed_sample_rtt_is_not_kept():
    w = LatencyWindow(1.0)
    w.add(1, 1, 0.0, False, 5.0)
    w.add(1, 1, 0.1, True, 0.5)
    stats = w.stats(1, 1, 0.1)
    assert stats.mean == 0.5 and (stats.ok_count, stats.failed_count) == (1, 1)


def test_running_sums_match_a_recomputation_over_a_long_stream():
    """Thousands of samples in and out of the window: the O(1) mean stays the mean."""
    import random
    rng = random.Random(4)
    w = LatencyWindow(5.0)
    kept = []
    for i in range(5000):
        t = i * 0.1
        ok = rng.random() > 0.1
        rtt = rng.choice([1e-4, 0.02, 0.242, 3.0]) * rng.random()
        w.add(1, 1, t, ok, rtt)
        kept = [(ts, o, r) for ts, o, r in kept if ts > t - 5.0] + [(t, ok, rtt)]
        good = [r for _, o, r in kept if o]
        stats = w.stats(1, 1, t)
        assert (stats.ok_count, stats.failed_count) == (len(good), len(kept) - len(good))
        if good:
            assert stats.mean == pytest.approx(sum(good) / len(good), rel=1e-9, abs=1e-12)


def test_a_pair_without_samples_is_forgotten():
    w = LatencyWindow(1.0)
    w.add(1, 1, 0.0, True, 0.1)
    assert w.stats(1, 1, 2.0)[:3] == (None, 0, 0)
    assert not w._pairs


def test_round_trips_beyond_an_hour_are_refused_so_sums_cannot_overflow():
    from server_select.core.ranking.window import MAX_RTT, valid_rtt
    assert valid_rtt(MAX_RTT) and not valid_rtt(MAX_RTT * 1.001) and not valid_rtt(1.7e308)
    w = LatencyWindow(5.0)
    for _ in range(3):
        with pytest.raises(ValueError, match='from 0 to 3600'):
            w.add(1, 1, 0.0, True, 1.7e308)
    w.add(1, 1, 0.0, True, MAX_RTT)
    assert w.stats(1, 1, 0.0).mean == MAX_RTT


def test_robust_errors_keep_the_spread_of_a_queue_that_is_empty_most_of_the_time():
    # a load-aware sample is the network's round trip + the server's wait, which is 0
    # most of the time and most of a second now and then
    w = LatencyWindow(10.0, robust=True)
    waits = [0.0, 0.0, 0.6, 0.0, 0.0, 0.3]
    for t, wait in enumerate(waits):
        w.add(1, 1, float(t), True, 0.001 + wait, wait)
    n = len(waits)
    mean = sum(waits) / n
    plain = (sum((x - mean) ** 2 for x in waits) / (n - 1) / n) ** 0.5
    stats = w.stats(1, 1, 5.0)
    assert stats.mean == pytest.approx(0.001 + mean)
    assert stats.se == pytest.approx(plain)     # the network part has no spread here
    # the same values given without their wait part: the median absolute deviation
    # calls them no spread at all
    blind = LatencyWindow(10.0, robust=True)
    for t, wait in enumerate(waits):
        blind.add(1, 1, float(t), True, 0.001 + wait)
    assert blind.stats(1, 1, 5.0).se == pytest.approx(0.0)


def test_a_step_in_the_network_still_does_not_widen_robust_errors_when_waits_are_known():
    w = LatencyWindow(10.0, robust=True)
    for t, rtt in enumerate([0.005, 0.005, 0.005, 0.005, 0.030, 0.030]):
        w.add(1, 1, float(t), True, rtt + 0.1, 0.1)      # a steady wait of 0.1 s
    assert w.stats(1, 1, 5.0).se == pytest.approx(0.0)


def test_load_aware_samples_rank_by_the_networks_median_plus_the_mean_wait():
    w = LatencyWindow(10.0)
    # a CPU-capped server answers some probes late (its quota spent); waits of its queue
    for t, (rtt, wait) in enumerate([(0.002, 0.0), (0.060, 0.0), (0.002, 0.5),
                                     (0.003, 0.0), (0.080, 0.3), (0.002, 0.0)]):
        w.add(1, 1, float(t), True, rtt + wait, wait)
    stats = w.stats(1, 1, 5.0)
    assert stats.value == pytest.approx(0.0025 + 0.8 / 6)   # median 2.5 ms + mean wait
    assert stats.mean == pytest.approx((0.149 + 0.8) / 6)     # the plain mean, as before
    plain = LatencyWindow(10.0)                                # wait not said: the paper's
    plain.add(1, 1, 0.0, True, 0.060)
    plain.add(1, 1, 1.0, True, 0.002)
    assert plain.stats(1, 1, 1.0).value == pytest.approx(0.031)


def test_the_median_of_the_network_part_has_the_larger_error_of_a_median():
    rtts = [0.010, 0.012, 0.009, 0.011, 0.013, 0.010]
    aware, blind = LatencyWindow(10.0, robust=True), LatencyWindow(10.0, robust=True)
    for t, rtt in enumerate(rtts):
        aware.add(1, 1, float(t), True, rtt, 0.0)
        blind.add(1, 1, float(t), True, rtt)
    # ranked by the median: its standard error is sqrt(pi / 2) x the mean's
    assert aware.stats(1, 1, 5.0).se == pytest.approx(
        blind.stats(1, 1, 5.0).se * (3.141592653589793 / 2) ** 0.5)
    assert aware.stats(1, 1, 5.0).value == pytest.approx(0.0105)
    assert blind.stats(1, 1, 5.0).value == pytest.approx(sum(rtts) / 6)
