"""Constrained quantities of a locked arm: active joint torques and the base disturbance.

For a motion state (q, qd, qdd) and a payload force, the constrained output vector is

    y = [tau_j (active joints, N m); F_base (3, N); M_base (3, N m)]

``tau`` comes from Pinocchio's RNEA on the full model (locked joint: zero velocity and
acceleration). The base disturbance is the wrench the arm exerts on the base through
joint 1 (minus the spatial force ``data.f[1]`` that the base applies to link 1),
expressed in the base frame, moment about the base centre of mass ``c``:

    F_base = -F_1,   M_base = -M_1(origin) + c x F_1.

The payload is a point mass at the end-effector origin; the arm applies to it the force
``m (a_ee - g)`` (world frame), so the payload acts on the arm with the opposite force.

:class:`ArmDynamics` is a worker's context: the (immutable) models plus its own
``pin.Data``. Create one per process/thread.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from capmap.core.batch_dynamics import BatchDynamics
from capmap.core.coefficients import Coefficients
from capmap.core.reduction import LockedArm

__all__ = ["ArmDynamics", "output_names", "torque_names", "payload_models", "BASE_OUTPUTS"]

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
BASE_OUTPUTS = ("base_fx_n", "base_fy_n", "base_fz_n", "base_mx_nm", "base_my_nm", "base_mz_nm")


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for (..., 3) arrays (np.cross is slow on tiny inputs)."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def torque_names(arm: LockedArm) -> tuple[str, ...]:
    """Names (with units) of the active joints' torques, ``tau_j<k>_nm`` (k 1-based)."""
    return tuple(f"tau_j{j}_nm" for j in arm.active_joint_numbers)


def output_names(arm: LockedArm) -> tuple[str, ...]:
    """Names (with units) of the constrained outputs, in order: active joint torques, base wrench."""
    return torque_names(arm) + BASE_OUTPUTS


def payload_models(arm: LockedArm, payload_kg: float) -> tuple[pin.Model, pin.Model]:
    """Copies of the robot's models (with and without gravity) carrying a point mass at the
    end-effector origin, appended to the body that holds the end-effector frame."""
    out = []
    for base in (arm.robot.model, arm.robot.model_no_gravity):
        model = base.copy()
        frame = model.frames[arm.robot.ee_frame_id]
        model.appendBodyToJoint(frame.parentJoint, pin.Inertia(float(payload_kg), np.zeros(3), np.zeros((3, 3))),
                                frame.placement)
        out.append(model)
    return out[0], out[1]


class ArmDynamics:
    """Per-worker dynamics context of a locked arm (models shared, Data owned)."""

    def __init__(self, arm: LockedArm):
        self.arm = arm
        robot = arm.robot
        self.model = robot.model
        self.model_ng = robot.model_no_gravity
        self.data = self.model.createData()
        self.data_ng = self.model_ng.createData()
        self.ee = robot.ee_frame_id
        self.ee_joint = self.model.frames[self.ee].parentJoint
        self.active = arm.active
        self.base_com = np.asarray(robot.base_com, dtype=float)
        self.gravity = np.asarray(robot.gravity, dtype=float)
        self.n_out = len(self.active) + 6
        self._zero = np.zeros(self.model.nv)
        self._fext = pin.StdVec_Force()
        for _ in range(self.model.njoints):
            self._fext.append(pin.Force.Zero())
        self.batch = BatchDynamics(arm)  # the same coefficients for a batch, compiled

    # ------------------------------------------------------------------ primitives
    def _payload_fext(self, data: pin.Data, p_ee: np.ndarray, force: np.ndarray) -> pin.StdVec_Force:
        """External forces for the payload reaction -force at p_ee (world), in joint-local frames."""
        reaction = pin.Force(-force, _cross(p_ee, -force))
        self._fext[self.ee_joint] = data.oMi[self.ee_joint].actInv(reaction)
        return self._fext

    def _ee_position(self, data: pin.Data) -> np.ndarray:
        """End-effector origin (3,) in the base frame, from the joint placements in ``data``."""
        return data.oMi[self.ee_joint].act(self.model.frames[self.ee].placement).translation.copy()

    def _rnea(self, model, data, q, v, a, fext=None) -> tuple[np.ndarray, np.ndarray]:
        """(tau (nv,), f_1 (6,) local) from one RNEA."""
        tau = pin.rnea(model, data, q, v, a) if fext is None else pin.rnea(model, data, q, v, a, fext)
        return tau.copy(), data.f[1].vector.copy()

    def _assemble(self, tau: np.ndarray, f1_local: np.ndarray, X1: np.ndarray) -> np.ndarray:
        """Outputs (..., n_out) from RNEA results tau (..., nv), f1_local (..., 6); X1 = dual action of oMi[1]."""
        fw = f1_local @ X1.T
        F, M = fw[..., :3], fw[..., 3:]
        base_f = -F
        base_m = -M + _cross(np.broadcast_to(self.base_com, F.shape), F)
        return np.concatenate([tau[..., self.active], base_f, base_m], axis=-1)

    def ee_jacobian(self, q: np.ndarray) -> np.ndarray:
        """6 x n_active Jacobian (world-aligned, at the end-effector origin; rows v, omega)."""
        J = pin.computeFrameJacobian(self.model, self.data, q, self.ee, LWA)
        return J[:, self.active]

    def drift(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Jdot qd: classical end-effector acceleration (6,) at qdd = 0 (full q, qd)."""
        pin.forwardKinematics(self.model_ng, self.data_ng, q, qd, self._zero)
        return pin.getFrameClassicalAcceleration(self.model_ng, self.data_ng, self.ee, LWA).vector

    # ------------------------------------------------------------------ public
    def outputs(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, payload_force: np.ndarray | None = None,
                gravity: bool = True) -> np.ndarray:
        """Constrained outputs (n_out,) for full q, qd, qdd (nv,) and the force on the payload (3,) N.

        gravity=False drops gravity on the links (the payload force is taken as given).
        """
        model, data = (self.model, self.data) if gravity else (self.model_ng, self.data_ng)
        pin.forwardKinematics(model, data, q)
        fext = None
        if payload_force is not None:
            fext = self._payload_fext(data, self._ee_position(data), np.asarray(payload_force, dtype=float))
        tau, f1 = self._rnea(model, data, q, qd, qdd, fext)
        return self._assemble(tau, f1, data.oMi[1].toDualActionMatrix())

    def motion(self, q_active: np.ndarray, v_lin: np.ndarray, a_lin: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint motion of one state: qd = J^-1 [v; 0], qdd = J^-1 ([a; 0] - Jdot qd).

        q_active (n_active,) rad; v_lin (3,) m/s; a_lin (3,) m/s^2. Returns full (q, qd, qdd).
        """
        q = self.arm.full_q(q_active)
        Jinv = np.linalg.inv(self.ee_jacobian(q))
        qd_a = Jinv @ np.concatenate([v_lin, np.zeros(3)])
        qd = self.arm.full_v(qd_a)
        qdd_a = Jinv @ (np.concatenate([a_lin, np.zeros(3)]) - self.drift(q, qd))
        return q, qd, self.arm.full_v(qdd_a)

    def coefficients(self, q_active: np.ndarray) -> Coefficients:
        """Exact polynomial form of the outputs over motion directions, for one configuration.

        With qd = v J^-1 [u; 0] and qdd = J^-1 ([a u; 0] - Jdot qd) for a unit direction u,
        and payload mass m, each output is exactly

            y(u, m) = c0 + a L u + v^2 sum_k Q_k phi_k(u) + m S (a u - g),
            phi(u) = [u0^2, u1^2, u2^2, u0 u1, u0 u2, u1 u2],

        because qdd is linear in u and the velocity terms (C(q, qd) qd, Jdot qd) are
        quadratic forms in qd. Q is obtained by polarisation of those quadratic forms.
        q_active (n_active,) rad. Returns the :class:`~capmap.core.coefficients.Coefficients` of this one
        configuration (no leading axis): c0 (n_out,), L (n_out, 3), Q (n_out, 6), S (n_out, 3), singular
        (numpy bool). For a batch, :meth:`capmap.core.batch_dynamics.BatchDynamics.coefficients`.
        """
        model, data, model_ng, data_ng = self.model, self.data, self.model_ng, self.data_ng
        q = self.arm.full_q(q_active)
        J = self.ee_jacobian(q)  # also places the joints (data.oMi)
        n_out = self.n_out
        try:
            Jinv = np.linalg.inv(J)
        except np.linalg.LinAlgError:
            Jinv = None
        if Jinv is None or np.abs(J).sum(0).max() * np.abs(Jinv).sum(0).max() > 1e12:  # 1-norm condition number
            z = np.zeros
            return Coefficients(c0=z(n_out), L=z((n_out, 3)), Q=z((n_out, 6)), S=z((n_out, 3)), singular=np.True_)
        A = np.array([self.arm.full_v(Jinv[:, i]) for i in range(3)])  # (3, nv) joint velocity per unit u_i
        X1 = data.oMi[1].toDualActionMatrix()
        p_ee = self._ee_position(data)
        zero = self._zero
        taus, f1s = [], []

        def record(res):
            taus.append(res[0])
            f1s.append(res[1])

        record(self._rnea(model, data, q, zero, zero))  # c0: gravity only
        for i in range(3):  # L: response to qdd = J^-1 e_i
            record(self._rnea(model_ng, data_ng, q, zero, A[i]))
        pairs = [(0,), (1,), (2,), (0, 1), (0, 2), (1, 2)]
        for idx in pairs:  # Z(w) = y(qd = w, qdd = -J^-1 Jdot w)
            w = A[list(idx)].sum(axis=0)
            qdd = self.arm.full_v(-Jinv @ self.drift(q, w))
            record(self._rnea(model_ng, data_ng, q, w, qdd))
        pin.forwardKinematics(model_ng, data_ng, q)
        for i in range(3):  # S: response to a unit force on the payload
            fext = self._payload_fext(data_ng, p_ee, np.eye(3)[i])
            record(self._rnea(model_ng, data_ng, q, zero, zero, fext))
        self._fext[self.ee_joint] = pin.Force.Zero()
        Y = self._assemble(np.array(taus), np.array(f1s), X1)  # (16, n_out)
        Zd, Zp = Y[4:7], Y[7:10]
        Q = np.concatenate([Zd, Zp - Zd[[0, 0, 1]] - Zd[[1, 2, 2]]], axis=0)
        return Coefficients(c0=Y[0], L=Y[1:4].T, Q=Q.T, S=Y[10:13].T, singular=np.False_)
