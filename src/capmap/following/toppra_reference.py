"""Time-optimal reference for the follower: TOPP-RA (``toppra``) on the same path and limits.

The joint path is given to toppra as a cubic spline through the exact IK samples of the
segment, extended by one virtual coordinate equal to the arc length s (its path
derivative is 1, its second derivative 0), so that the task's path-speed and
path-acceleration limits become toppra joint-velocity and joint-acceleration limits on
that coordinate. Joint torques are limited through Pinocchio's RNEA (payload and the drives'
armature included) as toppra's ``JointTorqueConstraint`` inverse dynamics, with the drives' Coulomb
friction as its dry-friction term (``fs_coef``: coulomb sign(q'(s)), the path's direction: a fixed
sign along a rest-to-rest segment where q' keeps its sign). Viscous friction cannot enter: it makes
TOPP-RA's problem non-convex (toppra issue #92); the torques of the result are reported both as
TOPP-RA modelled them and with the full drive model (:func:`capmap.core.drives.friction_torque`), so
what leaving viscous friction out costs is measured. The result is the time-optimal rest-to-rest
motion without a jerk limit: a lower bound for any follower's duration (for the follower's full
model, exactly so only without viscous friction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import toppra as ta
import toppra.algorithm as algo
import toppra.constraint as constraint

from capmap.core.drives import motor_torque, path_motion
from capmap.core.dynamics import payload_models
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm
from capmap.errors import SolverFailed
from capmap.following.path import JointPath

__all__ = ["ToppraResult", "ToppraSettings", "time_optimal"]

_FREE = 1e9  # "no limit" for the real joints' velocity/acceleration and the virtual joint's torque


@dataclass(frozen=True)
class ToppraSettings:
    """The task's path limits and TOPP-RA's grid: path speed |s'| <= v_max_mps m/s and acceleration
    |s''| <= a_max_mps2 m/s^2; n_grid intervals of the path for TOPP-RA; the result's torques
    re-evaluated every sample_dt_s s."""

    v_max_mps: float
    a_max_mps2: float
    n_grid: int = 400
    sample_dt_s: float = 1e-3


@dataclass(frozen=True)
class ToppraResult:
    """duration_s of the time-optimal motion; t_s (K,), s (K,) m, sd (K,) m/s sampled along it;
    tau (K, n) N m: exact torques of the sampled motion with the full drive model (RNEA on the spline
    path, armature, Coulomb and viscous friction); tau_modelled (K, n) N m: the terms TOPP-RA had (no
    viscous friction)."""

    duration_s: float
    t_s: np.ndarray
    s: np.ndarray
    sd: np.ndarray
    tau: np.ndarray
    tau_modelled: np.ndarray


def time_optimal(arm: LockedArm, path: JointPath, payload_kg: float, limits: AffineLimits,
                 settings: ToppraSettings) -> ToppraResult:
    """TOPP-RA on ``path`` carrying payload_kg kg under the joint-torque ``limits`` (n_active outputs)
    and the path speed and acceleration limits of ``settings`` (see the module docstring)."""
    v_max_mps, a_max_mps2 = settings.v_max_mps, settings.a_max_mps2
    n_grid, sample_dt_s = settings.n_grid, settings.sample_dt_s
    ta.setup_logging("WARNING")
    tau_max = limits.limit
    model, _ = payload_models(arm, payload_kg)
    data = model.createData()
    n = arm.n_active
    act = arm.active
    way = np.column_stack([path.q, path.s])
    spline = ta.SplineInterpolator(path.s, way)

    def inv_dyn(q, qd, qdd):
        tau = pin.rnea(model, data, arm.full_q(q[:n]), arm.full_v(qd[:n]), arm.full_v(qdd[:n]))[act]
        return np.append(tau, 0.0)

    tau_lim = np.column_stack([-np.append(tau_max, _FREE), np.append(tau_max, _FREE)])
    vlim = np.column_stack([np.full(n + 1, -_FREE), np.full(n + 1, _FREE)])
    vlim[n] = (-v_max_mps, v_max_mps)
    alim = vlim.copy()
    alim[n] = (-a_max_mps2, a_max_mps2)
    coulomb, viscous = arm.robot.coulomb_nm[act], arm.robot.viscous_nms[act]
    cons = [constraint.JointVelocityConstraint(vlim), constraint.JointAccelerationConstraint(alim),
            constraint.JointTorqueConstraint(inv_dyn, tau_lim, np.append(coulomb, 0.0),
                                             discretization_scheme=constraint.DiscretizationType.Interpolation)]
    instance = algo.TOPPRA(cons, spline, gridpoints=np.linspace(0, path.length_m, n_grid + 1),
                           parametrizer="ParametrizeConstAccel")
    traj = instance.compute_trajectory(0, 0)
    if traj is None:
        raise SolverFailed("TOPP-RA found no feasible time parametrisation of the path under these limits")
    t = np.arange(0.0, traj.duration, sample_dt_s)
    t = np.append(t, traj.duration)
    q, qd, qdd = traj(t), traj(t, 1), traj(t, 2)
    rigid = np.array([inv_dyn(q[k], qd[k], qdd[k])[:n] for k in range(len(t))])
    motion = path_motion(spline(q[:, n], 1)[:, :n], qd[:, n], qdd[:, n])
    modelled = motor_torque(rigid, qd[:, :n], motion, coulomb, np.zeros(n))
    full = motor_torque(rigid, qd[:, :n], motion, coulomb, viscous)
    return ToppraResult(float(traj.duration), t, q[:, n], qd[:, n], full, modelled)
