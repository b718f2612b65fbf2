"""Where to brake a failing joint: the run's tasks verified on the arm locked at each swept angle, and
the angle that leaves them the most margin.

At each lock angle of a joint's sweep (:mod:`capmap.capacity.lock_sweep`) every task (the main task at
each payload and the further tasks, each a :data:`Task`) starts on the IK branch at its start nearest its
own start configuration, and is verified carrying its payload
(:func:`capmap.capacity.verification.verify_path`) along three paths: its direct line, the path A* plans on
that lock's map (moves along the grid axes, :data:`PLANNER_MOVES`; where no path on the map carries the
payload, the widest one: planned for the largest payload any path carries), and the run's own planned path
(planned on the main map, at the run's lock). A path carries what its weakest segment carries when it is
tracked within the joint ranges, else nothing. The task's capacity is its best path's (one carrying the
payload first), and its margin that capacity over the payload, in % of the payload (``margin_pct``; -100:
nothing carried). At the angle the run's joint is locked at, the run's verified plan is among the paths, so
the advice never says less than the run's verification.

Beside the verification, the map along the task: the least voxel capacity on its direct line (0 kg where
the line leaves the locked arm's reach), and the same on the healthy arm's map (each voxel at its best
swept angle: a lower bound of the healthy arm's, and at least every lock's by construction): the
``line_margin_pct`` and the healthy reference; and the map over the task region (the voxels of every task's
direct line): its mean capacity, unreached voxels as 0 kg (``region_capacity_kg``).

The recommended angle has the largest worst-task margin; ties go to the largest capacity over the task
region, then to the angle nearest the one the joint stands at. The recommendation at every second and every
fourth swept angle shows whether the step has converged. No file I/O."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from capmap.capacity.engine import margin_pct
from capmap.capacity.plan_verify import plan_waypoints
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.verification import judge, verify_path
from capmap.capacity.voxels import Grid
from capmap.core import ik
from capmap.core.tracking import nearest_branch
from capmap.errors import CapmapError, NoPath

__all__ = ["ADVICE_TASK_COLUMNS", "ADVICE_COLUMNS", "PLANNER_MOVES", "AdviceSettings", "task_name", "full_grid", "line_voxels",
           "tasks_at_lock", "healthy_lines", "recommend", "neighbours_worst", "convergence"]

Task = Any
"""A task to verify: ``payload_kg``, ``start_m``, ``goal_m`` (3,) m, ``q_start_deg`` (every joint, deg: its start
configuration's reference), ``name`` (None: the main task), e.g. a :class:`capmap.config.jobs.PlanTask`."""

ADVICE_TASK_COLUMNS = ["joint", "angle_deg", "task", "payload_kg", "start_branch_offset_deg", "direct_capacity_kg",
                       "direct_note", "planned_capacity_kg", "planned_payload_kg", "planned_note", "run_plan_capacity_kg",
                       "run_plan_note", "capacity_kg", "path", "feasible", "margin_pct", "line_capacity_kg",
                       "line_margin_pct", "region_capacity_kg"]
"""advice/joint{j}/tasks.parquet: one row per (lock angle, task)."""

ADVICE_COLUMNS = ["joint", "step_deg", "n_angles", "stands_at_deg", "recommended_angle_deg", "worst_task",
                  "worst_margin_pct", "neighbours_worst_margin_pct", "worst_line_margin_pct", "region_capacity_kg",
                  "tasks_carried", "n_tasks", "stands_at_worst_margin_pct", "healthy_worst_line_margin_pct"]
"""advice/joint{j}/advice.parquet: the recommendation, and the angle the joint stands at for comparison."""


WIDEST_TOL = 0.01  # the widest path's payload, bisected to 1 % of the task's payload

PLANNER_MOVES = "axis"
"""The advice plans with A* on each lock's map, moves along the grid axes each at its own capacity: milliseconds
per plan, where the run's planner on the executed branch takes up to a minute per lock when no path exists (it then
tries every other branch). The verification of the planned path decides either way."""


@dataclass(frozen=True)
class AdviceSettings:
    """How each task is verified: the verification's largest sample spacing ``dt_s`` [s]."""

    dt_s: float


def task_name(task: Task) -> str:
    """A task's label in the tables: its name, or ``task`` for the main task."""
    return task.name or "task"


def full_grid(vox: pd.DataFrame, grid: Grid) -> pd.DataFrame:
    """A lock's voxel rows (i, j, k, capacity_kg, n_reachable, ...) as the whole ``grid`` in C order (the
    planner's layout): voxels without a row unreached."""
    flat = grid.flat(vox[["i", "j", "k"]].to_numpy())
    idx = grid.all_indices()
    out = pd.DataFrame({"i": idx[:, 0], "j": idx[:, 1], "k": idx[:, 2]})
    for c in vox.columns.drop(["i", "j", "k"], errors="ignore"):
        if pd.api.types.is_numeric_dtype(vox[c]) and c not in ("joint", "angle_deg"):
            col = np.zeros(grid.n_voxels) if c in ("n_points", "n_reachable") else np.full(grid.n_voxels, np.nan)
            col[flat] = vox[c].to_numpy()
            out[c] = col.astype(int) if c in ("n_points", "n_reachable") else col
    return out


def line_voxels(grid: Grid, a_m, b_m) -> np.ndarray:
    """Flat indices of the voxels of ``grid`` the segment a -> b (3,) m passes through (sampled every
    tenth of an edge; points outside the grid dropped), unique."""
    a, b = np.asarray(a_m, dtype=float), np.asarray(b_m, dtype=float)
    n = max(2, int(np.ceil(np.linalg.norm(b - a) / (grid.edge_m / 10))) + 1)
    idx = grid.index(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
    return np.unique(grid.flat(idx[idx[:, 0] >= 0]))


def _least_on(capacity_kg: np.ndarray, flat: np.ndarray) -> float:
    """The least capacity over voxels ``flat`` of a map (V,) kg, unreached voxels as 0 kg (none: 0)."""
    c = capacity_kg[flat]
    return float(np.min(np.where(np.isfinite(c), c, 0.0), initial=np.inf)) if len(flat) else 0.0


def _start(problem: CapacityProblem, task: Task) -> tuple[np.ndarray | None, float]:
    """The IK branch at the task's start nearest its start configuration (active joints, rad; a joint a whole
    turn out of its range turned back into it) and its largest joint offset [deg] (whole turns apart counted
    as equal); (None, NaN) when the locked arm does not reach the start."""
    arm = problem.arm
    sol = ik.solve(arm, np.asarray(task.start_m, dtype=float)[None], problem.rotation)
    n = int(sol.n_solutions[0])
    if n == 0:
        return None, np.nan
    ref = np.deg2rad(np.asarray(task.q_start_deg, dtype=float))[arm.active]
    _, q, _ = nearest_branch(sol.q[0, :n], ref)
    q = np.where(q > arm.q_upper, q - 2 * np.pi, q)  # a whole turn nearer the reference but out of range:
    q = np.where(q < arm.q_lower, q + 2 * np.pi, q)  # the same posture inside it
    return q, float(np.rad2deg(np.abs(np.angle(np.exp(1j * (q - ref)))).max()))


def _carried(problem: CapacityProblem, waypoints: np.ndarray, q0: np.ndarray, payload: float,
             s: AdviceSettings) -> tuple[float, bool, str]:
    """A path verified carrying ``payload``: what it carries [kg] (its weakest segment's; 0 when it is not
    tracked within the joint ranges), whether it carries the payload, and why not."""
    res = verify_path(problem.dyn, waypoints, problem.rotation, q0, problem.motion, s.dt_s, problem.limits)
    _, v = judge(res, problem.arm, problem.limits, payload)
    executable = v.tracking == "ok" and v.joint_range == "ok"
    note = "" if v.feasible else (v.tracking if v.tracking != "ok" else v.joint_range if v.joint_range != "ok"
                                  else f"exceeded: {v.limits_exceeded_at_payload}")
    return (v.capacity_kg if executable else 0.0), bool(v.feasible), note


def _plan(problem, vox, grid, job, payload: float) -> np.ndarray:
    wp, *_ = plan_waypoints(problem, vox, grid, replace(job, payload_kg=payload), PLANNER_MOVES)
    return wp[["x_m", "y_m", "z_m"]].to_numpy()


def _planned(problem, vox, grid, task, q_full_deg):
    """The path planned on the lock's map for the payload, else the widest: the one for the largest payload
    any path on the map carries (bisected to :data:`WIDEST_TOL` of the payload). (waypoints or None, the
    payload it was planned for [kg], note)."""
    job = replace(task, q_start_deg=tuple(float(v) for v in q_full_deg))
    m = float(task.payload_kg)
    try:
        return _plan(problem, vox, grid, job, m), m, ""
    except NoPath as exc:
        note = f"no path on the map carries {m:g} kg ({exc})"
    except CapmapError as exc:
        return None, np.nan, f"no plan: {exc}"
    lo, hi, wp = 0.0, m, None
    try:
        wp = _plan(problem, vox, grid, job, 0.0)
    except CapmapError:
        return None, np.nan, note + "; none reaches the goal"
    while hi - lo > WIDEST_TOL * m:
        mid = 0.5 * (lo + hi)
        try:
            wp, lo = _plan(problem, vox, grid, job, mid), mid
        except NoPath:
            hi = mid
    return wp, lo, note + f"; the widest carries {lo:.0f} kg on the map"


def _margin(capacity_kg: float, payload_kg: float, carried: bool) -> float:
    """Capacity over the payload in % of it; a 0 kg task: 0 where it is carried, else -100."""
    return margin_pct(capacity_kg, payload_kg) if payload_kg > 0 else (0.0 if carried else -100.0)


def tasks_at_lock(problem: CapacityProblem, vox: pd.DataFrame, grid: Grid, tasks: list[Task],
                  s: AdviceSettings, run_plans: list[np.ndarray | None] | None = None) -> list[dict]:
    """The tasks verified on ``problem``'s locked arm, planned on its map ``vox`` (:func:`full_grid`) on
    ``grid``: one row per task (:data:`ADVICE_TASK_COLUMNS` without joint and angle). ``run_plans``: per task
    the run's own planned path (W, 3) m (planned on the main map, None: none), verified here as well."""
    cap = vox.capacity_kg.to_numpy()
    run_plans = [None] * len(tasks) if run_plans is None else run_plans
    lines = [line_voxels(grid, t.start_m, t.goal_m) for t in tasks]
    region = np.unique(np.concatenate(lines)) if lines else np.zeros(0, dtype=int)
    region_kg = float(np.mean(np.nan_to_num(cap[region], nan=0.0))) if len(region) else 0.0
    rows = []
    for task, flat, known in zip(tasks, lines, run_plans):
        m = float(task.payload_kg)
        line = _least_on(cap, flat)
        row = {"task": task_name(task), "payload_kg": m, "start_branch_offset_deg": np.nan, "direct_capacity_kg": 0.0,
               "direct_note": "", "planned_capacity_kg": 0.0, "planned_payload_kg": np.nan, "planned_note": "",
               "run_plan_capacity_kg": np.nan, "run_plan_note": "no run plan" if known is None else "",
               "line_capacity_kg": line, "line_margin_pct": _margin(line, m, line >= m and line > 0),
               "region_capacity_kg": region_kg}
        q0, off = _start(problem, task)
        if q0 is None:
            row.update(direct_note="start not reachable", planned_note="start not reachable", capacity_kg=0.0,
                       path="", feasible=False, margin_pct=_margin(0.0, m, False))
            rows.append(row)
            continue
        row["start_branch_offset_deg"] = off
        paths = {"direct": np.array([task.start_m, task.goal_m], dtype=float)}
        paths["planned"], row["planned_payload_kg"], row["planned_note"] = _planned(
            problem, vox, grid, task, np.rad2deg(problem.arm.full_q(q0)))
        paths["run_plan"] = known
        verdicts = {}
        for name, wp in paths.items():
            if wp is not None:
                kg, ok, why = _carried(problem, wp, q0, m, s)
                verdicts[name] = (ok, kg)
                row[f"{name}_capacity_kg"] = kg
                row[f"{name}_note"] = "; ".join(t for t in (row[f"{name}_note"], why) if t)
        best = max(verdicts, key=verdicts.get)  # carries the payload first, then the most
        ok, kg = verdicts[best]
        row.update(path=best, capacity_kg=kg, feasible=any(v[0] for v in verdicts.values()),
                   margin_pct=_margin(kg, m, ok))
        rows.append(row)
    return [{c: r[c] for c in ADVICE_TASK_COLUMNS[2:]} for r in rows]


def healthy_lines(sweep: pd.DataFrame, grid: Grid, tasks: list[Task]) -> pd.DataFrame:
    """The healthy reference of each task: the least voxel capacity on its direct line of the best swept
    lock per voxel (``sweep``: one joint's lock sweep): task, payload_kg, line_capacity_kg, line_margin_pct."""
    best = np.full(grid.n_voxels, np.nan)
    flat = grid.flat(sweep[["i", "j", "k"]].to_numpy())
    np.fmax.at(best, flat, sweep.capacity_kg.to_numpy())
    rows = []
    for task in tasks:
        line = _least_on(best, line_voxels(grid, task.start_m, task.goal_m))
        rows.append({"task": task_name(task), "payload_kg": float(task.payload_kg), "line_capacity_kg": line,
                     "line_margin_pct": margin_pct(line, float(task.payload_kg))})
    return pd.DataFrame(rows)


def _per_angle(rows: pd.DataFrame) -> pd.DataFrame:
    """Per swept angle: the worst task's margin (and which), the worst line margin, tasks carried."""
    g = rows.groupby("angle_deg", sort=True)
    worst = rows.loc[g.margin_pct.idxmin().to_numpy()].set_index("angle_deg")
    return pd.DataFrame({"worst_margin_pct": worst.margin_pct,
                         "worst_task": worst.task + ", " + worst.payload_kg.map("{:g} kg".format),
                         "worst_line_margin_pct": g.line_margin_pct.min(), "region_capacity_kg": g.region_capacity_kg.first(),
                         "tasks_carried": g.feasible.sum(), "n_tasks": g.size()}).reset_index()


def recommend(rows: pd.DataFrame, stands_at_deg: float) -> pd.Series:
    """The recommended angle of one joint's task rows (:data:`ADVICE_TASK_COLUMNS`): the largest worst-task
    margin, ties to the largest capacity over the task region, then to the angle nearest ``stands_at_deg``. A
    row of :func:`_per_angle` (with ``angle_deg``)."""
    per = _per_angle(rows)
    key = np.lexsort((-np.abs(per.angle_deg.to_numpy() - stands_at_deg), per.region_capacity_kg.to_numpy(),
                      per.worst_margin_pct.to_numpy()))
    return per.iloc[key[-1]]


def neighbours_worst(rows: pd.DataFrame, angle_deg: float) -> float:
    """The worst task's margin [%] at the swept angles either side of ``angle_deg`` (a turn taken round
    when the sweep spans one): how far the margin falls if the brake holds a step off (NaN: no neighbour)."""
    per = _per_angle(rows).set_index("angle_deg").worst_margin_pct.sort_index()
    a = per.index.to_numpy()
    i = int(np.argmin(np.abs(a - angle_deg)))
    turn = len(a) > 2 and np.isclose((a[-1] - a[0]) + (a[1] - a[0]), 360.0)
    near = [i - 1, i + 1] if turn else [k for k in (i - 1, i + 1) if 0 <= k < len(a)]
    return float(per.iloc[[k % len(a) for k in near]].min()) if near else np.nan


def convergence(rows: pd.DataFrame, stands_at_deg: float, step_deg: float, strides=(4, 2, 1)) -> pd.DataFrame:
    """The recommendation on every ``stride``-th swept angle from the one the joint stands at (the sweep at
    stride x the step): step_deg, n_angles, recommended_angle_deg, worst_margin_pct, one row per stride."""
    angles = np.sort(rows.angle_deg.unique())
    k = np.rint((angles - stands_at_deg) / step_deg).astype(int)
    out = []
    for s in strides:
        keep = angles[k % s == 0]
        r = recommend(rows[rows.angle_deg.isin(keep)], stands_at_deg)
        out.append({"step_deg": s * step_deg, "n_angles": len(keep), "recommended_angle_deg": r.angle_deg,
                    "worst_margin_pct": r.worst_margin_pct})
    return pd.DataFrame(out)
