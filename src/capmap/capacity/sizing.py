"""A capacity map's size before any job (:class:`capmap.config.estimate.Estimate`): the grid from the
same seeded joint samples the sample stage draws, the points, motion states and the memory of its
largest job, refused with one line naming the key that drives it when it cannot fit this machine."""

from __future__ import annotations

import numpy as np

from capmap.capacity.refine_data import BATCH_VOXELS
from capmap.capacity.sampling import joint_samples
from capmap.capacity.voxels import Grid
from capmap.config.capacity import SamplingConfig
from capmap.config.estimate import (
    BASE_MB,
    CHUNK,
    MAP_VOXEL_KB,
    MAX_BRANCHES,
    MAX_SAMPLES,
    PLAN_VOXEL_KB,
    POINT_BYTES,
    REFINE_VOXEL_MB,
    Estimate,
    MapJobs,
    available_memory_mb,
)
from capmap.core.reduction import LockedArm
from capmap.errors import ConfigError

__all__ = ["estimate_map", "check_parallel_memory"]


def estimate_map(arm: LockedArm, sampling: SamplingConfig, edge_m: float, n_directions: int, n_outputs: int,
                 jobs: MapJobs, keys: dict[str, str]) -> tuple[Estimate, Grid | None]:
    """The size of one capacity map: the grid from the same seeded joint samples the sample stage
    draws (exact), the points voxel_fill adds, the states and the memory of its largest job.
    ``keys``: the config keys of n_points, edge_m, jitter and directions (the one driving the size is
    named when the map is refused). Returns the estimate and the map's grid (None when too large to build)."""
    if sampling.n_points > MAX_SAMPLES:
        raise ConfigError(f"{keys['n_points']} = {sampling.n_points:,} joint samples is more than this workflow "
                          f"handles ({MAX_SAMPLES:,})")
    _, pos = joint_samples(arm, sampling.n_points, np.random.default_rng(sampling.seed))
    span = np.ptp(pos, axis=0) / edge_m + 1
    shape = tuple(int(v) for v in np.floor(span) + 1)
    voxels = int(np.prod(np.asarray(shape, dtype=float)))
    grid = Grid.covering(pos, edge_m) if voxels < 1e9 else None  # the grid of the voxels stage (all samples)
    if sampling.mode == "voxel_fill" and grid is not None:
        shape = grid.shape
        voxels = grid.n_voxels
    fill = voxels * (1 + sampling.jitter_per_voxel) if sampling.mode == "voxel_fill" else 0
    points = sampling.n_points + fill
    states = points * 8.0 * n_directions
    chunk_mb = CHUNK * MAX_BRANCHES * n_directions * n_outputs * 8 * 3 / 2**20
    shard_mb = points / max(jobs.shards, 1) * POINT_BYTES / 2**20
    voxel_mb = points * POINT_BYTES / 2**20 + voxels * 200 / 2**20
    jobs_mb = {"capacity": BASE_MB + chunk_mb + shard_mb, "voxels": BASE_MB + voxel_mb,
               "maps": BASE_MB + MAP_VOXEL_KB * voxels / 1024, "plan": BASE_MB + PLAN_VOXEL_KB * voxels / 1024,
               "verify": BASE_MB}  # a verification holds its path's samples
    if jobs.refine:  # a batch of a shard's voxels at a time (the grid's voxels: an upper bound of the reachable)
        jobs_mb["refine"] = BASE_MB + REFINE_VOXEL_MB * min(voxels / max(jobs.shards, 1), BATCH_VOXELS)
    est = Estimate(grid_shape=shape, voxels=voxels, points=points, states=states, jobs_mb=jobs_mb)
    peak, free = est.peak_mb, available_memory_mb()
    if peak > 0.8 * free:
        key, what = _blame(sampling, keys, chunk_mb > shard_mb and chunk_mb > voxel_mb, fill)
        raise ConfigError(f"{key}: this map needs {est.describe(edge_m)}; this machine has "
                          f"{free / 1024:.1f} GB available: {what}")
    return est, grid


def _blame(sampling: SamplingConfig, keys: dict[str, str], directions_dominate: bool, fill: int) -> tuple[str, str]:
    """The key that drives the size most, and what to do about it: the direction count (a capacity
    chunk's arrays), the jittered points per voxel, the voxel edge (the fill) or the joint samples."""
    if directions_dominate:
        return keys["directions"], f"use fewer motion directions ({keys['directions']})"
    if sampling.mode == "voxel_fill" and fill > sampling.n_points:
        if sampling.jitter_per_voxel > 1:
            return keys["jitter"], f"lower {keys['jitter']}"
        return keys["edge_m"], f"coarsen {keys['edge_m']}"
    return keys["n_points"], f"lower {keys['n_points']}"


def check_parallel_memory(est: Estimate, cores: int, shards: int, edge_key: str = "voxels.edge_m") -> None:
    """The map's jobs that run side by side on ``cores`` (its capacity and refine jobs: ``shards`` of them) fit
    this machine's available memory; else one line naming what fixes it (fewer cores, a coarser voxel edge)."""
    together = max(1, min(int(cores), shards))
    need, free = together * est.peak_mb, available_memory_mb()
    if need > 0.8 * free:
        raise ConfigError(f"--cores {cores}: {together} jobs of up to {est.peak_mb / 1024:.1f} GB each side by side need "
                          f"{need / 1024:.1f} GB; this machine has {free / 1024:.1f} GB available: run with fewer cores "
                          f"(--cores {max(1, int(0.8 * free // est.peak_mb))}) or coarsen {edge_key}")
