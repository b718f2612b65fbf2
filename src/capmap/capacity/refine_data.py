"""The voxel refinement's data: its settings, the results of the points it evaluates, and the per-voxel
minima it starts from and returns (:mod:`capmap.capacity.refine` holds the rounds). Plain data: a
config section builds :class:`RefineSettings` without importing the algorithm."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.errors import CapmapError

__all__ = ["BATCH_VOXELS", "RefineSettings", "Evaluation", "VoxelMinima"]

BATCH_VOXELS = 4096  # voxels refined together: a refine job's memory is bounded by this, not by its shard's size


@dataclass(frozen=True)
class RefineSettings:
    """rel_tol: convergence (relative change of the minimum in the last round); min_points: points per
    voxel at least; max_points: a voxel holding that many stops searching (its brackets' bisections go
    on); payloads_kg with near_band and
    near_min_points: voxels whose value is within near_band of a payload get at least that many."""

    rel_tol: float = 0.005
    min_points: int = 8
    max_points: int = 256
    payloads_kg: tuple[float, ...] = ()
    near_band: float = 0.1
    near_min_points: int = 16
    fold_tol_m: float = 1e-3
    finest_step: float = 1 / 64  # of the voxel edge: the compasses stop shrinking there

    def __post_init__(self):
        if not 0 < self.rel_tol < 1:
            raise CapmapError(f"{{rel_tol}} = {self.rel_tol!r} must be in (0, 1)", rel_tol="rel_tol")
        if not 1 <= self.min_points <= self.max_points or self.near_min_points > self.max_points:
            raise CapmapError(f"points per voxel: min {self.min_points}, near a payload {self.near_min_points}, "
                              f"max {self.max_points}: need 1 <= min <= max and near <= max", rel_tol="rel_tol")


@dataclass(frozen=True)
class Evaluation:
    """Point results: capacity_kg (N,) kg (NaN where unreachable), axis_capacity_kg (N, A) kg,
    binding (N,) int: the binding limit's index (-1 where unreachable); n_branches (N,) int: IK
    branches at the point (0 where unreachable). Per configuration label (optional, C labels):
    config_capacity_kg (N, C), config_axis_capacity_kg (N, C, A), config_binding (N, C), NaN / -1
    where the point has no IK solution of that configuration; config_branches (N, C) int the point's
    solutions of each configuration."""

    capacity_kg: np.ndarray
    axis_capacity_kg: np.ndarray
    binding: np.ndarray
    n_branches: np.ndarray
    config_capacity_kg: np.ndarray | None = None
    config_axis_capacity_kg: np.ndarray | None = None
    config_binding: np.ndarray | None = None
    config_branches: np.ndarray | None = None


@dataclass(frozen=True)
class VoxelMinima:
    """Per refined voxel (V,): capacity_kg, axis_capacity_kg (V, A), n_points evaluated inside,
    n_reachable of them, last_change (relative drop of the minimum in the last round), converged,
    worst_m (V, 3) the point attaining the minimum and binding (V,) its binding limit; rounds and
    points evaluated in all. Per configuration label (optional, C labels; NaN / -1 where no point of
    that configuration was seen): config_capacity_kg (V, C), config_axis_capacity_kg (V, C, A),
    config_worst_m (V, C, 3), config_binding (V, C), config_n_points (V, C) the points holding it."""

    voxel: np.ndarray
    capacity_kg: np.ndarray
    axis_capacity_kg: np.ndarray
    n_points: np.ndarray
    n_reachable: np.ndarray
    last_change: np.ndarray
    converged: np.ndarray
    worst_m: np.ndarray
    binding: np.ndarray
    rounds: int
    n_evaluated: int
    config_capacity_kg: np.ndarray | None = None
    config_axis_capacity_kg: np.ndarray | None = None
    config_worst_m: np.ndarray | None = None
    config_binding: np.ndarray | None = None
    config_n_points: np.ndarray | None = None

    @classmethod
    def with_configurations(cls, n_configurations: int, **fields) -> "VoxelMinima":
        """The all-branch fields given, every configuration's not yet seen."""
        V, A = fields["axis_capacity_kg"].shape
        C = n_configurations
        return cls(**fields, config_capacity_kg=np.full((V, C), np.nan),
                   config_axis_capacity_kg=np.full((V, C, A), np.nan), config_worst_m=np.full((V, C, 3), np.nan),
                   config_binding=np.full((V, C), -1), config_n_points=np.zeros((V, C), dtype=int))
