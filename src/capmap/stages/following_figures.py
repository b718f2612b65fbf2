"""Figures of the torque-limited following (kept apart so that the follow jobs do not import
matplotlib for nothing)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.following import follow_infeasible, follow_progress
from capmap.plots.following_limits import follow_torque_split, follow_torques
from capmap.robots import load
from capmap.stages.common import Outputs

__all__ = ["stage_follow_plots"]


def _summary_beside(timeseries: str, case: str) -> dict:
    """The case's summary row (``summary.csv`` beside the time series, written by the same job): the S-curve
    command's exact duration and the torque terms of each run; empty when there is none for this case."""
    path = Path(timeseries).with_name("summary.csv")
    rows = pd.read_csv(path) if path.exists() else pd.DataFrame()
    rows = rows[rows["case"] == case] if "case" in rows else rows.iloc[:0]
    return rows.iloc[0].to_dict() if len(rows) else {}


def _limits_elsewhere(meta: dict) -> dict:
    """The torque limits the arm has outside this case, per limited joint's column (N m), to tell which the case
    tightened: a case with its own robot file (ground), its URDF's effort limits (the robot's rating); else the
    capacity map's ``limits.joint_torque_nm``. Empty when the run's configuration gives neither."""
    run = meta.get("config", {}).get("run", {})
    own = run.get("follow", {}).get(meta["case"], {}).get("robot")
    given = (load(own).effort_limit_nm if own and Path(own).exists() else None) if own else \
        run.get("limits", {}).get("joint_torque_nm")
    if given is None:
        return {}
    v = np.atleast_1d(np.asarray(given, dtype=float))
    at = {c: int(c.split("_")[1][1:]) - 1 for c in meta["torque_limits_nm"]}  # 'tau_j2_nm' -> 1
    return {c: float(v[0] if len(v) == 1 else v[i]) for c, i in at.items() if len(v) == 1 or i < len(v)}


def stage_follow_plots(timeseries: str, toppra: str, out: Outputs, slice_json: str) -> None:
    """Where the follower's time goes against TOPP-RA (``out["s"]``), the torques before and after
    limiting (``out["torques"]``) and their split into drive terms (``out["split"]``; a robot without
    drives: the follower's torques against TOPP-RA's). ``slice_json`` is not read: the tables (and the
    case's summary row beside them, when there) carry what the figures need."""
    ts, tp = datasets.read(timeseries), datasets.read(toppra)
    meta = ts.attrs["capmap"]
    if not meta.get("feasible", True):  # each figure says why the path cannot be followed
        for png in out.values():
            follow_infeasible(meta["reason"], meta["shortfall"], meta["torque_limits_nm"], meta["case"], png)
        stage_logger(__name__, f"follow plots {meta['case']}").info(f"infeasible -> {', '.join(out.values())}")
        return
    case, limits, summary = meta["case"], meta["torque_limits_nm"], _summary_beside(timeseries, meta["case"])
    follow_progress(ts, tp, limits, case, out["s"], summary)
    follow_torques(ts, limits, case, out["torques"], _limits_elsewhere(meta))
    follow_torque_split(ts, tp, limits, case, meta["terms"], out["split"], summary)
    stage_logger(__name__, f"follow plots {case}").info(f"-> {', '.join(out.values())}")
