"""Statistics over seeds (no rospy): a cell's median with a distribution-free 95 %
interval, and paired differences with a t-interval.

A cell (one variant on one scenario) is summarised by the median over its seeds and the
interval between the order statistics that cover the median with 95 % confidence (the
sign test's: no assumption about the figures' distribution). Two variants are compared
per seed (both saw the same arrivals, links and task sizes): the mean of the per-seed
differences and its Student-t 95 % interval, the paired test's.
"""

import math
import statistics

Z975 = statistics.NormalDist().inv_cdf(0.975)


def median_interval(values, confidence=0.95):
    """``(median, low, high)`` of ``values`` (None where there are none): low and high are
    the order statistics k and n + 1 - k with P(k <= rank of the median <= n + 1 - k) at
    least ``confidence``; with too few values for that, the extremes."""
    ordered = sorted(v for v in values if v is not None)
    n = len(ordered)
    if not n:
        return None, None, None
    alpha, cumulative, k = (1.0 - confidence) / 2.0, 0.0, 0
    while True:           # largest k with P(Binomial(n, 1/2) < k) <= alpha
        cumulative += math.comb(n, k) / 2.0 ** n
        if cumulative > alpha:
            break
        k += 1
    k = max(1, k)
    return statistics.median(ordered), ordered[k - 1], ordered[n - k]


def t_quantile(df, z=Z975):
    """The Student-t quantile with ``df`` degrees of freedom at the normal quantile ``z``
    (Cornish-Fisher expansion: within 1e-3 of the exact value from 3 degrees up)."""
    g1 = (z ** 3 + z) / 4.0
    g2 = (5 * z ** 5 + 16 * z ** 3 + 3 * z) / 96.0
    g3 = (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / 384.0
    g4 = (79 * z ** 9 + 776 * z ** 7 + 1482 * z ** 5 - 1920 * z ** 3 - 945 * z) / 92160.0
    return z + g1 / df + g2 / df ** 2 + g3 / df ** 3 + g4 / df ** 4


def paired(a, b):
    """``(mean, low, high)`` of ``a[i] - b[i]`` over the seeds both have (None: none), its
    95 % t-interval."""
    differences = [x - y for x, y in zip(a, b) if x is not None and y is not None]
    n = len(differences)
    if not n:
        return None, None, None
    mean = statistics.fmean(differences)
    if n < 2:
        return mean, mean, mean
    half = t_quantile(n - 1) * statistics.stdev(differences) / math.sqrt(n)
    return mean, mean - half, mean + half
