"""The back-substitution of the general 6R method (:mod:`capmap.core.ik.general.elimination`), compiled
(numba): for a root qa of det M(qa), qb and qc from the null space of M(qa) (a monomial vector
tan(qb/2)^i tan(qc/2)^j), split into its monomial vectors when several solutions share the root
(a null space of dimension k <= 4: the eigenvectors of a shift operator restricted to it)."""

from __future__ import annotations

import math

import numba
import numpy as np

from capmap.core.ik.general.kernels import _at, _eliminate
from capmap.core.ik.general.matrices import _matmul, _qr, _solve_upper
from capmap.core.ik.roots import _balance, _hqr

__all__ = ["back_substitute"]

_SPLIT_TOL = 1e-3  # pivots of M(root) below this (relative) span its null space: several solutions may share the root


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
    if k == 2:
        return _split2(V, B0, B1, out)
    # G (k, k) = R^-1 H1^T B1 from the pivoted QR of B0 (B0[:, perm] = H1 R): B0 G = B1 in least squares
    H, R = np.empty((6, 6)), np.empty((k, k))
    perm = np.empty(k, dtype=np.int64)
    if _qr(B0, H, R, perm) < 1e-14:
        return 0
    Y, G = np.empty((k, k)), np.empty((k, k))
    _matmul(H[:, :k].T, B1, Y)
    _solve_upper(R, Y, perm, G)
    A = G.copy()
    _hessenberg(A, k)
    _balance(A, k)
    wr, wi = np.empty(k), np.empty(k)
    if not _hqr(A, k, wr, wi):
        return 0
    m = 0
    E, x = np.empty((k, k)), np.empty((k, 1))
    pk = np.empty(k, dtype=np.int64)
    for e in range(k):
        if abs(wi[e]) > 1e-6 * (1 + abs(wr[e])):
            continue
        for r in range(k):  # the real eigenvector: the null vector of G - lambda I
            for c in range(k):
                E[r, c] = G[r, c] - (wr[e] if r == c else 0.0)
        _eliminate(E, pk)
        _null_basis(E, pk, 1, x)
        for r in range(12):
            acc = 0.0
            for c in range(k):
                acc += V[r, c] * x[c, 0]
            out[m, r] = acc
        m += 1
    return m


@numba.njit(cache=True)
def _hessenberg(a, n):
    """Reduce a[:n, :n] to upper Hessenberg form in place by stabilised elementary similarity
    transformations (EISPACK elmhes); the entries below the subdiagonal are zeroed."""
    for m in range(1, n - 1):
        x, i = 0.0, m
        for j in range(m, n):
            if abs(a[j, m - 1]) > abs(x):
                x, i = a[j, m - 1], j
        if i != m:
            for j in range(m - 1, n):
                a[i, j], a[m, j] = a[m, j], a[i, j]
            for j in range(n):
                a[j, i], a[j, m] = a[j, m], a[j, i]
        if x != 0.0:
            for i in range(m + 1, n):
                y = a[i, m - 1]
                if y != 0.0:
                    y /= x
                    a[i, m - 1] = y
                    for j in range(m, n):
                        a[i, j] -= y * a[m, j]
                    for j in range(n):
                        a[j, m] += y * a[j, i]
    for i in range(2, n):
        for j in range(i - 1):
            a[i, j] = 0.0


@numba.njit(cache=True)
def _split2(V, B0, B1, out):
    """:func:`_split` for k = 2 in closed form: G = R^-1 Q^T B1 from the Gram-Schmidt QR of B0 (6, 2),
    the eigenvalues of the 2 x 2 G from its trace and determinant, its eigenvectors from its rows."""
    n0 = math.sqrt(np.sum(B0[:, 0] ** 2))
    if n0 == 0.0:
        return 0
    q0 = B0[:, 0] / n0
    r01 = np.sum(q0 * B0[:, 1])
    u = B0[:, 1] - r01 * q0
    n1 = math.sqrt(np.sum(u * u))
    if n1 <= 1e-14 * n0:
        return 0
    q1 = u / n1
    # Q^T B1, then back-substitution with R = [[n0, r01], [0, n1]]
    c00, c01 = np.sum(q0 * B1[:, 0]), np.sum(q0 * B1[:, 1])
    c10, c11 = np.sum(q1 * B1[:, 0]), np.sum(q1 * B1[:, 1])
    g10, g11 = c10 / n1, c11 / n1
    g00, g01 = (c00 - r01 * g10) / n0, (c01 - r01 * g11) / n0
    half = (g00 + g11) / 2
    disc = half * half - (g00 * g11 - g01 * g10)
    if disc < 0.0:
        if math.sqrt(-disc) > 1e-6 * (1 + abs(half)):
            return 0
        disc = 0.0
    m = 0
    for sign in (1.0, -1.0):
        lam = half + sign * math.sqrt(disc)
        a0, a1 = g01, lam - g00  # (G - lam I) x = 0 from either row; the larger one
        b0, b1 = lam - g11, g10
        if a0 * a0 + a1 * a1 >= b0 * b0 + b1 * b1:
            x0, x1 = a0, a1
        else:
            x0, x1 = b0, b1
        if x0 == 0.0 and x1 == 0.0:  # G = lam I: every vector is an eigenvector
            x0, x1 = (1.0, 0.0) if sign > 0 else (0.0, 1.0)
        for r in range(12):
            out[m, r] = V[r, 0] * x0 + V[r, 1] * x1
        m += 1
        if disc == 0.0 and not (a0 == 0.0 and a1 == 0.0 and b0 == 0.0 and b1 == 0.0):
            break
    return m


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


