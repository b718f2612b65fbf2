"""What the stages of the capacity family (capacity, verify, follow) do first: build the robot
and its locked arm from their configuration (and the task's rotation, motion and load limits)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.capacity.engine import Motion
from capmap.config.failure import locked_arm
from capmap.config.robot_file import load
from capmap.config.run import RunConfig
from capmap.core.configuration import arm_configurations
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm
from capmap.core.robot import Robot

__all__ = ["arm_from", "ArmTask", "arm_task_from", "configuration_name"]


def arm_from(run: RunConfig) -> tuple[Robot, LockedArm]:
    """The robot and its arm locked as the resolved failure says."""
    robot = load(run.robot)
    return robot, locked_arm(robot, run.failure.joint, run.failure.angle_deg)


@dataclass(frozen=True)
class ArmTask:
    """The robot, its locked arm, the task's end-effector ``rotation`` (3, 3), ``motion`` and the
    load ``limits`` on the arm's outputs."""

    robot: Robot
    arm: LockedArm
    rotation: np.ndarray
    motion: Motion
    limits: AffineLimits


def arm_task_from(run: RunConfig) -> ArmTask:
    """:func:`arm_from` and the task's orientation, speed, acceleration and load limits."""
    robot, arm = arm_from(run)
    return ArmTask(robot, arm, run.task.rotation, run.task.motion, run.limits.resolve(robot.n_joints).for_arm(arm))


def configuration_name(run: RunConfig, q_deg) -> str:
    """The configuration (e.g. ``S+E-W+``) of the locked arm at q_deg (the robot's joints, deg)."""
    _, arm = arm_from(run)
    q = np.deg2rad(np.asarray(q_deg, dtype=float))[arm.active]
    labels = arm_configurations(arm)
    return labels.names[int(labels.labels(q[None])[0])]
