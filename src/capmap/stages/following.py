"""Stages of torque-limited following: follow (a case's path, segment by segment, and TOPP-RA
on the same path and limits) -> follow_plots. Cases: ``space`` (the space arm's verified
path at a payload) and ``ground`` (a ground arm's straight line)."""

from __future__ import annotations

from capmap.following.build import follow_case
from capmap.following.tables import follow_path, follow_tables, stored_rows, summary_row
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table
from capmap.stages.common import stage_config

__all__ = ["stage_follow"]


def stage_follow(case: str, out_timeseries: str, out_toppra: str, out_csv: str, out_md: str, slice_json: str,
                 waypoints: str | None = None) -> None:
    """Torque-limited following of a case's path, segment by segment, and TOPP-RA on the same."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, f"follow {case}")
    fc = follow_case(case, sc.run, sc.job, datasets.read(waypoints) if waypoints else None)
    run = follow_path(fc.arm, fc.waypoints, fc.rotation, fc.q_start, fc.settings, log.info)
    ts, tp = follow_tables(case, fc.arm, run)
    limits, st, cmp = fc.settings.torque_limits(fc.arm), fc.settings, run.comparison
    every = sc.run.follow.store_every
    prov = datasets.provenance("follow", sc.doc, case=case, torque_limits_nm=dict(zip(limits.names, limits.limit.tolist())),
                               payload_kg=st.payload_kg, terms=cmp.follower_terms, control_period_s=st.period_s,
                               rows=f"every {every} control periods and each window's torque peak" if every > 1
                               else "every control period")
    datasets.write(stored_rows(ts, every, limits.limit), out_timeseries, prov)
    datasets.write(tp, out_toppra, prov)
    write_table(summary_row(case, fc.arm, fc.label, st, run), out_csv, out_md)
    log.info(f"{cmp.length_m:.3f} m in {cmp.follower_duration_s:.3f} s vs TOPP-RA {cmp.toppra_duration_s:.3f} s "
             f"(ratio {cmp.duration_ratio:.3f}); peak torque {cmp.follower_peak_torque_pct:.3f}% of limit "
             f"(TOPP-RA {cmp.toppra_peak_torque_pct:.3f}%); command would need {cmp.command_peak_torque_pct:.1f}%; "
             f"max path deviation {cmp.max_deviation_m:.2e} m; torque model {cmp.follower_terms}")
    if cmp.follower_terms != cmp.toppra_terms:
        log.info(f"TOPP-RA ({cmp.toppra_terms}, no viscous friction) peaks at {cmp.toppra_peak_torque_pct:.1f}% of the "
                 f"limit with it; the follower without viscous friction (like for like): "
                 f"{cmp.follower_no_viscous_duration_s:.3f} s, ratio {cmp.duration_ratio_no_viscous:.3f}")
