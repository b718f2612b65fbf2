"""The plan-gain experiment: what direction-aware moves change, on a run's own map.

For every task payload M and a few payloads from the map itself (percentiles of its voxel
capacities), random (start, goal) pairs of voxel centres whose voxels carry M in every direction
are planned twice, with the paper's isotropic map and with direction-aware moves; every
direction-aware plan is verified (the spec's step 9: trapezoidal segments, continuous IK, loads
carrying M) on the first IK branch at its start that tracks the whole path within the joint
ranges, and so is the direct line on that branch: the tasks where the line fails and the verified
detour carries M are what the planner is for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pandas as pd

from capmap.capacity import planning
from capmap.capacity.engine import Motion
from capmap.capacity.verification import judge, verify_path
from capmap.capacity.voxels import Grid
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.core.limits import AffineLimits
from capmap.errors import NoPath

__all__ = ["GainMap", "GainVerifier", "MIN_SEPARATION", "SWEEP_PERCENTILES", "gain_payloads", "gain_tasks", "gain_summary"]

MIN_SEPARATION = 3  # voxels between start and goal (Chebyshev), so that a detour is possible
SWEEP_PERCENTILES = (50, 75, 90)  # payloads besides the task's: these percentiles of the map (2 significant digits)


@dataclass(frozen=True)
class GainMap:
    """The map the tasks are drawn on: its grid, per-voxel capacity (V,) kg (NaN: unreachable),
    per-axis capacities (V, 13) kg and voxel indices (V, 3)."""

    grid: Grid
    capacity_kg: np.ndarray
    axis_capacity_kg: np.ndarray
    index: np.ndarray


@dataclass(frozen=True)
class GainVerifier:
    """What a verification needs: the arm's dynamics, the end-effector rotation (3, 3), the motion
    limits, the sample spacing dt_s [s] and the load limits."""

    dyn: ArmDynamics
    rotation: np.ndarray
    motion: Motion
    dt_s: float
    limits: AffineLimits

    def verdict(self, waypoints: np.ndarray, q_start: np.ndarray, payload_kg: float):
        """The judged verification of a path (W, 3) m from configuration q_start (n_active,) rad."""
        res = verify_path(self.dyn, waypoints, self.rotation, q_start, self.motion, self.dt_s, self.limits)
        return judge(res, self.dyn.arm, self.limits, payload_kg)[1]


def _try(fn: Callable):
    try:
        return fn()
    except NoPath:
        return None


def _two_digits(x: float) -> float:
    """x rounded to two significant digits (3217 -> 3200 kg for the SSRMS, 9.437 -> 9.4 kg for a Panda)."""
    return float(f"{x:.2g}") if x > 0 else 0.0


def gain_payloads(capacity_kg: np.ndarray, task_payloads_kg) -> tuple[list[float], list[float]]:
    """(every payload of the experiment, sorted; the map's percentile payloads) [kg]."""
    positive = capacity_kg[np.nan_to_num(capacity_kg, nan=0.0) > 0]
    sweep = [_two_digits(float(np.percentile(positive, q))) for q in SWEEP_PERCENTILES] if len(positive) else []
    return sorted(set(map(float, task_payloads_kg)) | set(sweep)), sweep


def _task_row(gm: GainMap, ver: GainVerifier, M: float, t: int, a: int, b: int) -> dict:
    s_m, g_m = gm.grid.centres(gm.index[[a]])[0], gm.grid.centres(gm.index[[b]])[0]
    iso = _try(lambda: planning.plan(gm.grid, gm.capacity_kg, s_m, g_m, M))
    aware = _try(lambda: planning.plan(gm.grid, gm.capacity_kg, s_m, g_m, M, gm.axis_capacity_kg))
    row = {"payload_kg": M, "task": t, "start_x_m": s_m[0], "start_y_m": s_m[1], "start_z_m": s_m[2],
           "goal_x_m": g_m[0], "goal_y_m": g_m[1], "goal_z_m": g_m[2],
           "isotropic_path": iso is not None, "axis_path": aware is not None,
           "isotropic_length_m": iso.length_m if iso else np.nan,
           "axis_length_m": aware.length_m if aware else np.nan,
           "verified_branch": -1, "verified_capacity_kg": np.nan, "verified_feasible": False,
           "direct_capacity_kg": np.nan, "direct_feasible": False}
    if aware is not None:  # verified on the first branch that tracks it; the direct line on that branch
        sol = ik.solve(ver.dyn.arm, s_m[None], ver.rotation)
        for br in range(int(sol.n_solutions[0])):
            verdict = ver.verdict(aware.waypoints, sol.q[0, br], M)
            if verdict.tracking == "ok" and verdict.joint_range == "ok":
                line = ver.verdict(np.array([s_m, g_m]), sol.q[0, br], M)
                row.update(verified_branch=br, verified_capacity_kg=verdict.capacity_kg,
                           verified_feasible=verdict.feasible, direct_capacity_kg=line.capacity_kg,
                           direct_feasible=line.feasible)
                break
    return row


def gain_tasks(gm: GainMap, ver: GainVerifier, payloads_kg, n_tasks: int, rng: np.random.Generator,
               progress: Callable[[str], None] = lambda _: None) -> pd.DataFrame:
    """One row per (payload, random task): both plans' existence and length, and the verified
    direction-aware plan and direct line (branch, capacity, feasibility)."""
    rows = []
    finite = np.nan_to_num(gm.capacity_kg, nan=-1.0)
    for M in payloads_kg:
        ends = np.flatnonzero(finite >= M)
        if len(ends) < 2:
            progress(f"{M:g} kg: fewer than 2 voxels carry it in every direction; no tasks")
            continue
        for t in range(n_tasks):
            for _ in range(100):  # a pair far enough apart
                a, b = rng.choice(ends, 2, replace=False)
                if np.abs(gm.index[a] - gm.index[b]).max() >= MIN_SEPARATION:
                    break
            rows.append(_task_row(gm, ver, M, t, a, b))
        progress(f"{M:g} kg: {n_tasks} tasks planned both ways")
    return pd.DataFrame(rows)


def gain_summary(tasks: pd.DataFrame) -> pd.DataFrame:
    """Per payload: tasks, paths found each way, gained/lost by direction-aware moves, how many of
    the gained are tracked and verified carrying the payload, and where only the detour carries it."""
    summary = []
    for M, grp in tasks.groupby("payload_kg") if len(tasks) else []:
        gained = grp[grp.axis_path & ~grp.isotropic_path]
        summary.append({
            "payload_kg": M, "tasks": len(grp), "isotropic_path": int(grp.isotropic_path.sum()),
            "axis_path": int(grp.axis_path.sum()), "gained_by_axis_moves": len(gained),
            "lost_by_axis_moves": int((grp.isotropic_path & ~grp.axis_path).sum()),
            "gained_tracked": int((gained.verified_branch >= 0).sum()),
            "gained_verified_carrying": int(gained.verified_feasible.sum()),
            "gained_min_verified_capacity_kg": round(float(gained.verified_capacity_kg.min()), 1) if len(gained) else np.nan,
            "axis_path_verified_carrying": int(grp.verified_feasible.sum()),
            "direct_line_fails_detour_carries": int((grp.verified_feasible & ~grp.direct_feasible).sum())})
    return pd.DataFrame(summary)
