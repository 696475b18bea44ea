"""Summary statistics used by reports and benchmarks."""

import math

import numpy as np


def summarize(values):
    """n, mean, sd, min, median, p95, p99, max of the finite ``values`` (None when empty)."""
    array = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    if array.size == 0:
        return {'n': 0}
    p50, p95, p99 = np.percentile(array, [50, 95, 99])
    return {
        'n': int(array.size),
        'mean': float(array.mean()),
        'sd': float(array.std(ddof=1)) if array.size > 1 else 0.0,
        'min': float(array.min()),
        'median': float(p50),
        'p95': float(p95),
        'p99': float(p99),
        'max': float(array.max()),
    }


def format_ms(summary, keys=('median', 'p95', 'p99', 'max')):
    """``median 1.23 ms, p95 ...`` for a summary of seconds."""
    if summary.get('n', 0) == 0:
        return 'no samples'
    return ', '.join('%s %.3f ms' % (k, summary[k] * 1e3) for k in keys)
