"""Stages of torque-limited following: follow (a case's path, segment by segment, and TOPP-RA
on the same path and limits) -> follow_plots. Cases: ``space`` (the space arm's verified
path at a payload) and ``ground`` (a ground arm's straight line)."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from capmap.config.robot_file import load
from capmap.config.validation import per_item
from capmap.core.reduction import LockedArm, free
from capmap.following.comparison import compare
from capmap.following.follower import FollowSettings, follow_segment
from capmap.following.toppra_reference import time_optimal
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table
from capmap.stages.arm import arm_from
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
        robot, arm = arm_from(sc.run)
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
        return FollowCase(arm, pts, task.rotation, q0, settings, label)
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
    arm, st, pts = fc.arm, fc.settings, fc.waypoints
    limits = st.torque_limits(arm)
    joints = arm.active_joint_numbers
    parts, tparts, followed, optimal = [], [], [], []
    t_off = t_off_topp = s_off = 0.0
    q = fc.q_start
    for k in range(len(pts) - 1):
        t0 = time.perf_counter()
        seg = follow_segment(arm, pts[k], pts[k + 1], fc.rotation, q, st)
        el = time.perf_counter() - t0
        top = time_optimal(arm, seg.table, st.payload_kg, limits, st.v_max_mps, st.a_max_mps2, sample_dt_s=st.period_s)
        r = seg.result
        df = pd.DataFrame({"case": case, "segment": k, "t_s": t_off + r.t_s, "s_cmd_m": s_off + r.s_cmd,
                           "sd_cmd_mps": r.sd_cmd, "sdd_cmd_mps2": r.sdd_cmd, "s_m": s_off + r.s, "sd_mps": r.sd,
                           "sdd_mps2": r.sdd, "lag_m": r.s_cmd - r.s, "limited": r.limited,
                           "infeasible": r.infeasible})
        for prefix, values in (("tau_cmd", seg.tau_cmd), ("tau", seg.tau)):
            for c, jn in enumerate(joints):
                df[f"{prefix}_j{jn}_nm"] = values[:, c]
        for c, jn in enumerate(joints):
            df[f"q_j{jn}_deg"] = np.rad2deg(seg.q[:, c])
        df["deviation_m"] = seg.deviation_m
        df["deviation_rad"] = seg.deviation_rad
        parts.append(df)
        tdf = pd.DataFrame({"case": case, "segment": k, "t_s": t_off_topp + top.t_s, "s_m": s_off + top.s,
                            "sd_mps": top.sd})
        for c, jn in enumerate(joints):
            tdf[f"tau_j{jn}_nm"] = top.tau[:, c]
        tparts.append(tdf)
        followed.append(seg)
        optimal.append(top)
        log.info(f"segment {k + 1}/{len(pts) - 1}: {seg.table.length_m:.3f} m, command {seg.command.duration_s:.3f} s, "
                 f"follower {r.duration_s:.3f} s ({int(r.limited.sum())} of {len(r.t_s)} periods limited), "
                 f"TOPP-RA {top.duration_s:.3f} s; {el:.2f} s wall incl. path preparation and exact evaluation")
        t_off += r.duration_s
        t_off_topp += top.duration_s
        s_off += seg.table.length_m
        q = seg.q[-1]
    ts = pd.concat(parts, ignore_index=True)
    tp = pd.concat(tparts, ignore_index=True)
    cmp = compare(followed, optimal, limits)
    summary = pd.DataFrame([{"case": case, "robot": arm.robot.name, "path": fc.label, "payload_kg": st.payload_kg,
                             **asdict(cmp), "period_s": st.period_s}])
    prov = datasets.provenance("follow", sc.doc, case=case, torque_limits_nm=dict(zip(limits.names, limits.limit.tolist())),
                               payload_kg=st.payload_kg)
    datasets.write(ts, out_timeseries, prov)
    datasets.write(tp, out_toppra, prov)
    write_table(summary, out_csv, out_md)
    log.info(f"{cmp.length_m:.3f} m in {cmp.follower_duration_s:.3f} s vs TOPP-RA {cmp.toppra_duration_s:.3f} s "
             f"(ratio {cmp.duration_ratio:.3f}); peak torque {cmp.follower_peak_torque_pct:.3f}% of limit "
             f"(TOPP-RA {cmp.toppra_peak_torque_pct:.3f}%); command would need {cmp.command_peak_torque_pct:.1f}%; "
             f"max path deviation {cmp.max_deviation_m:.2e} m")


