"""capmap.core.parallel.by_rows: a row-wise function's rows computed in forked processes equal one call's,
in order; each slice is computed by its own process; a child's error is raised in the caller."""

import os

import numpy as np
import pytest

from capmap.core.parallel import by_rows


def _rowwise(x: np.ndarray) -> np.ndarray:
    """Each row's sum of squares, and the process that computed it."""
    return np.stack([(x ** 2).sum(axis=1), np.full(len(x), os.getpid())], axis=1)


def test_rows_split_over_processes_equal_one_call_in_order():
    x = np.random.default_rng(0).normal(size=(101, 4))
    got = by_rows(_rowwise, x, 3)
    np.testing.assert_array_equal(got[:, 0], (x ** 2).sum(axis=1))
    pids = got[:, 1]
    assert len(np.unique(pids)) == 3 and (pids[:34] == os.getpid()).all()  # the first slice here, two children
    assert (np.diff(pids) != 0).sum() == 2  # each a contiguous slice, in order


def test_one_worker_or_one_row_runs_here():
    x = np.ones((5, 2))
    assert set(by_rows(_rowwise, x, 1)[:, 1]) == {os.getpid()}
    assert set(by_rows(_rowwise, x[:1], 4)[:, 1]) == {os.getpid()}
    assert by_rows(_rowwise, x[:0], 4).shape == (0, 2)


def test_a_childs_error_is_raised_here():
    def fails_on_negative(x):
        if (x < 0).any():
            raise ValueError("negative row")
        return x

    with pytest.raises(RuntimeError, match="ValueError: negative row"):
        by_rows(fails_on_negative, np.array([[1.0], [2.0], [-1.0]]), 2)
