"""Checks that need the robot, run once before any job: everything a stage would otherwise
find out late (the robot file builds, the lock, limit lengths, reachable start and goal, a
start configuration on an IK branch, the follow cases). Numerics raise in their own terms;
here their messages are re-worded with the config keys (:meth:`CapmapError.in_terms`)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from capmap.config.atlas import AtlasConfig
from capmap.config.capacity import TaskConfig, refine_settings
from capmap.config.dualarm import load_dual_arm_file
from capmap.config.estimate import estimate_map
from capmap.config.failure import Failure, locked_arm, resolve_failure
from capmap.config.following import FollowConfig
from capmap.config.reconfig import rate_limits, reconfig_problem
from capmap.config.robot_file import load
from capmap.config.run import RunConfig, parse_config
from capmap.config.scene_file import load_scene
from capmap.config.validation import per_item
from capmap.core import ik
from capmap.core.profiles import MIN_PHASE_INTERVALS
from capmap.core.reduction import LockedArm, free
from capmap.core.robot import Robot
from capmap.core.tracking import start_branch
from capmap.errors import CapmapError, ConfigError

__all__ = ["check_run_config", "check_goal", "check_dt", "check_follow", "check_atlas"]


def check_run_config(doc: dict, source: str = "config") -> RunConfig:
    """Everything that can be checked before any job: schema, robot file, lock, limits, directions."""
    cfg = parse_config(doc, source)
    robot = load(cfg.robot)
    failure = resolve_failure(robot, cfg.lock, cfg.task, source)
    arm = locked_arm(robot, failure.joint, failure.angle_deg)
    limits = cfg.limits.resolve(robot.n_joints).for_arm(arm)
    dirs = cfg.directions.build()
    check_goal(arm, cfg.task, failure, source)
    check_tasks(doc.get("tasks", []), arm, cfg.task, failure, source)
    check_dt(cfg, source)
    try:
        refine_settings(doc["voxels"], cfg.task.payload_kg)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    keys = {"n_points": "sampling.n_points", "edge_m": "voxels.edge_m"}
    try:
        estimate = estimate_map(arm, cfg.sampling, cfg.voxel_edge_m, len(dirs), len(limits.names), cfg.shards, keys)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    if cfg.follow is not None:
        check_follow(cfg.follow, cfg, source)
    if cfg.reconfig is not None:
        rate_limits(cfg.reconfig, reconfig_problem(cfg.reconfig))
    if cfg.atlas is not None:
        check_atlas(cfg.atlas, robot, source)
        keys = {"n_points": "atlas.sampling.n_points", "edge_m": "atlas.edge_m"}
        try:
            estimate_map(arm, cfg.atlas.sampling, cfg.atlas.edge_m, len(cfg.atlas.directions.build()),
                         len(limits.names), 1, keys)
        except ConfigError as exc:
            raise ConfigError(f"{source}: {exc}") from None
    if cfg.dualarm is not None:
        load_dual_arm_file(cfg.dualarm.robot)
        load_scene(cfg.dualarm.scene)
    return replace(cfg, failure=failure, estimate=estimate)


def check_dt(cfg: RunConfig, source: str = "config") -> None:
    """verification.dt_s resolves the motion: at most a tenth of the acceleration phase (v/a)."""
    t_acc = cfg.task.v_max_mps / cfg.task.a_max_mps2
    if cfg.verification.dt_s > t_acc / MIN_PHASE_INTERVALS:
        raise ConfigError(f"{source}: verification.dt_s = {cfg.verification.dt_s:g} s is too coarse for the motion: its "
                          f"acceleration phase lasts task.v_max_mps / task.a_max_mps2 = {t_acc:.3g} s; use at most "
                          f"{t_acc / MIN_PHASE_INTERVALS:.3g} s ({MIN_PHASE_INTERVALS} samples per phase)")


def check_goal(arm: LockedArm, task: TaskConfig, failure: Failure, source: str = "config",
               goal_m=None, key: str = "task.goal_m") -> None:
    """The goal (``task.goal_m``, or ``goal_m`` named ``key``) reachable at the task orientation by
    the locked arm (the start is, by resolution)."""
    goal = task.goal_m if goal_m is None else goal_m
    if ik.solve(arm, np.asarray(goal, dtype=float)[None], task.rotation).n_solutions[0] == 0:
        raise ConfigError(f"{source}: {key} = [{', '.join(f'{v:g}' for v in goal)}] is not reachable "
                          f"at task.orientation_rpy_deg = {list(task.orientation_rpy_deg)} with joint {failure.joint} "
                          f"locked at {failure.angle_deg:g} deg")


def check_tasks(tasks: list, arm: LockedArm, task: TaskConfig, failure: Failure, source: str = "config") -> None:
    """``tasks``: distinct names; every start configuration a branch at its start (the locked joint
    at the lock angle), every goal reachable, at the task's orientation."""
    names = [t["name"] for t in tasks]
    if len(set(names)) < len(names):
        raise ConfigError(f"{source}: tasks: names must differ ({names})")
    for i, t in enumerate(tasks):
        key = f"tasks[{i}] ({t['name']})"
        q = np.asarray(t["q_start_deg"], dtype=float)
        if len(q) != arm.robot.n_joints:
            raise ConfigError(f"{source}: {key}.q_start_deg has {len(q)} values but {arm.robot.name} has "
                              f"{arm.robot.n_joints} joints")
        if abs(q[failure.joint - 1] - failure.angle_deg) > 1e-6:
            raise ConfigError(f"{source}: {key}.q_start_deg[{failure.joint - 1}] = {q[failure.joint - 1]:g} but joint "
                              f"{failure.joint} is locked at {failure.angle_deg:g} deg")
        try:
            start_branch(arm, np.asarray(t["start_m"], dtype=float), task.rotation, np.deg2rad(q)[arm.active])
        except CapmapError as exc:
            raise ConfigError(f"{source}: {exc.in_terms(start=f'{key}.start_m', q_ini=f'{key}.q_start_deg')}") from None
        check_goal(arm, task, failure, source, t["goal_m"], f"{key}.goal_m")


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


def check_atlas(at: AtlasConfig, robot: Robot, source: str = "config") -> None:
    """Every atlas joint exists and every angle is inside every listed joint's range."""
    for j in at.joints:
        if not 1 <= j <= robot.n_joints:
            raise ConfigError(f"{source}: atlas.joints: joint {j} is out of range: {robot.name} has joints "
                              f"1..{robot.n_joints}")
        lo, hi = np.rad2deg(robot.q_lower[j - 1]), np.rad2deg(robot.q_upper[j - 1])
        for a in at.angles_deg:
            if not lo - 1e-9 <= a <= hi + 1e-9:
                raise ConfigError(f"{source}: atlas.angles_deg: {a:g} is outside joint {j}'s range [{lo:g}, {hi:g}] deg")
