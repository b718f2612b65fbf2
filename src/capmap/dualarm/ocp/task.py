"""The assembly task as constraints on one node's configuration: what must hold where.

- closed chain (every node, 6): the right gripper's pose in the left gripper's frame stays as
  at the start, log6(M_rel_ref^-1 M_L^-1 M_R) = 0;
- transfer (nodes before ``n_transfer``, 2): the panel's z axis vertical, (R_P e_z)_xy = 0;
- pre-insertion (node ``n_transfer``, 6): log6(M_pre^-1 M_P) = 0;
- insertion (nodes after it, 5): the panel's centre on the insertion axis (its offsets along
  two directions across the axis) and its orientation fixed, log3(R_final^T R_P) = 0;
- terminal (node N, 6 + nv): log6(M_final^-1 M_P) = 0 and zero velocity.

Values and Jacobians (by q, world-aligned or local as each needs) come from a ``pin.Data``
with the frames placed and, for Jacobians, the joint Jacobians computed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

__all__ = ["AssemblyTask", "Constraint", "node_constraints"]

LOCAL, LWA = pin.ReferenceFrame.LOCAL, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class AssemblyTask:
    """N nodes (N + 1 states) dt s apart; the pre-insertion node; frame ids of the grippers and the
    panel; the closed chain's reference M_L^-1 M_R; the panel's pre-insertion and final poses;
    the insertion axis (a point, two unit directions across it); the panel's reference path
    (N + 1 poses) for the end-effector error cost."""

    N: int
    dt: float
    n_transfer: int
    left: int
    right: int
    panel: int
    rel_ref: pin.SE3
    pre: pin.SE3
    final: pin.SE3
    axis_point: np.ndarray
    axis_across: np.ndarray
    reference: tuple[pin.SE3, ...]


@dataclass(frozen=True)
class Constraint:
    """An equality block: name, value c (m,), Jacobian by q (m, nq) (None when not asked), and
    whether it constrains the velocity instead (c = v)."""

    name: str
    value: np.ndarray
    jac: np.ndarray | None
    on_velocity: bool = False


def _pose_error(model, data, fid: int, target: pin.SE3, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
    err = target.actInv(data.oMf[fid])
    value = pin.log6(err).vector
    if not jac:
        return value, None
    return value, pin.Jlog6(err) @ pin.getFrameJacobian(model, data, fid, LOCAL)


def node_constraints(task: AssemblyTask, k: int, model: pin.Model, data: pin.Data, v: np.ndarray,
                     jac: bool = False) -> list[Constraint]:
    """The equality constraints of node k (see the module docstring)."""
    out = []
    ML, MR = data.oMf[task.left], data.oMf[task.right]
    rel = ML.actInv(MR)
    err = task.rel_ref.actInv(rel)
    value = pin.log6(err).vector
    J = None
    if jac:
        JL = pin.getFrameJacobian(model, data, task.left, LOCAL)
        JR = pin.getFrameJacobian(model, data, task.right, LOCAL)
        J = pin.Jlog6(err) @ (JR - rel.inverse().toActionMatrix() @ JL)
    out.append(Constraint("closed_chain", value, J))
    MP = data.oMf[task.panel]
    if k < task.n_transfer:
        z = MP.rotation[:, 2]
        J = None
        if jac:
            Jw = pin.getFrameJacobian(model, data, task.panel, LWA)[3:]
            J = (-pin.skew(z) @ Jw)[:2]
        out.append(Constraint("vertical", z[:2].copy(), J))
    elif k == task.n_transfer:
        out.append(Constraint("pre_insertion", *_pose_error(model, data, task.panel, task.pre, jac)))
    elif k < task.N:
        d = MP.translation - task.axis_point
        J = pin.getFrameJacobian(model, data, task.panel, LWA)[:3] if jac else None
        out.append(Constraint("on_axis", task.axis_across @ d, None if J is None else task.axis_across @ J))
        errR = task.final.rotation.T @ MP.rotation
        value = pin.log3(errR)
        J = pin.Jlog3(errR) @ pin.getFrameJacobian(model, data, task.panel, LOCAL)[3:] if jac else None
        out.append(Constraint("orientation", value, J))
    else:
        out.append(Constraint("final", *_pose_error(model, data, task.panel, task.final, jac)))
        out.append(Constraint("rest", np.asarray(v, dtype=float).copy(), None, on_velocity=True))
    return out
