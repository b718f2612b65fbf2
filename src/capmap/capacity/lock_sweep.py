"""A joint's lock angle swept: the arm locked at each angle of a sweep, and its capacity map.

Every lock's map is evaluated on the same points, the healthy arm's samples (its joint-space Monte
Carlo and, for ``voxel_fill``, every voxel of their box:
:func:`capmap.capacity.healthy_map.healthy_samples`), so every map of every joint shares one grid: a
voxel is the same box whichever joint is locked where, and a minimum or a maximum over locks is taken
voxel by voxel (:mod:`capmap.capacity.tolerant`, :mod:`capmap.capacity.advice`). A voxel's value is the
map's: the minimum over its reachable points of their capacity (every IK branch x every direction);
NaN where the locked arm reaches none of them. No file I/O."""

from __future__ import annotations

import time
from typing import Callable

import numpy as np
import pandas as pd

from capmap.capacity.problem import CapacityProblem
from capmap.capacity.self_motion import self_motion_angles
from capmap.capacity.tables import AXIS_COLUMNS, capacity_table, voxel_table
from capmap.core.robot import Robot

__all__ = ["SWEEP_COLUMNS", "lock_angles", "lock_sweep", "lock_map"]

SWEEP_COLUMNS = ["joint", "angle_deg", "i", "j", "k", "x_m", "y_m", "z_m", "n_points", "n_reachable", "capacity_kg",
                 "binding", *AXIS_COLUMNS]
"""advice/sweep_joint{j}.parquet: one row per (lock angle, voxel holding a sampled point)."""


def lock_angles(robot: Robot, joint: int, through_deg: float, step_deg: float) -> np.ndarray:
    """The lock angles (T,) deg of ``joint`` (1-based) swept: ``through_deg`` plus multiples of
    ``step_deg``, one turn when the joint turns a full turn or more (an angle and the same angle a turn
    later lock the arm alike), else every such angle in its range and both ends. Sorted."""
    lo, hi = np.rad2deg(robot.q_lower[joint - 1]), np.rad2deg(robot.q_upper[joint - 1])
    return self_motion_angles(float(lo), float(hi), float(through_deg), float(step_deg))


def lock_map(problem: CapacityProblem, points: np.ndarray, edge_m: float) -> pd.DataFrame:
    """The capacity map of ``problem``'s locked arm on ``points`` (N, 3) m: the voxel table of the grid of
    ``edge_m`` [m] covering the points (:func:`capmap.capacity.tables.voxel_table`), only voxels holding a
    point."""
    cap = capacity_table(problem, np.arange(len(points)), points, None, chunk=1000)
    vox, _ = voxel_table(cap, edge_m)
    return vox[vox.n_points > 0].reset_index(drop=True)


def lock_sweep(problem_at: Callable[[float], CapacityProblem], joint: int, angles_deg: np.ndarray,
               points: np.ndarray, edge_m: float, log=None) -> pd.DataFrame:
    """The maps of the arm with ``joint`` locked at each of ``angles_deg`` (T,) (``problem_at(angle)``: the
    locked problem) on the same ``points`` (N, 3) m, voxels of ``edge_m`` [m]: :data:`SWEEP_COLUMNS`, one
    row per (angle, voxel holding a point), sorted by angle then voxel."""
    parts = []
    t0 = time.perf_counter()
    for n, a in enumerate(angles_deg, 1):
        vox = lock_map(problem_at(float(a)), points, edge_m)
        vox.insert(0, "angle_deg", float(a))
        vox.insert(0, "joint", int(joint))
        parts.append(vox[SWEEP_COLUMNS])
        if log:
            el = time.perf_counter() - t0
            log.info(f"joint {joint} at {a:g} deg: {int((vox.n_reachable > 0).sum())} of {len(vox)} voxels reached "
                     f"({n}/{len(angles_deg)} angles, eta {el / n * (len(angles_deg) - n):.0f} s)")
    return pd.concat(parts, ignore_index=True)
