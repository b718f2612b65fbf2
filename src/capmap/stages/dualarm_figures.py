"""Stages of the dual-arm family, for people: dualarm_plots and dualarm_animation."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pinocchio as pin

from capmap.config.dualarm import SolverConfig
from capmap.dualarm.build import al_settings, job_setup
from capmap.dualarm.scene_file import load_scene
from capmap.dualarm.tables import envelope_from
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.plots.common import not_done_figure
from capmap.plots.dualarm import constraint_errors, convergence, distances
from capmap.plots.dualarm_motion import joints, torques, velocities
from capmap.plots.dualarm_scene import Held, Surroundings, animation
from capmap.plots.scene3d import Overlay
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_dualarm_plots", "stage_dualarm_animation"]


FIGURES = {"errors": "task-constraint errors", "distances": "safety distances", "joints": "joint positions",
           "velocities": "joint velocities", "torques": "joint torques", "convergence": "solver convergence"}


def stage_dualarm_plots(trajectory: str, fine: str, outer: str, torques_file: str, out: Outputs) -> None:
    """Constraint errors, safety distances, joints and velocities vs their limits, torques vs the
    effort limits, convergence (``out``: errors, distances, joints, velocities, torques, convergence)."""
    traj, fine_df, outer_df = datasets.read(trajectory), datasets.read(fine), datasets.read(outer)
    tq = datasets.read(torques_file)
    meta = traj.attrs["capmap"]
    if traj.empty:  # no motion could be planned: each figure says what it would show, and why it does not
        for key, png in out.items():
            not_done_figure(f"Dual-arm assembly, {FIGURES.get(key, key)}: no motion could be planned", meta["reason"], png)
        return stage_logger(__name__, "dualarm plots").info("infeasible -> " + ", ".join(out.values()))
    solver = outer_df.attrs["capmap"]["config"]["run"]["dualarm"]["solver"]  # the run's, in its provenance
    tolerance = al_settings(SolverConfig(**solver)).tolerance
    constraint_errors(traj, out["errors"], tolerance)
    distances(traj, fine_df, meta["margin_m"], meta["active"], tolerance, out["distances"])
    joints(traj, meta, out["joints"])
    velocities(traj, meta, out["velocities"])
    t_pre = float(traj.t_s[traj.phase == "pre_insertion"].iloc[0])
    torques(tq, tq.attrs["capmap"], t_pre, out["torques"])
    node_errors = tuple(float(traj[cols].max().max()) for cols in (["closed_chain_pos_err_m", "path_err_m"],
                                                                   ["closed_chain_rot_err_rad", "path_err_rad"]))
    convergence(outer_df, out["convergence"], tolerance, node_errors)
    stage_logger(__name__, "dualarm plots").info("-> " + ", ".join(out.values()))


def stage_dualarm_animation(trajectory: str, environment: str, capsules: str, out_html: str, slice_json: str) -> None:
    """MeshCat static HTML of the motion (capsules, the panel with its holes and final pose, the pins, the fitted
    environment), with its title, the verdict, a legend and, as it plays, the simulated time, phase, closest pair
    and how far the panel is from its final pose."""
    da = stage_config(slice_json).run.dualarm
    caps, env_df = datasets.read(capsules), datasets.read(environment)
    robot, asm = job_setup(da, env_df, caps, da.horizon)
    traj = datasets.read(trajectory)
    scene = load_scene(da.scene)
    q = traj[[f"q_{j}_rad" for j in robot.joint_names]].to_numpy()
    if traj.empty:  # no motion could be planned: the scene at the start, the reason in the caption
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
    held = _held(scene, model.frames[asm.task.panel])
    env, (tri_label, _) = envelope_from(env_df)
    to_go = [np.linalg.norm(f[held.body][:3, :3] @ held.in_body[:3, 3] + f[held.body][:3, 3] - scene.final[:3, 3])
             for f in frames]  # the panel's centre from its final pose, m
    title = f"{robot.description.name.capitalize()} carries a panel in both grippers onto {len(held.pins)} pins"
    animation(capsules_at, np.array(frames), held,
              Surroundings(env.tri, [(a, b, r) for (a, b), r in zip(env.seg, env.seg_radius)], tri_label),
              1.0 / (step * asm.task.dt), _caption(traj, step, title, to_go), out_html)
    stage_logger(__name__, "dualarm animation").info(f"{len(frames)} frames -> {out_html}")


def _held(scene, panel_frame) -> Held:
    """The panel (on the body the model's panel frame hangs from), its holes, final pose and the pins: the scene's
    cylinders inside its pin zone."""
    lo, hi = scene.pin_zone
    pins = tuple((c.p0, c.p1, c.radius) for c in scene.cylinders
                 if all(((lo <= p) & (p <= hi)).all() for p in (c.p0, c.p1)))
    p = scene.panel
    return Held(panel_frame.parentJoint, panel_frame.placement.homogeneous, p.size, p.holes, p.hole_radius,
                scene.final, pins)


PHASES = {"transfer": "transfer", "pre_insertion": "pre-insertion pose", "insertion": "insertion",
          "final": "final pose"}


def _caption(traj: pd.DataFrame, step: int, title: str, to_go: list[float]) -> Overlay:
    """The animation's words: its ``title``, the verdict (the smallest safety distance at the nodes against the
    margin), and per frame (every ``step``-th node) the phase, the panel's distance ``to_go`` (m) from its final pose
    and the closest pair; or why there is no motion."""
    meta = traj.attrs["capmap"]
    if traj.empty:
        return Overlay(f"{title}: no motion planned", (f"no motion: {meta['reason']}",),
                       frame_text=("t = 0 s: the scene at the start pose (no motion)",))
    d, margin = 1e3 * float(traj.min_distance_m.min()), 1e3 * meta["margin_m"]
    verdict = "collision-free" if d > 0 else "IN COLLISION"
    lines = (f"{verdict}: smallest distance {d:.2f} mm at the nodes (margin {margin:g} mm)",)
    texts = tuple(f"{PHASES.get(r.phase, r.phase)}: panel {100 * g:.1f} cm from its final pose\n"
                  f"closest: {r.min_distance_pair}, {1e3 * r.min_distance_m:.2f} mm"
                  for r, g in zip(traj.iloc[::step].itertuples(), to_go))
    return Overlay(title, lines, frame_text=texts)
