"""Stages of the lock-angle advice: the run's tasks verified at each angle of a joint's lock sweep
(:mod:`capmap.stages.lock_sweep`), and the recommendation with its figure."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.capacity.advice import (
    AdviceSettings,
    convergence,
    full_grid,
    healthy_lines,
    neighbours_worst,
    recommend,
    tasks_at_lock,
)
from capmap.capacity.build import capacity_problem
from capmap.capacity.tables import grid_of
from capmap.config.jobs import PlanTask, payload_label
from capmap.config.run import RunConfig
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.advice import advice_figure
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_advice_tasks", "stage_advice", "advice_tasks"]


def advice_tasks(run: RunConfig) -> list[PlanTask]:
    """The tasks the advice verifies: the main task at each payload (from its start, its reference
    configuration the arm when the joint failed, ``task.q_ini_deg``) and the further tasks of ``tasks``."""
    main = [PlanTask(payload_kg=float(m), start_m=run.failure.start_m, goal_m=run.task.goal_m,
                     q_start_deg=run.task.q_ini_deg) for m in run.task.payload_kg]
    return main + list(run.tasks)


def _run_plans(run: RunConfig, tasks: list[PlanTask], plans: list[str]) -> list[np.ndarray | None]:
    """Each task's planned path of the run (its plan folder's waypoints; None where the run found none)."""
    def folder(t: PlanTask) -> str:
        return f"tasks/{t.name}" if t.name is not None else f"plan/payload_{payload_label(t.payload_kg)}kg"

    by_folder = {str(Path(p).parent.relative_to(Path(p).parents[2])): p for p in plans}
    out = []
    for t in tasks:
        wp = datasets.read(by_folder[folder(t)])
        out.append(wp[["x_m", "y_m", "z_m"]].to_numpy() if len(wp) else None)
    return out


def stage_advice_tasks(sweep_path: str, plans: list[str], out: Outputs, slice_json: str, joint: int) -> None:
    """The run's tasks verified at every angle of ``joint``'s sweep (planned on that angle's map; the run's own
    plans, ``plans``: the waypoints of its plan folders, verified too), and the healthy reference of each task
    (the best swept lock per voxel along its direct line)."""
    cfg = stage_config(slice_json)
    run = cfg.run
    log = stage_logger(__name__, f"advice tasks joint {joint}")
    sweep = datasets.read(sweep_path)
    grid = grid_of(sweep)
    tasks = advice_tasks(run)
    known = _run_plans(run, tasks, plans)
    settings = AdviceSettings(run.verification.dt_s)
    rows = []
    for angle, vox in sweep.groupby("angle_deg", sort=True):
        problem = capacity_problem(run, joint, float(angle))
        part = tasks_at_lock(problem, full_grid(vox, grid), grid, tasks, settings, known)
        rows += [{"joint": joint, "angle_deg": float(angle), **r} for r in part]
        log.info(f"{angle:g} deg: " + "; ".join(f"{r['task']} {r['payload_kg']:g} kg {r['margin_pct']:+.0f} % "
                                                f"({r['path'] or 'none'})" for r in part))
    prov = datasets.provenance("advice_tasks", cfg.doc, joint=joint, grid=sweep.attrs["capmap"]["grid"],
                               stands_at_deg=sweep.attrs["capmap"]["stands_at_deg"])
    datasets.write(pd.DataFrame(rows), out["tasks"], prov)
    datasets.write(healthy_lines(sweep, grid, tasks), out["healthy"], prov)


def stage_advice(tasks_path: str, healthy_path: str, out: Outputs, slice_json: str, joint: int) -> None:
    """The recommended lock angle of ``joint`` (the largest worst-task margin), its convergence with the
    step, and the figure of every task's margin against the lock angle."""
    cfg = stage_config(slice_json)
    rows, healthy = datasets.read(tasks_path), datasets.read(healthy_path)
    stands_at, step = float(rows.attrs["capmap"]["stands_at_deg"]), float(cfg.run.advice.step_deg)
    best = recommend(rows, stands_at)
    here = rows[np.isclose(rows.angle_deg, stands_at)]
    advice = pd.DataFrame([{
        "joint": joint, "step_deg": step, "n_angles": rows.angle_deg.nunique(), "stands_at_deg": stands_at,
        "recommended_angle_deg": best.angle_deg, "worst_task": best.worst_task,
        "worst_margin_pct": best.worst_margin_pct, "neighbours_worst_margin_pct": neighbours_worst(rows, best.angle_deg),
        "worst_line_margin_pct": best.worst_line_margin_pct, "region_capacity_kg": best.region_capacity_kg,
        "tasks_carried": int(best.tasks_carried), "n_tasks": int(best.n_tasks),
        "stands_at_worst_margin_pct": float(here.margin_pct.min()) if len(here) else np.nan,
        "healthy_worst_line_margin_pct": float(healthy.line_margin_pct.min())}])
    conv = convergence(rows, stands_at, step)
    prov = datasets.provenance("advice", cfg.doc, joint=joint)
    datasets.write(advice, out["advice"], prov)
    datasets.write(conv, out["convergence"], prov)
    advice_figure(rows, healthy, advice.iloc[0], conv, out["figure"])
    stage_logger(__name__, f"advice joint {joint}").info(
        f"brake joint {joint} at {best.angle_deg:g} deg: worst task {best.worst_task} {best.worst_margin_pct:+.1f} % "
        f"({int(best.tasks_carried)}/{int(best.n_tasks)} tasks carried); where it stands ({stands_at:g} deg): "
        f"{advice.stands_at_worst_margin_pct.iloc[0]:+.1f} %")
