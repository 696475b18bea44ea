import random
import sys

import pytest

from server_select.core.flow.sort_kernel import (INT32_MAX, INT32_MIN, TaskError, check_sorted,
                                                 fingerprint, make_values, sort_values)


def test_make_values_is_int32_of_requested_size_and_reproducible():
    a = make_values(random.Random(1), 1000)
    b = make_values(random.Random(1), 1000)
    assert len(a) == 1000 and a == b and a != make_values(random.Random(2), 1000)
    assert all(INT32_MIN <= v <= INT32_MAX for v in a)
    assert min(a) < -2 ** 30 and max(a) > 2 ** 30        # the whole int32 range is used


def test_sort_values_sorts_tuples_and_lists():
    assert sort_values((3, -1, 2), 10) == [-1, 2, 3]
    values = make_values(random.Random(2), 1000)
    assert sort_values(values, 1000) == sorted(values)


def test_numpy_integers_in_a_task_handed_over_in_process_are_sorted_too():
    import numpy as np
    assert sort_values(np.asarray([3, 1, 2], np.int32), 10) == [1, 2, 3]


def test_sort_extremes():
    assert sort_values([INT32_MAX, INT32_MIN, 0], 3) == [INT32_MIN, 0, INT32_MAX]


def test_empty_oversized_and_nested_tasks_raise():
    with pytest.raises(TaskError, match='empty'):
        sort_values([], 10)
    with pytest.raises(TaskError, match='exceeds max_task_len 3'):
        sort_values([1, 2, 3, 4], 3)
    with pytest.raises(TaskError, match='flat'):
        sort_values([[1, 2], [3, 4]], 10)


def test_check_sorted_accepts_a_correct_result():
    values = make_values(random.Random(3), 500)
    assert check_sorted(sorted(values), fingerprint(values)) is None


def test_check_sorted_rejects_unsorted_and_lost_values():
    values = (5, 1, 3)
    fp = fingerprint(values)
    assert 'not sorted' in check_sorted([1, 5, 3], fp)
    assert 'length/sum' in check_sorted([1, 3], fp)
    assert 'length/sum' in check_sorted([1, 3, 6], fp)


def test_fingerprint_does_not_overflow():
    assert fingerprint((INT32_MAX,) * 10) == (10, 10 * INT32_MAX)


def test_the_kernel_needs_no_numpy():
    assert 'numpy' not in sys.modules['server_select.core.flow.sort_kernel'].__dict__
