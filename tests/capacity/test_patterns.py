"""The refinement's exact row sets (capmap.capacity.patterns) against numpy's sort of rows (np.unique with
axis=0), on rows with many repeats and both zeros, and with every row hashed alike (the collision path)."""

import numpy as np
import pytest

from capmap.capacity import patterns


def _rows(rng, n, k):
    """Rows of few distinct values (many repeats), zeros of either sign."""
    r = rng.integers(-2, 3, (n, k)).astype(float) * rng.choice([0.5, 1.0, 1e-300])
    zero = r == 0
    r[zero] = np.where(rng.uniform(size=zero.sum()) < 0.5, -0.0, 0.0)
    return r


def _check(r, known):
    first, inverse = patterns.unique_rows(r)
    _, idx, inv = np.unique(r, axis=0, return_index=True, return_inverse=True)
    assert np.array_equal(first, np.sort(idx))  # the same first occurrences, in index order
    assert np.array_equal(r[first][inverse], r)  # -0.0 == 0.0 as floats compare
    assert len(np.unique(inverse)) == len(first)
    assert np.array_equal(patterns.sorted_unique_rows(r), idx)  # np.unique's order, exactly
    both = np.concatenate([known, r])
    _, b = np.unique(both, axis=0, return_inverse=True)
    b = b.reshape(-1)
    expected = np.isin(b[len(known):], b[:len(known)]) if len(r) and len(known) else np.zeros(len(r), dtype=bool)
    assert np.array_equal(patterns.rows_in(r, known), expected)


@pytest.mark.parametrize("seed", range(40))
def test_rows_as_numpys_sort_of_rows(seed):
    rng = np.random.default_rng(seed)
    k = int(rng.integers(1, 5))
    _check(_rows(rng, int(rng.integers(0, 400)), k), _rows(rng, int(rng.integers(0, 300)), k))


@pytest.mark.parametrize("seed", range(10))
def test_rows_when_every_hash_collides(seed, monkeypatch):
    monkeypatch.setattr(patterns, "_hash", lambda rows: np.zeros(len(rows), dtype=np.uint64))
    rng = np.random.default_rng(seed)
    _check(_rows(rng, 200, 4), _rows(rng, 150, 4))


def test_a_point_of_the_refinement_against_the_points_seen():
    """Rows as the refinement keeps them (voxel, x, y, z): a point moved by one ulp is new, the same point
    again is not, and the same point in another voxel is new."""
    rng = np.random.default_rng(3)
    seen = np.column_stack([rng.integers(0, 50, 1000).astype(float), rng.uniform(-5, 5, (1000, 3))])
    ask = seen[:3].copy()
    ask[1, 2] = np.nextafter(ask[1, 2], np.inf)
    ask[2, 0] += 1.0 if ask[2, 0] < 49 else -1.0
    assert not np.any(np.all(seen == ask[2], axis=1))  # no such row was seen (the check's premise)
    assert patterns.rows_in(ask, seen).tolist() == [True, False, False]
