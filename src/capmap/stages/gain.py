"""Stage plan_gain: what direction-aware moves change, shown on the run's own map. For every
task payload M and a few payloads from the map itself (percentiles of its voxel capacities),
random (start, goal) pairs of voxel centres whose voxels carry M in every direction are planned
twice, with the paper's isotropic map and with direction-aware moves; every direction-aware
plan is verified (the spec's step 9: trapezoidal segments, continuous IK, loads carrying M) on
the first IK branch at its start that tracks the whole path within the joint ranges, and so is
the direct line on that branch: the tasks where the line fails and the verified detour carries
M are what the planner is for."""

from __future__ import annotations

import numpy as np
import pandas as pd

from capmap.capacity import planning
from capmap.capacity.verification import judge, verify_path
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.errors import NoPath
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table
from capmap.stages.arm import arm_task_from
from capmap.stages.capacity import AXIS_COLUMNS, grid_of
from capmap.stages.common import stage_config

__all__ = ["stage_plan_gain"]

MIN_SEPARATION = 3  # voxels between start and goal (Chebyshev), so that a detour is possible
SWEEP_PERCENTILES = (50, 75, 90)  # payloads besides the task's: these percentiles of the map (rounded to 100 kg)


def _try(fn):
    try:
        return fn()
    except NoPath:
        return None


def stage_plan_gain(voxels: str, out_tasks: str, out_csv: str, out_md: str, slice_json: str) -> None:
    sc = stage_config(slice_json)
    run = sc.run
    log = stage_logger(__name__, "plan gain")
    at = arm_task_from(run)
    arm, rotation, motion, limits = at.arm, at.rotation, at.motion, at.limits
    dyn = ArmDynamics(arm)
    dt = run.verification.dt_s
    vox = datasets.read(voxels)
    grid = grid_of(vox)
    cap = vox.capacity_kg.to_numpy()
    axis_cap = vox[AXIS_COLUMNS].to_numpy()
    idx = vox[["i", "j", "k"]].to_numpy()
    rng = np.random.default_rng(run.sampling.seed)
    rows = []
    positive = cap[np.nan_to_num(cap, nan=0.0) > 0]
    sweep = [float(np.round(np.percentile(positive, q), -2)) for q in SWEEP_PERCENTILES] if len(positive) else []
    task_payloads = sorted(run.task.payload_kg)
    payloads = sorted(set(task_payloads) | set(sweep))
    log.info(f"payloads: the task's {task_payloads} and the map's percentiles {SWEEP_PERCENTILES} of the positive "
             f"voxel capacities, {sweep} kg")
    for M in payloads:
        ends = np.flatnonzero(np.nan_to_num(cap, nan=-1.0) >= M)
        if len(ends) < 2:
            log.info(f"{M:g} kg: fewer than 2 voxels carry it in every direction; no tasks")
            continue
        for t in range(run.planning.gain_tasks):
            for _ in range(100):  # a pair far enough apart
                a, b = rng.choice(ends, 2, replace=False)
                if np.abs(idx[a] - idx[b]).max() >= MIN_SEPARATION:
                    break
            s_m, g_m = grid.centres(idx[[a]])[0], grid.centres(idx[[b]])[0]
            iso = _try(lambda: planning.plan(grid, cap, s_m, g_m, M))
            aware = _try(lambda: planning.plan(grid, cap, s_m, g_m, M, axis_cap))
            row = {"payload_kg": M, "task": t, "start_x_m": s_m[0], "start_y_m": s_m[1], "start_z_m": s_m[2],
                   "goal_x_m": g_m[0], "goal_y_m": g_m[1], "goal_z_m": g_m[2],
                   "isotropic_path": iso is not None, "axis_path": aware is not None,
                   "isotropic_length_m": iso.length_m if iso else np.nan,
                   "axis_length_m": aware.length_m if aware else np.nan,
                   "verified_branch": -1, "verified_capacity_kg": np.nan, "verified_feasible": False,
                   "direct_capacity_kg": np.nan, "direct_feasible": False}
            if aware is not None:  # verified on the first branch that tracks it; the direct line on that branch
                sol = ik.solve(arm, s_m[None], rotation)
                for br in range(int(sol.n_solutions[0])):
                    res = verify_path(dyn, aware.waypoints, rotation, sol.q[0, br], motion, dt, limits)
                    _, verdict = judge(res, arm, limits, M)
                    if verdict.tracking == "ok" and verdict.joint_range == "ok":
                        _, line = judge(verify_path(dyn, np.array([s_m, g_m]), rotation, sol.q[0, br], motion, dt,
                                                    limits), arm, limits, M)
                        row.update(verified_branch=br, verified_capacity_kg=verdict.capacity_kg,
                                   verified_feasible=verdict.feasible, direct_capacity_kg=line.capacity_kg,
                                   direct_feasible=line.feasible)
                        break
            rows.append(row)
        log.info(f"{M:g} kg: {run.planning.gain_tasks} tasks planned both ways")
    tasks = pd.DataFrame(rows)
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
    datasets.write(tasks, out_tasks, datasets.provenance("plan_gain", sc.doc))
    write_table(pd.DataFrame(summary), out_csv, out_md)
    for r in summary:
        log.info(f"{r['payload_kg']:g} kg: {r['tasks']} tasks, isotropic A* finds {r['isotropic_path']}, direction-aware "
                 f"{r['axis_path']}; gained {r['gained_by_axis_moves']}, of which {r['gained_tracked']} tracked and "
                 f"{r['gained_verified_carrying']} verified carrying the payload; direct line fails where the "
                 f"verified detour carries it: {r['direct_line_fails_detour_carries']} -> {out_csv}")
