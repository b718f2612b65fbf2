"""The drives' own torque terms, as the method's joint dynamics write them:

    M(q) qdd + C(q, qd) qd + g(q) + f(qd) = tau,   M = M_links + diag(armature)

armature_j: the joint's reflected rotor inertia (rotor and gear input inertia x gear ratio^2), a
constant diagonal inertia. Pinocchio carries it as ``model.armature`` and adds armature_j qdd_j in
its RNEA and CRBA, so every torque capmap computes with Pinocchio includes it; the compiled capacity
coefficients add it likewise (:mod:`capmap.core.ne_coefficients`). Friction at the joint:

    f_j = viscous_j qd_j + coulomb_j sign(motion_j)

with motion the direction the joint moves in: the sign of its velocity, or at rest the direction it
starts in (breakaway: dry friction opposes the motion that starts). A joint at rest that does not
start (held, or just stopped) is held by static friction: any friction torque in
[-coulomb_j, coulomb_j] (a band) — the motor then gives the smallest torque that holds it. A joint
velocity alone cannot tell a start from a stop, so the caller says which (:func:`path_motion` for a
path followed forward). Pinocchio's models keep the coefficients (``model.friction``: Coulomb,
``model.damping``: viscous; a URDF's <dynamics friction damping>) but use them in no algorithm:
:func:`motor_torque` adds them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["motor_torque", "friction_torque", "path_motion"]


def path_motion(dq_ds: np.ndarray, sd: np.ndarray, sdd: np.ndarray) -> np.ndarray:
    """Each joint's direction of motion (..., n) in {-1, 0, 1} on a path followed forward: sign(q'(s)) (dq_ds
    (..., n) rad/m) while moving (sd (...,) > 0 m/s) or starting from rest (sd = 0, sdd (...,) > 0 m/s^2);
    0 at rest otherwise (held or stopped: static friction)."""
    sd, sdd = np.asarray(sd, dtype=float)[..., None], np.asarray(sdd, dtype=float)[..., None]
    return np.where((sd > 0) | ((sd == 0) & (sdd > 0)), np.sign(dq_ds), 0.0)


def friction_torque(tau_rigid: np.ndarray, qd: np.ndarray, motion: np.ndarray, coulomb_nm: np.ndarray,
                    viscous_nms: np.ndarray) -> np.ndarray:
    """Friction torque (..., n) N m the motor must also give, at rigid-body torques tau_rigid (..., n) N m
    (links and armature), joint velocities qd (..., n) rad/s and directions of motion ``motion`` (..., n)
    (-1, 0, 1; e.g. :func:`path_motion`, or sign(qd)): viscous qd + coulomb motion; where motion is 0
    static friction takes up to coulomb of tau_rigid (the band): -clip(tau_rigid, -coulomb, coulomb)."""
    tau_rigid, qd, motion = (np.asarray(x, dtype=float) for x in (tau_rigid, qd, motion))
    static = -np.clip(tau_rigid, -coulomb_nm, coulomb_nm)
    return np.where(motion != 0.0, viscous_nms * qd + coulomb_nm * motion, static)


def motor_torque(tau_rigid: np.ndarray, qd: np.ndarray, motion: np.ndarray, coulomb_nm: np.ndarray,
                 viscous_nms: np.ndarray) -> np.ndarray:
    """The motor torque (..., n) N m at the joint: tau_rigid + :func:`friction_torque` (same arguments)."""
    return np.asarray(tau_rigid, dtype=float) + friction_torque(tau_rigid, qd, motion, coulomb_nm, viscous_nms)
