"""The capacity family's one meeting of configuration and numerics: config sections (frozen data of
:mod:`capmap.config`) in, the family's numerics objects out.

- the task: :func:`task_rotation` (3, 3), :func:`task_motion`;
- the sets and limits: :func:`directions_of`, :func:`load_limits`, :func:`refine_settings`;
- the failure: :func:`resolve_failure` (the lock angle, the start and the start configuration: the IK
  branch at the start nearest q_ini; the lock itself: :func:`capmap.robots.locked_arm`);
- the problem: :func:`capacity_problem` (the run's locked arm and task as a
  :class:`CapacityProblem`), :func:`configuration_name`; the healthy arm's problem in
  :mod:`capmap.capacity.build_healthy` (apart, so that the map's stages do not depend on its search).

The pre-run checks (:mod:`capmap.checks`), the stages and the command line call these; nothing else
turns a capacity config section into numerics.
"""

from __future__ import annotations

import numpy as np

from capmap.capacity import directions as dirs_mod
from capmap.capacity.directions import Directions, grid_axes
from capmap.capacity.engine import LoadLimits, Motion
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.refine_data import RefineSettings
from capmap.config.capacity import DirectionsConfig, LimitsConfig, LockConfig, RefineConfig, TaskConfig
from capmap.config.failure import Failure
from capmap.config.run import RunConfig
from capmap.config.typed import per_item
from capmap.core import ik
from capmap.core.configuration import arm_configurations
from capmap.core.kinematics import rotation_from_rpy, rotation_log
from capmap.core.reduction import LockedArm
from capmap.core.robot import Robot
from capmap.core.tracking import nearest_branch
from capmap.errors import CapmapError, ConfigError
from capmap.robots import load, locked_arm

__all__ = ["task_rotation", "task_motion", "directions_of", "load_limits", "refine_settings",
           "resolve_failure", "capacity_problem", "configuration_name"]


def task_rotation(task: TaskConfig) -> np.ndarray:
    """``task.orientation_rpy_deg`` as a rotation (3, 3) in the base frame."""
    return rotation_from_rpy(task.orientation_rpy_deg)


def task_motion(task: TaskConfig) -> Motion:
    """``task.v_max_mps``, ``task.a_max_mps2`` as the capacity's straight-line motion."""
    return Motion(task.v_max_mps, task.a_max_mps2)


def directions_of(cfg: DirectionsConfig) -> Directions:
    """The motion-direction set of a ``directions`` section (the run's or the atlas')."""
    if cfg.kind == "exact":
        return dirs_mod.exact()
    return dirs_mod.paper_grid(cfg.step_deg) if cfg.kind == "paper_grid" else dirs_mod.sphere(cfg.n)


def load_limits(cfg: LimitsConfig, n_joints: int) -> LoadLimits:
    """:class:`LoadLimits` of ``limits`` for an arm with n_joints joints (lengths checked here, errors
    naming the key); the joint torque limits must be resolved (:meth:`LimitsConfig.for_robot`)."""
    if cfg.joint_torque_nm is None:
        raise CapmapError("limits.joint_torque_nm: the URDF's effort limits are not filled in "
                          "(LimitsConfig.for_robot, done by check_run_config)")
    return LoadLimits(per_item(cfg.joint_torque_nm, n_joints, "limits.joint_torque_nm"),
                      per_item(cfg.base_force_n, 3, "limits.base_force_n"),
                      per_item(cfg.base_moment_nm, 3, "limits.base_moment_nm"))


def refine_settings(cfg: RefineConfig, payloads_kg) -> RefineSettings:
    """The refinement's numerics settings around the task payloads; their own check re-worded with the
    keys (the schema bounds rel_tol, so only the point counts can contradict each other)."""
    try:
        return RefineSettings(rel_tol=float(cfg.rel_tol), min_points=int(cfg.min_points),
                              max_points=int(cfg.max_points), payloads_kg=tuple(float(p) for p in sorted(payloads_kg)),
                              near_band=float(cfg.near_band), near_min_points=int(cfg.near_min_points))
    except CapmapError:
        raise ConfigError(f"voxels.refine: min_points = {cfg.min_points}, near_min_points = {cfg.near_min_points} "
                          f"and max_points = {cfg.max_points}: need min_points <= max_points and "
                          "near_min_points <= max_points") from None


def resolve_failure(robot: Robot, lock: LockConfig, task: TaskConfig, source: str = "config"
                    ) -> tuple[Failure, LockedArm]:
    """Resolve the lock angle, the start position and the start configuration, and the arm locked as it
    says (one-line
    :class:`ConfigError` naming the key for a wrong q_ini length, a lock angle outside the joint's
    range, or a start the locked arm cannot reach at the task orientation). See
    :mod:`capmap.config.failure` for what is resolved and why."""
    q_ini_deg = np.asarray(task.q_ini_deg, dtype=float)
    if len(q_ini_deg) != robot.n_joints:
        raise ConfigError(f"{source}: task.q_ini_deg has {len(q_ini_deg)} values but {robot.name} has "
                          f"{robot.n_joints} joints")
    if not 1 <= lock.joint <= robot.n_joints:
        raise ConfigError(f"{source}: lock.joint = {lock.joint} is out of range: {robot.name} has joints "
                          f"1..{robot.n_joints}")
    angle_given = lock.angle_deg is not None and abs(lock.angle_deg - q_ini_deg[lock.joint - 1]) > 1e-9
    angle = float(lock.angle_deg) if lock.angle_deg is not None else float(q_ini_deg[lock.joint - 1])
    try:
        arm = locked_arm(robot, lock.joint, angle)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}" if lock.angle_deg is not None else
                          f"{source}: {str(exc).replace('lock.angle_deg', f'task.q_ini_deg[{lock.joint - 1}]')}") from None
    rotation = task_rotation(task)
    q_ini = np.deg2rad(q_ini_deg)
    T_ini = robot.fk(q_ini[None])[0]
    start_given = task.start_m is not None
    start = np.asarray(task.start_m if start_given else T_ini[:3, 3], dtype=float)
    where = "task.start_m" if start_given else "the end effector at task.q_ini_deg"
    sol = ik.solve(arm, start[None], rotation)
    n = int(sol.n_solutions[0])
    if n == 0:
        raise ConfigError(f"{source}: {where} [{', '.join(f'{v:.4g}' for v in start)}] m is not reachable at "
                          f"task.orientation_rpy_deg = {list(task.orientation_rpy_deg)} with joint {lock.joint} "
                          f"locked at {angle:g} deg")
    k, q_branch, off = nearest_branch(sol.q[0, :n], q_ini[arm.active])
    q_start = np.rad2deg(arm.full_q(q_branch))
    q_start[lock.joint - 1] = angle  # exactly as given, not through radians
    return Failure(joint=int(lock.joint), angle_deg=angle, start_m=tuple(float(v) for v in start),
                   q_start_deg=tuple(float(v) for v in q_start), branch=k, n_branches=n,
                   offset_deg=float(np.rad2deg(off)), angle_given=angle_given, start_given=start_given,
                   ini_miss_m=float(np.linalg.norm(T_ini[:3, 3] - start)),
                   ini_miss_deg=float(np.rad2deg(np.linalg.norm(rotation_log(rotation @ T_ini[:3, :3].T))))), arm


def capacity_problem(run: RunConfig, joint: int | None = None, angle_deg: float | None = None,
                     directions: DirectionsConfig | None = None, per_configuration: bool = False) -> CapacityProblem:
    """The run's capacity problem: its robot locked as the resolved failure says (or ``joint`` at
    ``angle_deg``: an atlas map, a what-if), the task's rotation and motion, the load limits, the run's
    direction set (or ``directions``: the atlas'), per-axis minima along the 13 grid axes and, with
    ``per_configuration``, each configuration label's minima."""
    robot = load(run.robot)
    j = run.failure.joint if joint is None else int(joint)
    arm = locked_arm(robot, j, run.failure.angle_deg if angle_deg is None else float(angle_deg))
    return CapacityProblem(arm, task_rotation(run.task), task_motion(run.task),
                           load_limits(run.limits, robot.n_joints).for_arm(arm),
                           directions_of(run.directions if directions is None else directions), grid_axes(),
                           arm_configurations(arm) if per_configuration else None)


def configuration_name(arm: LockedArm, q_deg) -> str:
    """The configuration (e.g. ``S+E-W+``) of ``arm`` at q_deg (the robot's joints, deg)."""
    q = np.deg2rad(np.asarray(q_deg, dtype=float))[arm.active]
    labels = arm_configurations(arm)
    return labels.names[int(labels.labels(q[None])[0])]
