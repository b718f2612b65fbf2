"""Stages of the reconfigurable robot: reconfig (one job per method: nullspace, pinv) ->
reconfig_summary, reconfig_plots, reconfig_animation."""

from __future__ import annotations

import json
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table
from capmap.reconfig.build import planner_settings, reconfig_problem
from capmap.reconfig.multiarm import platform_model
from capmap.reconfig.planner import reconfigure
from capmap.reconfig.problem import closure_errors, summarise
from capmap.reconfig.tables import column, run_table
from capmap.stages.common import stage_config

__all__ = ["stage_reconfig", "stage_reconfig_summary"]


def stage_reconfig(method: str, out: str, out_timing: str, slice_json: str) -> None:
    """Plan the reconfiguration with one method; a table row per step (the whole loop's joints)."""
    sc = stage_config(slice_json)
    cfg = sc.run.reconfig
    log = stage_logger(__name__, f"reconfig {method}")
    problem = reconfig_problem(cfg)
    split = problem.split
    settings = planner_settings(cfg, problem, method)  # the pseudo-inverse has no null-space gain
    log.info(f"{split.unlocked} unlocked in the loop of capture {split.capture}: moving side {split.moving.dof} "
             f"joints ({', '.join(split.moving.joints)}), fixed side {split.fixed.dof}; capture closed by IK with a "
             f"change of {np.rad2deg(np.abs(problem.correction_rad).max()):.2e} deg")
    t0 = time.perf_counter()
    run = reconfigure(split, problem.fixed_end, problem.q0, problem.law, settings)
    wall = time.perf_counter() - t0
    closure = closure_errors(problem, platform_model(problem.description), run)
    df = run_table(method, problem, run, closure)
    summary = summarise(run, closure, settings, split.moving.joints)
    prov = datasets.provenance(
        "reconfig", sc.doc, method=method, status=run.status, message=run.message, unlocked=split.unlocked,
        capture=split.capture, moving_joints=list(split.moving.joints), fixed_joints=list(split.fixed.joints),
        rate_limits_deg_s={f"qd_{column(j)}_deg_s": float(np.rad2deg(v)) for j, v in
                           zip(split.moving.joints, settings.rate_limit)},
        ranges_deg={f"q_{column(j)}_deg": np.rad2deg([lo, hi]).tolist() for j, lo, hi in
                    zip(split.moving.joints, settings.q_lower, settings.q_upper)},
        passive_ranges={"theta_deg": np.rad2deg(problem.description.joint(split.unlocked).range_rad).tolist(),
                        "d_m": problem.description.joint(split.unlocked).range_m.tolist()},
        capture_correction_deg=float(np.rad2deg(np.abs(problem.correction_rad).max())), summary=asdict(summary))
    datasets.write(df, out, prov)
    Path(out_timing).write_text(json.dumps({"method": method, "steps": run.steps, "wall_s": wall,
                                            "per_step_ms": 1e3 * wall / max(run.steps, 1)}) + "\n")
    log.info(f"{run.status}{': ' + run.message if run.message else ''}; {run.steps} steps in {wall:.2f} s "
             f"({1e3 * wall / max(run.steps, 1):.2f} ms/step); m {summary.m_initial:.1f} -> min {summary.m_min:.1f} "
             f"-> {summary.m_final:.1f}; dm/dt < 0 in {summary.steps_dm_dt_negative} steps; closure "
             f"{summary.max_closure_pos_err_m:.1e} m, {summary.max_closure_rot_err_rad:.1e} rad; peak rate "
             f"{summary.max_joint_rate_deg_s:.3f} deg/s ({summary.max_rate_pct_of_limit:.0f}% of its limit)")


def stage_reconfig_summary(tables: list[str], timings: list[str], out_csv: str, out_md: str) -> None:
    """One row per method: the run's summary and its wall time per step."""
    rows = []
    for table, timing in zip(tables, timings):
        meta = datasets.read(table).attrs["capmap"]
        t = json.loads(Path(timing).read_text())
        rows.append({"method": meta["method"], "unlocked": meta["unlocked"], **meta["summary"],
                     "message": meta["message"], "per_step_ms": t["per_step_ms"]})
    write_table(pd.DataFrame(rows), out_csv, out_md)
    stage_logger(__name__, "reconfig summary").info(f"{len(rows)} methods -> {out_csv}")


