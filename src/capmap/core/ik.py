"""All inverse-kinematics branches of a locked 6-joint arm, batched over target poses.

Closed form (complete, up to 8 branches) for chains of the shape

    joint 0 | joints 1, 2, 3 with parallel axes | joints 4, 5 with intersecting axes

(the SSRMS-type arm with joint 1, 2, 6 or 7 locked; UR-type arms), and for the same
shape reversed (solved on the inverse chain). It is derived from the chain's own fixed
transforms, so it does not assume any particular link lengths:

1. The point w where axes 4 and 5 meet is known from the target and is fixed in the
   link of joint 3. Its coordinate along the parallel-axis direction n is constant,
   and n depends on joint 0 only: ``A cos q0 + B sin q0 = C`` -> two q0.
2. n must map onto the target's frame through joints 4, 5 (a vector equation:
   Paden-Kahan subproblem 2) -> two q4, then q5.
3. The parallel group is a planar 3R with known end rotation and known point w:
   law of cosines -> two q2, then q1 and q3.

Semi-analytical (complete) for chains of the shape

    joint 0 | joint 1 | joints 2, 3 with parallel axes | joints 4, 5 with intersecting axes

(the SSRMS-type arm with joint 3, 4 or 5 locked: two parallel joints left), and reversed:
a 1-D search over joint 0 (Xu, She, Xu, Acta Astronautica 105, 2014). For a fixed q0 steps
1-3 above give joints 1, 4, 5 in closed form (2 x 2 branches) and leave the planar 2R group
one condition too many: the wrist point must lie at the 2R's reach, a residual f(q0) in
metres that is continuous along each branch. Its roots are bracketed on a fine periodic grid
(``SEARCH_STEPS`` over 360 deg; where a branch ends, the interval is subdivided and finally
closed at the end point found by bisection, so roots next to the fold are kept), refined by
Illinois false position and polished by Newton on the full pose. Two roots closer than a
grid step leave no sign change, and f can swing steeply near a wrist singularity: every
interval whose end values are small against the local change of f is subdivided (8 x, up
to 4 levels), and what stays suspect at the finest level is a Newton start (a double
root). Every root returned is an exact solution.

Every solution is polished by two Newton steps, checked by forward kinematics
(position and orientation residual <= ``tol``), put inside the joint ranges and
de-duplicated. Other chain shapes use a multi-start Newton solver (a deterministic Halton
set of starts): found solutions are exact, but completeness is not guaranteed (a
warning is logged once per chain).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from capmap.core import ik_semi
from capmap.core.ik_numeric import multi_start, newton
from capmap.core.kinematics import Chain, inverse_transform, pose_error
from capmap.core.reduction import LockedArm

__all__ = ["IKSolutions", "solve", "newton", "wrap_to_range", "method_for", "closed_form_shape",
           "semi_analytic_shape", "COMPLETE_METHODS", "RESIDUAL_TOL", "SEARCH_STEPS"]

log = logging.getLogger(__name__)

RESIDUAL_TOL = 1e-9  # m and rad
POLISHED = 1e-13  # m, rad: candidates with a larger residual get two Newton steps
DUPLICATE_TOL = 1e-6  # rad: two solutions closer than this (wrapped) are one
_GEOM_TOL = 1e-9
COMPLETE_METHODS = ("closed_form", "closed_form_reversed", "semi_analytic", "semi_analytic_reversed")
_CHUNK_EVALS = 400_000  # (target, grid point) pairs per batch of the search: bounds memory (~0.1 GB)
SEARCH_STEPS = ik_semi.SEARCH_STEPS


@dataclass(frozen=True)
class IKSolutions:
    """Solutions for N targets; ``q`` is NaN beyond ``n_solutions`` in each row.

    q: (N, K, n) rad (active joints of the locked arm), n_solutions: (N,) int, method: str.
    """

    q: np.ndarray
    n_solutions: np.ndarray
    method: str


# --------------------------------------------------------------------------- structure


def _parallel(X: np.ndarray) -> bool:
    """Axis of the next joint parallel to the current one (rotation maps e_z to +-e_z)."""
    return abs(X[2, 2]) > 1 - _GEOM_TOL


def _intersecting(X: np.ndarray) -> bool:
    p, d = X[:3, 3], X[:3, 2]
    if _parallel(X):
        return False
    cross = np.cross([0.0, 0.0, 1.0], d)
    return abs(p @ cross) / np.linalg.norm(cross) < _GEOM_TOL


def closed_form_shape(chain: Chain) -> bool:
    """True when the chain is ``0 | 1 2 3 parallel | 4 5 intersecting``."""
    X = chain.X
    return (chain.n == 6 and not _parallel(X[1]) and _parallel(X[2]) and _parallel(X[3])
            and not _parallel(X[4]) and _intersecting(X[5]))


def semi_analytic_shape(chain: Chain) -> bool:
    """True when the chain is ``0 | 1 | 2 3 parallel | 4 5 intersecting`` (joint 0 searched)."""
    X = chain.X
    return (chain.n == 6 and not _parallel(X[2]) and _parallel(X[3]) and np.hypot(*X[3][:2, 3]) > _GEOM_TOL
            and not _parallel(X[4]) and _intersecting(X[5]))


def method_for(chain: Chain) -> str:
    """Which solver :func:`solve` uses for this chain."""
    if closed_form_shape(chain):
        return "closed_form"
    if chain.n == 6 and closed_form_shape(chain.reversed()):
        return "closed_form_reversed"
    if semi_analytic_shape(chain):
        return "semi_analytic"
    if chain.n == 6 and semi_analytic_shape(chain.reversed()):
        return "semi_analytic_reversed"
    return "numeric"


# --------------------------------------------------------------------------- closed form


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


def _closed_form(chain: Chain, T_target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Raw branches (N, 8, 6) and their validity (N, 8) for a ``closed_form_shape`` chain."""
    X = chain.X
    N = len(T_target)
    # -- constants of the chain
    p5, d5 = X[5][:3, 3], X[5][:3, 2]
    s_star = -(p5[:2] @ d5[:2]) / (d5[:2] @ d5[:2])  # axis 5 meets axis 4 at (0, 0, s*) in frame 5
    w3 = (X[4] @ np.array([0, 0, p5[2] + s_star * d5[2], 1.0]))[:3]  # that point, in link 3
    h = (X[2] @ X[3] @ np.append(w3, 1.0))[2]  # its coordinate along the parallel axes
    n1, t1 = X[1][:3, 2], X[1][:3, 3]
    sigma = (X[2][:3, :3] @ X[3][:3, :3])[2, 2]
    a = X[4][2, :3]  # n in frame 4 coordinates (R4^T e_z)
    R2, t2, t3 = X[2][:3, :3], X[2][:3, 3], X[3][:3, 3]
    R4, R5 = X[4][:3, :3], X[5][:3, :3]
    p_ = t2 + R2 @ np.array([0, 0, t3[2]])
    u1 = R2 @ np.array([t3[0], t3[1], 0])
    u2 = R2 @ np.array([-t3[1], t3[0], 0])
    # -- 1. joint 0 from the coordinate of w along n
    w = (T_target @ (inverse_transform(X[6]) @ np.array([0, 0, s_star, 1.0])))[:, :3]  # (N, 3)
    r = (inverse_transform(X[0]) @ np.concatenate([w, np.ones((N, 1))], 1).T).T[:, :3]
    A0 = n1[0] * r[:, 0] + n1[1] * r[:, 1]
    B0 = n1[0] * r[:, 1] - n1[1] * r[:, 0]
    C0 = h + n1 @ t1 - n1[2] * r[:, 2]
    q0, ok0 = _trig_roots(A0, B0, C0)  # (N, 2)
    P1 = X[0] @ _rz4(q0) @ X[1]  # (N, 2, 4, 4) frame of joint 1 before its rotation
    # -- 2. joints 4, 5 from the orientation: n maps to the target through them
    W = np.swapaxes(P1[..., :3, :3], -1, -2) @ T_target[:, None, :3, :3] @ X[6][:3, :3].T  # (N, 2, 3, 3)
    b = sigma * W[..., 2, :]  # (N, 2, 3)
    A4 = d5[0] * a[0] + d5[1] * a[1]
    B4 = d5[0] * a[1] - d5[1] * a[0]
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
    q2, ok2 = _trig_roots(np.full_like(C2, 2 * p_[:2] @ u1[:2]), np.full_like(C2, 2 * p_[:2] @ u2[:2]), C2)  # (N, 2, 2, 2)
    k = p_ + np.cos(q2)[..., None] * u1 + np.sin(q2)[..., None] * u2  # (N, 2, 2, 2, 3)
    q1 = np.arctan2(e[..., None, 1], e[..., None, 0]) - np.arctan2(k[..., 1], k[..., 0])
    M = np.swapaxes(_rz(q1) @ R2 @ _rz(q2) @ X[3][:3, :3], -1, -2) @ Rg[..., None, :, :]
    q3 = np.arctan2(M[..., 1, 0], M[..., 0, 0])
    shape = q2.shape
    theta = np.stack([np.broadcast_to(q0[:, :, None, None], shape), q1, q2, q3,
                      np.broadcast_to(q4[..., None], shape), np.broadcast_to(q5[..., None], shape)], axis=-1)
    ok = ok0[:, :, None, None] & ok45[..., None] & ok2
    return theta.reshape(N, 8, 6), ok.reshape(N, 8)


# --------------------------------------------------------------------------- semi-analytical


def _semi_analytic(chain: Chain, T_target: np.ndarray, steps: int = SEARCH_STEPS) -> tuple[np.ndarray, np.ndarray]:
    """Candidate solutions (N, K, 6) and validity (N, K) by the 1-D search over joint 0."""
    N = len(T_target)
    per = max(1, _CHUNK_EVALS // steps)
    parts = []
    for s in range(0, N, per):
        theta, ok, seed = ik_semi.search(chain, T_target[s:s + per], steps)
        theta[seed] = newton(chain, theta[seed], np.repeat(T_target[s:s + per], seed.shape[1], 0)[seed.ravel()], iters=8)
        parts.append((theta, ok))
    K = max(1, max(p[0].shape[1] for p in parts))
    theta = np.zeros((N, K, 6))
    ok = np.zeros((N, K), dtype=bool)
    for s, (th, o) in zip(range(0, N, per), parts):
        theta[s:s + len(th), :th.shape[1]], ok[s:s + len(th), :th.shape[1]] = th, o
    return theta, ok


# --------------------------------------------------------------------------- driver

_WARNED: set[bytes] = set()


def _warn_incomplete(chain: Chain) -> None:
    key = chain.X.tobytes()
    if key not in _WARNED:
        _WARNED.add(key)
        log.warning("IK: this chain has no closed-form or semi-analytical solver; multi-start Newton finds exact "
                    "solutions but may miss branches (capacity can be optimistic)")


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
            lower: np.ndarray, upper: np.ndarray, tol: float, method: str) -> IKSolutions:
    N, K, n = theta.shape
    flat = np.where(ok[..., None], theta, 0.0).reshape(-1, n)
    # residuals of the candidates; two Newton steps polish those not already at rounding level
    idx = np.flatnonzero(ok.reshape(-1) & np.all(np.isfinite(flat), axis=1))
    target = T_target[idx // K]
    err = pose_error(chain.fk(flat[idx]), target)
    rough = np.flatnonzero(np.abs(err).max(axis=1, initial=0.0) > POLISHED)
    if len(rough):
        flat[idx[rough]] = newton(chain, flat[idx[rough]], target[rough], iters=2)
        err[rough] = pose_error(chain.fk(flat[idx[rough]]), target[rough])
    good = np.zeros(N * K, dtype=bool)
    good[idx] = ((np.linalg.norm(err[:, :3], axis=1) <= tol) & (np.linalg.norm(err[:, 3:], axis=1) <= tol)
                 & np.all(np.isfinite(flat[idx]), axis=1))
    wrapped, inside = wrap_to_range(flat, lower, upper)
    good &= np.all(inside, axis=1) & ok.reshape(-1)
    wrapped = wrapped.reshape(N, K, n)
    good = good.reshape(N, K)
    # de-duplicate: solution j repeats an earlier good i when all wrapped differences are tiny
    diff = wrapped[:, :, None, :] - wrapped[:, None, :, :]
    same = np.all(np.abs(np.mod(diff + np.pi, 2 * np.pi) - np.pi) < DUPLICATE_TOL, axis=-1)  # (N, K, K)
    earlier = np.tril(np.ones((K, K), dtype=bool), -1)  # [j, i]: i < j
    dup = np.any(same & earlier & good[:, None, :], axis=-1)
    keep = good & ~dup
    order = np.argsort(~keep, axis=1, kind="stable")
    q = np.take_along_axis(wrapped, order[..., None], axis=1)
    count = keep.sum(axis=1)
    q[np.arange(K)[None, :] >= count[:, None]] = np.nan
    width = K if method.startswith("closed_form") else max(int(count.max(initial=0)), 1)
    return IKSolutions(q=q[:, :width], n_solutions=count, method=method)


def solve(arm: LockedArm, positions: np.ndarray, rotation: np.ndarray, tol: float = RESIDUAL_TOL) -> IKSolutions:
    """Every distinct IK solution of the locked arm for each target position.

    positions: (N, 3) m. rotation: (3, 3) or (N, 3, 3), end-effector orientation in the
    base frame. Returns active-joint angles within the joint ranges, residual <= tol.
    """
    positions = np.atleast_2d(np.asarray(positions, dtype=float))
    N = len(positions)
    T = np.zeros((N, 4, 4))
    T[:, :3, :3] = rotation
    T[:, :3, 3] = positions
    T[:, 3, 3] = 1.0
    chain, lower, upper = arm.chain, arm.q_lower, arm.q_upper
    method = method_for(chain)
    if method == "closed_form":
        theta, ok = _closed_form(chain, T)
    elif method == "closed_form_reversed":
        theta_r, ok = _closed_form(chain.reversed(), inverse_transform(T))
        theta = -theta_r[..., ::-1]
    elif method == "semi_analytic":
        theta, ok = _semi_analytic(chain, T)
    elif method == "semi_analytic_reversed":
        theta_r, ok = _semi_analytic(chain.reversed(), inverse_transform(T))
        theta = -theta_r[..., ::-1]
    else:
        _warn_incomplete(chain)
        theta, ok = multi_start(chain, T, lower, upper)
    return _finish(chain, theta, ok, T, lower, upper, tol, method)
