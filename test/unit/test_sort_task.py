import numpy as np
import pytest

from server_select.core.flow.sort_kernel import (TaskError, check_sorted, fingerprint, make_values,
                                                 sort_values)


def test_make_values_is_int32_of_requested_size_and_reproducible():
    a = make_values(np.random.default_rng(1), 1000)
    b = make_values(np.random.default_rng(1), 1000)
    assert a.dtype == np.int32 and a.shape == (1000,)
    assert np.array_equal(a, b)


def test_sort_values_sorts_tuples_and_arrays():
    assert sort_values((3, -1, 2), 10).tolist() == [-1, 2, 3]
    values = make_values(np.random.default_rng(2), 1000)
    result = sort_values(values, 1000)
    assert result.dtype == np.int32
    assert np.array_equal(result, np.sort(values))


def test_sort_extremes():
    info = np.iinfo(np.int32)
    assert sort_values([info.max, info.min, 0], 3).tolist() == [info.min, 0, info.max]


def test_empty_and_oversized_tasks_raise():
    with pytest.raises(TaskError, match='empty'):
        sort_values([], 10)
    with pytest.raises(TaskError, match='exceeds max_task_len 3'):
        sort_values([1, 2, 3, 4], 3)
    with pytest.raises(TaskError, match='flat'):
        sort_values([[1, 2], [3, 4]], 10)


def test_check_sorted_accepts_a_correct_result():
    values = make_values(np.random.default_rng(3), 500)
    assert check_sorted(np.sort(values), fingerprint(values)) is None


def test_check_sorted_rejects_unsorted_and_lost_values():
    values = np.array([5, 1, 3], dtype=np.int32)
    fp = fingerprint(values)
    assert 'not sorted' in check_sorted([1, 5, 3], fp)
    assert 'length/sum' in check_sorted([1, 3], fp)
    assert 'length/sum' in check_sorted([1, 3, 6], fp)


def test_fingerprint_does_not_overflow():
    info = np.iinfo(np.int32)
    values = np.full(10, info.max, dtype=np.int32)
    assert fingerprint(values) == (10, 10 * int(info.max))
