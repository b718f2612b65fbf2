"""The one type of the exact capacity coefficients of a locked arm.

For a configuration, a unit motion direction u (3,), speed v (m/s), acceleration a (m/s^2) and
payload mass m (kg), each constrained output (``capmap.core.dynamics.output_names``: active joint
torques N m, base force N, base moment N m) is exactly

    y(u, m) = c0 + a L u + v^2 Q phi(u) + m S (a u - g),
    phi(u) = [u0^2, u1^2, u2^2, u0 u1, u0 u2, u1 u2]

(see :meth:`capmap.core.dynamics.ArmDynamics.coefficients`). :class:`Coefficients` holds c0, L, Q,
S and the singular flag for one configuration (no leading axis: what ``ArmDynamics.coefficients``
returns) or a batch of B configurations on the leading axis (what
:meth:`capmap.core.batch_dynamics.BatchDynamics.coefficients` and
:func:`capmap.capacity.engine.coefficients` return). A singular configuration (Jacobian not
invertible, or 1-norm condition number > 1e12) has all coefficients zero and ``singular`` True.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Coefficients"]


@dataclass(frozen=True)
class Coefficients:
    """Exact polynomial coefficients of the constrained outputs over motion directions.

    Shapes, with ``...`` empty (one configuration) or (B,) (a batch):

    - c0 (..., n_out): the outputs at rest (gravity only), in the outputs' units (N m, N);
    - L (..., n_out, 3): per unit linear end-effector acceleration along each base axis, per m/s^2;
    - Q (..., n_out, 6): per v^2 (m^2/s^2), on the quadratic features phi(u);
    - S (..., n_out, 3): per kg of payload and per m/s^2 of (a u - g), the payload's reaction;
    - singular (...,) bool: the configuration is singular (its coefficients are all zero).
    """

    c0: np.ndarray
    L: np.ndarray
    Q: np.ndarray
    S: np.ndarray
    singular: np.ndarray
    joined: np.ndarray | None = field(default=None, repr=False, compare=False)  # [c0, L, Q] when they are its views

    @classmethod
    def from_stacked(cls, C: np.ndarray, S: np.ndarray, singular: np.ndarray) -> "Coefficients":
        """c0, L and Q as views of C (..., n_out, 10) = [c0, L, Q] (what :meth:`stacked` then returns, not
        copied)."""
        return cls(C[..., 0], C[..., 1:4], C[..., 4:], S, singular, C)

    def stacked(self) -> np.ndarray:
        """[c0, L, Q] (..., n_out, 10): the outputs at rest are ``stacked() @ motion_features(u, motion).T``
        (:func:`capmap.capacity.engine.motion_features`). Not to be written to (it may be c0, L and Q's own
        memory)."""
        if self.joined is not None:
            return self.joined
        return np.concatenate([self.c0[..., None], self.L, self.Q], axis=-1)

    def take(self, rows: np.ndarray) -> "Coefficients":
        """The configurations ``rows`` (M,) of a batch (indices or a mask on the leading axis)."""
        if self.joined is not None:
            return Coefficients.from_stacked(self.joined[rows], self.S[rows], self.singular[rows])
        return Coefficients(*(getattr(self, name)[rows] for name in _PARTS))

    @classmethod
    def empty(cls, n_out: int) -> "Coefficients":
        """A batch of no configurations (B = 0) with n_out outputs."""
        return cls(np.zeros((0, n_out)), np.zeros((0, n_out, 3)), np.zeros((0, n_out, 6)), np.zeros((0, n_out, 3)),
                   np.zeros(0, dtype=bool))

    @classmethod
    def stack(cls, rows: list["Coefficients"]) -> "Coefficients":
        """One batch (B = len(rows)) from per-configuration coefficients (no leading axis)."""
        return cls(*(np.array([getattr(r, name) for r in rows]) for name in _PARTS))


_PARTS = ("c0", "L", "Q", "S", "singular")
