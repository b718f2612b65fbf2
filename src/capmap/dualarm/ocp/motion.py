"""The assembly motion: key poses checked, warm start, the augmented-Lagrangian DDP solve and its
independent evaluation (errors at the nodes, safety on the nodes and on a finer grid, the active
pairs); and the family's tables of it (column schemas, units in the names)."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from typing import Callable

import numpy as np
import pandas as pd

from capmap.dualarm.ocp.assembly import Assembly, clearance_at, warm_start
from capmap.dualarm.ocp.evaluate import active_pairs, fine_grid, node_errors, safety
from capmap.dualarm.ocp.settings import ALSettings, SolveOptions, Weights
from capmap.dualarm.ocp.solver import OuterStats, initial_guess, solve
from capmap.dualarm.ocp.torques import HeldPart, held_torques
from capmap.dualarm.scene.robot import DualArm
from capmap.dualarm.scene.solids import Scene
from capmap.errors import CapmapError

__all__ = ["ACTIVE_WITHIN_M", "AssemblyMotion", "key_poses", "plan_assembly", "motion_tables", "motion_quantities",
           "torque_table", "motion_lines", "no_motion_tables"]

ACTIVE_WITHIN_M = 0.01  # a collision constraint is reported active within 1 cm


def _quiet(_: str) -> None:
    """No progress lines."""


def key_poses(asm: Assembly, qs: np.ndarray, progress: Callable[[str], None] = lambda _: None
              ) -> dict[str, tuple[float, str]]:
    """Clearance [m] and nearest pair of the start, pre-insertion and final poses, each for the best
    self-motion of the arms tried (the start as given); a :class:`CapmapError` with the role
    ``scene`` when one is in collision (the optimiser would stall)."""
    out = {}
    for name, node in (("start", 0), ("pre-insertion", asm.task.n_transfer), ("final", asm.task.N)):
        _, d, pair = clearance_at(asm, qs[node], node, iters=1 if node == 0 else 40)
        out[name] = (d, pair)
        progress(f"{name} pose: clearance {1e3 * d:.1f} mm ({pair})")
        if d < 0:
            raise CapmapError(f"{{scene}}: the {name} pose is not collision-free for any self-motion of the arms tried "
                              f"({pair} at {1e3 * d:.1f} mm); the optimiser would stall", scene="the scene")
    return out


@dataclass(frozen=True)
class AssemblyMotion:
    """The solve (``sol``: states, controls, outer-loop stats), its times [s], the key poses'
    clearances, and the evaluation: node errors, safety at the nodes and on the finer grid
    (``t_fine``, ``node_fine``), the pairs active within ACTIVE_WITHIN_M."""

    sol: object
    solve_s: float
    prepare_s: float
    clearances: dict
    errors: object
    at_nodes: object
    t_fine: np.ndarray
    node_fine: np.ndarray
    fine: object
    active: list
    fine_factor: int


def plan_assembly(asm: Assembly, robot: DualArm, weights: Weights, solver: ALSettings, fine_factor: int,
                  options: SolveOptions = SolveOptions(), warm: np.ndarray | None = None) -> AssemblyMotion:
    """Key poses, warm start (``warm`` (N + 1, nq) rad: :func:`capmap.dualarm.ocp.assembly.warm_start`'s, when
    already computed), solve within the joint limits, evaluation on the nodes and on a grid ``fine_factor``
    times finer; ``options`` (:func:`capmap.dualarm.ocp.solver.solve`'s): ``log`` the progress lines,
    ``compiled=False``: Pinocchio's node models (the reference)."""
    progress = options.log or _quiet
    t0 = time.perf_counter()
    qs = warm_start(asm) if warm is None else warm
    clear = key_poses(asm, qs, progress)
    xs0, us0 = initial_guess(qs, asm.task.dt)
    t1 = time.perf_counter()
    sol = solve(asm, weights, (robot.q_lower, robot.q_upper, robot.v_max), solver, xs0, us0, options)
    solve_s = time.perf_counter() - t1
    nq = asm.model.nq
    err = node_errors(asm, sol.xs)
    at_nodes = safety(asm, sol.xs[:, :nq], within_m=ACTIVE_WITHIN_M)  # what is used: minima and the active pairs
    t_fine, q_fine, node_fine = fine_grid(sol.xs, sol.us, asm.task.dt, fine_factor)
    fine = safety(asm, q_fine, within_m=ACTIVE_WITHIN_M)
    return AssemblyMotion(sol, solve_s, t1 - t0, clear, err, at_nodes, t_fine, node_fine, fine,
                          active_pairs(fine, t_fine, ACTIVE_WITHIN_M), fine_factor)


def motion_tables(asm: Assembly, robot: DualArm, m: AssemblyMotion) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """(trajectory: one row per node with phase, joints, velocities, controls, errors, the nearest
    pair; the finer grid's safety; the outer iterations)."""
    xs, us, nq, N, dt = m.sol.xs, m.sol.us, asm.model.nq, asm.task.N, asm.task.dt
    k = np.arange(N + 1)
    phase = np.where(k < asm.task.n_transfer, "transfer", np.where(k == asm.task.n_transfer, "pre_insertion",
                                                                   np.where(k < N, "insertion", "final")))
    traj = pd.DataFrame({"t_s": k * dt, "node": k, "phase": pd.Categorical(phase)})
    u = np.vstack([us, np.full((1, nq), np.nan)])
    for prefix, values, unit in (("q", xs[:, :nq], "rad"), ("qd", xs[:, nq:], "rad_s"), ("u", u, "rad_s2")):
        for c, j in enumerate(robot.joint_names):
            traj[f"{prefix}_{j}_{unit}"] = values[:, c]
    err = m.errors
    traj["closed_chain_pos_err_m"], traj["closed_chain_rot_err_rad"] = err.closed_chain_pos, err.closed_chain_rot
    traj["path_err_m"], traj["path_err_rad"] = err.path_pos, err.path_rot
    traj["min_distance_m"], traj["min_distance_pair"] = m.at_nodes.min_distance, m.at_nodes.min_pair
    fine_df = pd.DataFrame({"t_s": m.t_fine, "node": m.node_fine, "min_distance_m": m.fine.min_distance,
                            "min_distance_pair": m.fine.min_pair})
    return traj, fine_df, pd.DataFrame([asdict(s) for s in m.sol.stats])


def motion_quantities(asm: Assembly, robot: DualArm, m: AssemblyMotion, weights: Weights) -> list[tuple[str, object]]:
    """The summary's (quantity, value) rows."""
    sol, err, xs, nq, N = m.sol, m.errors, m.sol.xs, asm.model.nq, asm.task.N
    margins = np.minimum(xs[:, :nq] - robot.q_lower, robot.q_upper - xs[:, :nq]).min()
    vmargin = (robot.v_max - np.abs(xs[:, nq:])).min()
    return [
        ("converged", sol.converged), ("message", sol.message or "-"),
        ("solve time [s]", round(m.solve_s, 2)), ("warm start and key-pose checks [s]", round(m.prepare_s, 2)),
        ("outer iterations", len(sol.stats)), ("FDDP iterations", int(sum(s.inner_iterations for s in sol.stats))),
        ("final penalty mu", float(sol.stats[-1].mu)), ("final equality violation", sol.stats[-1].eq_violation),
        ("max closed-chain error at nodes [m]", err.closed_chain_pos.max()),
        ("max closed-chain error at nodes [rad]", err.closed_chain_rot.max()),
        ("max path error at nodes [m]", err.path_pos.max()), ("max path error at nodes [rad]", err.path_rot.max()),
        ("min safety distance at nodes [m]", m.at_nodes.min_distance.min()),
        (f"min safety distance, {m.fine_factor}x finer grid [m]", m.fine.min_distance.min()),
        ("pair at the min (finer grid)", m.fine.min_pair[int(m.fine.min_distance.argmin())]),
        ("collision margin at nodes [m]", weights.margin_m),
        ("min joint position margin [rad]", margins), ("min joint velocity margin [rad/s]", vmargin),
        ("candidate collision pairs", len(asm.pairs)),
        ("pairs checked per node (mean)", round(sol.stats[-1].pairs / (N + 1), 1)),
        *((f"clearance at the {name} pose [m]", d) for name, (d, _) in m.clearances.items()),
        *((f"active within 1 cm: {name}", f"{1e3 * d:.1f} mm at {tm:.2f} s (within 1 cm {t0_:.2f}-{t1_:.2f} s)")
          for name, d, tm, t0_, t1_ in m.active),
    ]


def torque_table(asm: Assembly, robot: DualArm, scene: Scene, m: AssemblyMotion) -> tuple[pd.DataFrame, list]:
    """Joint torques by inverse dynamics with the panel held by both grippers (its mass and inertia from
    the scene; :func:`capmap.dualarm.ocp.torques.held_torques`) at every node (the last at rest): one row per
    node with ``tau_<joint>_nm`` (least-norm internal force), ``tau_best_<joint>_nm`` (the internal force
    that minimises the peak |torque| / effort limit) and the panel's required force ``panel_force_n``;
    and the summary's rows."""
    xs, us, nq = m.sol.xs, m.sol.us, asm.model.nq
    a = np.vstack([us, np.zeros((1, nq))])  # the final node: at rest, holding the panel
    part = HeldPart(asm.task.panel, scene.panel.mass, np.zeros(3), np.diag(scene.panel.inertia))
    effort = asm.model.effortLimit.copy()
    ht = held_torques(asm.model, (asm.task.left, asm.task.right), part, xs[:, :nq], xs[:, nq:], a, effort)
    k = np.arange(len(xs))
    df = pd.DataFrame({"t_s": k * asm.task.dt, "node": k})
    for c, j in enumerate(robot.joint_names):
        df[f"tau_{j}_nm"] = ht.tau_least_norm_nm[:, c]
    for c, j in enumerate(robot.joint_names):
        df[f"tau_best_{j}_nm"] = ht.tau_nm[:, c]
    df["panel_force_n"] = np.linalg.norm(ht.f_part[:, :3], axis=1)
    ratio, best = np.abs(ht.tau_least_norm_nm) / effort, np.abs(ht.tau_nm) / effort
    node, joint = np.unravel_index(int(ratio.argmax()), ratio.shape)
    rows = [
        ("panel mass [kg]", scene.panel.mass),
        ("peak torque / effort limit, least-norm internal force [%]", 100 * float(ratio.max())),
        ("joint at the peak (least-norm)", f"{robot.joint_names[joint]} at {node * asm.task.dt:.2f} s"),
        ("peak torque / effort limit, best internal force [%]", 100 * float(best.max())),
        ("within the effort limits (least-norm internal force)", bool(ratio.max() <= 1.0)),
        ("max grasp-map residual [N, N m]", float(ht.residual.max())),
    ]
    return df, rows


def motion_lines(m, outer, panel_kg: float, torque_rows: list[tuple[str, object]]) -> tuple[str, str, bool]:
    """The log lines of a planned assembly ``m`` (:func:`plan_assembly`; ``outer``: its outer iterations'
    table): how the solve went, the held panel's peak torques (``torque_rows``: :func:`torque_table`'s),
    and whether they are within the effort limits."""
    sol, err = m.sol, m.errors
    solved = (f"{'converged' if sol.converged else 'NOT converged: ' + sol.message}; {len(sol.stats)} outer / "
              f"{int(outer.inner_iterations.sum())} FDDP iterations in {m.solve_s:.1f} s; closed chain "
              f"{err.closed_chain_pos.max():.1e} m; path {err.path_pos.max():.1e} m; min distance "
              f"{1e3 * m.fine.min_distance.min():.2f} mm on the finer grid; active: "
              f"{', '.join(a[0] for a in m.active) or 'none'}")
    peak = dict(torque_rows)
    held = (f"joint torques with the {panel_kg:g} kg panel: peak "
            f"{peak['peak torque / effort limit, least-norm internal force [%]']:.0f} % of the effort limit "
            f"({peak['joint at the peak (least-norm)']}), {peak['peak torque / effort limit, best internal force [%]']:.0f} % "
            "with the best internal force")
    within = bool(peak["within the effort limits (least-norm internal force)"])
    return solved, held if within else held + ": the motion EXCEEDS the effort limits (torque limits are not in the " \
        "optimisation)", within


def no_motion_tables(joints) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """The tables of :func:`motion_tables` and :func:`torque_table` with their columns and no rows, for a
    job whose motion cannot be planned (a key pose with no collision-free self-motion): the result says so."""
    traj = pd.DataFrame({"t_s": [], "node": [], "phase": pd.Categorical([])})
    for prefix, unit in (("q", "rad"), ("qd", "rad_s"), ("u", "rad_s2")):
        for j in joints:
            traj[f"{prefix}_{j}_{unit}"] = np.zeros(0)
    for c in ("closed_chain_pos_err_m", "closed_chain_rot_err_rad", "path_err_m", "path_err_rad", "min_distance_m"):
        traj[c] = np.zeros(0)
    traj["min_distance_pair"] = pd.Series(dtype=str)
    fine = pd.DataFrame({"t_s": np.zeros(0), "node": np.zeros(0, dtype=int), "min_distance_m": np.zeros(0),
                         "min_distance_pair": pd.Series(dtype=str)})
    outer = pd.DataFrame({f: pd.Series(dtype=float) for f in OuterStats.__dataclass_fields__})
    torques = pd.DataFrame({"t_s": np.zeros(0), "node": np.zeros(0, dtype=int),
                            **{f"tau_{j}_nm": np.zeros(0) for j in joints},
                            **{f"tau_best_{j}_nm": np.zeros(0) for j in joints}, "panel_force_n": np.zeros(0)})
    return traj, fine, outer, torques

