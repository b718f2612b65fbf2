"""A posture's capacity computed independently of capmap's engine: joint rates from Pinocchio's frame
Jacobian and classical acceleration (LOCAL_WORLD_ALIGNED), loads by Craig's recursive Newton-Euler,
the largest payload by an LP; the least over the directions given."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from tests.reference.lp import lp_capacity
from tests.reference.newton_euler import newton_euler


def posture_capacity(robot, arm, q_active: np.ndarray, u: np.ndarray, v_max: float, a_max: float,
                     limit: np.ndarray) -> float:
    """min over directions u (D, 3) of the LP capacity [kg] of the locked arm's posture q_active (rad) moving
    along u at v_max [m/s], a_max [m/s^2]; ``limit`` on the active torques, base force and moment."""
    model = arm.reduced_model
    data = model.createData()
    f = arm.reduced_ee_frame_id
    J = pin.computeFrameJacobian(model, data, q_active, f, pin.LOCAL_WORLD_ALIGNED)
    best = np.inf
    for d in u:
        qd = np.linalg.solve(J, np.r_[v_max * d, 0, 0, 0])
        pin.forwardKinematics(model, data, q_active, qd, np.zeros(6))
        bias = pin.getFrameClassicalAcceleration(model, data, f, pin.LOCAL_WORLD_ALIGNED).vector
        qdd = np.linalg.solve(J, np.r_[a_max * d, 0, 0, 0] - bias)
        full = [np.insert(x, arm.locked_joint - 1, v) for x, v in ((q_active, arm.locked_angle_rad), (qd, 0), (qdd, 0))]
        t0, _, f0, m0 = newton_euler(*full, robot.gravity, 0.0, robot.base_com)
        t1, _, f1, m1 = newton_euler(*full, robot.gravity, 1.0, robot.base_com)
        keep = np.arange(robot.n_joints) != arm.locked_joint - 1
        y0 = np.concatenate([t0[keep], f0, m0])
        best = min(best, lp_capacity(y0, np.concatenate([t1[keep], f1, m1]) - y0, limit))
    return best
