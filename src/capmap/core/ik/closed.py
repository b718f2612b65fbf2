"""The closed-form inverse kinematics (see :mod:`capmap.core.ik`, steps 1-3) of a chain of the shape
``0 | 1 2 3 parallel | 4 5 intersecting``: up to 8 raw branches per target, batched over targets
(numpy over the leading axis), derived from the chain's own fixed transforms."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from capmap.core.kinematics import Chain, inverse_transform

__all__ = ["branches", "flags"]


def _trig_roots(A, B, C):
    """Both roots of A cos x + B sin x = C: (..., 2) angles and validity."""
    rho = np.hypot(A, B)
    ratio = C / np.where(rho > 0, rho, 1.0)
    ok = (rho > 1e-12) & (np.abs(ratio) <= 1 + 1e-10)
    phi = np.arctan2(B, A)
    delta = np.arccos(np.clip(ratio, -1.0, 1.0))
    roots = np.stack([phi + delta, phi - delta], axis=-1)
    return roots, np.stack([ok, ok], axis=-1)


def _rz(theta):
    """Rotation matrices about z, (..., 3, 3)."""
    c, s = np.cos(theta), np.sin(theta)
    R = np.zeros(np.shape(theta) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, -s, s, c, 1.0
    return R


def _rz4(theta):
    T = np.zeros(np.shape(theta) + (4, 4))
    T[..., :3, :3] = _rz(theta)
    T[..., 3, 3] = 1.0
    return T


class _Constants(NamedTuple):
    """The chain's fixed quantities the closed form uses (see :func:`branches`)."""

    s_star: float
    w3: np.ndarray
    h: float
    n1: np.ndarray
    t1: np.ndarray
    sigma: float
    a: np.ndarray
    d5: np.ndarray
    p_: np.ndarray
    u1: np.ndarray
    u2: np.ndarray


def _constants(chain: Chain) -> _Constants:
    X = chain.X
    p5, d5 = X[5][:3, 3], X[5][:3, 2]
    s_star = -(p5[:2] @ d5[:2]) / (d5[:2] @ d5[:2])  # axis 5 meets axis 4 at (0, 0, s*) in frame 5
    w3 = (X[4] @ np.array([0, 0, p5[2] + s_star * d5[2], 1.0]))[:3]  # that point, in link 3
    h = (X[2] @ X[3] @ np.append(w3, 1.0))[2]  # its coordinate along the parallel axes
    R2, t2, t3 = X[2][:3, :3], X[2][:3, 3], X[3][:3, 3]
    return _Constants(s_star=s_star, w3=w3, h=h, n1=X[1][:3, 2], t1=X[1][:3, 3],
                      sigma=(X[2][:3, :3] @ X[3][:3, :3])[2, 2], a=X[4][2, :3], d5=d5,
                      p_=t2 + R2 @ np.array([0, 0, t3[2]]), u1=R2 @ np.array([t3[0], t3[1], 0]),
                      u2=R2 @ np.array([-t3[1], t3[0], 0]))


def _wrist_point(chain: Chain, c: _Constants, T: np.ndarray) -> np.ndarray:
    """(N, 3): the point where axes 4 and 5 meet, in the frame X[0] (before joint 0's rotation), for
    end poses T (N, 4, 4)."""
    w = (T @ (inverse_transform(chain.X[6]) @ np.array([0, 0, c.s_star, 1.0])))[:, :3]
    return (inverse_transform(chain.X[0]) @ np.concatenate([w, np.ones((len(w), 1))], 1).T).T[:, :3]


def _coefficients(c: _Constants, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float, float, float]:
    """A, B of the three trigonometric equations A cos x + B sin x = C the branches choose between:
    joint 0 (from the wrist point r (N, 3)), joint 4 and joint 2 (constants)."""
    A0 = c.n1[0] * r[:, 0] + c.n1[1] * r[:, 1]
    B0 = c.n1[0] * r[:, 1] - c.n1[1] * r[:, 0]
    A4 = c.d5[0] * c.a[0] + c.d5[1] * c.a[1]
    B4 = c.d5[0] * c.a[1] - c.d5[1] * c.a[0]
    return A0, B0, A4, B4, 2 * c.p_[:2] @ c.u1[:2], 2 * c.p_[:2] @ c.u2[:2]


def flags(chain: Chain, theta: np.ndarray) -> np.ndarray:
    """(M, 3) float: for configurations theta (M, 6) rad of a ``closed_form_shape`` chain, the values
    B cos x - A sin x of the equations for joints 0, 2 and 4 (shoulder, elbow, wrist) at the
    configuration's own x. Their signs are the branch choices of :func:`branches` (x = phi -+ delta:
    + / -); each vanishes exactly where its two roots merge, a fold of the IK map, i.e. a singular
    configuration, so each sign is constant between singular surfaces."""
    c = _constants(chain)
    theta = np.asarray(theta, dtype=float)
    A0, B0, A4, B4, A2, B2 = _coefficients(c, _wrist_point(chain, c, chain.fk(theta)))
    q0, q2, q4 = theta[:, 0], theta[:, 2], theta[:, 4]
    return np.stack([B0 * np.cos(q0) - A0 * np.sin(q0), B2 * np.cos(q2) - A2 * np.sin(q2),
                     B4 * np.cos(q4) - A4 * np.sin(q4)], axis=1)


def branches(chain: Chain, T_target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Raw branches (N, 8, 6) rad and their validity (N, 8) for a ``closed_form_shape`` chain and
    targets T_target (N, 4, 4) (before polishing, range and duplicate checks). Branch k = 4 i + 2 j + l
    takes the root phi + delta (i, j, l = 0: :func:`flags` < 0) or phi - delta (1: > 0) of the
    equations of joints 0, 4 and 2."""
    X = chain.X
    N = len(T_target)
    c = _constants(chain)
    s_star, w3, h, n1, t1, sigma, a, d5, p_, u1, u2 = c
    R2, R4, R5 = X[2][:3, :3], X[4][:3, :3], X[5][:3, :3]
    # -- 1. joint 0 from the coordinate of w along n
    w = (T_target @ (inverse_transform(X[6]) @ np.array([0, 0, s_star, 1.0])))[:, :3]  # (N, 3)
    r = _wrist_point(chain, c, T_target)
    A0, B0, A4, B4, A2, B2 = _coefficients(c, r)
    C0 = h + n1 @ t1 - n1[2] * r[:, 2]
    q0, ok0 = _trig_roots(A0, B0, C0)  # (N, 2)
    P1 = X[0] @ _rz4(q0) @ X[1]  # (N, 2, 4, 4) frame of joint 1 before its rotation
    # -- 2. joints 4, 5 from the orientation: n maps to the target through them
    W = np.swapaxes(P1[..., :3, :3], -1, -2) @ T_target[:, None, :3, :3] @ X[6][:3, :3].T  # (N, 2, 3, 3)
    b = sigma * W[..., 2, :]  # (N, 2, 3)
    C4 = b[..., 2] - d5[2] * a[2]
    q4, ok4 = _trig_roots(np.full_like(C4, A4), np.full_like(C4, B4), C4)  # (N, 2, 2)
    v = np.einsum("ji,...jk,k->...i", R5, _rz(-q4), a)  # R5^T Rz(-q4) a, (N, 2, 2, 3)
    q5 = np.arctan2(v[..., 1], v[..., 0]) - np.arctan2(b[..., None, 1], b[..., None, 0])
    ok45 = ok4 & (np.hypot(b[..., 0], b[..., 1]) > 1e-12)[..., None]
    # -- 3. planar group: rotation Rg and point w known
    Rg = W[:, :, None] @ _rz(-q5) @ R5.T @ _rz(-q4) @ R4.T  # (N, 2, 2, 3, 3)
    w_P1 = np.einsum("...ij,...j->...i", inverse_transform(P1), np.concatenate([w, np.ones((N, 1))], 1)[:, None])[..., :3]
    e = w_P1[:, :, None] - Rg @ w3  # (N, 2, 2, 3)
    C2 = e[..., 0] ** 2 + e[..., 1] ** 2 - p_[:2] @ p_[:2] - u1[:2] @ u1[:2]
    q2, ok2 = _trig_roots(np.full_like(C2, A2), np.full_like(C2, B2), C2)  # (N, 2, 2, 2)
    k = p_ + np.cos(q2)[..., None] * u1 + np.sin(q2)[..., None] * u2  # (N, 2, 2, 2, 3)
    q1 = np.arctan2(e[..., None, 1], e[..., None, 0]) - np.arctan2(k[..., 1], k[..., 0])
    M = np.swapaxes(_rz(q1) @ R2 @ _rz(q2) @ X[3][:3, :3], -1, -2) @ Rg[..., None, :, :]
    q3 = np.arctan2(M[..., 1, 0], M[..., 0, 0])
    shape = q2.shape
    theta = np.stack([np.broadcast_to(q0[:, :, None, None], shape), q1, q2, q3,
                      np.broadcast_to(q4[..., None], shape), np.broadcast_to(q5[..., None], shape)], axis=-1)
    ok = ok0[:, :, None, None] & ok45[..., None] & ok2
    return theta.reshape(N, 8, 6), ok.reshape(N, 8)
