"""Stages of torque-limited following: follow (a case's path, segment by segment, and TOPP-RA
on the same path and limits) -> follow_plots. Cases: ``space`` (the space arm's verified
path at a payload) and ``ground`` (a ground arm's straight line)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.capacity.build import run_arm, task_rotation
from capmap.config.robot_file import load
from capmap.config.validation import per_item
from capmap.core.reduction import LockedArm, free
from capmap.following.follower import FollowSettings
from capmap.following.tables import follow_path, follow_tables, stored_rows, summary_row
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table
from capmap.stages.common import StageConfig, stage_config

__all__ = ["FollowCase", "follow_case", "stage_follow"]


@dataclass(frozen=True)
class FollowCase:
    """A follow case ready to run: the arm, its waypoints (W, 3) m followed as straight segments
    at ``rotation`` (3, 3) from q_start (n_active,) rad, the follower's settings and a label."""

    arm: LockedArm
    waypoints: np.ndarray
    rotation: np.ndarray
    q_start: np.ndarray
    settings: FollowSettings
    label: str


def follow_case(case: str, sc: StageConfig, waypoints: str | None) -> FollowCase:
    """The ``space`` case follows its payload's verified path (planned, else the direct line);
    the ``ground`` case a straight line from FK(q_start)."""
    fol = sc.run.follow
    if case == "space":
        sp = fol.space
        arm = run_arm(sc.run)
        robot = arm.robot
        task, vt = sc.run.task, sc.job
        wp = datasets.read(waypoints)
        if wp.attrs["capmap"]["status"] == "ok":
            pts, label = wp[["x_m", "y_m", "z_m"]].to_numpy(), "planned path"
        else:
            pts, label = np.array([vt.start_m, vt.goal_m], dtype=float), "direct line (no planned path)"
        tau = per_item(sp.joint_torque_nm, robot.n_joints, "follow.space.joint_torque_nm")[arm.active]
        settings = FollowSettings(float(sp.payload_kg), tau, task.v_max_mps, task.a_max_mps2, sp.j_max_mps3,
                                  fol.period_s, sp.catch_up_hz)
        q0 = np.deg2rad(np.asarray(vt.q_start_deg, dtype=float))[arm.active]
        return FollowCase(arm, pts, task_rotation(task), q0, settings, label)
    g = fol.ground
    robot = load(g.robot)
    arm = free(robot)
    q0 = np.deg2rad(np.asarray(g.q_start_deg, dtype=float))
    T0 = arm.fk(q0[None])[0]
    pts = np.array([T0[:3, 3], T0[:3, 3] + np.asarray(g.line_m, dtype=float)])
    tau = per_item(g.joint_torque_nm, robot.n_joints, "follow.ground.joint_torque_nm")
    settings = FollowSettings(float(g.payload_kg), tau, g.v_max_mps, g.a_max_mps2, g.j_max_mps3, fol.period_s,
                              g.catch_up_hz)
    return FollowCase(arm, pts, T0[:3, :3], q0, settings, "straight line")


def stage_follow(case: str, out_timeseries: str, out_toppra: str, out_csv: str, out_md: str, slice_json: str,
                 waypoints: str | None = None) -> None:
    """Torque-limited following of a case's path, segment by segment, and TOPP-RA on the same."""
    sc = stage_config(slice_json)
    log = stage_logger(__name__, f"follow {case}")
    fc = follow_case(case, sc, waypoints)
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
