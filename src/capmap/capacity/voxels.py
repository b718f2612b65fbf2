"""Voxel grid and voxelisation of point capacities.

The grid is a cube lattice of edge c_w anchored at multiples of c_w (so voxel centres are
at (n + 1/2) c_w, as in the paper), covering the bounding box of the points:
voxel (i, j, k) spans lower + [i, i+1) c_w etc., centre = lower + (index + 1/2) c_w.
A voxel's capacity is the minimum over the reachable points inside it; a voxel with no
reachable point has NaN capacity (not traversable).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.errors import CapmapError

__all__ = ["Grid", "VoxelMap", "voxelise", "capacity_volume"]


@dataclass(frozen=True)
class Grid:
    """lower (3,) m corner, shape (3,) voxels per axis, edge_m."""

    lower: np.ndarray
    shape: tuple[int, int, int]
    edge_m: float

    @classmethod
    def covering(cls, points: np.ndarray, edge_m: float) -> "Grid":
        """Smallest c_w-anchored grid containing all points (N, 3)."""
        if edge_m <= 0:
            raise CapmapError(f"edge_m = {edge_m!r} must be > 0")
        if len(points) == 0:
            raise CapmapError("no points to voxelise")
        lo = np.floor(points.min(axis=0) / edge_m) * edge_m
        hi_idx = np.floor((points.max(axis=0) - lo) / edge_m).astype(int)
        return cls(lower=lo, shape=tuple(int(v) + 1 for v in hi_idx), edge_m=float(edge_m))

    @property
    def n_voxels(self) -> int:
        return int(np.prod(self.shape))

    def index(self, points: np.ndarray) -> np.ndarray:
        """Integer voxel indices (N, 3) of points; -1 rows for points outside the grid."""
        idx = np.floor((np.asarray(points) - self.lower) / self.edge_m).astype(int)
        inside = np.all((idx >= 0) & (idx < np.array(self.shape)), axis=-1)
        return np.where(inside[..., None], idx, -1)

    def touching(self, point: np.ndarray, tol_m: float = 1e-6) -> np.ndarray:
        """Indices (K, 3), K in 0..8, of the voxels whose closed box holds ``point`` (3,) m to within
        ``tol_m``: one inside a voxel, two on a face, four on an edge, eight on a corner (as a voxel's
        stored worst point often is: the voxel's value holds on its closed box); none outside the grid."""
        u = (np.asarray(point, dtype=float) - self.lower) / self.edge_m
        near = np.round(u)
        on = np.abs(u - near) * self.edge_m <= tol_m
        lo = np.where(on, near - 1, np.floor(u)).astype(int)
        hi = np.where(on, near, np.floor(u)).astype(int)
        axes = [np.arange(a, b + 1) for a, b in zip(lo, hi)]
        idx = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        return idx[np.all((idx >= 0) & (idx < np.array(self.shape)), axis=1)]

    def flat(self, idx: np.ndarray) -> np.ndarray:
        return np.ravel_multi_index(tuple(np.moveaxis(idx, -1, 0)), self.shape)

    def all_indices(self) -> np.ndarray:
        """(V, 3) indices in C order (flat index = position)."""
        return np.stack(np.unravel_index(np.arange(self.n_voxels), self.shape), axis=1)

    def centres(self, idx: np.ndarray | None = None) -> np.ndarray:
        idx = self.all_indices() if idx is None else idx
        return self.lower + (idx + 0.5) * self.edge_m


@dataclass(frozen=True)
class VoxelMap:
    """Per-voxel arrays over the whole grid (C order): n_points, n_reachable (V,) int;
    capacity_kg (V,) min over reachable points (NaN if none); worst_point (V,) int (-1 if none)."""

    grid: Grid
    n_points: np.ndarray
    n_reachable: np.ndarray
    capacity_kg: np.ndarray
    worst_point: np.ndarray


def voxelise(grid: Grid, points: np.ndarray, capacity_kg: np.ndarray, reachable: np.ndarray) -> VoxelMap:
    """Minimum capacity per voxel. points (N, 3) m, capacity_kg (N,), reachable (N,) bool."""
    idx = grid.index(points)
    inside = idx[:, 0] >= 0
    flat = grid.flat(idx[inside])
    V = grid.n_voxels
    n_points = np.bincount(flat, minlength=V)
    r = reachable[inside]
    n_reach = np.bincount(flat[r], minlength=V)
    cap = np.full(V, np.inf)
    np.minimum.at(cap, flat[r], capacity_kg[inside][r])
    # the point attaining each voxel's minimum
    ids = np.flatnonzero(inside)[r]
    worst = np.full(V, -1)
    hit = capacity_kg[ids] == cap[flat[r]]
    worst[flat[r][hit]] = ids[hit]
    cap[n_reach == 0] = np.nan
    return VoxelMap(grid=grid, n_points=n_points, n_reachable=n_reach, capacity_kg=cap, worst_point=worst)


def capacity_volume(capacity_kg: np.ndarray, edge_m: float, payloads_kg: np.ndarray) -> np.ndarray:
    """Volume (P,) m^3 of the voxels that carry at least each payload (P,) kg: the capacity-volume
    curve of a map whose reachable voxels have capacities (V,) kg (NaN: unreachable, ignored)."""
    cap = np.sort(np.asarray(capacity_kg, dtype=float)[np.isfinite(capacity_kg)])
    count = len(cap) - np.searchsorted(cap, np.asarray(payloads_kg, dtype=float), side="left")
    return count * edge_m**3
