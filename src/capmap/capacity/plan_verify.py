"""A plan and its verification as tables: the waypoints of A* on the voxel map or on the executed IK
branch (:mod:`capmap.capacity.planning`, :mod:`capmap.capacity.branch_planning`), and a job's direct line
and planned path verified carrying its payload (:mod:`capmap.capacity.verification`), with the column
schemas of these tables. A job is a plan/verify job of the run (``start_m``, ``goal_m``, ``q_start_deg``
(every joint, deg), ``payload_kg``, ``name``: a :class:`capmap.config.jobs.PlanTask`). No file I/O."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pandas as pd

from capmap.capacity import branch_planning, planning
from capmap.capacity.directions import AXIS_LABELS, axis_of
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.tables import AXIS_COLUMNS
from capmap.capacity.verification import PathResult, judge, verify_path
from capmap.capacity.voxels import Grid
from capmap.core.limits import AffineLimits
from capmap.core.profiles import PHASES
from capmap.core.reduction import LockedArm

__all__ = ["WAYPOINT_COLUMNS", "plan_waypoints", "no_waypoints", "path_tables", "branch_deviation_deg", "verify_job"]

WAYPOINT_COLUMNS = ["waypoint", "kind", "x_m", "y_m", "z_m", "i", "j", "k", "voxel_capacity_kg"]


def plan_waypoints(problem: CapacityProblem, vox: pd.DataFrame, grid: Grid, task, moves: str,
                   track_step_m: float | None = None) -> tuple[pd.DataFrame, float, int, str]:
    """Plan ``task`` through the voxels of ``vox`` (on ``grid``) that carry its payload: ``moves`` ``branch``
    (on the executed branch, tracked every ``track_step_m``), ``axis`` or ``isotropic`` (A* on the map's
    values). The waypoints table (:data:`WAYPOINT_COLUMNS`, and the moves' capacities and planned
    configurations where known), cost, expansions and a log line; raises
    :class:`~capmap.errors.NoPath` where no path carries the payload."""
    if moves == "branch":
        return _branch_plan(problem, grid, vox, task, task.payload_kg, track_step_m)
    return _grid_plan(grid, vox, task, task.payload_kg, moves)


def no_waypoints() -> pd.DataFrame:
    """The waypoints table of a job with no path (zero rows)."""
    return pd.DataFrame({c: pd.Series(dtype=object if c == "kind" else float) for c in WAYPOINT_COLUMNS})


def _waypoint_frame(p, grid, capacity_kg: np.ndarray) -> pd.DataFrame:
    """The :data:`WAYPOINT_COLUMNS` of a plan (:class:`~capmap.capacity.planning.Plan` or
    :class:`~capmap.capacity.branch_planning.BranchPlan`) on the map's voxel capacities (V,) kg."""
    wp, wv = p.waypoints, p.waypoint_voxel
    return pd.DataFrame({"waypoint": np.arange(len(wp)), "kind": p.waypoint_kind, "x_m": wp[:, 0], "y_m": wp[:, 1],
                         "z_m": wp[:, 2], "i": wv[:, 0], "j": wv[:, 1], "k": wv[:, 2],
                         "voxel_capacity_kg": capacity_kg[grid.flat(wv)]})


def _grid_plan(grid: Grid, vox: pd.DataFrame, task, payload: float, moves: str) -> tuple[pd.DataFrame, float, int, str]:
    """A* on the voxel map (``axis`` or ``isotropic`` moves): waypoints table, cost, expansions, log line."""
    cap = vox.capacity_kg.to_numpy()
    axis_cap = vox[AXIS_COLUMNS].to_numpy() if moves == "axis" else None
    p = planning.plan(grid, cap, task.start_m, task.goal_m, payload, axis_cap)
    wv = p.waypoint_voxel
    df = _waypoint_frame(p, grid, cap)
    if axis_cap is not None:  # the capacity along the move that arrives at each voxel (both voxels)
        f = grid.flat(wv)
        step = np.diff(wv, axis=0)
        move = np.r_[False, np.any(step != 0, axis=1)]
        a = np.zeros(len(wv), dtype=int)
        a[move] = axis_of(step[move[1:]])
        along = np.full(len(wv), np.nan)
        along[move] = np.minimum(axis_cap[f[move], a[move]], axis_cap[f[:-1][move[1:]], a[move]])
        df["move_axis"] = np.where(move, np.array(AXIS_LABELS)[a], "")
        df["move_capacity_kg"] = along
    line = (f"{moves} moves: {len(p.voxel_path)} voxels, {len(df)} waypoints, A* cost {p.cost_m:.3f} m, path "
            f"{p.length_m:.3f} m, {p.expanded} voxels expanded; weakest voxel on it {df.voxel_capacity_kg.min():.1f} kg"
            + (f", weakest move {np.nanmin(df.move_capacity_kg):.1f} kg" if axis_cap is not None
               and df.move_capacity_kg.notna().any() else ""))
    return df, p.cost_m, p.expanded, line


def _branch_plan(at: CapacityProblem, grid: Grid, vox: pd.DataFrame, task, payload: float,
                 step: float | None) -> tuple[pd.DataFrame, float, int, str]:
    """A* over (voxel, IK branch) states on the start configuration's branch (tracked every ``step`` m;
    None: the planner's own): waypoints table with the planned configuration at each waypoint, cost,
    expansions, log line."""
    arm = at.arm
    problem = branch_planning.BranchProblem(at.dyn, grid, at.rotation, at.motion, at.limits,
                                            (vox.n_reachable > 0).to_numpy(), **({} if step is None else {"step_m": step}))
    q_start = np.deg2rad(np.asarray(task.q_start_deg, dtype=float))[arm.active]
    p = branch_planning.plan_on_branch(problem, task.start_m, task.goal_m, q_start, payload)
    df = _waypoint_frame(p, grid, vox.capacity_kg.to_numpy())
    df["move_capacity_kg"] = p.move_capacity_kg
    for c, j in enumerate(arm.active_joint_numbers):
        df[f"q_j{j}_deg"] = np.rad2deg(p.q[:, c])
    line = (f"branch moves: {len(df)} waypoints, path {p.length_m:.3f} m, {p.expanded} of {p.states} states expanded "
            f"({p.voxels_solved} voxels' moves tracked); weakest move {np.nanmin(p.move_capacity_kg):.1f} kg at the "
            f"tracked samples (the voxel map, every branch: {df.voxel_capacity_kg.min():.1f} kg)")
    return df, p.length_m, p.expanded, line


def path_tables(name: str, res: PathResult, arm: LockedArm, limits: AffineLimits, payload: float,
                planner: str) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """Time series, segment table and summary row of one verified path."""
    tl, tr, ld = res.timeline, res.tracking, res.loads
    ts = pd.DataFrame({"path": name, "t_s": tl.t_s, "segment": tl.segment,
                       "phase": pd.Categorical.from_codes(tl.phase, list(PHASES)),
                       "x_m": tl.p[:, 0], "y_m": tl.p[:, 1], "z_m": tl.p[:, 2],
                       "vx_mps": tl.v[:, 0], "vy_mps": tl.v[:, 1], "vz_mps": tl.v[:, 2],
                       "ax_mps2": tl.a[:, 0], "ay_mps2": tl.a[:, 1], "az_mps2": tl.a[:, 2]})
    joints = arm.active_joint_numbers
    for prefix, values, unit in (("q", tr.q, "deg"), ("qd", ld.qd, "deg_s"), ("qdd", ld.qdd, "deg_s2")):
        for c, j in enumerate(joints):
            ts[f"{prefix}_j{j}_{unit}"] = np.rad2deg(values[:, c])
    y = ld.at(payload)
    for c, col in enumerate(limits.names):
        ts[col] = y[:, c]
    ts["state_capacity_kg"] = ld.capacity_kg
    ts["binding"] = np.array(list(limits.names) + ["untracked"])[ld.binding]
    ts["tracked"] = ~np.isnan(tr.q).any(axis=1)
    ts["in_joint_range"] = tr.in_range.all(axis=1)
    segments, verdict = judge(res, arm, limits, payload)
    seg = pd.DataFrame([{"path": name, **asdict(s)} for s in segments])
    return ts, seg, {"path": name, "planner": planner, **asdict(verdict)}


def branch_deviation_deg(res: PathResult, q_plan_deg: np.ndarray) -> float:
    """Largest difference (deg) between the configurations the verification tracked at the
    waypoints (the end of each segment, and the start) and the planned ones q_plan_deg (W, n)."""
    rows = res.timeline.waypoint_rows()
    return float(np.nanmax(np.abs(np.rad2deg(res.tracking.q[rows]) - q_plan_deg), initial=np.nan)) \
        if not np.isnan(res.tracking.q[rows]).any() else float("inf")


def verify_job(problem: CapacityProblem, job, wp: pd.DataFrame, plan: dict, dt_s: float,
               log) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Verify the job's direct line and its planned path ``wp`` (the waypoints table; ``plan``: its status
    and reason) carrying the job's payload, samples at most ``dt_s`` apart: time series, segments and the
    summary (one row per path; a planned path that does not exist is a row with its reason)."""
    arm, payload = problem.arm, job.payload_kg
    q_start = np.deg2rad(np.asarray(job.q_start_deg, dtype=float))[arm.active]
    paths = {"direct": np.array([job.start_m, job.goal_m], dtype=float)}
    if plan["status"] == "ok":
        paths["planned"] = wp[["x_m", "y_m", "z_m"]].to_numpy()
    ts_parts, seg_parts, rows = [], [], []
    for name, pts in paths.items():
        res = verify_path(problem.dyn, pts, problem.rotation, q_start, problem.motion, dt_s, problem.limits)
        q_cols = [f"q_j{j}_deg" for j in arm.active_joint_numbers]
        on_branch = name == "planned" and q_cols[0] in wp  # planned on the start's branch
        planner = ("straight line" if name == "direct" else
                   f"A* on the start's IK branch, {len(pts)} waypoints" if on_branch else f"A*, {len(pts)} waypoints")
        ts, seg, row = path_tables(name, res, arm, problem.limits, payload, planner)
        if on_branch:  # does the execution stay on the planned branch?
            row["branch_deviation_deg"] = branch_deviation_deg(res, wp[q_cols].to_numpy())
        ts_parts.append(ts)
        seg_parts.append(seg)
        rows.append(row)
        log.info(f"{name}: {row['segments']} segments, {row['duration_s']:.1f} s, capacity {row['capacity_kg']:.1f} kg "
                 f"({row['binding']}), mean segment capacity {row['mean_segment_capacity_kg']:.1f} kg = "
                 f"{row['margin_pct']:+.1f}% vs {payload:g} kg; exceeded: {row['limits_exceeded_at_payload'] or 'none'}; "
                 f"tracking {row['tracking']}; joint range {row['joint_range']}")
    if plan["status"] != "ok":
        rows.append({"path": "planned", "planner": f"A*: {plan['reason']}", "feasible": False})
        log.info(f"planned: none ({plan['reason']})")
    summary = pd.DataFrame(rows)
    summary.insert(0, "payload_kg", payload)
    summary["task"] = job.name or "task"  # "task": the config's task; else its name under `tasks`
    if job.name is not None:
        summary["path"] = job.name + ": " + summary.path  # headed "3200 kg, around_singularity: direct"
    ts = pd.concat(ts_parts, ignore_index=True)
    ts["path"] = ts.path.astype("category")
    ts["binding"] = ts.binding.astype("category")
    return ts, pd.concat(seg_parts, ignore_index=True), summary
