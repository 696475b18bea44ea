import math
import random
import statistics

import pytest

from server_select.core.util.stats import mean_error, median_deviation, median_error


def test_mean_error_is_statistics_mean_and_stdev_over_the_root_of_n_in_floats():
    rng = random.Random(7)
    for count in (2, 3, 15, 64):
        values = [rng.gauss(0.012, 0.0007) for _ in range(count)]
        mean, error = mean_error(values)
        assert math.isclose(mean, statistics.mean(values), rel_tol=1e-12)
        assert math.isclose(error, statistics.stdev(values) / math.sqrt(count), rel_tol=1e-9)


def test_mean_error_counts_only_the_independent_values_and_one_value_has_none():
    values = [1.0, 2.0, 3.0, 4.0]
    assert mean_error(values, independent=1)[1] == statistics.stdev(values)
    assert mean_error(values, independent=100)[1] == statistics.stdev(values) / 2.0
    assert mean_error([5.0]) == (5.0, 0.0)


def test_median_error_is_the_median_with_an_error_from_the_absolute_deviations():
    rng = random.Random(1)
    values = [rng.gauss(10.0, 2.0) for _ in range(2000)]
    median, error = median_error(values)
    assert median == statistics.median(values)
    assert error == pytest.approx(1.2533 * 2.0 / math.sqrt(2000), rel=0.1)
    # one value far off moves neither, where it would take the mean and its error along
    spoiled = values[:9] + [1000.0]
    assert abs(median_error(spoiled)[0] - statistics.median(values[:9])) < 2.0
    assert median_error(spoiled)[1] < mean_error(spoiled)[1] / 10
    assert median_error([3.0]) == (3.0, 0.0)


def test_median_deviation_is_the_median_over_series_of_each_one_s_spread():
    assert median_deviation([[1.0, 2.0, 3.0, 100.0], [5.0, 5.0, 5.0], [0.0, 4.0, 8.0],
                             [7.0, 9.0]]) == 1.0      # 1, 0 and 4 (too short: left out)
    assert median_deviation([[1.0, 2.0]]) is None
