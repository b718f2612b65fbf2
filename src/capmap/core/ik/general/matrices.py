"""The per-pose matrices of the general 6R elimination (:mod:`capmap.core.ik.general.elimination`), compiled
(numba): the right-hand quantities fitted on the (qu, qv) grid, the left null space and the
least-squares map of their 14 x 8 coefficient matrix Q by a Householder QR with column pivoting
(an SVD costs ten times more here), and M(qa) = M0 + cos qa M1 + sin qa M2."""

from __future__ import annotations

import math

import numba
import numpy as np

from capmap.core.ik.general.kernels import _times

__all__ = ["matrices"]


@numba.njit(cache=True)
def _quantities(F, out):
    """The 14 Raghavan-Roth quantities of the frame F (4, 4) (see ik_general.quantities)."""
    p0, p1, p2 = F[0, 3], F[1, 3], F[2, 3]
    l0, l1, l2 = F[0, 2], F[1, 2], F[2, 2]
    pp = p0 * p0 + p1 * p1 + p2 * p2
    pl = p0 * l0 + p1 * l1 + p2 * l2
    out[0], out[1], out[2], out[3], out[4], out[5] = p0, p1, p2, l0, l1, l2
    out[6], out[7] = pp, pl
    out[8], out[9], out[10] = p1 * l2 - p2 * l1, p2 * l0 - p0 * l2, p0 * l1 - p1 * l0
    out[11], out[12], out[13] = pp * l0 - 2 * pl * p0, pp * l1 - 2 * pl * p1, pp * l2 - 2 * pl * p2


@numba.njit(cache=True)
def _qr(Q, H, R, perm):
    """Householder QR with column pivoting of Q (m, k), m > k: Q[:, perm] = H[:, :k] R with H (m, m)
    orthogonal (written out) and R (k, k) upper triangular; returns |R[k-1, k-1]| / |R[0, 0]|."""
    m, k = Q.shape
    A = Q.copy()
    for j in range(k):
        perm[j] = j
    for i in range(m):
        for j in range(m):
            H[i, j] = 1.0 if i == j else 0.0
    v = np.empty(m)
    for c in range(k):
        best, bj = -1.0, c  # the remaining column of largest norm
        for j in range(c, k):
            s = 0.0
            for i in range(c, m):
                s += A[i, j] * A[i, j]
            if s > best:
                best, bj = s, j
        if bj != c:
            for i in range(m):
                A[i, c], A[i, bj] = A[i, bj], A[i, c]
            perm[c], perm[bj] = perm[bj], perm[c]
        norm = math.sqrt(best)
        if norm == 0.0:  # rank c: R's rows from c on are 0 (the rows above are written on the way out)
            for i in range(k):
                for j in range(k):
                    R[i, j] = A[i, j] if (i < c and j >= i) else 0.0
            return 0.0
        alpha = -norm if A[c, c] >= 0 else norm
        for i in range(m):
            v[i] = A[i, c] if i > c else 0.0
        v[c] = A[c, c] - alpha
        vv = 0.0
        for i in range(c, m):
            vv += v[i] * v[i]
        if vv > 0.0:
            for j in range(c, k):  # A = (I - 2 v v^T / v.v) A
                s = 0.0
                for i in range(c, m):
                    s += v[i] * A[i, j]
                s *= 2.0 / vv
                for i in range(c, m):
                    A[i, j] -= s * v[i]
            for i in range(m):  # H = H (I - 2 v v^T / v.v)
                s = 0.0
                for j in range(c, m):
                    s += H[i, j] * v[j]
                s *= 2.0 / vv
                for j in range(c, m):
                    H[i, j] -= s * v[j]
    for i in range(k):
        for j in range(k):
            R[i, j] = A[i, j] if j >= i else 0.0
    return abs(R[k - 1, k - 1]) / abs(R[0, 0])


@numba.njit(cache=True)
def _matmul(A, B, out):
    """out = A @ B for small matrices (loops: no BLAS call per pose)."""
    for i in range(A.shape[0]):
        for j in range(B.shape[1]):
            s = 0.0
            for k in range(A.shape[1]):
                s += A[i, k] * B[k, j]
            out[i, j] = s


@numba.njit(cache=True)
def _solve_upper(R, Y, perm, out):
    """The least-squares solution of Q X = B from the pivoted QR of :func:`_qr`: given Y = H[:, :k]^T B
    (k, c), out[perm[r], :] = (R^-1 Y)[r, :] (a zero pivot gives 0 in its row)."""
    k, c = Y.shape
    Z = np.empty((k, c))
    for col in range(c):
        for r in range(k - 1, -1, -1):
            s = Y[r, col]
            for j in range(r + 1, k):
                s -= R[r, j] * Z[j, col]
            Z[r, col] = s / R[r, r] if R[r, r] != 0.0 else 0.0
    for r in range(k):
        for col in range(c):
            out[perm[r], col] = Z[r, col]


@numba.njit(cache=True)
def matrices(Ainv, Binv, B2inv, HH, CL, T, M, lstsq, const, rank):
    """Per pose n of the targets T (N, 4, 4): the quantities of F = A^-1 T B^-1 on the 9 grid
    points (Ainv, Binv (9, 4, 4)), their monomial coefficients CR = B2inv @ V (9, 14), the left null
    space Nl (6, 14) and the least-squares map lstsq[n] (8, 14) of Q = CR[1:]^T, rank[n] =
    |R_88| / |R_11| of its pivoted QR, const[n] = CR[0], and M[n] (3, 12, 12): E_a = Nl (CL_a -
    const e_0^T) HH in rows 0..5, columns 0..8 and again in rows 6..11, columns 3..11."""
    N = T.shape[0]
    F, G = np.empty((4, 4)), np.empty((4, 4))
    V, CR = np.empty((9, 14)), np.empty((9, 14))
    Q, H, R = np.empty((14, 8)), np.empty((14, 14)), np.empty((8, 8))
    perm = np.empty(8, dtype=np.int64)
    P, E = np.empty((6, 9)), np.empty((6, 9))
    for n in range(N):
        for g in range(9):
            _times(T[n], Binv[g], G)
            _times(Ainv[g], G, F)
            _quantities(F, V[g])
        _matmul(B2inv, V, CR)
        for q in range(14):
            const[n, q] = CR[0, q]
            for r in range(8):
                Q[q, r] = CR[r + 1, q]
        rank[n] = _qr(Q, H, R, perm)
        _solve_upper(R, H[:, :8].T, perm, lstsq[n])  # least squares of Q y = b: lstsq[n] b (B = I)
        for a in range(3):
            for e in range(6):  # P = Nl CL_a (minus the constant in monomial 0 for a = 0)
                for mo in range(9):
                    s = 0.0
                    for q in range(14):
                        c = CL[a, q, mo] - (const[n, q] if a == 0 and mo == 0 else 0.0)
                        s += H[q, 8 + e] * c
                    P[e, mo] = s
            _matmul(P, HH, E)
            for i in range(12):
                for j in range(12):
                    M[n, a, i, j] = 0.0
            for e in range(6):
                for mo in range(9):
                    M[n, a, e, mo] = E[e, mo]
                    M[n, a, 6 + e, 3 + mo] = E[e, mo]
