"""The sort task kernel (paper 1's workload): generate, process and check int32 arrays.

Plain Python on purpose: a robot that sends sort tasks, and a server that sorts them, need
no numpy (14 MiB of a node's resident memory, bench-robot). genpy reads an ``int32[]``
field into a tuple and writes any sequence of ints, so ``sorted`` does the work in C.
"""

import itertools
import numbers
import operator
import struct

INT32_MIN, INT32_MAX = -2 ** 31, 2 ** 31 - 1


class TaskError(ValueError):
    """A task that cannot be processed; the message goes back in the error result."""


def make_values(rng, size):
    """``size`` random int32 values (a tuple) from ``rng`` (a ``random.Random``)."""
    return struct.unpack('<%di' % size, rng.randbytes(4 * size))


def sort_values(values, max_len):
    """Sorted copy (a list) of the int32 ``values``; empty, oversized or non-integer input
    raises TaskError."""
    if len(values) == 0:
        raise TaskError('empty task: nothing to sort')
    if len(values) > max_len:
        raise TaskError('task of %d values exceeds max_task_len %d' % (len(values), max_len))
    if not all(isinstance(v, numbers.Integral) for v in values):    # numpy's too
        raise TaskError('task data must be a flat array of integers')
    return sorted(values)


def fingerprint(values):
    """(length, sum) of the values: cheap to keep per task, enough to catch a lost value."""
    return len(values), sum(values)


def check_sorted(result, expected_fingerprint):
    """None when ``result`` is non-decreasing with the expected fingerprint, else why not."""
    if fingerprint(result) != expected_fingerprint:
        return 'result has length/sum %s, task had %s' % (fingerprint(result),
                                                          expected_fingerprint)
    if any(map(operator.gt, result, itertools.islice(result, 1, None))):
        return 'result is not sorted'
    return None
