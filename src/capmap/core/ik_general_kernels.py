"""Compiled per-pose kernels of the general 6R method (:mod:`capmap.core.ik_general`): the
determinant of M(qa) sampled and turned into the companion polynomial, and the back-substitution
of a root into qb, qc through the null space of M(qa). Scalar loops compiled with numba: 12 x 12
matrices, where numpy's per-call overhead would dominate."""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["polynomials", "back_substitute"]

_SPLIT_TOL = 1e-3  # pivots of M(root) below this (relative) span its null space: several solutions may share the root
_DEGREE_TOL = 1e-9  # coefficients above the chain's degree must be below this (relative)
_LIVE_TOL = 1e-12  # smallest / largest full-pivoting pivot of M(qa) above this at some sample: M is not singular for all qa


@numba.njit(cache=True, inline="always")
def _below(A, k):
    """One elimination step: rows below pivot row k minus their multiple of it (columns > k)."""
    n = A.shape[0]
    for i in range(k + 1, n):
        m = A[i, k] / A[k, k]
        for j in range(k + 1, n):
            A[i, j] -= m * A[k, j]


@numba.njit(cache=True)
def _det(A):
    """Determinant of a small square matrix by partial-pivot elimination (A is overwritten)."""
    n = A.shape[0]
    d = 1.0
    for k in range(n):
        p = k
        for i in range(k + 1, n):
            if abs(A[i, k]) > abs(A[p, k]):
                p = i
        if A[p, k] == 0.0:
            return 0.0
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
            d = -d
        d *= A[k, k]
        _below(A, k)
    return d


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
def _null_basis(A, perm, k, V):
    """Columns 0..k-1 of V (n, >=k): a basis of the null space of the eliminated A (see
    :func:`_eliminate`) taking its last k pivots as zero."""
    n = A.shape[0]
    y = np.zeros(n)
    for c in range(k):
        y[:] = 0.0
        y[n - k + c] = 1.0
        for r in range(n - k - 1, -1, -1):
            s = 0.0
            for j in range(r + 1, n):
                s += A[r, j] * y[j]
            y[r] = -s / A[r, r]
        norm = math.sqrt(np.sum(y * y))
        for r in range(n):
            V[perm[r], c] = y[r] / norm


@numba.njit(cache=True)
def _ratio_angle(a, b):
    """The angle q with tan(q/2) = b / a (a projective pair, either may be 0)."""
    r = a * a + b * b
    return math.atan2(2 * a * b, a * a - b * b) if r > 0 else 0.0


@numba.njit(cache=True)
def _angles_of(v):
    """qb, qc of a monomial vector v[3 i + j] ~ xb^i xc^j (i < 4, j < 3): from the pair of consecutive
    powers with the largest entries, so neither angle at 180 deg is special."""
    bi, bj, best = 0, 0, -1.0
    for i in range(3):
        for j in range(3):
            w = abs(v[3 * i + j]) + abs(v[3 * (i + 1) + j])
            if w > best:
                best, bi, bj = w, i, j
    ci, cj, best = 0, 0, -1.0
    for i in range(4):
        for j in range(2):
            w = abs(v[3 * i + j]) + abs(v[3 * i + j + 1])
            if w > best:
                best, ci, cj = w, i, j
    return (_ratio_angle(v[3 * bi + bj], v[3 * (bi + 1) + bj]), _ratio_angle(v[3 * ci + cj], v[3 * ci + cj + 1]))


@numba.njit(cache=True)
def _is_monomial(v):
    """Whether the unit vector v is (to 1e-5 rad) the monomial vector xb^i xc^j of its own angles."""
    qb, qc = _angles_of(v)
    m = np.empty(12)
    cb, sb, cc, sc = math.cos(qb / 2), math.sin(qb / 2), math.cos(qc / 2), math.sin(qc / 2)
    for i in range(4):
        for j in range(3):  # (cos^(3-i) sin^i)(cos^(2-j) sin^j): the monomials times cos^3 cos^2
            m[3 * i + j] = cb ** (3 - i) * sb ** i * cc ** (2 - j) * sc ** j
    norm = math.sqrt(np.sum(m * m))
    return 1.0 - abs(np.sum(m * v)) / norm < 1e-10


_ROWS0 = np.array([3 * i + j for i in range(3) for j in range(2)])  # monomials with both shifts inside
_SHIFT_B, _SHIFT_C = _ROWS0 + 3, _ROWS0 + 1
_MIX = (0.7548776662466927, 0.5698402909980532)  # a fixed generic combination of the two shifts


@numba.njit(cache=True)
def _split(V, k, out):
    """A k-dimensional null space V[:, :k] spanned by k monomial vectors (several solutions at one
    qa): its monomial vectors from the eigenvectors of the shift operator (a xb + b xc) restricted
    to it, written to out (k, 12); returns how many were found."""
    B0 = np.empty((6, k))
    B1 = np.empty((6, k))
    for r in range(6):
        for c in range(k):
            B0[r, c] = V[_ROWS0[r], c]
            B1[r, c] = _MIX[0] * V[_SHIFT_B[r], c] + _MIX[1] * V[_SHIFT_C[r], c]
    G = np.linalg.lstsq(B0, B1)[0]  # (k, k): B0 G = B1
    w, W = np.linalg.eig(G.astype(np.complex128))
    m = 0
    for e in range(k):
        if abs(w[e].imag) > 1e-6 * (1 + abs(w[e].real)):
            continue
        x = W[:, e]
        # a real representative: rotate the complex eigenvector to its largest real part
        big = 0
        for c in range(k):
            if abs(x[c]) > abs(x[big]):
                big = c
        x = x / x[big]
        for r in range(12):
            acc = 0.0
            for c in range(k):
                acc += V[r, c] * x[c].real
            out[m, r] = acc
        m += 1
    return m


@numba.njit(cache=True)
def _at(M, n, qa, A):
    """A = M(qa) of pose n."""
    c, sn = math.cos(qa), math.sin(qa)
    for i in range(12):
        for j in range(12):
            A[i, j] = M[n, 0, i, j] + c * M[n, 1, i, j] + sn * M[n, 2, i, j]


@numba.njit(cache=True)
def polynomials(M, dft, theta, W, degree, poly, status):
    """Per pose n: det M(qa) sampled at ``theta``, its Fourier coefficients (dft) and the polynomial
    poly[n] (x^0 .. x^2D, W) whose real roots x give qa = phase + 2 atan x. status[n]: 0 solved,
    1 M(qa) singular for every qa (a degenerate elimination: full pivoting at up to four samples
    finds no full rank), 2 a determinant of higher degree than the chain's."""
    N, S, D = M.shape[0], len(theta), degree
    A, B = np.empty((12, 12)), np.empty((12, 12))
    perm = np.empty(12, dtype=np.int64)
    d = np.empty(S, dtype=np.complex128)
    for n in range(N):
        live = False
        for s in range(S):
            _at(M, n, theta[s], A)
            if s % 8 == 3 and not live:
                B[:] = A
                piv = _eliminate(B, perm)
                live = piv[11] > _LIVE_TOL * piv[0]
            d[s] = _det(A)
        if not live:
            status[n] = 1
            continue
        coef = dft @ d  # k = -12..12
        big, high = 0.0, 0.0
        for k in range(25):
            big = max(big, abs(coef[k]))
            if abs(k - 12) > D:
                high = max(high, abs(coef[k]))
        status[n] = 2 if high > _DEGREE_TOL * big else 0
        poly[n] = (W @ coef[12 - D: 13 + D]).real


@numba.njit(cache=True)
def back_substitute(M, pose, roots, phase, qa_out, qb_out, qc_out, n_out):
    """For roots x (R,) of pose ``pose`` (R,): qa = phase + 2 atan x and qb, qc from the null space of
    M(qa) (split into monomial vectors when several solutions share the root); rows of the outputs
    per pose, counts in n_out."""
    A = np.empty((12, 12))
    V = np.empty((12, 4))
    vecs = np.empty((4, 12))
    perm = np.empty(12, dtype=np.int64)
    cap = qa_out.shape[1]
    for r in range(len(roots)):
        n = pose[r]
        qa = phase + 2.0 * math.atan(roots[r])
        _at(M, n, qa, A)
        piv = _eliminate(A, perm)
        _null_basis(A, perm, 1, V)
        for i in range(12):
            vecs[0, i] = V[i, 0]
        found = 1
        if not _is_monomial(vecs[0]):  # several solutions share the root: split the null space
            k = 2
            while k < 4 and piv[11 - k] < _SPLIT_TOL * piv[0]:
                k += 1
            _null_basis(A, perm, k, V)
            found = _split(V, k, vecs)
        for f in range(found):
            m = n_out[n]
            if m >= cap:
                n_out[n] = cap + 1  # overflow: the caller treats the pose as degenerate
                break
            qb, qc = _angles_of(vecs[f])
            qa_out[n, m], qb_out[n, m], qc_out[n, m] = qa, qb, qc
            n_out[n] = m + 1
