"""Stages of the dual-arm family, the motion: dualarm_optimise (feasibility of the key poses, warm
start, augmented-Lagrangian DDP, independent evaluation) and dualarm_check (the equality-only
problem by AL-FDDP and by mim-solvers CSQP)."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pandas as pd

from capmap.dualarm.build import al_settings, job_inputs, job_setup, plan_settings, planning_error
from capmap.dualarm.ocp.assembly import warm_start
from capmap.dualarm.ocp.evaluate import node_errors
from capmap.dualarm.ocp.motion import motion_lines, motion_quantities, motion_tables, no_motion_tables, torque_table
from capmap.dualarm.ocp.settings import SolveOptions, StopRule, Weights
from capmap.dualarm.ocp.solver import equality_cost, initial_guess, solve, solve_csqp
from capmap.dualarm.plan import plan_outside_unknown, unobserved_reason
from capmap.dualarm.tables import unknown_boxes
from capmap.errors import CapmapError
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_quantities, write_table
from capmap.stages.common import Outputs, stage_config

__all__ = ["stage_dualarm_optimise", "stage_dualarm_check"]


def _no_motion(reason: str, joints, doc: dict, out: Outputs, log) -> None:
    """A motion that cannot be planned, written as such: the tables' columns, no rows; the summary says why."""
    log.warning(f"infeasible: {reason}")
    prov = datasets.provenance("dualarm_optimise", doc, feasible=False, reason=reason)
    for name, table in zip(("trajectory", "fine", "outer", "torques"), no_motion_tables(joints)):
        datasets.write(table, out[name], prov)
    write_quantities([("feasible", False), ("reason", reason)], out["csv"], out["md"])


def stage_dualarm_optimise(environment: str, unknown: str, capsules: str, out: Outputs, slice_json: str) -> None:
    """The satellite-panel assembly by augmented-Lagrangian DDP, then checked on a finer grid
    (:func:`capmap.dualarm.ocp.motion.plan_assembly`) and by inverse dynamics with the held panel against
    the effort limits (:func:`capmap.dualarm.ocp.motion.torque_table`). A motion that cannot be planned (a
    key pose with no collision-free self-motion) or that stays in unobserved space is a result: the summary's
    ``feasible`` and ``reason`` say so (the job succeeds). ``out``: trajectory, fine, outer, torques, csv, md."""
    sc = stage_config(slice_json)
    da = sc.run.dualarm
    log = stage_logger(__name__, "dualarm optimise")
    boxes, caps = unknown_boxes(datasets.read(unknown)), datasets.read(capsules)
    inputs, ps = job_inputs(da, datasets.read(environment), caps), plan_settings(da)
    try:
        robot, scene, asm, m, check, used, n_boxes = plan_outside_unknown(inputs, boxes, ps, log.info)
    except CapmapError as exc:  # a key pose in collision: the scene's, or the cameras' (unknown space)
        return _no_motion(str(planning_error(da, exc, inputs, boxes)), inputs.robot.joint_names, sc.doc, out, log)
    reason = unobserved_reason(check)
    traj, fine_df, outer = motion_tables(asm, robot, m)
    torques, torque_rows = torque_table(asm, robot, scene, m)
    prov = datasets.provenance("dualarm_optimise", sc.doc, converged=m.sol.converged, message=m.sol.message,
                               joints=list(robot.joint_names), q_lower=robot.q_lower.tolist(),
                               q_upper=robot.q_upper.tolist(), v_max=robot.v_max.tolist(), margin_m=da.weights.margin_m,
                               active=[list(a) for a in m.active], feasible=not reason, reason=reason)
    for name, table in (("trajectory", traj), ("fine", fine_df), ("outer", outer)):
        datasets.write(table, out[name], prov)
    datasets.write(torques, out["torques"], datasets.provenance(
        "dualarm_optimise", sc.doc, joints=list(robot.joint_names), effort_nm=asm.model.effortLimit.tolist(),
        panel_kg=scene.panel.mass))
    unknown_rows = [("unknown-space boxes given to the optimiser", f"{used} of {n_boxes}"),
                    ("min distance to unknown space, finer grid [m]", check.distance),
                    ("body nearest unknown space", check.body)]
    write_quantities([("feasible", not reason), ("reason", reason or "-")] + motion_quantities(asm, robot, m, ps.weights)
                     + unknown_rows + torque_rows, out["csv"], out["md"])
    solved, held, within = motion_lines(m, outer, scene.panel.mass, torque_rows)
    log.info(solved)
    (log.info if within else log.warning)(held)
    if reason:
        log.warning(f"infeasible: {reason}")


def stage_dualarm_check(environment: str, capsules: str, out_csv: str, out_md: str, slice_json: str) -> None:
    """The equality-only problem (closed chain and path, no collisions or limits) on the check's
    horizon, solved by AL-FDDP and by mim-solvers CSQP from the same warm start."""
    da = stage_config(slice_json).run.dualarm
    log = stage_logger(__name__, "dualarm check")
    check = da.check
    caps = datasets.read(capsules)
    robot, asm = job_setup(da, datasets.read(environment), caps, check.horizon)
    dw = da.weights  # the equality-only problem has no safety constraints: no margin
    w = Weights(dw.control, dw.velocity, dw.panel, 0.0)
    settings = replace(al_settings(da.solver), tolerance=check.al_tolerance)
    xs0, us0 = initial_guess(warm_start(asm), asm.task.dt)
    limits = (robot.q_lower, robot.q_upper, robot.v_max)
    t0 = time.perf_counter()
    al = solve(asm, w, limits, settings, xs0, us0, SolveOptions(inequalities=False))
    t_al = time.perf_counter() - t0
    t0 = time.perf_counter()
    csqp = solve_csqp(asm, w, limits, xs0, us0, StopRule(check.max_iterations, check.tolerance))
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
