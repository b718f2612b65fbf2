"""Compiled per-pose kernels of the general 6R method (:mod:`capmap.core.ik.general.elimination`): the
determinant of M(qa) sampled and turned into the companion polynomial, and the remaining joints of
a root (the back-substitution of qb, qc is :mod:`capmap.core.ik.general.back`). Scalar loops
compiled with numba: 12 x 12 matrices, where numpy's per-call overhead would dominate."""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["polynomials", "finish_angles"]

_DEGREE_TOL = 1e-9  # coefficients above the chain's degree must be below this (relative)
_LIVE_TOL = 1e-12  # smallest / largest partial-pivoting pivot of M(qa) above this at some sample: M is not singular for all qa


@numba.njit(cache=True, inline="always")
def _below(A, k):
    """One elimination step: rows below pivot row k minus their multiple of it (columns > k; rows
    with a zero there, as M(qa)'s lower half in its first three columns, skipped)."""
    n = A.shape[0]
    for i in range(k + 1, n):
        if A[i, k] == 0.0:
            continue
        m = A[i, k] / A[k, k]
        for j in range(k + 1, n):
            A[i, j] -= m * A[k, j]


@numba.njit(cache=True)
def _det(A):
    """Determinant of a small square matrix by partial-pivot elimination (A is overwritten) and the
    ratio of its smallest to its largest pivot (0 when a column has no pivot)."""
    n = A.shape[0]
    d = 1.0
    lo, hi = np.inf, 0.0
    for k in range(n):
        p = k
        for i in range(k + 1, n):
            if abs(A[i, k]) > abs(A[p, k]):
                p = i
        if A[p, k] == 0.0:
            return 0.0, 0.0
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
            d = -d
        d *= A[k, k]
        lo, hi = min(lo, abs(A[k, k])), max(hi, abs(A[k, k]))
        _below(A, k)
    return d, lo / hi


@numba.njit(cache=True)
def _eliminate(A, perm):
    """Full-pivot elimination of a square A in place (rows and columns swapped, columns recorded in
    perm); returns the pivots' magnitudes (decreasing up to rounding)."""
    n = A.shape[0]
    piv = np.zeros(n)
    for k in range(n):
        perm[k] = k
    for k in range(n):
        bi, bj, best = k, k, -1.0
        for i in range(k, n):
            for j in range(k, n):
                if abs(A[i, j]) > best:
                    best, bi, bj = abs(A[i, j]), i, j
        piv[k] = best
        if best == 0.0:
            break
        for j in range(n):
            A[k, j], A[bi, j] = A[bi, j], A[k, j]
        for i in range(n):
            A[i, k], A[i, bj] = A[i, bj], A[i, k]
        perm[k], perm[bj] = perm[bj], perm[k]
        _below(A, k)
    return piv


@numba.njit(cache=True)
def _at(M, n, qa, A):
    """A = M(qa) of pose n."""
    c, sn = math.cos(qa), math.sin(qa)
    for i in range(12):
        for j in range(12):
            A[i, j] = M[n, 0, i, j] + c * M[n, 1, i, j] + sn * M[n, 2, i, j]


@numba.njit(cache=True)
def polynomials(M, dft, theta, W, degree, poly, status, noise):
    """Per pose n: det M(qa) sampled at ``theta`` (S,), its Fourier coefficients (dft (S, S), k =
    -(S-1)/2 ..) and the polynomial poly[n] (x^0 .. x^2D, W) whose real roots x give qa = phase + 2
    atan x. status[n]: 0 solved, 1 M(qa) singular for every qa (a degenerate elimination: at
    every sample the partial-pivoting pivots span more than 1e12), 2 a determinant of higher degree
    than the chain's (a coefficient above D larger than 1e-9 of the largest). noise[n]: the largest
    coefficient above D relative to the largest (their exact value is 0: the polynomial's relative
    error; inf when no harmonic above D is sampled, D = 12)."""
    N, S, D = M.shape[0], len(theta), degree
    c = (S - 1) // 2
    A = np.empty((12, 12))
    d = np.empty(S, dtype=np.complex128)
    for n in range(N):
        live = False
        for s in range(S):
            _at(M, n, theta[s], A)
            d[s], ratio = _det(A)
            live = live or ratio > _LIVE_TOL
        if not live:
            status[n] = 1
            continue
        coef = dft @ d
        big, high = 0.0, 0.0
        for k in range(S):
            big = max(big, abs(coef[k]))
            if abs(k - c) > D:
                high = max(high, abs(coef[k]))
        status[n] = 2 if high > _DEGREE_TOL * big else 0
        noise[n] = high / big if S > 2 * D + 1 else np.inf
        poly[n] = (W @ coef[c - D: c + D + 1]).real


@numba.njit(cache=True, inline="always")
def _times_rz(F, q, out):
    """out = F @ Rz(q) (4, 4)."""
    c, s = math.cos(q), math.sin(q)
    for i in range(4):
        a, b = F[i, 0], F[i, 1]
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = c * a + s * b, c * b - s * a, F[i, 2], F[i, 3]


@numba.njit(cache=True, inline="always")
def _times(A, B, out):
    """out = A @ B (4, 4)."""
    for i in range(4):
        for j in range(4):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j] + A[i, 3] * B[3, j]


@numba.njit(cache=True)
def _product(X, first, angles, out):
    """out = X[first] Rz(angles[0]) X[first + 1] Rz(angles[1]) ... X[first + len(angles)]."""
    W, V = np.empty((4, 4)), np.empty((4, 4))
    out[:] = X[first]
    for k in range(len(angles)):
        _times_rz(out, angles[k], W)
        _times(W, X[first + k + 1], V)
        out[:] = V


@numba.njit(cache=True)
def finish_angles(X, f, CL, lstsq, const, T, qa, qb, qc, count, theta):
    """Per pose n and root r < count[n]: the remaining joints qu, qv (least squares on Q: the map
    lstsq (N, 8, 14), the right-hand constant const (N, 14)) and qf (orientation, from the target T
    (N, 4, 4)), written with qa, qb, qc (N, R) into theta (N, R, 6) rad."""
    a = f - 3
    L, A, B, F, G = np.empty((4, 4)), np.empty((4, 4)), np.empty((4, 4)), np.empty((4, 4)), np.empty((4, 4))
    lhs, y = np.empty(14), np.empty(8)
    one, two, abc = np.empty(1), np.empty(2), np.empty(3)
    for n in range(T.shape[0]):
        for r in range(count[n]):
            abc[0], abc[1], abc[2] = qa[n, r], qb[n, r], qc[n, r]
            _rz_left(X, a, abc, L)
            ca, sa = math.cos(qa[n, r]), math.sin(qa[n, r])
            bb = (1.0, math.cos(qb[n, r]), math.sin(qb[n, r]))
            bc = (1.0, math.cos(qc[n, r]), math.sin(qc[n, r]))
            for q in range(14):
                s = 0.0
                for i in range(3):
                    for j in range(3):
                        s += (CL[0, q, 3 * i + j] + ca * CL[1, q, 3 * i + j] + sa * CL[2, q, 3 * i + j]) * bb[i] * bc[j]
                lhs[q] = s - const[n, q]
            for k in range(8):
                s = 0.0
                for q in range(14):
                    s += lstsq[n, k, q] * lhs[q]
                y[k] = s
            qv = math.atan2(y[1], y[0])
            qu = math.atan2(y[5], y[2])
            if f == 5:
                two[0], two[1] = qu, qv
                _product(X, 0, two, A)
                B[:] = X[6]
            elif f == 4:
                one[0] = qu
                _product(X, 0, one, A)
                one[0] = qv
                _product(X, 5, one, B)
            else:
                A[:] = X[0]
                two[0], two[1] = qu, qv
                _product(X, 4, two, B)
            _times(A, L, F)  # Rz(qf) = (A L)^-1 T B^-1: its first column is (A L)^T T B^T e_x rotated
            for i in range(3):  # G = T @ B^-1, rotation part only: T[:3, :3] B[:3, :3]^T
                for j in range(3):
                    G[i, j] = T[n, i, 0] * B[j, 0] + T[n, i, 1] * B[j, 1] + T[n, i, 2] * B[j, 2]
            r00 = F[0, 0] * G[0, 0] + F[1, 0] * G[1, 0] + F[2, 0] * G[2, 0]
            r10 = F[0, 1] * G[0, 0] + F[1, 1] * G[1, 0] + F[2, 1] * G[2, 0]
            theta[n, r, a], theta[n, r, a + 1], theta[n, r, a + 2] = qa[n, r], qb[n, r], qc[n, r]
            theta[n, r, f] = math.atan2(r10, r00)
            rest = 0
            for j in range(6):
                if j < a or (j > a + 2 and j != f):
                    theta[n, r, j] = qu if rest == 0 else qv
                    rest += 1


@numba.njit(cache=True)
def _rz_left(X, a, angles, L):
    """L = Rz(qa) X[a+1] Rz(qb) X[a+2] Rz(qc) X[a+3]."""
    W = np.empty((4, 4))
    E = np.eye(4)
    _times_rz(E, angles[0], W)
    _times(W, X[a + 1], L)
    for k in range(1, 3):
        _times_rz(L, angles[k], W)
        _times(W, X[a + k + 1], L)
