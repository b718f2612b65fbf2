"""Stages of the dual-arm family, the motion: dualarm_optimise (feasibility of the key poses, warm
start, augmented-Lagrangian DDP, independent evaluation) and dualarm_check (the equality-only
problem by AL-FDDP and by mim-solvers CSQP)."""

from __future__ import annotations

import time
from dataclasses import asdict, replace

import numpy as np
import pandas as pd

from capmap.config.dualarm import DualArmConfig, Horizon
from capmap.config.scene_file import load_scene
from capmap.dualarm.assembly import Assembly, assemble, clearance_at, warm_start
from capmap.dualarm.evaluate import active_pairs, fine_grid, node_errors, safety
from capmap.dualarm.settings import Weights
from capmap.dualarm.solver import equality_cost, initial_guess, solve, solve_csqp
from capmap.errors import ConfigError
from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_quantities, write_table
from capmap.stages.common import stage_config
from capmap.stages.dualarm import envelope_from, robot_from

__all__ = ["setup", "stage_dualarm_optimise", "stage_dualarm_check", "ACTIVE_WITHIN_M"]

ACTIVE_WITHIN_M = 0.01  # a collision constraint is reported active within 1 cm


def setup(da: DualArmConfig, environment: str, capsules: str, h: Horizon):
    """(robot, assembly) of a dual-arm job on horizon ``h``: ``da`` names the robot and scene files."""
    robot = robot_from(da.robot, datasets.read(capsules))
    env, labels = envelope_from(datasets.read(environment))
    return robot, assemble(robot, load_scene(da.scene), env, labels, h.nodes, h.dt_s, h.pre_insertion_node)


def _key_poses(asm: Assembly, qs: np.ndarray, scene_file: str, log) -> dict[str, tuple[float, str]]:
    """The start, pre-insertion and final poses must each be collision-free for some self-motion of
    the arms (the start as given); a one-line error otherwise."""
    out = {}
    for name, node in (("start", 0), ("pre-insertion", asm.task.n_transfer), ("final", asm.task.N)):
        _, d, pair = clearance_at(asm, qs[node], node, iters=1 if node == 0 else 40)
        out[name] = (d, pair)
        log.info(f"{name} pose: clearance {1e3 * d:.1f} mm ({pair})")
        if d < 0:
            raise ConfigError(f"dualarm.scene = {scene_file!r}: the {name} pose is not collision-free for any "
                              f"self-motion of the arms tried ({pair} at {1e3 * d:.1f} mm); the optimiser would stall")
    return out


def stage_dualarm_optimise(environment: str, capsules: str, out_trajectory: str, out_fine: str, out_outer: str,
                           out_csv: str, out_md: str, slice_json: str) -> None:
    """The satellite-panel assembly by augmented-Lagrangian DDP, then checked on a finer grid."""
    sc = stage_config(slice_json)
    da = sc.run.dualarm
    log = stage_logger(__name__, "dualarm optimise")
    robot, asm = setup(da, environment, capsules, da.horizon)
    w, fine_factor = da.weights, da.fine_factor  # the start within the joint limits: checked before any job
    t0 = time.perf_counter()
    qs = warm_start(asm)
    clear = _key_poses(asm, qs, da.scene, log)
    xs0, us0 = initial_guess(qs, asm.task.dt)
    t1 = time.perf_counter()
    sol = solve(asm, w, (robot.q_lower, robot.q_upper, robot.v_max), da.solver, xs0, us0, log=log.info)
    solve_s = time.perf_counter() - t1
    xs, us = sol.xs, sol.us
    nq = asm.model.nq
    N, dt = asm.task.N, asm.task.dt
    err = node_errors(asm, xs)
    at_nodes = safety(asm, xs[:, :nq])
    t_fine, q_fine, node_fine = fine_grid(xs, us, dt, fine_factor)
    fine = safety(asm, q_fine)
    active = active_pairs(fine, t_fine, ACTIVE_WITHIN_M)
    # -- tables
    joints = robot.joint_names
    t = np.arange(N + 1) * dt
    k = np.arange(N + 1)
    phase = np.where(k < asm.task.n_transfer, "transfer", np.where(k == asm.task.n_transfer, "pre_insertion",
                                                                   np.where(k < N, "insertion", "final")))
    traj = pd.DataFrame({"t_s": t, "node": k, "phase": pd.Categorical(phase)})
    u = np.vstack([us, np.full((1, nq), np.nan)])
    for prefix, values, unit in (("q", xs[:, :nq], "rad"), ("qd", xs[:, nq:], "rad_s"), ("u", u, "rad_s2")):
        for c, j in enumerate(joints):
            traj[f"{prefix}_{j}_{unit}"] = values[:, c]
    traj["closed_chain_pos_err_m"], traj["closed_chain_rot_err_rad"] = err.closed_chain_pos, err.closed_chain_rot
    traj["path_err_m"], traj["path_err_rad"] = err.path_pos, err.path_rot
    traj["min_distance_m"], traj["min_distance_pair"] = at_nodes.min_distance, at_nodes.min_pair
    fine_df = pd.DataFrame({"t_s": t_fine, "node": node_fine, "min_distance_m": fine.min_distance,
                            "min_distance_pair": fine.min_pair})
    outer = pd.DataFrame([asdict(s) for s in sol.stats])
    margins = np.minimum(xs[:, :nq] - robot.q_lower, robot.q_upper - xs[:, :nq]).min()
    vmargin = (robot.v_max - np.abs(xs[:, nq:])).min()
    rows = [
        ("converged", sol.converged), ("message", sol.message or "-"),
        ("solve time [s]", round(solve_s, 2)), ("warm start and key-pose checks [s]", round(t1 - t0, 2)),
        ("outer iterations", len(sol.stats)), ("FDDP iterations", int(outer.inner_iterations.sum())),
        ("final penalty mu", float(sol.stats[-1].mu)), ("final equality violation", sol.stats[-1].eq_violation),
        ("max closed-chain error at nodes [m]", err.closed_chain_pos.max()),
        ("max closed-chain error at nodes [rad]", err.closed_chain_rot.max()),
        ("max path error at nodes [m]", err.path_pos.max()), ("max path error at nodes [rad]", err.path_rot.max()),
        ("min safety distance at nodes [m]", at_nodes.min_distance.min()),
        (f"min safety distance, {fine_factor}x finer grid [m]", fine.min_distance.min()),
        ("pair at the min (finer grid)", fine.min_pair[int(fine.min_distance.argmin())]),
        ("collision margin at nodes [m]", w.margin_m),
        ("min joint position margin [rad]", margins), ("min joint velocity margin [rad/s]", vmargin),
        ("candidate collision pairs", len(asm.pairs)),
        ("pairs checked per node (mean)", round(sol.stats[-1].pairs / (N + 1), 1)),
        *((f"clearance at the {name} pose [m]", d) for name, (d, _) in clear.items()),
        *((f"active within 1 cm: {name}", f"{1e3 * d:.1f} mm at {tm:.2f} s (within 1 cm {t0_:.2f}-{t1_:.2f} s)")
          for name, d, tm, t0_, t1_ in active),
    ]
    prov = datasets.provenance("dualarm_optimise", sc.doc, converged=sol.converged, message=sol.message,
                               joints=list(joints), q_lower=robot.q_lower.tolist(), q_upper=robot.q_upper.tolist(),
                               v_max=robot.v_max.tolist(), margin_m=w.margin_m,
                               active=[list(a) for a in active])
    datasets.write(traj, out_trajectory, prov)
    datasets.write(fine_df, out_fine, prov)
    datasets.write(outer, out_outer, prov)
    write_quantities(rows, out_csv, out_md)
    log.info(f"{'converged' if sol.converged else 'NOT converged: ' + sol.message}; {len(sol.stats)} outer / "
             f"{int(outer.inner_iterations.sum())} FDDP iterations in {solve_s:.1f} s; closed chain "
             f"{err.closed_chain_pos.max():.1e} m; path {err.path_pos.max():.1e} m; min distance "
             f"{1e3 * fine.min_distance.min():.2f} mm on the finer grid; active: "
             f"{', '.join(a[0] for a in active) or 'none'}")


def stage_dualarm_check(environment: str, capsules: str, out_csv: str, out_md: str, slice_json: str) -> None:
    """The equality-only problem (closed chain and path, no collisions or limits) on the check's
    horizon, solved by AL-FDDP and by mim-solvers CSQP from the same warm start."""
    da = stage_config(slice_json).run.dualarm
    log = stage_logger(__name__, "dualarm check")
    check = da.check
    robot, asm = setup(da, environment, capsules, check.horizon)
    dw = da.weights  # the equality-only problem has no safety constraints: no margin
    w = Weights(dw.control, dw.velocity, dw.panel, 0.0)
    settings = replace(da.solver, tolerance=check.al_tolerance)
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
