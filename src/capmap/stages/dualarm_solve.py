"""Stages of the dual-arm family, the motion: dualarm_optimise (feasibility of the key poses, warm
start, augmented-Lagrangian DDP, independent evaluation) and dualarm_check (the equality-only
problem by AL-FDDP and by mim-solvers CSQP)."""

from __future__ import annotations

import re
import time
from dataclasses import replace

import numpy as np
import pandas as pd

from capmap.config.dualarm import DualArmConfig, Horizon
from capmap.dualarm.build import al_settings, scan_settings, unknown_settings, weights
from capmap.dualarm.ocp.assembly import assemble, warm_start
from capmap.dualarm.ocp.evaluate import fine_grid, node_errors
from capmap.dualarm.ocp.motion import motion_lines, motion_quantities, motion_tables, plan_assembly, torque_table
from capmap.dualarm.ocp.settings import Weights
from capmap.dualarm.ocp.solver import equality_cost, initial_guess, solve, solve_csqp
from capmap.dualarm.scene.cloud import depth
from capmap.dualarm.scene.unknown import Grid, near_boxes, with_boxes
from capmap.dualarm.scene.unobserved import swept_balls, unknown_mask, unobserved_check, viewpoints_that_see
from capmap.dualarm.scene_file import load_scene
from capmap.dualarm.tables import envelope_from, unknown_boxes
from capmap.errors import CapmapError, ConfigError, DataError
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_quantities, write_table
from capmap.stages.common import Outputs, stage_config
from capmap.stages.dualarm import robot_from

__all__ = ["setup", "stage_dualarm_optimise", "stage_dualarm_check"]


def _inputs(da: DualArmConfig, environment: str, capsules: str) -> tuple:
    """(robot, envelope, its labels, scene) of a dual-arm job: ``da`` names the robot and scene files."""
    robot = robot_from(da.robot, datasets.read(capsules))
    env, labels = envelope_from(datasets.read(environment))
    return robot, env, labels, load_scene(da.scene)


def _assembly(da: DualArmConfig, inputs: tuple, h: Horizon, boxes: np.ndarray | None = None):
    """The assembly of :func:`_inputs` on horizon ``h``; ``boxes`` (B, 2, 3) m of unknown space join the
    environment."""
    robot, env, labels, scene = inputs
    if boxes is not None and len(boxes):
        env, labels = with_boxes(env, labels, boxes, unknown_settings(da.unknown).voxel_m)
    return assemble(robot, scene, env, labels, h.nodes, h.dt_s, h.pre_insertion_node)


def setup(da: DualArmConfig, environment: str, capsules: str, h: Horizon, boxes: np.ndarray | None = None):
    """(robot, assembly) of a dual-arm job on horizon ``h``: ``da`` names the robot and scene files;
    ``boxes`` (B, 2, 3) m of unknown space join the environment."""
    inputs = _inputs(da, environment, capsules)
    return inputs[0], _assembly(da, inputs, h, boxes)


def _plan_outside_unknown(da: DualArmConfig, environment: str, capsules: str, unknown: str, log):
    """Plan with the unknown boxes near the motion in the environment: first those within ``near_m``
    of the warm start; after each solve the motion (finer grid) is checked against every unknown voxel
    and the boxes near it are added, up to three solves. Returns (robot, scene, assembly, motion, the
    check, boxes used, boxes in all)."""
    u = unknown_settings(da.unknown)
    boxes = unknown_boxes(datasets.read(unknown))
    grid = Grid.over(u.work_lower, u.work_upper, u.voxel_m)
    mask = unknown_mask(grid, boxes)
    inputs = _inputs(da, environment, capsules)
    robot, corners = inputs[0], inputs[3].panel.corners()
    asm = _assembly(da, inputs, da.horizon)
    warm = warm_start(asm)  # the boxes do not change it
    balls, radii, _, slack = swept_balls(asm, robot, corners, warm[::5])
    use = near_boxes(boxes, balls.reshape(-1, 3), np.tile(radii + slack, len(balls)), u.near_m)
    for attempt in range(3):
        log.info(f"unknown space: {int(use.sum())} of {len(boxes)} boxes near the motion go to the optimiser")
        asm = _assembly(da, inputs, da.horizon, boxes[use])
        m = plan_assembly(asm, robot, weights(da.weights), al_settings(da.solver), da.fine_factor, log.info, warm=warm)
        balls, radii, names, slack = swept_balls(asm, robot, corners, fine_grid(m.sol.xs, m.sol.us, asm.task.dt,
                                                                                 da.fine_factor)[1])
        check = unobserved_check(balls, radii, names, grid, mask, slack=slack)
        if check.distance >= 0:
            break
        every = balls[::da.fine_factor]
        more = near_boxes(boxes, every.reshape(-1, 3), np.tile(radii + slack, len(every)), u.near_m) & ~use
        if not more.any():
            break
        use |= more
    return robot, inputs[3], asm, m, check, int(use.sum()), len(boxes)


def _suggest(da: DualArmConfig, environment: str, unknown: str, msg: str) -> str:
    """Where a camera would see the unknown region named in ``msg`` ('unknown [x0 x1, y0 y1, z0 z1]'):
    the candidates nearest the configured viewpoints (:func:`capmap.dualarm.scene.unobserved.viewpoints_that_see`)."""
    x = [float(v) for v in re.search(r"unknown \[([-\d.]+) ([-\d.]+), ([-\d.]+) ([-\d.]+), ([-\d.]+) ([-\d.]+)\]",
                                     msg).groups()]
    region = np.array([[x[0], x[2], x[4]], [x[1], x[3], x[5]]])
    u = unknown_settings(da.unknown)
    grid = Grid.over(u.work_lower, u.work_upper, u.voxel_m)
    env, _ = envelope_from(datasets.read(environment))
    seen = viewpoints_that_see(region, grid, unknown_mask(grid, unknown_boxes(datasets.read(unknown))),
                               lambda p: depth(p, env), scan_settings(da.scan).viewpoints.mean(axis=0))
    if not len(seen):
        return "no point of the work volume in the open has a line of sight to it"
    return "a camera at " + " or ".join(str(np.round(v, 2).tolist()) for v in seen[:2]) + " m would see it"


def stage_dualarm_optimise(environment: str, unknown: str, capsules: str, out: Outputs, slice_json: str) -> None:
    """The satellite-panel assembly by augmented-Lagrangian DDP, then checked on a finer grid
    (:func:`capmap.dualarm.ocp.motion.plan_assembly`) and by inverse dynamics with the held panel against
    the effort limits (:func:`capmap.dualarm.ocp.motion.torque_table`); the start within the joint limits
    is checked before any job. ``out``: trajectory, fine, outer, torques, csv, md."""
    sc = stage_config(slice_json)
    da = sc.run.dualarm
    log = stage_logger(__name__, "dualarm optimise")
    try:
        robot, scene, asm, m, check, used, n_boxes = _plan_outside_unknown(da, environment, capsules, unknown, log)
    except CapmapError as exc:  # a key pose in collision: the scene's, or the cameras' (unknown space)
        msg = exc.in_terms(scene=f"dualarm.scene = {da.scene!r}")
        if "unknown [" in msg:
            msg += ("; that region (x, y, z ranges in m) was observed by no viewpoint of dualarm.cloud.viewpoints_m: "
                    f"{_suggest(da, environment, unknown, msg)}, or move the task away from it")
        raise ConfigError(msg) from None
    if check.distance < 0:
        raise DataError(f"the optimised motion reaches {1e3 * -check.distance:.1f} mm into space no camera observed "
                        f"({check.body} near {np.round(check.voxel_centre, 2).tolist()} m) after three solves with the "
                        f"unknown boxes near it; add a viewpoint of dualarm.cloud.viewpoints_m that sees that region")
    traj, fine_df, outer = motion_tables(asm, robot, m)
    torques, torque_rows = torque_table(asm, robot, scene, m)
    prov = datasets.provenance("dualarm_optimise", sc.doc, converged=m.sol.converged, message=m.sol.message,
                               joints=list(robot.joint_names), q_lower=robot.q_lower.tolist(),
                               q_upper=robot.q_upper.tolist(), v_max=robot.v_max.tolist(), margin_m=da.weights.margin_m,
                               active=[list(a) for a in m.active])
    datasets.write(traj, out["trajectory"], prov)
    datasets.write(fine_df, out["fine"], prov)
    datasets.write(outer, out["outer"], prov)
    datasets.write(torques, out["torques"], datasets.provenance(
        "dualarm_optimise", sc.doc, joints=list(robot.joint_names), effort_nm=asm.model.effortLimit.tolist(),
        panel_kg=scene.panel.mass))
    unknown_rows = [("unknown-space boxes given to the optimiser", f"{used} of {n_boxes}"),
                    ("min distance to unknown space, finer grid [m]", check.distance),
                    ("body nearest unknown space", check.body)]
    write_quantities(motion_quantities(asm, robot, m, weights(da.weights)) + unknown_rows + torque_rows, out["csv"],
                     out["md"])
    solved, held, within = motion_lines(m, outer, scene.panel.mass, torque_rows)
    log.info(solved)
    (log.info if within else log.warning)(held)


def stage_dualarm_check(environment: str, capsules: str, out_csv: str, out_md: str, slice_json: str) -> None:
    """The equality-only problem (closed chain and path, no collisions or limits) on the check's
    horizon, solved by AL-FDDP and by mim-solvers CSQP from the same warm start."""
    da = stage_config(slice_json).run.dualarm
    log = stage_logger(__name__, "dualarm check")
    check = da.check
    robot, asm = setup(da, environment, capsules, check.horizon)
    dw = da.weights  # the equality-only problem has no safety constraints: no margin
    w = Weights(dw.control, dw.velocity, dw.panel, 0.0)
    settings = replace(al_settings(da.solver), tolerance=check.al_tolerance)
    xs0, us0 = initial_guess(warm_start(asm), asm.task.dt)
    limits = (robot.q_lower, robot.q_upper, robot.v_max)
    t0 = time.perf_counter()
    al = solve(asm, w, limits, settings, xs0, us0, inequalities=False)
    t_al = time.perf_counter() - t0
    t0 = time.perf_counter()
    csqp = solve_csqp(asm, w, limits, xs0, us0, check.max_iterations, check.tolerance)
    t_csqp = time.perf_counter() - t0
    nq, xc, uc = asm.model.nq, csqp.xs, csqp.us
    cost_csqp = equality_cost(asm, w, xc, uc)
    rows = []
    for name, xs, us, iters, ok, secs in (
            ("AL-FDDP", al.xs, al.us, sum(s.inner_iterations for s in al.stats), al.converged, t_al),
            ("CSQP", xc, uc, csqp.iterations, csqp.converged, t_csqp)):
        e = node_errors(asm, xs)
        cost = equality_cost(asm, w, xs, us)
        rows.append({"solver": name, "horizon": f"N = {asm.task.N}, dt = {asm.task.dt:g} s", "converged": ok,
                     "iterations": int(iters), "time_s": secs, "cost": cost,
                     "cost_rel_diff_to_csqp": (cost - cost_csqp) / abs(cost_csqp),
                     "max_closed_chain_err_m": e.closed_chain_pos.max(),
                     "max_path_err_m": e.path_pos.max(), "max_path_err_rad": e.path_rot.max(),
                     "max_q_diff_rad": float(np.abs(xs[:, :nq] - xc[:, :nq]).max()),
                     "max_qd_diff_rad_s": float(np.abs(xs[:, nq:] - xc[:, nq:]).max()),
                     "max_u_diff_rad_s2": float(np.abs(us - uc).max())})
    df = pd.DataFrame(rows)
    write_table(df, out_csv, out_md)
    log.info(f"equality-only optimum: AL-FDDP cost {rows[0]['cost']:.8g} ({t_al:.1f} s), CSQP {rows[1]['cost']:.8g} "
             f"({t_csqp:.1f} s); max |q difference| {rows[0]['max_q_diff_rad']:.2e} rad")
