"""The common end of every IK method (see :mod:`capmap.core.ik`): candidates polished by Newton
steps, checked by forward kinematics, put inside the joint ranges and de-duplicated."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.core.ik.polish import PolishSettings, distinct, polish
from capmap.core.kinematics import Chain

__all__ = ["IKSolutions", "wrap_to_range", "RESIDUAL_TOL", "POLISHED", "DUPLICATE_TOL"]

RESIDUAL_TOL = 1e-9  # m and rad
POLISHED = 1e-13  # m, rad: candidates with a larger residual get Newton steps
DUPLICATE_TOL = 1e-6  # rad: two solutions closer than this (wrapped) are one


@dataclass(frozen=True)
class IKSolutions:
    """Solutions for N targets; ``q`` is NaN beyond ``n_solutions`` in each row.

    q: (N, K, n) rad (active joints of the locked arm), n_solutions: (N,) int, method: str.
    """

    q: np.ndarray
    n_solutions: np.ndarray
    method: str


def wrap_to_range(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shift angles by multiples of 2 pi into [lower, upper]; (theta', inside) elementwise.

    Among the representatives inside the range the one nearest 0 is taken (a joint with a
    range wider than 360 deg has further solutions 2 pi apart that are not listed).
    """
    base = np.mod(theta + np.pi, 2 * np.pi) - np.pi  # (-pi, pi]
    best = np.full_like(theta, np.nan)
    for k in (0, -1, 1, -2, 2):
        cand = base + 2 * np.pi * k
        inside = (cand >= lower - 1e-12) & (cand <= upper + 1e-12)
        take = inside & (np.isnan(best) | (np.abs(cand) < np.abs(best)))
        best = np.where(take, np.clip(cand, lower, upper), best)
    return best, ~np.isnan(best)


def _finish(chain: Chain, theta: np.ndarray, ok: np.ndarray, T_target: np.ndarray,
            lower: np.ndarray, upper: np.ndarray, tol: float, method: str, polish_steps: int = 2) -> IKSolutions:
    N, K, n = theta.shape
    flat = np.where(ok[..., None], theta, 0.0).reshape(-1, n)
    # Newton steps (``polish``, compiled) for the candidates not already at rounding level, their residuals
    idx = np.flatnonzero(ok.reshape(-1) & np.all(np.isfinite(flat), axis=1))
    flat[idx], err = polish(chain.X, flat[idx], T_target, idx // K, PolishSettings(polish_steps, POLISHED))
    wrapped, inside = wrap_to_range(flat[idx], lower, upper)
    good = np.zeros(N * K, dtype=bool)
    good[idx] = ((np.linalg.norm(err[:, :3], axis=1) <= tol) & (np.linalg.norm(err[:, 3:], axis=1) <= tol)
                 & np.all(np.isfinite(flat[idx]), axis=1) & np.all(inside, axis=1))
    flat[idx] = wrapped
    wrapped, good = flat.reshape(N, K, n), good.reshape(N, K)
    q, count = distinct(wrapped, good, DUPLICATE_TOL)  # a solution repeating an earlier good one is dropped
    width = K if method.startswith("closed_form") else max(int(count.max(initial=0)), 1)
    return IKSolutions(q=q[:, :width], n_solutions=count, method=method)
