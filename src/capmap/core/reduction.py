"""Reduce an arm: lock one joint at a fixed angle (:func:`lock`), or keep every joint (:func:`free`).

The locked arm keeps the full Pinocchio model for dynamics (the locked joint has zero
velocity and acceleration; the base wrench is read at joint 1 even when joint 1 is the
locked one) and a reduced model (``pin.buildReducedModel``) for kinematics.
Users count joints from 1; arrays index from 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from capmap.core.kinematics import Chain
from capmap.core.robot import EE_FRAME, Robot
from capmap.errors import CapmapError

__all__ = ["LockedArm", "lock", "free"]


@dataclass(frozen=True, eq=False)
class LockedArm:
    """An arm with joint ``locked_joint`` (1-based; 0 = none, see :func:`free`) held at ``locked_angle_rad``."""

    robot: Robot
    locked_joint: int
    locked_angle_rad: float
    reduced_model: pin.Model
    reduced_ee_frame_id: int
    active: np.ndarray  # (n-1,) configuration indices of the joints that still move
    chain: Chain  # the reduced arm in product form (for IK)

    @property
    def n_active(self) -> int:
        return len(self.active)

    @property
    def q_lower(self) -> np.ndarray:
        return self.robot.q_lower[self.active]

    @property
    def q_upper(self) -> np.ndarray:
        return self.robot.q_upper[self.active]

    @property
    def active_joint_numbers(self) -> tuple[int, ...]:
        """1-based numbers of the joints that still move."""
        return tuple(int(i) + 1 for i in self.active)

    def full_q(self, q_active: np.ndarray) -> np.ndarray:
        """Full configuration(s) (..., n) from active ones (..., n-1), locked angle inserted."""
        q_active = np.asarray(q_active, dtype=float)
        out = np.empty(q_active.shape[:-1] + (self.robot.n_joints,))
        out[..., self.active] = q_active
        if self.locked_joint:
            out[..., self.locked_joint - 1] = self.locked_angle_rad
        return out

    def full_v(self, v_active: np.ndarray) -> np.ndarray:
        """Full joint velocities/accelerations (..., n) with zero at the locked joint."""
        v_active = np.asarray(v_active, dtype=float)
        out = np.zeros(v_active.shape[:-1] + (self.robot.n_joints,))
        out[..., self.active] = v_active
        return out

    def fk(self, q_active: np.ndarray) -> np.ndarray:
        """End-effector pose(s) (N, 4, 4) of the reduced arm (batched numpy)."""
        return self.chain.fk(q_active)


def lock(robot: Robot, joint: int, angle_rad: float) -> LockedArm:
    """Lock joint ``joint`` (1-based) at ``angle_rad``. A bad index or angle is a one-line
    :class:`CapmapError` with the roles ``joint`` and ``angle`` (re-worded by config checks)."""
    n = robot.n_joints
    if isinstance(joint, bool) or not isinstance(joint, (int, np.integer)) or not 1 <= joint <= n:
        raise CapmapError(f"{{joint}} = {joint!r} is out of range: {robot.name} has joints 1..{n}",
                          joint="the locked joint")
    lo, hi = robot.q_lower[joint - 1], robot.q_upper[joint - 1]
    if not lo - 1e-12 <= angle_rad <= hi + 1e-12:
        raise CapmapError(f"{{angle}} = {np.rad2deg(angle_rad):g} is outside joint {joint}'s range "
                          f"[{np.rad2deg(lo):g}, {np.rad2deg(hi):g}] deg", angle="the lock angle")
    q_ref = pin.neutral(robot.model)
    q_ref[joint - 1] = angle_rad
    reduced = pin.buildReducedModel(robot.model, [joint], q_ref)
    ee = reduced.getFrameId(EE_FRAME)
    active = np.array([i for i in range(n) if i != joint - 1])
    return LockedArm(robot=robot, locked_joint=int(joint), locked_angle_rad=float(angle_rad),
                     reduced_model=reduced, reduced_ee_frame_id=ee, active=active,
                     chain=Chain.from_model(reduced, ee))


def free(robot: Robot) -> LockedArm:
    """The arm with no joint locked (every joint active), for the same kinematics/dynamics API."""
    ee = robot.model.getFrameId(EE_FRAME)
    return LockedArm(robot=robot, locked_joint=0, locked_angle_rad=0.0, reduced_model=robot.model,
                     reduced_ee_frame_id=ee, active=np.arange(robot.n_joints), chain=Chain.from_model(robot.model, ee))
