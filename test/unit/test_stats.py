import math
import random
import statistics

from server_select.core.util.stats import mean_error


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
