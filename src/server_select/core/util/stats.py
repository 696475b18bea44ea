"""Summary statistics used by reports and benchmarks, and the mean and its error on a
robot's hot path; the spread of a series about its trend and where its last step began."""

import math
import statistics


def percentile(ordered, q):
    """The ``q`` percentile (0-100) of the sorted ``ordered``, interpolated linearly
    between the two nearest ranks (numpy's default)."""
    position = (len(ordered) - 1) * q / 100.0
    low = int(math.floor(position))
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (position - low)


def mean_error(values, independent=None):
    """``(mean, its standard error)`` of the non-empty ``values`` (error 0.0 for one), as
    if ``independent`` of them (at most all) were independent. In floats: ``statistics``
    computes exact fractions, two thirds of a fleet robot's choice per task (1.0 against
    0.2 ms here), on robots that may have a Pi's CPU."""
    count = len(values)
    mean = math.fsum(values) / count       # statistics.fmean's sum, without its checks
    if count < 2:
        return mean, 0.0
    variance = math.fsum([(v - mean) ** 2 for v in values]) / (count - 1)
    n = count if independent is None else max(1.0, min(count, independent))
    return mean, math.sqrt(variance / n)


def median_error(values):
    """``(median, its standard error)`` of the non-empty ``values``, the error from their
    median absolute deviation (1.4826 x MAD estimates a normal sigma; a median's error is
    1.2533 x sigma / the square root of their number): a value or two far off move
    neither."""
    ordered = sorted(values)
    median = percentile(ordered, 50)
    if len(ordered) < 2:
        return median, 0.0
    mad = percentile(sorted([abs(v - median) for v in ordered]), 50)
    return median, 1.2533 * 1.4826 * mad / math.sqrt(len(ordered))


def median_deviation(series):
    """The median over ``series`` (lists of numbers) of each one's median absolute
    deviation from its median (None: no list of 3 or more): how far a value strays, robust
    to a list's own level and to a few far ones."""
    deviations = []
    for values in series:
        if len(values) >= 3:
            middle = statistics.median(values)
            deviations.append(statistics.median(abs(v - middle) for v in values))
    return statistics.median(deviations) if deviations else None


def summarize(values):
    """n, mean, sd, min, median, p95, p99, max of the finite ``values`` (``{'n': 0}``
    when there are none)."""
    ordered = sorted(float(v) for v in values if v is not None and math.isfinite(v))
    if not ordered:
        return {'n': 0}
    return {
        'n': len(ordered),
        'mean': math.fsum(ordered) / len(ordered),
        'sd': statistics.stdev(ordered) if len(ordered) > 1 else 0.0,
        'min': ordered[0],
        'median': percentile(ordered, 50),
        'p95': percentile(ordered, 95),
        'p99': percentile(ordered, 99),
        'max': ordered[-1],
    }


def format_ms(summary, keys=('median', 'p95', 'p99', 'max')):
    """``median 1.23 ms, p95 ...`` for a summary of seconds."""
    if summary.get('n', 0) == 0:
        return 'no samples'
    return ', '.join('%s %.3f ms' % (k, summary[k] * 1e3) for k in keys)


def spread_of(levels):
    """The standard deviation of ``levels`` about their trend: the median of their second
    differences over 0.6745 x sqrt 6 (0.0 for fewer than four)."""
    return 0.0 if len(levels) < 4 else statistics.median(
        [abs(a - 2.0 * b + c) for a, b, c in zip(levels, levels[1:], levels[2:])]) \
        / (0.6745 * math.sqrt(6.0))


def since_step(levels, z):
    """``levels`` from the first of the last three or more that all lie beyond the range
    of those before by more than ``z`` times their own range (all of them: none such). A
    server's load that came and went (a burst of other robots' frames queued there) says
    nothing of how its level strays now; noise makes such a gap about never: the newest
    all beyond every earlier one, and far beyond their own spread."""
    for first in range(4, len(levels) - 2):
        before, after = levels[:first], levels[first:]
        reach = z * (max(after) - min(after))
        if max(after) + reach < min(before) or min(after) - reach > max(before):
            return after
    return levels
