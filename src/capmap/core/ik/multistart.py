"""Numerical inverse kinematics: damped Newton steps on the pose error (polishing, path
following) and the multi-start fallback for chains without a closed-form or semi-analytical
solver (exact solutions, but branches may be missed)."""

from __future__ import annotations

import numpy as np

from capmap.core.ik.finish import POLISHED
from capmap.core.ik.polish import PolishSettings, polish
from capmap.core.kinematics import Chain, pose_error

__all__ = ["newton", "multi_start"]


def newton(chain: Chain, theta: np.ndarray, T_target: np.ndarray, iters: int, damping: float = 0.0) -> np.ndarray:
    """Damped Newton steps on the pose error; theta (M, n), T_target (M, 4, 4)."""
    eye = np.eye(6)
    for _ in range(iters):
        T, J = chain.jacobian(theta)
        err = pose_error(T, T_target)
        JJt = J @ np.swapaxes(J, -1, -2) + damping**2 * eye
        try:
            step = np.einsum("mji,mj->mi", J, np.linalg.solve(JJt, err[..., None])[..., 0])
        except np.linalg.LinAlgError:
            step = np.einsum("mji,mj->mi", J, (np.linalg.pinv(JJt) @ err[..., None])[..., 0])
        theta = theta + np.clip(step, -0.5, 0.5)
    return theta


def _halton(n: int, d: int) -> np.ndarray:
    """The first n points (n, d) of the Halton sequence in [0, 1)^d (bases: the first d primes)."""
    primes = [p for p in range(2, 200) if all(p % q for q in range(2, int(p**0.5) + 1))][:d]
    out = np.zeros((n, d))
    for j, b in enumerate(primes):
        i = np.arange(1, n + 1)
        f = 1.0
        while np.any(i > 0):
            f /= b
            out[:, j] += f * (i % b)
            i //= b
    return out


def multi_start(chain: Chain, T_target: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                n_starts: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Multi-start Newton from a deterministic Halton set of starts: 40 damped steps (1e-2) then 5
    undamped, each joint's step clipped to 0.5 rad, compiled (:func:`capmap.core.ik.polish.polish`,
    stopping at rounding level; a start whose undamped J J^T is exactly singular stops there, where
    numpy's version took a pseudo-inverse step): (N, n_starts, n) rad."""
    N, n = len(T_target), chain.n
    starts = lower + (upper - lower) * _halton(n_starts, n)
    theta = np.broadcast_to(starts, (N, n_starts, n)).reshape(-1, n).copy()
    which = np.repeat(np.arange(N), n_starts)
    targets = np.ascontiguousarray(T_target, dtype=float)
    theta, _ = polish(chain.X, theta, targets, which, PolishSettings(40, POLISHED, give_up=np.inf, damping=1e-2))
    theta, _ = polish(chain.X, theta, targets, which, PolishSettings(5, POLISHED, give_up=np.inf))
    return theta.reshape(N, n_starts, n), np.ones((N, n_starts), dtype=bool)
