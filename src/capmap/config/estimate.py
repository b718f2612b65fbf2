"""Size estimates before any job: how many voxels, points, motion states and how much memory
a run asks for, so that what cannot fit on this machine is refused with one line naming the
key (before a stage deletes a good output and dies in numpy), and what will run is announced.

The memory model is per kind of job, its constants measured (``tests/benchmarks/bench_memory.py`` prints
each estimate beside the measured peak at three voxel edges): a Python process with Pinocchio and numba
imported holds ~400 MB; a capacity shard holds one chunk of 500 points x IK branches x directions x limit
outputs in a few float64 arrays; the voxels stage holds every point of the map in a table of ~40 columns;
a refine job holds one batch of voxels (:data:`capmap.capacity.refine_data.BATCH_VOXELS`) and their points;
the jobs that read the whole map hold a few KB per voxel. The estimate itself draws the seeded joint samples:
:func:`capmap.capacity.sizing.estimate_map`; this module holds its result and the step guards."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from capmap.errors import ConfigError

__all__ = ["Estimate", "MapJobs", "REFINE_VOXEL_MB", "MAP_VOXEL_KB", "PLAN_VOXEL_KB",
           "available_memory_mb", "BASE_MB", "CHUNK", "MAX_BRANCHES", "POINT_BYTES", "MAX_SAMPLES",
           "MAX_STEPS", "MAX_MOTION_S", "check_steps", "check_duration", "line_duration_s"]

BASE_MB = 400.0  # a job's Python with numpy, pandas, numba and Pinocchio imported (measured: 396 MB)
# a refine job's memory per voxel of its batch: 0.12, 0.15, 0.21 MB measured at 0.75, 0.375, 0.25 m
REFINE_VOXEL_MB = 0.17
# a job reading the whole map's tables (merge, summary, 3D page, figures), per grid voxel: 3.2 KB measured
MAP_VOXEL_KB = 3.3
PLAN_VOXEL_KB = 0.5  # a plan job (A* over the map's voxels and IK branches), per grid voxel: 0.4-0.5 KB measured
CHUNK = 500  # points per capacity chunk (capmap.capacity.tables.capacity_table)
MAX_BRANCHES = 16
POINT_BYTES = 1000  # one point in the capacity and voxels stages' tables, with pandas' overhead
MAX_SAMPLES = 20_000_000
MAX_STEPS = 5_000_000  # samples of a verified motion, control periods of a follow case, RK4 steps, OCP nodes x grid


def line_duration_s(length_m: float, v_max_mps: float, a_max_mps2: float) -> float:
    """Duration [s] of a rest-to-rest trapezoidal move of ``length_m`` (triangular when short)."""
    return length_m / v_max_mps + v_max_mps / a_max_mps2 if length_m >= v_max_mps**2 / a_max_mps2 \
        else 2.0 * np.sqrt(length_m / a_max_mps2)


MAX_MOTION_S = 1e5  # a verified or followed straight line: about a day


def check_duration(t_s: float, v_key: str, a_key: str, what: str) -> None:
    """One ConfigError line naming the speed and acceleration keys when a move lasts over MAX_MOTION_S."""
    if not t_s <= MAX_MOTION_S:
        raise ConfigError(f"{v_key}, {a_key}: {what} would take {t_s:.3g} s at this speed and acceleration (at most "
                          f"{MAX_MOTION_S:.0e} s): raise {v_key} or {a_key}")


def check_steps(steps: float, key: str, what: str, fix: str = "raise") -> None:
    """One ConfigError line naming ``key`` when ``what`` takes more than MAX_STEPS steps (``fix``:
    what to do with the key, raise or lower)."""
    if not steps <= MAX_STEPS:
        raise ConfigError(f"{key}: {what} would take {steps:.3g} steps, more than this workflow handles "
                          f"({MAX_STEPS:,}); {fix} {key}")


@dataclass(frozen=True)
class MapJobs:
    """How a map's work is cut into jobs: ``shards`` capacity (and refine) jobs, ``refine`` whether the
    refinement runs."""

    shards: int
    refine: bool


@dataclass(frozen=True)
class Estimate:
    """A capacity map's size: grid shape, voxels, points, motion states (upper bound: every point
    reachable with 8 branches), the peak memory of each kind of job (MB, by stage: ``jobs_mb``) and of
    the largest."""

    grid_shape: tuple[int, int, int]
    voxels: int
    points: int
    states: float
    jobs_mb: dict

    @property
    def peak_mb(self) -> float:
        return max(self.jobs_mb.values())

    def describe(self, edge_m: float) -> str:
        g = "x".join(map(str, self.grid_shape))
        return (f"grid {g} = {self.voxels:,} voxels of {edge_m:g} m, {self.points:,} points, <= {self.states:.2g} "
                f"motion states, peak memory ~{self.peak_mb / 1024:.1f} GB per job")


def available_memory_mb() -> float:
    """MemAvailable of this machine (MB); the physical memory when /proc/meminfo is missing."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**20
