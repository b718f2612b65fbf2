"""The compiled end of the IK methods (numba): the Newton polish of candidates and their
de-duplication. The polish: per candidate the chain's forward kinematics
``T = X[0] Rz(q1) X[1] ... Rz(qn) X[n]``, the world-frame pose error [p_t - p; log(R_t R^T)] and
Newton steps dq = J^T (J J^T + damping^2 I)^-1 e (damping 0 unless asked; each joint's step clipped to 0.5 rad), as
:func:`capmap.core.ik.multistart.newton` and :func:`capmap.core.kinematics.pose_error` do in numpy
(tests/core/test_ik_compiled.py compares them)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["PolishSettings", "polish", "distinct"]


@dataclass(frozen=True)
class PolishSettings:
    """How :func:`polish` steps: up to ``steps`` Newton steps per candidate, stopping once max |error|
    <= done_tol (m, rad); after two steps going on only while max |error| < give_up (m, rad: what has
    not come close by then is another branch's start or no solution); ``damping`` (m, rad): the steps
    solve J J^T + damping^2 I."""

    steps: int
    done_tol: float
    give_up: float = 0.1
    damping: float = 0.0


@numba.njit(cache=True)
def _log(R, out):
    """The rotation vector of R (3, 3) into out[3:6] (robust near pi, as kinematics.rotation_log)."""
    cos = min(max((R[0, 0] + R[1, 1] + R[2, 2] - 1.0) / 2.0, -1.0), 1.0)
    angle = math.acos(cos)
    w0, w1, w2 = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    if angle > math.pi - 1e-4:  # the antisymmetric part vanishes: the axis from the symmetric part
        best, col = -1.0, 0
        for i in range(3):
            d = ((R[i, i] + R[i, i]) / 2 - cos) / (1 - cos)
            if d > best:
                best, col = d, i
        a = np.empty(3)
        for i in range(3):
            a[i] = ((R[i, col] + R[col, i]) / 2 - (cos if i == col else 0.0)) / (1 - cos)
        norm = math.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2)
        sign = 1.0 if a[0] * w0 + a[1] * w1 + a[2] * w2 >= 0 else -1.0
        for i in range(3):
            out[3 + i] = a[i] / norm * angle * sign
        return
    sin = math.sin(angle)
    scale = 0.5 + angle * angle / 12 if sin < 1e-6 else angle / (2 * sin)
    out[3], out[4], out[5] = w0 * scale, w1 * scale, w2 * scale


@numba.njit(cache=True)
def _fk(X, q, frames):
    """frames[k] (4, 4): the frame before joint k's rotation, frames[n]: the tip."""
    n = len(q)
    for i in range(4):  # element by element: a 2-D array assignment compiles numba's shape-error path (~3 s)
        for j in range(4):
            frames[0, i, j] = X[0, i, j]
    for k in range(n):
        c, s = math.cos(q[k]), math.sin(q[k])
        F = frames[k]
        G = frames[k + 1]
        for i in range(4):
            a0, a1, a2, a3 = c * F[i, 0] + s * F[i, 1], c * F[i, 1] - s * F[i, 0], F[i, 2], F[i, 3]
            for j in range(4):
                G[i, j] = a0 * X[k + 1, 0, j] + a1 * X[k + 1, 1, j] + a2 * X[k + 1, 2, j] + a3 * X[k + 1, 3, j]


@numba.njit(cache=True)
def _error(T, Tt, err, dR):
    """err (6,): [p_t - p; log(R_t R^T)] (dR (3, 3): scratch); returns max |err|."""
    for i in range(3):
        err[i] = Tt[i, 3] - T[i, 3]
        for j in range(3):
            dR[i, j] = Tt[i, 0] * T[j, 0] + Tt[i, 1] * T[j, 1] + Tt[i, 2] * T[j, 2]
    _log(dR, err)
    e = 0.0
    for i in range(6):
        e = max(e, abs(err[i]))
    return e


@numba.njit(cache=True)
def _step(frames, err, n, dq, damping2, J, A, b):
    """dq (n,) = J^T (J J^T + damping2 I)^-1 err, J the geometric Jacobian of the frames; False if
    that matrix is singular. J (6, n), A (6, 6), b (6,): scratch (no allocation, no BLAS call per step)."""
    tip = frames[n]
    for k in range(n):
        F = frames[k]
        z0, z1, z2 = F[0, 2], F[1, 2], F[2, 2]
        r0, r1, r2 = tip[0, 3] - F[0, 3], tip[1, 3] - F[1, 3], tip[2, 3] - F[2, 3]
        J[0, k], J[1, k], J[2, k] = z1 * r2 - z2 * r1, z2 * r0 - z0 * r2, z0 * r1 - z1 * r0
        J[3, k], J[4, k], J[5, k] = z0, z1, z2
    for i in range(6):
        b[i] = err[i]
        for j in range(i + 1):
            s = 0.0
            for k in range(n):
                s += J[i, k] * J[j, k]
            A[i, j] = s
            A[j, i] = s
        A[i, i] += damping2
    for k in range(6):  # Gaussian elimination with partial pivoting
        p = k
        for i in range(k + 1, 6):
            if abs(A[i, k]) > abs(A[p, k]):
                p = i
        if A[p, k] == 0.0:
            return False
        if p != k:
            for j in range(6):
                A[k, j], A[p, j] = A[p, j], A[k, j]
            b[k], b[p] = b[p], b[k]
        for i in range(k + 1, 6):
            m = A[i, k] / A[k, k]
            for j in range(k, 6):
                A[i, j] -= m * A[k, j]
            b[i] -= m * b[k]
    for k in range(5, -1, -1):
        s = b[k]
        for j in range(k + 1, 6):
            s -= A[k, j] * b[j]
        b[k] = s / A[k, k]
    for i in range(n):
        s = 0.0
        for k in range(6):
            s += J[k, i] * b[k]
        dq[i] = min(max(s, -0.5), 0.5)
    return True


@numba.njit(cache=True)
def _polish(X, theta, targets, which, steps, done_tol, give_up, damping2, err_out):
    n = theta.shape[1]
    frames = np.empty((n + 1, 4, 4))
    err, dq = np.empty(6), np.empty(n)
    J, A, b, dR = np.empty((6, n)), np.empty((6, 6)), np.empty(6), np.empty((3, 3))
    for m in range(len(theta)):
        Tt = targets[which[m]]
        _fk(X, theta[m], frames)
        e = _error(frames[n], Tt, err, dR)
        k = 0
        while k < steps and e > done_tol and (k < 2 or e < give_up):
            if not _step(frames, err, n, dq, damping2, J, A, b):
                break
            for i in range(n):
                theta[m, i] += dq[i]
            _fk(X, theta[m], frames)
            e = _error(frames[n], Tt, err, dR)
            k += 1
        err_out[m] = err


def polish(X: np.ndarray, theta: np.ndarray, targets: np.ndarray, which: np.ndarray,
           settings: PolishSettings) -> tuple[np.ndarray, np.ndarray]:
    """Newton-polished candidates theta (M, n) rad of the chain X (n+1, 4, 4) toward the poses
    targets[which] ((P, 4, 4), which (M,) int) and their final errors (M, 6) [m; rad], stepped as
    ``settings`` says."""
    s = settings
    theta = np.ascontiguousarray(theta, dtype=float).copy()
    err = np.empty((len(theta), 6))
    if len(theta):
        _polish(np.ascontiguousarray(X, dtype=float), theta, np.ascontiguousarray(targets, dtype=float),
                np.ascontiguousarray(which, dtype=np.int64), int(s.steps), float(s.done_tol), float(s.give_up),
                float(s.damping) ** 2, err)
    return theta, err


@numba.njit(cache=True)
def _distinct(wrapped, good, tol, q, count):
    N, K, n = wrapped.shape
    for p in range(N):
        m = 0
        for k in range(K):
            if not good[p, k]:
                continue
            repeat = False
            for i in range(m):
                same = True
                for j in range(n):
                    d = (wrapped[p, k, j] - q[p, i, j] + math.pi) % (2 * math.pi) - math.pi
                    if abs(d) >= tol:
                        same = False
                        break
                if same:
                    repeat = True
                    break
            if not repeat:
                q[p, m] = wrapped[p, k]
                m += 1
        count[p] = m


def distinct(wrapped: np.ndarray, good: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Per pose, the good candidates wrapped (N, K, n) rad (good (N, K) bool) without repeats (every
    wrapped difference below ``tol`` rad from an earlier kept one), in their order: (q (N, K, n)
    rad, NaN beyond count; count (N,) int)."""
    q = np.full(wrapped.shape, np.nan)
    count = np.zeros(len(wrapped), dtype=np.int64)
    _distinct(np.ascontiguousarray(wrapped, dtype=float), np.ascontiguousarray(good, dtype=np.bool_), float(tol),
              q, count)
    return q, count
