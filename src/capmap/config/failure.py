"""The failure in one edit: from ``lock`` and ``task`` to the locked arm's start.

``task.q_ini_deg`` is the configuration when the joint failed and ``lock.joint`` the failed
joint. By default the joint is locked where it stood (``lock.angle_deg`` = its q_ini) and
the task starts where the end effector stood (``task.start_m`` = FK(q_ini)). The start
configuration is the IK branch of the locked arm at the start pose (``task.start_m``,
``task.orientation_rpy_deg``) nearest to q_ini:

- lock angle = q_ini's: q_ini itself up to rounding (a q_ini typed to whole degrees is a
  few tenths of a degree from its branch);
- an explicit lock angle that differs ("what if it had locked at ..."): the nearest branch,
  however far.

Either way the choice is reported (which branch, how far from q_ini, and how far q_ini's own
end effector is from the start pose when that is more than 1 mm or 0.5 deg), never refused:
a q_ini that only roughly matches the start still names a branch. An unreachable start is
an error naming the key.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from capmap.config.capacity import LockConfig, TaskConfig
from capmap.config.jobs import PlanTask
from capmap.config.typed import ROUND
from capmap.core import ik
from capmap.core.kinematics import rotation_log
from capmap.core.reduction import LockedArm
from capmap.core.reduction import lock as lock_joint
from capmap.core.robot import Robot
from capmap.core.tracking import nearest_branch
from capmap.errors import CapmapError, ConfigError

__all__ = ["Failure", "resolve_failure", "main_task", "locked_arm"]


def locked_arm(robot: Robot, joint: int, angle_deg: float) -> LockedArm:
    """:func:`capmap.core.reduction.lock` with its errors in config terms."""
    try:
        return lock_joint(robot, joint, np.deg2rad(angle_deg))
    except CapmapError as exc:
        raise ConfigError(exc.in_terms(joint="lock.joint", angle="lock.angle_deg")) from None


@dataclass(frozen=True)
class Failure:
    """The resolved failure: locked joint (1-based) and angle, start position, start configuration
    (every joint, deg; the locked one at ``angle_deg``), and which IK branch it is."""

    joint: int
    angle_deg: float = field(metadata=ROUND)  # rounded in slices (1e-9): equal failures give equal slices
    start_m: tuple[float, float, float] = field(metadata=ROUND)
    q_start_deg: tuple[float, ...] = field(metadata=ROUND)
    branch: int  # index among the n_branches solutions at the start (ik.solve order)
    n_branches: int
    offset_deg: float  # largest |q_start - q_ini| over the joints that still move
    angle_given: bool
    start_given: bool
    ini_miss_m: float = 0.0  # how far q_ini's end effector is from the start position
    ini_miss_deg: float = 0.0  # and from the task orientation

    def describe(self) -> str:
        """One line for the log: what was resolved and from where."""
        angle = "lock.angle_deg" if self.angle_given else "where it stood (task.q_ini_deg)"
        start = "task.start_m" if self.start_given else "FK(task.q_ini_deg)"
        miss = (f" (at q_ini the end effector is {self.ini_miss_m:.3g} m from the start and {self.ini_miss_deg:.2f} "
                "deg from task.orientation_rpy_deg)" if self.ini_miss_m > 1e-3 or self.ini_miss_deg > 0.5 else "")
        return (f"joint {self.joint} locked at {self.angle_deg:g} deg ({angle}); start "
                f"[{', '.join(f'{v:.4f}' for v in self.start_m)}] m ({start}); start configuration = IK branch "
                f"{self.branch + 1} of {self.n_branches}, {self.offset_deg:.2f} deg from task.q_ini_deg{miss}")


def resolve_failure(robot: Robot, lock: LockConfig, task: TaskConfig, source: str = "config") -> Failure:
    """Resolve the lock angle, the start position and the start configuration (one-line
    :class:`ConfigError` naming the key for a wrong q_ini length, a lock angle outside the joint's
    range, or a start the locked arm cannot reach at the task orientation)."""
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
    q_ini = np.deg2rad(q_ini_deg)
    T_ini = robot.fk(q_ini[None])[0]
    start_given = task.start_m is not None
    start = np.asarray(task.start_m if start_given else T_ini[:3, 3], dtype=float)
    where = "task.start_m" if start_given else "the end effector at task.q_ini_deg"
    sol = ik.solve(arm, start[None], task.rotation)
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
                   ini_miss_deg=float(np.rad2deg(np.linalg.norm(rotation_log(task.rotation @ T_ini[:3, :3].T)))))


def main_task(task: TaskConfig, failure: Failure, payload_kg: float) -> PlanTask:
    """The plan/verify job of the main task at one of its payloads: the resolved start and start
    configuration, the task's goal."""
    return PlanTask(payload_kg=float(payload_kg), start_m=failure.start_m, goal_m=task.goal_m,
                    q_start_deg=failure.q_start_deg)
