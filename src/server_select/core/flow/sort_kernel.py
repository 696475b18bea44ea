"""The sort task kernel (paper 1's workload): generate, process and check int32 arrays."""

import numpy as np

INT32 = np.iinfo(np.int32)


class TaskError(ValueError):
    """A task that cannot be processed; the message goes back in the error result."""


def make_values(rng, size):
    """``size`` random int32 values from ``rng`` (a ``numpy.random.Generator``)."""
    return rng.integers(INT32.min, INT32.max, size=size, dtype=np.int32, endpoint=True)


def sort_values(values, max_len):
    """Sorted copy of ``values`` as int32; empty or oversized input raises TaskError."""
    array = np.asarray(values)
    if array.ndim != 1:
        raise TaskError('task data must be a flat array, got shape %s' % (array.shape,))
    if array.size == 0:
        raise TaskError('empty task: nothing to sort')
    if array.size > max_len:
        raise TaskError('task of %d values exceeds max_task_len %d' % (array.size, max_len))
    return np.sort(array.astype(np.int32, copy=False))


def fingerprint(values):
    """(length, int64 sum) of an array: cheap to keep per task, enough to catch a lost value."""
    array = np.asarray(values, dtype=np.int64)
    return int(array.size), int(array.sum())


def check_sorted(result, expected_fingerprint):
    """None when ``result`` is non-decreasing with the expected fingerprint, else why not."""
    array = np.asarray(result, dtype=np.int64)
    if fingerprint(array) != expected_fingerprint:
        return 'result has length/sum %s, task had %s' % (fingerprint(array), expected_fingerprint)
    if array.size > 1 and bool(np.any(array[1:] < array[:-1])):
        return 'result is not sorted'
    return None
