"""The common end of every IK method (see :mod:`capmap.core.ik`): candidates polished by Newton
steps, checked by forward kinematics, put inside the joint ranges and de-duplicated."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.core.ik_numeric import newton
from capmap.core.kinematics import Chain, pose_error

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
            lower: np.ndarray, upper: np.ndarray, tol: float, method: str, polish: int = 2) -> IKSolutions:
    N, K, n = theta.shape
    flat = np.where(ok[..., None], theta, 0.0).reshape(-1, n)
    # residuals of the candidates; Newton steps (``polish``) polish those not already at rounding level
    idx = np.flatnonzero(ok.reshape(-1) & np.all(np.isfinite(flat), axis=1))
    target = T_target[idx // K]
    err = pose_error(chain.fk(flat[idx]), target)
    rough = np.flatnonzero(np.abs(err).max(axis=1, initial=0.0) > POLISHED)
    if len(rough):
        flat[idx[rough]] = newton(chain, flat[idx[rough]], target[rough], iters=min(polish, 2))
        err[rough] = pose_error(chain.fk(flat[idx[rough]]), target[rough])
    for _ in range(polish - 2):  # further steps only for what has not converged, while it still converges
        e = np.abs(err).max(axis=1, initial=0.0)
        rough = np.flatnonzero((e > POLISHED) & (e < 0.1))
        if not len(rough):
            break
        flat[idx[rough]] = newton(chain, flat[idx[rough]], target[rough], iters=1)
        err[rough] = pose_error(chain.fk(flat[idx[rough]]), target[rough])
    good = np.zeros(N * K, dtype=bool)
    good[idx] = ((np.linalg.norm(err[:, :3], axis=1) <= tol) & (np.linalg.norm(err[:, 3:], axis=1) <= tol)
                 & np.all(np.isfinite(flat[idx]), axis=1))
    wrapped, inside = wrap_to_range(flat, lower, upper)
    good &= np.all(inside, axis=1) & ok.reshape(-1)
    wrapped = wrapped.reshape(N, K, n)
    good = good.reshape(N, K)
    # the good candidates first (their order kept), then de-duplicate: solution j repeats an earlier good i
    # when all wrapped differences are tiny
    first = np.argsort(~good, axis=1, kind="stable")
    Kg = max(int(good.sum(axis=1).max(initial=0)), 1)
    wrapped = np.take_along_axis(wrapped, first[..., None], axis=1)[:, :Kg]
    good = np.take_along_axis(good, first, axis=1)[:, :Kg]
    diff = wrapped[:, :, None, :] - wrapped[:, None, :, :]
    same = np.all(np.abs(np.mod(diff + np.pi, 2 * np.pi) - np.pi) < DUPLICATE_TOL, axis=-1)  # (N, Kg, Kg)
    earlier = np.tril(np.ones((Kg, Kg), dtype=bool), -1)  # [j, i]: i < j
    dup = np.any(same & earlier & good[:, None, :], axis=-1)
    keep = good & ~dup
    order = np.argsort(~keep, axis=1, kind="stable")
    q = np.full((N, max(K, Kg), n), np.nan)
    q[:, :Kg] = np.take_along_axis(wrapped, order[..., None], axis=1)
    count = keep.sum(axis=1)
    q[np.arange(q.shape[1])[None, :] >= count[:, None]] = np.nan
    width = K if method.startswith("closed_form") else max(int(count.max(initial=0)), 1)
    return IKSolutions(q=q[:, :width], n_solutions=count, method=method)
