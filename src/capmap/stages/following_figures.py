"""Figures of the torque-limited following (kept apart so that the follow jobs do not import
matplotlib for nothing)."""

from __future__ import annotations

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.following import follow_progress, follow_torque_split, follow_torques

__all__ = ["stage_follow_plots"]


def stage_follow_plots(timeseries: str, toppra: str, out_s: str, out_torques: str, out_split: str,
                       slice_json: str) -> None:
    ts, tp = datasets.read(timeseries), datasets.read(toppra)
    meta = ts.attrs["capmap"]
    follow_progress(ts, tp, meta["case"], out_s)
    follow_torques(ts, meta["torque_limits_nm"], meta["case"], out_torques)
    follow_torque_split(ts, meta["torque_limits_nm"], meta["case"], meta["terms"], out_split)
    stage_logger(__name__, f"follow plots {meta['case']}").info(f"-> {out_s}, {out_torques}, {out_split}")
