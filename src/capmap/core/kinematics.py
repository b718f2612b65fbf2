"""Batched kinematics of a serial revolute chain in product form.

A chain with n revolute joints is written

    T(theta) = X[0] Rz(theta_1) X[1] Rz(theta_2) ... Rz(theta_n) X[n]

with fixed 4x4 transforms X (every joint turned to rotate about its own z). This is
the form the closed-form IK works on; it is extracted from any serial Pinocchio model
whose joints are 1-DOF revolute (RX, RY, RZ or unaligned), so DH and URDF arms alike.
All functions batch on the leading axis: theta (N, n) rad -> poses (N, 4, 4) m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from capmap.errors import CapmapError

__all__ = ["rotation_from_rpy", "Chain", "inverse_transform", "rotation_log", "pose_error", "align_z", "FLIP_Z"]


def align_z(axis: np.ndarray) -> np.ndarray:
    """A rotation R with R e_z = axis (unit)."""
    z = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _homogeneous(R: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = R
    if t is not None:
        T[:3, 3] = t
    return T


def inverse_transform(T: np.ndarray) -> np.ndarray:
    """Inverse of homogeneous transforms (..., 4, 4)."""
    R = T[..., :3, :3]
    Rt = np.swapaxes(R, -1, -2)
    out = np.zeros_like(T)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, T[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def _joint_axis(jmodel) -> np.ndarray:
    name = jmodel.shortname()
    fixed = {"JointModelRX": [1.0, 0, 0], "JointModelRY": [0, 1.0, 0], "JointModelRZ": [0, 0, 1.0]}
    if name in fixed:
        return np.array(fixed[name])
    if name == "JointModelRevoluteUnaligned":
        return np.asarray(jmodel.extract().axis, dtype=float)
    raise CapmapError(f"joint type {name} is not a 1-DOF revolute joint; closed-chain IK needs revolute joints")


FLIP_Z = np.diag([1.0, -1.0, -1.0, 1.0])  # Rx(pi): turns a joint's z axis over (its own inverse)


@dataclass(frozen=True)
class Chain:
    """Serial revolute chain ``T = X[0] Rz(q1) X[1] ... Rz(qn) X[n]``; X: (n+1, 4, 4)."""

    X: np.ndarray

    @property
    def n(self) -> int:
        return len(self.X) - 1

    @classmethod
    def from_model(cls, model: pin.Model, frame_id: int) -> "Chain":
        """Chain from base to ``frame_id`` of a serial Pinocchio model of 1-DOF revolute joints."""
        for j in range(1, model.njoints):
            if model.parents[j] != j - 1:
                raise CapmapError("the robot is not a serial chain (a joint's parent is not the previous joint)")
        frame = model.frames[frame_id]
        if frame.parentJoint != model.njoints - 1:
            raise CapmapError(f"frame {frame.name!r} is not on the last joint of the chain")
        X = []
        prev_align = np.eye(3)
        for j in range(1, model.njoints):
            align = align_z(_joint_axis(model.joints[j]))
            M = model.jointPlacements[j].homogeneous
            X.append(_homogeneous(prev_align.T) @ M @ _homogeneous(align))
            prev_align = align
        X.append(_homogeneous(prev_align.T) @ frame.placement.homogeneous)
        return cls(np.array(X))

    def reversed(self) -> "Chain":
        """Chain of the inverse transform: T(theta)^-1 = chain'(-theta[::-1])."""
        return Chain(inverse_transform(self.X[::-1]))

    def inverted(self) -> "Chain":
        """Chain of the inverse transform in the same joint angles, joints in reverse order:
        T(theta)^-1 = inverted().fk(theta[::-1]). (Rz(-q) = F Rz(q) F^-1 with F = Rx(pi), so
        each joint of :meth:`reversed` is turned over to take +q.)"""
        X = inverse_transform(self.X[::-1]).copy()
        X[:-1] = X[:-1] @ FLIP_Z
        X[1:] = FLIP_Z @ X[1:]  # F^-1 = F
        return Chain(X)

    def then(self, other: "Chain") -> "Chain":
        """The chain ``self`` followed by ``other`` (other's base at self's tip); joints concatenated."""
        X = np.concatenate([self.X[:-1], (self.X[-1] @ other.X[0])[None], other.X[1:]])
        return Chain(X)

    @classmethod
    def fixed(cls, T: np.ndarray) -> "Chain":
        """A chain with no joint: the fixed transform T (4, 4)."""
        return cls(np.asarray(T, dtype=float)[None].copy())

    def _frames(self, theta: np.ndarray):
        """Yield the frame before each joint's rotation (..., 4, 4), then the tip pose."""
        T = np.broadcast_to(self.X[0], theta.shape[:-1] + (4, 4)).copy()
        for k in range(self.n):
            yield T
            T = T.copy()  # the yielded frame stays intact
            c, s = np.cos(theta[..., k])[..., None], np.sin(theta[..., k])[..., None]
            c0, c1 = T[..., :, 0].copy(), T[..., :, 1].copy()
            T[..., :, 0] = c * c0 + s * c1  # T @ Rz(theta_k) mixes only columns 0 and 1
            T[..., :, 1] = c * c1 - s * c0
            T = T @ self.X[k + 1]
        yield T

    def fk(self, theta: np.ndarray) -> np.ndarray:
        """Poses (N, 4, 4) for joint angles theta (N, n) rad."""
        *_, T = self._frames(np.atleast_2d(theta))
        return T

    def jacobian(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Geometric Jacobian at the chain tip in world-aligned axes.

        Returns (pose (N, 4, 4), J (N, 6, n)) with rows [linear velocity; angular velocity].
        """
        *joints, T = self._frames(np.atleast_2d(theta))
        z = np.stack([F[..., :3, 2] for F in joints], axis=-1)  # (N, 3, n) joint axes
        o = np.stack([F[..., :3, 3] for F in joints], axis=-1)  # points on them
        Jv = np.cross(z, T[..., :3, 3][..., None] - o, axis=-2)
        return T, np.concatenate([Jv, z], axis=-2)

    def jacobian_derivatives(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The geometric Jacobian and its derivatives by every joint angle.

        Returns (pose (N, 4, 4), J (N, 6, n), dJ (N, n, 6, n)) with dJ[:, i] = dJ / dtheta_i. For
        the world-aligned Jacobian at the tip p (column j = [z_j x (p - o_j); z_j]) a turn of
        joint i rotates everything outboard of it about z_i, so with r_j = p - o_j

            i <= j:  d[z_j x r_j] = (z_i x z_j) x r_j + z_j x (z_i x r_j),   d z_j = z_i x z_j
            i >  j:  d[z_j x r_j] = z_j x (z_i x r_i),                         d z_j = 0.
        """
        *joints, T = self._frames(np.atleast_2d(theta))
        z = np.stack([F[..., :3, 2] for F in joints], axis=-1)  # (N, 3, n)
        r = T[..., :3, 3][..., None] - np.stack([F[..., :3, 3] for F in joints], axis=-1)  # (N, 3, n)
        Jv = _cross1(z, r)
        zi, zj = z[..., :, None], z[..., None, :]  # (N, 3, n_i, 1), (N, 3, 1, n_j)
        zz = _cross1(zi, zj)  # z_i x z_j, (N, 3, n, n)
        after = _cross1(zz, r[..., None, :]) + _cross1(zj, _cross1(zi, r[..., None, :]))
        before = _cross1(zj, Jv[..., :, None])  # z_j x (z_i x r_i)
        upper = np.triu(np.ones((z.shape[-1],) * 2, dtype=bool))  # [i, j]: i <= j
        dJv = np.where(upper, after, before)
        dJw = np.where(upper, zz, 0.0)
        dJ = np.moveaxis(np.concatenate([dJv, dJw], axis=1), 2, 1)  # (N, n_i, 6, n_j)
        return T, np.concatenate([Jv, z], axis=-2), dJ


def _cross1(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b with the vectors on axis 1 of (N, 3, ...) arrays (broadcast); faster than np.cross(axis=1)."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


def rotation_from_rpy(rpy_deg) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) (3, 3) from [roll, pitch, yaw] deg."""
    return pin.rpy.rpyToMatrix(*np.deg2rad(np.asarray(rpy_deg, dtype=float)))


def rotation_log(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3) of rotation matrices (..., 3, 3) (robust near pi)."""
    cos = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1) / 2, -1.0, 1.0)
    angle = np.arccos(cos)
    w = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    sin = np.sin(angle)
    small = sin < 1e-6
    scale = np.where(small, 0.5 + angle**2 / 12, angle / (2 * np.where(small, 1, sin)))
    out = w * scale[..., None]
    # near pi the antisymmetric part vanishes: use the symmetric part
    near_pi = angle > np.pi - 1e-4
    if np.any(near_pi):
        Rn, cn = R[near_pi], cos[near_pi][..., None, None]
        nnT = ((Rn + np.swapaxes(Rn, -1, -2)) / 2 - cn * np.eye(3)) / (1 - cn)  # R_sym = cI + (1-c) n n^T
        col = np.argmax(np.diagonal(nnT, axis1=-2, axis2=-1), axis=-1)
        axis = nnT[np.arange(len(Rn)), :, col]
        axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
        sign = np.sign(np.einsum("...i,...i->...", axis, w[near_pi]))
        sign[sign == 0] = 1
        out[near_pi] = axis * (angle[near_pi] * sign)[..., None]
    return out


def pose_error(T: np.ndarray, T_target: np.ndarray) -> np.ndarray:
    """World-frame error [p_target - p; log(R_target R^T)] (..., 6)."""
    dp = T_target[..., :3, 3] - T[..., :3, 3]
    dR = T_target[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)
    return np.concatenate([dp, rotation_log(dR)], axis=-1)
