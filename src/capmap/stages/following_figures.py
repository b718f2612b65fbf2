"""Figures of the torque-limited following (kept apart so that the follow jobs do not import
matplotlib for nothing)."""

from __future__ import annotations

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.following import follow_infeasible, follow_progress, follow_torque_split, follow_torques
from capmap.stages.common import Outputs

__all__ = ["stage_follow_plots"]


def stage_follow_plots(timeseries: str, toppra: str, out: Outputs, slice_json: str) -> None:
    """The follower's progress and duration against TOPP-RA (``out["s"]``), the torques before and after
    limiting (``out["torques"]``) and their split into drive terms (``out["split"]``; a robot without
    drives: the follower's torques against TOPP-RA's along the path). ``slice_json`` is not read: the
    tables carry what the figures need."""
    ts, tp = datasets.read(timeseries), datasets.read(toppra)
    meta = ts.attrs["capmap"]
    if not meta.get("feasible", True):  # each figure says why the path cannot be followed
        for png in out.values():
            follow_infeasible(meta["reason"], meta["shortfall"], meta["torque_limits_nm"], meta["case"], png)
        stage_logger(__name__, f"follow plots {meta['case']}").info(f"infeasible -> {', '.join(out.values())}")
        return
    follow_progress(ts, tp, meta["case"], out["s"])
    follow_torques(ts, meta["torque_limits_nm"], meta["case"], out["torques"])
    follow_torque_split(ts, tp, meta["torque_limits_nm"], meta["case"], meta["terms"], out["split"])
    stage_logger(__name__, f"follow plots {meta['case']}").info(f"-> {', '.join(out.values())}")
