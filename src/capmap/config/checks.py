"""Checks that need the robot, run once before any job: everything a stage would otherwise
find out late (the robot file builds, the lock, limit lengths, reachable start and goal, a
start configuration on an IK branch, the follow cases). Numerics raise in their own terms;
here their messages are re-worded with the config keys (:meth:`CapmapError.in_terms`)."""

from __future__ import annotations

import numpy as np

from capmap.config.capacity import TaskConfig, per_item
from capmap.config.dualarm import load_dual_arm_file
from capmap.config.following import FollowConfig
from capmap.config.reconfig import rate_limits, reconfig_problem
from capmap.config.robot_file import load
from capmap.config.scene_file import load_scene
from capmap.config.run import RunConfig, parse_config
from capmap.core import ik
from capmap.core.reduction import LockedArm, free, lock
from capmap.core.tracking import start_branch
from capmap.errors import CapmapError, ConfigError

__all__ = ["check_run_config", "check_task_poses", "check_follow", "locked_arm"]


def locked_arm(robot, joint: int, angle_deg: float) -> LockedArm:
    """:func:`capmap.core.reduction.lock` with its errors in config terms."""
    try:
        return lock(robot, joint, np.deg2rad(angle_deg))
    except CapmapError as exc:
        raise ConfigError(exc.in_terms(joint="lock.joint", angle="lock.angle_deg")) from None


def check_run_config(doc: dict, source: str = "config") -> RunConfig:
    """Everything that can be checked before any job: schema, robot file, lock, limits, directions."""
    cfg = parse_config(doc, source)
    robot = load(cfg.robot)
    arm = locked_arm(robot, cfg.lock.joint, cfg.lock.angle_deg)
    cfg.limits.resolve(robot.n_joints).for_arm(arm)
    cfg.directions.build()
    if len(cfg.task.q_ini_deg) != robot.n_joints:
        raise ConfigError(f"{source}: task.q_ini_deg has {len(cfg.task.q_ini_deg)} values but {robot.name} has "
                          f"{robot.n_joints} joints")
    locked = cfg.task.q_ini_deg[cfg.lock.joint - 1]
    if abs(locked - cfg.lock.angle_deg) > 1e-9:
        raise ConfigError(f"{source}: task.q_ini_deg[{cfg.lock.joint - 1}] = {locked:g} must equal lock.angle_deg = "
                          f"{cfg.lock.angle_deg:g} (joint {cfg.lock.joint} is locked)")
    check_task_poses(arm, cfg.task, source)
    if cfg.follow is not None:
        check_follow(cfg.follow, cfg, source)
    if cfg.reconfig is not None:
        rate_limits(cfg.reconfig, reconfig_problem(cfg.reconfig))
    if cfg.dualarm is not None:
        load_dual_arm_file(cfg.dualarm.robot)
        load_scene(cfg.dualarm.scene)
    return cfg


def check_task_poses(arm: LockedArm, task: TaskConfig, source: str = "config") -> None:
    """Start and goal reachable at the task orientation; q_ini an IK solution at the start."""
    sol = ik.solve(arm, np.array([task.start_m, task.goal_m]), task.rotation)
    for key, n, x in zip(("start_m", "goal_m"), sol.n_solutions, (task.start_m, task.goal_m)):
        if n == 0:
            raise ConfigError(f"{source}: task.{key} = [{', '.join(f'{v:g}' for v in x)}] is not reachable by the "
                              f"locked arm at task.orientation_rpy_deg = {list(task.orientation_rpy_deg)}")
    try:
        start_branch(arm, np.asarray(task.start_m), task.rotation, np.deg2rad(np.asarray(task.q_ini_deg))[arm.active])
    except CapmapError as exc:
        raise ConfigError(f"{source}: {exc.in_terms(q_ini='task.q_ini_deg', start='task.start_m')}") from None


def check_follow(fol: FollowConfig, cfg: RunConfig, source: str = "config") -> None:
    """The follow section's cross-checks (payload known, robot loads, lengths match, line reachable)."""
    if fol.space is not None and float(fol.space.payload_kg) not in cfg.task.payload_kg:
        raise ConfigError(f"{source}: follow.space.payload_kg = {fol.space.payload_kg:g} is not one of "
                          f"task.payload_kg {[f'{m:g}' for m in cfg.task.payload_kg]} (its verified path is followed)")
    g = fol.ground
    if g is None:
        return
    robot = load(g.robot)
    if len(g.q_start_deg) != robot.n_joints:
        raise ConfigError(f"{source}: follow.ground.q_start_deg has {len(g.q_start_deg)} values but "
                          f"{robot.name} has {robot.n_joints} joints")
    per_item(g.joint_torque_nm, robot.n_joints, "follow.ground.joint_torque_nm")
    if not np.linalg.norm(g.line_m) > 0:
        raise ConfigError(f"{source}: follow.ground.line_m must not be zero")
    arm = free(robot)
    T0 = arm.fk(np.deg2rad(np.asarray(g.q_start_deg, dtype=float))[None])[0]
    end = T0[:3, 3] + np.asarray(g.line_m, dtype=float)
    if ik.solve(arm, end[None], T0[:3, :3]).n_solutions[0] == 0:
        raise ConfigError(f"{source}: follow.ground.line_m = {list(g.line_m)} ends at "
                          f"[{', '.join(f'{v:.4g}' for v in end)}], which {robot.name} cannot reach at the "
                          f"start orientation")
