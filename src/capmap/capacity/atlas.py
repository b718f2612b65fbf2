"""The fault atlas' map: one coarse capacity map of the arm with a joint locked at an angle (sample
-> capacity -> voxels), and its summary rows per task payload: the reachable volume, capacity
quantiles, the volume carrying the payload, the direct line's verified capacity and whether a plan
through the map exists."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pandas as pd

from capmap.capacity import planning
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.tables import capacity_table, sample_table, voxel_table
from capmap.capacity.verification import judge, verify_path
from capmap.capacity.voxels import Grid, capacity_volume
from capmap.core import ik
from capmap.errors import CapmapError

__all__ = ["AtlasTask", "AtlasMap", "atlas_map"]


@dataclass(frozen=True)
class AtlasTask:
    """The run's task on one locked arm (its rotation, motion and limits are the problem's): start and
    goal (3,) m (start None when unknown), the payloads [kg], the verification's dt_s [s], and the start
    configuration q_start (n_active,) rad on this lock (None, with ``start_note`` saying why, when the
    start is not reachable on it)."""

    start_m: np.ndarray | None
    goal_m: np.ndarray
    payloads_kg: tuple[float, ...]
    dt_s: float
    q_start: np.ndarray | None
    start_offset_deg: float
    start_note: str = ""


@dataclass(frozen=True)
class AtlasMap:
    """The map's voxel table, its grid and one summary row per payload."""

    voxels: pd.DataFrame
    grid: Grid
    rows: list[dict]


def atlas_map(problem: CapacityProblem, lock: tuple[int, float], sampling, edge_m: float, task: AtlasTask,
              reword: Callable[[CapmapError], str] = str, log=None) -> AtlasMap:
    """The coarse map of ``problem``'s arm, locked as ``lock`` (joint number, angle deg), (``sampling``:
    mode, n_points, seed, jitter_per_voxel) on voxels of ``edge_m`` [m], and its summary rows;
    ``reword`` turns a planner's error into the row's note (in config terms)."""
    arm = problem.arm
    pts = sample_table(arm, sampling, edge_m, log)
    cap = capacity_table(problem, pts.point_id.to_numpy(), pts[["x_m", "y_m", "z_m"]].to_numpy(), log, chunk=1000)
    vox, grid = voxel_table(cap, edge_m)
    reach = vox.capacity_kg[vox.n_reachable > 0].to_numpy()
    q = np.quantile(reach, [0.0, 0.05, 0.5, 0.95, 1.0]) if len(reach) else np.full(5, np.nan)
    base = {"joint": lock[0], "angle_deg": float(lock[1]),
            "ik_method": ik.method_for(arm.chain), "reachable_volume_m3": len(reach) * edge_m**3,
            "capacity_min_kg": q[0], "capacity_p5_kg": q[1], "capacity_median_kg": q[2], "capacity_p95_kg": q[3],
            "capacity_max_kg": q[4], "start_branch_offset_deg": task.start_offset_deg,
            "start_reachable": task.q_start is not None}
    start_note, direct = task.start_note, None
    if task.q_start is not None:
        try:
            direct = verify_path(problem.dyn, np.array([task.start_m, task.goal_m]), problem.rotation, task.q_start,
                                 problem.motion, task.dt_s, problem.limits)
        except CapmapError as exc:
            start_note = f"direct line: {exc}"
    rows = []
    for payload in task.payloads_kg:
        row = {**base, "payload_kg": payload,
               "volume_carrying_payload_m3": float(capacity_volume(reach, edge_m, [payload])[0])}
        if direct is not None:
            _, verdict = judge(direct, arm, problem.limits, payload)
            row.update(direct_capacity_kg=verdict.capacity_kg, direct_feasible=verdict.feasible,
                       direct_note="" if verdict.feasible else (verdict.limits_exceeded_at_payload
                                                                or (verdict.tracking if verdict.tracking != "ok"
                                                                    else verdict.joint_range)))
        else:
            row.update(direct_capacity_kg=np.nan, direct_feasible=False, direct_note=start_note)
        try:
            p = planning.plan(grid, vox.capacity_kg.to_numpy(), task.start_m, task.goal_m, payload)
            row.update(plan_exists=True, plan_length_m=p.length_m, plan_note="")
        except CapmapError as exc:
            row.update(plan_exists=False, plan_length_m=np.nan, plan_note=reword(exc))
        rows.append(row)
        if log:
            log.info(f"{payload:g} kg: {row['volume_carrying_payload_m3']:.1f} m^3 carry it; direct line "
                     f"{row['direct_capacity_kg']:.1f} kg; plan {'found' if row['plan_exists'] else 'none'}")
    return AtlasMap(vox, grid, rows)
