"""The capacity coefficients of a whole batch of configurations at once: a recursive
Newton-Euler algorithm compiled with numba over the leading axis, in place of 16 Pinocchio
RNEA calls and 6 drift calls per configuration in a Python loop.

The model is read once from the Pinocchio model (serial chain of 1-DOF revolute joints):
per joint its placement in the parent joint's frame, its axis, and its body's mass, centre of
mass and rotational inertia; the end-effector frame's placement on its joint. Everything is
in Pinocchio's own joint frames and spatial conventions (motion (v, w) at the frame origin,
force (f, n) about it), so :class:`BatchDynamics.coefficients` returns the same c0, L, Q, S (one
:class:`~capmap.core.coefficients.Coefficients`, batched) as
:meth:`capmap.core.dynamics.ArmDynamics.coefficients` (checked against it per configuration to a
rounding bound 8 eps cond(J) times the size of the terms that cancel (tests/core/test_batch_dynamics.py),
and so against Pinocchio and the independent Newton-Euler of the tests).

Why numba and not a numpy batch: the recursion is 7 joints deep with 3-vectors, i.e. tiny
arrays, where numpy's per-call overhead is 100x the arithmetic; compiled scalar loops do the
~10^4 flops of a configuration in a few microseconds.
"""

from __future__ import annotations

import numpy as np

from capmap.core.coefficients import Coefficients
from capmap.core.ne_coefficients import batch_coefficients
from capmap.core.reduction import LockedArm

__all__ = ["BatchDynamics"]


def _axis(jmodel) -> np.ndarray:
    name = jmodel.shortname()
    fixed = {"JointModelRX": [1.0, 0, 0], "JointModelRY": [0, 1.0, 0], "JointModelRZ": [0, 0, 1.0]}
    if name in fixed:
        return np.array(fixed[name])
    return np.asarray(jmodel.extract().axis, dtype=float)


class BatchDynamics:
    """Batched coefficients of a locked arm (see module docstring). Immutable model arrays;
    safe to share between threads, cheap to build per worker."""

    def __init__(self, arm: LockedArm):
        robot = arm.robot
        m = robot.model
        n = m.njoints - 1
        for j in range(1, m.njoints):
            if m.parents[j] != j - 1 or m.joints[j].nq != 1:
                raise ValueError("BatchDynamics needs a serial chain of 1-DOF revolute joints")
        self.n = n
        self.arm = arm
        self.R0 = np.array([m.jointPlacements[j].rotation for j in range(1, n + 1)])  # (n, 3, 3)
        self.p0 = np.array([m.jointPlacements[j].translation for j in range(1, n + 1)])  # (n, 3)
        self.axis = np.array([_axis(m.joints[j]) for j in range(1, n + 1)])  # (n, 3)
        self.mass = np.array([m.inertias[j].mass for j in range(1, n + 1)])
        self.com = np.array([m.inertias[j].lever for j in range(1, n + 1)])
        self.Ic = np.array([m.inertias[j].inertia for j in range(1, n + 1)])  # about the com
        self.armature = np.asarray(m.armature, dtype=float).copy()  # (n,) the drives' reflected rotor inertia
        frame = m.frames[robot.ee_frame_id]
        self.ee_joint = int(frame.parentJoint) - 1  # 0-based
        self.ee_p = np.asarray(frame.placement.translation, dtype=float).copy()
        self.gravity = np.asarray(robot.gravity, dtype=float)
        self.base_com = np.asarray(robot.base_com, dtype=float)
        self.active = np.asarray(arm.active, dtype=np.int64)
        self.locked = -1 if not arm.locked_joint else arm.locked_joint - 1
        self.locked_q = float(arm.locked_angle_rad)
        self.n_out = len(arm.active) + 6

    def coefficients(self, q_active: np.ndarray, held_rad: np.ndarray | None = None) -> Coefficients:
        """The :class:`~capmap.core.coefficients.Coefficients` of configurations q_active (B, n_active) rad
        (a single (n_active,) is a batch of one): c0 (B, n_out), L (B, n_out, 3), Q (B, n_out, 6),
        S (B, n_out, 3), singular (B,). ``held_rad`` (B,): the locked joint held at these angles instead
        of the arm's (one batch over several lock angles of the same joint: the model arrays do not depend
        on it)."""
        q_active = np.ascontiguousarray(np.atleast_2d(q_active), dtype=float)
        B = len(q_active)
        q = np.empty((B, self.n))
        q[:, self.active] = q_active
        if self.locked >= 0:
            q[:, self.locked] = self.locked_q if held_rad is None else held_rad
        elif held_rad is not None:
            raise ValueError("held_rad needs an arm with a locked joint")
        C = np.zeros((B, self.n_out, 10))  # [c0, L, Q]: what the capacity kernels read
        S = np.zeros((B, self.n_out, 3))
        singular = np.zeros(B, dtype=np.bool_)
        batch_coefficients(self.R0, self.p0, self.axis, self.mass, self.com, self.Ic, self.armature, self.ee_joint,
                           self.ee_p, self.gravity, self.base_com, self.active, q, C, S, singular)
        return Coefficients.from_stacked(C, S, singular)
