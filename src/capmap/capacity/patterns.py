"""Points of the voxel refinement's local search (:mod:`capmap.capacity.refine`): the voxel's
corners, a compass around a centre clipped to its voxel, and which rows of points are already known.

Rows (a voxel and a point, or a point) are compared exactly, with -0.0 equal to 0.0 as floats compare. The
refinement asks this every round of tens of thousands of rows against every row evaluated so far, so the
rows are grouped by a 64-bit hash of their bits (a sort of integers instead of numpy's sort of rows) and each
group is then checked row by row: rows of equal hash that differ (a collision) fall back to the exact sort."""

from __future__ import annotations

import numpy as np

from capmap.capacity.voxels import Grid

__all__ = ["CORNERS", "COMPASS", "around", "rows_in", "unique_rows", "sorted_unique_rows"]

CORNERS = np.array([[i, j, k] for i in (0.0, 1.0) for j in (0.0, 1.0) for k in (0.0, 1.0)])
"""(8, 3): the corners of the unit cube."""
COMPASS = np.concatenate([np.eye(3), -np.eye(3)])
"""(6, 3): the six axis directions."""


_MIX = np.uint64(0x9E3779B97F4A7C15)  # 2^64 / golden ratio: a multiplicative hash's odd constant


def _hash(rows: np.ndarray) -> np.ndarray:
    """(n,) uint64: a hash of each row of rows (n, k) float from its bits, -0.0 as 0.0."""
    bits = (np.asarray(rows, dtype=float) + 0.0).view(np.uint64)  # + 0.0: -0.0 -> 0.0 (float equality's classes)
    h = np.zeros(len(bits), dtype=np.uint64)
    for col in bits.T:  # unsigned products wrap modulo 2^64
        h = (h ^ col) * _MIX
        h ^= h >> np.uint64(29)
    return h


def _by_first(order: np.ndarray, new: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`unique_rows`' (first, inverse) from a stable sort ``order`` (n,) of the rows and ``new`` (n,)
    bool, where a group of equal rows starts in that order."""
    group = np.empty(len(order), dtype=np.int64)
    group[order] = np.cumsum(new) - 1
    first = order[new]  # stable: a group's first index is its first occurrence
    by_index = np.argsort(first)
    rank = np.empty_like(by_index)
    rank[by_index] = np.arange(len(first))
    return first[by_index], rank[group]


def _exact_first(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`unique_rows` by a lexicographic sort of the rows (the fallback on a hash collision)."""
    order = np.lexsort(rows.T[::-1])
    s = rows[order]
    return _by_first(order, np.r_[True, np.any(s[1:] != s[:-1], axis=1)])


def unique_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of rows (n, k) float, exactly: (first, inverse), first (u,) ascending the index of
    each distinct row's first occurrence, inverse (n,) the position in first of each row's
    (``rows[first][inverse] == rows``). As ``np.unique(rows, axis=0, return_index=True,
    return_inverse=True)`` with the distinct rows in order of first occurrence instead of sorted."""
    rows = np.asarray(rows, dtype=float)
    if not len(rows):
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    h = _hash(rows)
    order = np.argsort(h, kind="stable")
    hs = h[order]
    new = np.r_[True, hs[1:] != hs[:-1]]
    lead = order[new]  # the first occurrence of each hash (stable sort)
    if not np.all(rows[order] == rows[lead[np.cumsum(new) - 1]]):  # a hash shared by different rows
        return _exact_first(rows)
    return _by_first(order, new)


def sorted_unique_rows(rows: np.ndarray) -> np.ndarray:
    """(u,): the index of the first occurrence of each distinct row of rows (n, k) float, in the rows'
    lexicographic order (``np.unique(rows, axis=0, return_index=True)[1]``)."""
    rows = np.asarray(rows, dtype=float)
    first, _ = unique_rows(rows)
    return first[np.lexsort(rows[first].T[::-1])]


def rows_in(rows: np.ndarray, known: np.ndarray) -> np.ndarray:
    """(n,) bool: each row of rows (n, k) is one of known (m, k) exactly."""
    if not len(rows) or not len(known):
        return np.zeros(len(rows), dtype=bool)
    rows, known = np.asarray(rows, dtype=float), np.asarray(known, dtype=float)
    hk = _hash(known)
    order = np.argsort(hk)
    hk = hk[order]
    hr = _hash(rows)
    at = np.minimum(np.searchsorted(hk, hr), len(hk) - 1)
    hit = hk[at] == hr
    same = np.all(rows[hit] == known[order[at[hit]]], axis=1)
    if not np.all(same):  # a hash shared with a different known row: compare exactly
        both = np.concatenate([known, rows])
        _, inv = _exact_first(both)
        return np.isin(inv[len(known):], inv[:len(known)])
    return hit


def around(centres: np.ndarray, pattern: np.ndarray, h: float, grid: Grid, idx3: np.ndarray) -> np.ndarray:
    """Points (len(centres) * len(pattern), 3) m: each centre (n, 3) plus h times the pattern (p, 3),
    clipped to its voxel idx3 (n, 3)."""
    lo = (grid.lower + idx3 * grid.edge_m)[:, None, :]
    return np.clip(centres[:, None, :] + h * pattern, lo, lo + grid.edge_m).reshape(-1, 3)
