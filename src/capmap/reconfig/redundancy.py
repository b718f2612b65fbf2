"""Redundancy resolution quantities of a chain at one configuration: the Jacobian, its
pseudo-inverse, Yoshikawa's manipulability and its exact gradient, the null-space projection.

For a task Jacobian J (r x n, r <= n, rows chosen from [v; omega]) of full row rank,
m = sqrt(det(J J^T)) = prod of the singular values, and (Jacobi's formula with
J^+ = J^T (J J^T)^-1)

    dm / dq_i = m trace(J^+ dJ/dq_i),

with dJ/dq_i exact from the chain's twists (:meth:`capmap.core.kinematics.Chain.jacobian_derivatives`).
The null-space projector is N = I - J^+ J; N grad m is the steepest ascent of m among the
joint motions that leave the task still.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.core.kinematics import Chain

__all__ = ["Redundancy", "evaluate"]


@dataclass(frozen=True)
class Redundancy:
    """At one configuration: pose (4, 4) of the tip, J (r, n), pinv (n, r), singular values (r,),
    m, grad (n,) = dm/dq, null_grad (n,) = N grad."""

    pose: np.ndarray
    J: np.ndarray
    pinv: np.ndarray
    singular_values: np.ndarray
    m: float
    grad: np.ndarray
    null_grad: np.ndarray

    def null(self, k: np.ndarray) -> np.ndarray:
        """N k = k - J^+ (J k) for joint vectors k (..., n)."""
        return k - (self.pinv @ (self.J @ np.asarray(k).T)).T


def evaluate(chain: Chain, q: np.ndarray, rows: np.ndarray | None = None) -> Redundancy:
    """The quantities at joint angles q (n,) rad for the task rows ``rows`` of [v; omega]
    (default all six: the tip's full twist)."""
    T, J, dJ = chain.jacobian_derivatives(np.asarray(q, dtype=float)[None])
    T, J, dJ = T[0], J[0], dJ[0]
    if rows is not None:
        J, dJ = J[rows], dJ[:, rows]
    U, sv, Vt = np.linalg.svd(J, full_matrices=False)
    pinv = Vt.T @ (U.T / sv[:, None])
    m = float(np.prod(sv))
    grad = m * np.einsum("jk,ikj->i", pinv, dJ)  # m trace(J^+ dJ_i)
    null_grad = grad - pinv @ (J @ grad)
    return Redundancy(T, J, pinv, sv, m, grad, null_grad)
