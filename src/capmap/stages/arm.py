"""What the stages of the capacity family (capacity, verify, follow) do first: build the robot
and its locked arm from their config slice."""

from __future__ import annotations

from capmap.config.capacity import LockConfig
from capmap.config.failure import locked_arm
from capmap.config.robot_file import load
from capmap.core.reduction import LockedArm
from capmap.core.robot import Robot

__all__ = ["arm_from"]


def arm_from(deps: dict) -> tuple[Robot, LockedArm]:
    """The robot (``model`` slice) and its arm locked as in the ``sample`` slice."""
    robot = load(deps["model"]["robot"])
    lk = LockConfig.from_doc(deps["sample"]["lock"])
    return robot, locked_arm(robot, lk.joint, lk.angle_deg)
