"""What the stages of the capacity family (capacity, verify, follow) do first: build the robot
and its locked arm from their config slice (and the task's rotation, motion and load limits)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.capacity.engine import Motion
from capmap.config.capacity import LimitsConfig, LockConfig, rotation_from_rpy
from capmap.config.failure import locked_arm
from capmap.config.robot_file import load
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm
from capmap.core.robot import Robot

__all__ = ["arm_from", "ArmTask", "arm_task_from"]


def arm_from(deps: dict) -> tuple[Robot, LockedArm]:
    """The robot (``model`` slice) and its arm locked as in the ``sample`` slice."""
    robot = load(deps["model"]["robot"])
    lk = LockConfig.from_doc(deps["sample"]["lock"])
    return robot, locked_arm(robot, lk.joint, lk.angle_deg)


@dataclass(frozen=True)
class ArmTask:
    """The robot, its locked arm, the task's end-effector ``rotation`` (3, 3), ``motion`` and the
    load ``limits`` on the arm's outputs."""

    robot: Robot
    arm: LockedArm
    rotation: np.ndarray
    motion: Motion
    limits: AffineLimits


def arm_task_from(deps: dict) -> ArmTask:
    """:func:`arm_from` and the ``capacity`` slice's task orientation, speed, acceleration and limits."""
    robot, arm = arm_from(deps)
    cs = deps["capacity"]
    task = cs["task"]
    return ArmTask(robot, arm, rotation_from_rpy(task["orientation_rpy_deg"]), Motion(task["v_max_mps"], task["a_max_mps2"]),
                   LimitsConfig.from_doc(cs["limits"]).resolve(robot.n_joints).for_arm(arm))
