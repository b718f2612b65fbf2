"""Points of the voxel refinement's local search (:mod:`capmap.capacity.refine`): the voxel's
corners, a compass around a centre clipped to its voxel, and which rows of points are already known."""

from __future__ import annotations

import numpy as np

from capmap.capacity.voxels import Grid

__all__ = ["CORNERS", "COMPASS", "around", "rows_in"]

CORNERS = np.array([[i, j, k] for i in (0.0, 1.0) for j in (0.0, 1.0) for k in (0.0, 1.0)])
"""(8, 3): the corners of the unit cube."""
COMPASS = np.concatenate([np.eye(3), -np.eye(3)])
"""(6, 3): the six axis directions."""


def rows_in(rows: np.ndarray, known: np.ndarray) -> np.ndarray:
    """(n,) bool: each row of rows (n, k) is one of known (m, k) exactly."""
    if not len(rows) or not len(known):
        return np.zeros(len(rows), dtype=bool)
    both = np.concatenate([known, rows])
    _, inv = np.unique(both, axis=0, return_inverse=True)
    return np.isin(inv.reshape(-1)[len(known):], inv.reshape(-1)[:len(known)])


def around(centres: np.ndarray, pattern: np.ndarray, h: float, grid: Grid, idx3: np.ndarray) -> np.ndarray:
    """Points (len(centres) * len(pattern), 3) m: each centre (n, 3) plus h times the pattern (p, 3),
    clipped to its voxel idx3 (n, 3)."""
    lo = (grid.lower + idx3 * grid.edge_m)[:, None, :]
    return np.clip(centres[:, None, :] + h * pattern, lo, lo + grid.edge_m).reshape(-1, 3)
