"""What every stage does first: read its config slice, build the robot and its locked arm."""

from __future__ import annotations

import json

from capmap.config.capacity import LockConfig
from capmap.config.checks import locked_arm
from capmap.config.robot_file import load
from capmap.core.reduction import LockedArm
from capmap.core.robot import Robot

__all__ = ["parse_slice", "arm_from"]


def parse_slice(slice_json: str) -> dict:
    """A stage's config slice (see :func:`capmap.config.slices.stage_slices`) from its canonical JSON."""
    return json.loads(slice_json)


def arm_from(deps: dict) -> tuple[Robot, LockedArm]:
    """The robot (``model`` slice) and its arm locked as in the ``sample`` slice."""
    robot = load(deps["model"]["robot"])
    lk = LockConfig.from_doc(deps["sample"]["lock"])
    return robot, locked_arm(robot, lk.joint, lk.angle_deg)
