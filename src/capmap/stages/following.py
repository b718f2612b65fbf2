"""Stages of torque-limited following: follow (a case's path, segment by segment, and TOPP-RA
on the same path and limits) -> follow_plots. Cases: ``space`` (the space arm's verified
path at a payload) and ``ground`` (a ground arm's straight line)."""

from __future__ import annotations

from dataclasses import asdict

from capmap.following.build import follow_case
from capmap.following.tables import follow_path, follow_tables, run_lines, stored_rows, summary_row
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table
from capmap.stages.common import stage_config

__all__ = ["stage_follow"]


def stage_follow(case: str, out_timeseries: str, out_toppra: str, out_csv: str, out_md: str, slice_json: str,
                 waypoints: str | None = None) -> None:
    """Torque-limited following of a case's path, segment by segment, and TOPP-RA on the same; a path
    the arm cannot follow is written as such (``feasible`` False, the reason; the job succeeds)."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, f"follow {case}")
    fc = follow_case(case, sc.run, sc.job, datasets.read(waypoints) if waypoints else None)
    run = follow_path(fc.arm, fc.waypoints, fc.rotation, fc.q_start, fc.settings, log.info)
    ts, tp = follow_tables(case, fc.arm, run)
    limits, st = fc.settings.torque_limits(fc.arm), fc.settings
    every = sc.run.follow.store_every
    prov = datasets.provenance("follow", sc.doc, case=case, torque_limits_nm=dict(zip(limits.names, limits.limit.tolist())),
                               payload_kg=st.payload_kg, terms=run.terms, control_period_s=st.period_s,
                               feasible=run.feasible, reason=run.reason,
                               shortfall=asdict(run.shortfall) if run.shortfall else None,
                               rows=f"every {every} control periods and each window's torque peak" if every > 1
                               else "every control period")
    datasets.write(stored_rows(ts, every, limits.limit), out_timeseries, prov)
    datasets.write(stored_rows(tp, every, limits.limit), out_toppra, prov)
    write_table(summary_row(case, fc.arm, fc.label, st, run), out_csv, out_md)
    for line in run_lines(run):
        log.info(line)
