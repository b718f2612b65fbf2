"""Stages of the dual-arm family, for people: dualarm_plots and dualarm_animation."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from capmap.config.dualarm import SolverConfig
from capmap.dualarm.build import al_settings, job_setup
from capmap.dualarm.scene_file import load_scene
from capmap.dualarm.tables import envelope_from
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.common import not_done_figure
from capmap.plots.dualarm import (
    Surroundings,
    animation,
    constraint_errors,
    convergence,
    distances,
    joints,
    torques,
)
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_dualarm_plots", "stage_dualarm_animation"]


def stage_dualarm_plots(trajectory: str, fine: str, outer: str, torques_file: str, out: Outputs) -> None:
    """Constraint errors, safety distances, joints and velocities vs their limits, torques vs the
    effort limits, convergence (``out``: errors, distances, joints, velocities, torques, convergence)."""
    traj, fine_df, outer_df = datasets.read(trajectory), datasets.read(fine), datasets.read(outer)
    tq = datasets.read(torques_file)
    meta = traj.attrs["capmap"]
    if traj.empty:  # no motion could be planned: each figure says why
        for png in out.values():
            not_done_figure("dual-arm assembly: no motion could be planned", meta["reason"], png)
        return stage_logger(__name__, "dualarm plots").info("infeasible -> " + ", ".join(out.values()))
    constraint_errors(traj, out["errors"])
    distances(traj, fine_df, meta["margin_m"], meta["active"], out["distances"])
    joints(traj, meta, "q", out["joints"])
    joints(traj, meta, "qd", out["velocities"])
    t_pre = float(traj.t_s[traj.phase == "pre_insertion"].iloc[0])
    torques(tq, tq.attrs["capmap"], t_pre, out["torques"])
    solver = outer_df.attrs["capmap"]["config"]["run"]["dualarm"]["solver"]  # the run's, in its provenance
    convergence(outer_df, out["convergence"], al_settings(SolverConfig(**solver)).tolerance)
    stage_logger(__name__, "dualarm plots").info("-> " + ", ".join(out.values()))


def stage_dualarm_animation(trajectory: str, environment: str, capsules: str, out_html: str, slice_json: str) -> None:
    """MeshCat static HTML of the motion (capsules, the panel, the fitted environment)."""
    da = stage_config(slice_json).run.dualarm
    caps, env_df = datasets.read(capsules), datasets.read(environment)
    robot, asm = job_setup(da, env_df, caps, da.horizon)
    traj = datasets.read(trajectory)
    scene = load_scene(da.scene)
    q = traj[[f"q_{j}_rad" for j in robot.joint_names]].to_numpy()
    if traj.empty:  # no motion could be planned: the scene at the start, the reason in the title
        q = np.asarray(scene.q_start, dtype=float)[None]
    step = max(1, int(round(1.0 / (da.animation_fps * asm.task.dt))))
    model = asm.model
    data = model.createData()
    frames = []
    for qk in q[::step]:
        pin.forwardKinematics(model, data, qk)
        frames.append([M.homogeneous for M in data.oMi])
    jid = {name: model.getJointId(name) for name in robot.joint_names}
    capsules_at = [(c.name, jid.get(c.joint, 0), c.a, c.b, c.r) for c in robot.capsules]
    fp = model.frames[asm.task.panel]
    env, _ = envelope_from(env_df)
    panel = (fp.parentJoint, fp.placement.homogeneous, scene.panel.size)
    animation(capsules_at, np.array(frames), panel,
              Surroundings(env.tri, [(a, b, r) for (a, b), r in zip(env.seg, env.seg_radius)]),
              1.0 / (step * asm.task.dt), f"{robot.description.name}: {scene.name}"
              + (f" (no motion: {traj.attrs['capmap']['reason']})" if traj.empty else ""), out_html)
    stage_logger(__name__, "dualarm animation").info(f"{len(frames)} frames -> {out_html}")
