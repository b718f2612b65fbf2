"""Figures of the torque-limited following (kept apart so that the follow jobs do not import
matplotlib for nothing)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.following import follow_infeasible, follow_progress, follow_torque_split, follow_torques
from capmap.stages.common import Outputs

__all__ = ["stage_follow_plots"]


def _summary_beside(timeseries: str, case: str) -> dict:
    """The case's summary row (``summary.csv`` beside the time series, written by the same job): the S-curve
    command's exact duration and the torque terms of each run; empty when there is none for this case."""
    path = Path(timeseries).with_name("summary.csv")
    rows = pd.read_csv(path) if path.exists() else pd.DataFrame()
    rows = rows[rows["case"] == case] if "case" in rows else rows.iloc[:0]
    return rows.iloc[0].to_dict() if len(rows) else {}


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
    follow_torques(ts, limits, case, out["torques"])
    follow_torque_split(ts, tp, limits, case, meta["terms"], out["split"], summary)
    stage_logger(__name__, f"follow plots {case}").info(f"-> {', '.join(out.values())}")
