"""Every inverse-kinematics solution of a general 6R chain, batched over poses: the elimination of
Raghavan and Roth (J. Mech. Des. 115, 1993) in the numerically stable form of Manocha and Canny
(IEEE Trans. Robot. Autom. 10, 1994), with the coefficients fitted from the chain itself.

For the chain ``T = X0 Rz(q0) X1 ... Rz(q5) X6`` and an eliminated joint f (3, 4 or 5; on the chain
or on its inverse) write the loop as

    L(qa, qb, qc) Rz(qf) = A(..)^-1 T B(..)^-1,     L = Rz(qa) X Rz(qb) X Rz(qc) X_f,

with (a, b, c) = (f-3, f-2, f-1) and the two remaining joints (u, v) in A and B. The origin p and
the z axis l of both sides are free of qf; the 14 quantities p, l, p.p, p.l, p x l,
(p.p) l - 2 (p.l) p (:func:`quantities`) are, on the left, trigonometric polynomials of degree 1 in
each of qa, qb, qc and, on the right, of degree 1 in each of qu, qv (Raghavan-Roth). Their
coefficients are fitted exactly from 27 and 9 evaluations on the grid {0, 120, 240} deg per joint
(the left side once per chain, the right side per pose), which replaces the symbolic derivation and
holds for any frame convention. The 8 right-hand monomials that involve qu or qv are eliminated
by the left null space of their 14 x 8 coefficient matrix Q: 6 equations in the 9 monomials of
(qb, qc) with coefficients linear in cos qa, sin qa. With the half-angle substitution in qb, qc and
a copy multiplied by tan(qb/2) they are a 12 x 12 matrix M(qa) acting on tan(qb/2)^i tan(qc/2)^j,
i < 4, j < 3; every solution makes M(qa) singular. det M(qa) is a trigonometric polynomial of
degree <= 12 in qa (8 for a general chain: at most 16 solutions); it is sampled at 25 equispaced
qa, its Fourier coefficients are exact, and its real roots are the eigenvalues of a companion
matrix (in x = tan((qa - phase)/2), a fixed phase chosen so that no root lies at x = infinity).
For each root the null vector of M(qa) gives qb, qc (from projective ratios, so qb = 180 deg is
no special case), the least-squares solution of Q gives qu, qv, and the orientation gives qf.

Degenerate cases are detected, never silently dropped: a rank-deficient Q or a determinant that
vanishes identically (special geometries, where some formulations fail), or a determinant of
higher degree than the chain's, marks the pose; :func:`candidates` then tries the other
formulations, and a pose none of them solves is returned in ``degenerate`` (the caller falls back
to a search there and says so). The chain's formulation (the best-conditioned one) and the degree
of its determinant are found once per chain (:func:`prepare`) from poses of a seeded generator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numba
import numpy as np

from capmap.core.kinematics import Chain, inverse_transform

__all__ = ["Formulation", "GeneralSolver", "prepare", "candidates", "quantities", "MAX_ROOTS"]

MAX_ROOTS = 48  # candidates per pose (24 roots of a degree-12 determinant, some shared by several solutions); more: degenerate
_SAMPLES = 25  # qa samples of the determinant: exact for degree <= 12
_RANK_TOL = 1e-9  # sigma_8 / sigma_1 of Q below this: Q is rank deficient (special geometry)
_DEGREE_TOL = 1e-9  # coefficients above the chain's degree must be below this (relative)
_REAL_TOL = 1e-2  # companion eigenvalues with |imag| <= this (relative) are candidates (then polished, checked)

_SPLIT_TOL = 1e-3  # pivots of M(root) below this (relative) span its null space: several solutions may share the root

_G1 = np.array([0.0, 2 * np.pi / 3, 4 * np.pi / 3])


def _basis(q: np.ndarray) -> np.ndarray:
    """(..., 3): 1, cos q, sin q."""
    return np.stack([np.ones_like(q), np.cos(q), np.sin(q)], axis=-1)


def _grid(k: int) -> np.ndarray:
    return np.stack(np.meshgrid(*([_G1] * k), indexing="ij"), axis=-1).reshape(-1, k)


def _tensor(Q: np.ndarray) -> np.ndarray:
    out = _basis(Q[:, 0])
    for j in range(1, Q.shape[1]):
        out = np.einsum("ni,nj->nij", out, _basis(Q[:, j])).reshape(len(Q), -1)
    return out


_G2, _G3 = _grid(2), _grid(3)
_B2_INV, _B3_INV = np.linalg.inv(_tensor(_G2)), np.linalg.inv(_tensor(_G3))
_H = np.array([[1.0, 0.0, 1.0], [1.0, 0.0, -1.0], [0.0, 2.0, 0.0]])  # (1+x^2)(1, c, s) in x^0, x^1, x^2
_HH = np.kron(_H, _H)  # (9 monomials of (qb, qc), 9 of (xb, xc))


def _rz(q: np.ndarray) -> np.ndarray:
    c, s = np.cos(q), np.sin(q)
    T = np.zeros(np.shape(q) + (4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 1, 0], T[..., 1, 1] = c, -s, s, c
    T[..., 2, 2] = T[..., 3, 3] = 1.0
    return T


def quantities(F: np.ndarray) -> np.ndarray:
    """The 14 Raghavan-Roth quantities (..., 14) of frames F (..., 4, 4): p, l, p.p, p.l, p x l,
    (p.p) l - 2 (p.l) p with p the origin and l the z axis."""
    p, l = F[..., :3, 3], F[..., :3, 2]
    pp = np.sum(p * p, axis=-1, keepdims=True)
    pl = np.sum(p * l, axis=-1, keepdims=True)
    return np.concatenate([p, l, pp, pl, np.cross(p, l), pp * l - 2 * pl * p], axis=-1)


@dataclass(frozen=True)
class Formulation:
    """One elimination: joint ``f`` (3, 4 or 5) eliminated, on the chain or (``reversed``) on its inverse."""

    f: int
    reversed: bool

    @property
    def name(self) -> str:
        return f"f{self.f}{'r' if self.reversed else ''}"


FORMULATIONS = tuple(Formulation(f, r) for r in (False, True) for f in (5, 4, 3))


def _sides(X: np.ndarray, f: int, qu: np.ndarray, qv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A (..., 4, 4) and B (..., 4, 4) of the loop for the remaining joints' angles qu, qv."""
    if f == 5:
        return X[0] @ _rz(qu) @ X[1] @ _rz(qv) @ X[2], np.broadcast_to(X[6], np.shape(qu) + (4, 4))
    if f == 4:
        return X[0] @ _rz(qu) @ X[1], X[5] @ _rz(qv) @ X[6]
    return np.broadcast_to(X[0], np.shape(qu) + (4, 4)), X[4] @ _rz(qu) @ X[5] @ _rz(qv) @ X[6]


def _left(X: np.ndarray, f: int, qa, qb, qc) -> np.ndarray:
    a = f - 3
    return _rz(qa) @ X[a + 1] @ _rz(qb) @ X[a + 2] @ _rz(qc) @ X[a + 3]


@dataclass(frozen=True, eq=False)
class GeneralSolver:
    """A chain prepared for :func:`candidates`: its formulations (best first), each with the left-side
    coefficients CL (3, 14, 9) [basis of qa, quantity, monomial of (qb, qc)] and the degree of its
    determinant."""

    chain: Chain
    order: tuple[Formulation, ...]
    left: tuple[np.ndarray, ...]
    degrees: tuple[int, ...]
    phase: float  # rad: x = tan((qa - phase) / 2)
    recovered: tuple[float, ...]  # share of the test poses whose known solution each formulation recovered

    @property
    def degree(self) -> int:
        """The degree of the best formulation's determinant (8 for a general chain: <= 16 solutions)."""
        return self.degrees[0]

    def formulation_chain(self, k: int) -> Chain:
        return self.chain.reversed() if self.order[k].reversed else self.chain


def _left_coefficients(X: np.ndarray, f: int) -> np.ndarray:
    V = quantities(_left(X, f, _G3[:, 0], _G3[:, 1], _G3[:, 2]))  # (27, 14)
    return np.moveaxis((_B3_INV @ V).reshape(3, 9, 14), 2, 1).copy()  # (3, 14, 9)


def _matrices(X: np.ndarray, f: int, CL: np.ndarray, T: np.ndarray):
    """Per pose: M (N, 3, 12, 12) (M(qa) = M0 + cos qa M1 + sin qa M2), the least-squares map of Q
    (N, 8, 14), the right-hand constant (N, 14), and sigma_8 / sigma_1 of Q (N,)."""
    N = len(T)
    A, B = _sides(X, f, _G2[:, 0], _G2[:, 1])  # (9, 4, 4)
    F = inverse_transform(A)[None] @ T[:, None] @ inverse_transform(B)[None]  # (N, 9, 4, 4)
    CR = np.einsum("rg,ngq->nrq", _B2_INV, quantities(F))  # (N, 9, 14): monomials of (qu, qv)
    Q = np.swapaxes(CR[:, 1:], 1, 2)  # (N, 14, 8)
    U, S, Vt = np.linalg.svd(Q)
    rank = S[:, 7] / np.maximum(S[:, 0], 1e-300)
    Nl = np.swapaxes(U[:, :, 8:], 1, 2)  # (N, 6, 14)
    lstsq = np.swapaxes(Vt, 1, 2) @ (np.swapaxes(U[:, :, :8], 1, 2) / np.maximum(S, 1e-300)[:, :, None])
    P = np.broadcast_to(CL, (N, 3, 14, 9)).copy()
    P[:, 0, :, 0] -= CR[:, 0]
    E = np.einsum("nek,nakm->naem", Nl, P) @ _HH  # (N, 3, 6, 9) in xb^i xc^j, index 3 i + j
    M = np.zeros((N, 3, 12, 12))
    M[:, :, :6, :9] = E
    M[:, :, 6:, 3:] = E
    return M, lstsq, CR[:, 0], rank


@lru_cache(maxsize=None)
def _companion_map(degree: int, phase: float) -> np.ndarray:
    """W (2D+1, 2D+1) complex: the coefficients (x^0 .. x^2D) of (1+x^2)^D P(phase + 2 atan x) are
    Re(W @ c) for the Fourier coefficients c_k, k = -D..D, of P."""
    D = degree
    W = np.zeros((2 * D + 1, 2 * D + 1), dtype=complex)
    plus, minus = np.poly1d([1j, 1.0]), np.poly1d([-1j, 1.0])  # 1 + i x, 1 - i x
    for k in range(-D, D + 1):
        p = (plus ** (D + k)) * (minus ** (D - k)) * np.exp(1j * k * phase)
        coeffs = p.coeffs[::-1]  # x^0 upward
        W[: len(coeffs), k + D] = coeffs
    return W


_DFT = np.exp(-2j * np.pi * np.outer(np.arange(-12, 13), np.arange(_SAMPLES)) / _SAMPLES) / _SAMPLES  # (25 k, 25 n)
_THETA = 2 * np.pi * np.arange(_SAMPLES) / _SAMPLES


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
        for i in range(k + 1, n):
            m = A[i, k] / A[k, k]
            for j in range(k + 1, n):
                A[i, j] -= m * A[k, j]
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
        for i in range(k + 1, n):
            m = A[i, k] / A[k, k]
            for j in range(k + 1, n):
                A[i, j] -= m * A[k, j]
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
def _polynomials(M, dft, theta, W, degree, poly, status):
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
                live = piv[11] > 1e-12 * piv[0]
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
def _back_substitute(M, pose, roots, phase, qa_out, qb_out, qc_out, n_out):
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


def _real_roots(poly: np.ndarray, usable: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Real roots of the polynomials poly (N, 2D+1) (x^0 upward) of the ``usable`` poses, by the
    eigenvalues of their companion matrices (numpy, batched per effective degree): (pose (R,), x (R,)).
    Eigenvalues with |imag| <= _REAL_TOL (1 + |real|) are kept: near-double roots split into
    complex pairs of small imaginary part, and every candidate is polished and checked later."""
    scale = np.max(np.abs(poly), axis=1, keepdims=True)
    nz = np.abs(poly) > 1e-14 * np.maximum(scale, 1e-300)
    top = np.where(nz.any(axis=1), poly.shape[1] - 1 - np.argmax(nz[:, ::-1], axis=1), 0)
    poses, xs = [], []
    for deg in np.unique(top[usable & (top > 0)]):
        rows = np.flatnonzero(usable & (top == deg))
        comp = np.zeros((len(rows), deg, deg))
        comp[:, 0, :] = -poly[rows, deg - 1::-1] / poly[rows, deg, None]
        comp[:, np.arange(1, deg), np.arange(deg - 1)] = 1.0
        ev = np.linalg.eigvals(comp)  # (R, deg)
        keep = np.abs(ev.imag) <= _REAL_TOL * (1.0 + np.abs(ev.real))
        r, k = np.nonzero(keep)
        poses.append(rows[r])
        xs.append(ev.real[r, k])
    if not poses:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    return np.concatenate(poses).astype(np.int64), np.concatenate(xs)


def _finish_angles(X: np.ndarray, f: int, CL, lstsq, const, T, qa, qb, qc):
    """The remaining joints qu, qv (least squares on Q) and qf (orientation) for roots (N, R): theta (N, R, 6)."""
    L = _left(X, f, qa, qb, qc)  # (N, R, 4, 4)
    mono = np.einsum("nri,nrj->nrij", _basis(qb), _basis(qc)).reshape(*qb.shape, 9)
    lhs = np.einsum("nri,iqm,nrm->nrq", _basis(qa), CL, mono) - const[:, None]  # (N, R, 14)
    y = np.einsum("nkq,nrq->nrk", lstsq, lhs)  # (N, R, 8): monomials of (qu, qv) but the constant
    qv = np.arctan2(y[..., 1], y[..., 0])
    qu = np.arctan2(y[..., 5], y[..., 2])
    A, B = _sides(X, f, qu, qv)
    R = inverse_transform(A @ L) @ T[:, None] @ inverse_transform(B)  # = Rz(qf)
    qf = np.arctan2(R[..., 1, 0], R[..., 0, 0])
    a = f - 3
    theta = np.zeros(qa.shape + (6,))
    theta[..., a], theta[..., a + 1], theta[..., a + 2], theta[..., f] = qa, qb, qc, qf
    rest = [j for j in range(6) if j not in (a, a + 1, a + 2, f)]
    theta[..., rest[0]], theta[..., rest[1]] = qu, qv
    return theta


def _solve_formulation(chain: Chain, f: int, CL: np.ndarray, degree: int, phase: float, T: np.ndarray):
    """theta (N, K, 6), ok (N, K), status (N,) of one formulation on ``chain``; status 0 solved, 1 a
    determinant vanishing identically, 2 of too high a degree, 3 a rank-deficient Q, 4 more
    candidates than MAX_ROOTS."""
    N = len(T)
    M, lstsq, const, rank = _matrices(chain.X, f, CL, T)
    M = np.ascontiguousarray(M)
    poly, status = np.zeros((N, 2 * degree + 1)), np.zeros(N, dtype=np.int64)
    _polynomials(M, _DFT, _THETA, _companion_map(degree, phase), degree, poly, status)
    status[rank < _RANK_TOL] = 3
    pose, x = _real_roots(poly, status == 0)
    qa, qb, qc = (np.zeros((N, MAX_ROOTS)) for _ in range(3))
    count = np.zeros(N, dtype=np.int64)
    _back_substitute(M, pose, x, phase, qa, qb, qc, count)
    status[count > MAX_ROOTS] = 4
    count = np.minimum(count, MAX_ROOTS)
    width = max(int(count.max(initial=0)), 1)
    qa, qb, qc = qa[:, :width], qb[:, :width], qc[:, :width]
    ok = (np.arange(width)[None] < count[:, None]) & (status == 0)[:, None]
    theta = _finish_angles(chain.X, f, CL, lstsq, const, T, qa, qb, qc)
    return theta, ok, status


def _recovered(theta: np.ndarray, ok: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(N,) bool: the known solution q (N, 6) is within 1e-4 rad of one of the raw candidates."""
    d = np.abs(np.mod(theta - q[:, None] + np.pi, 2 * np.pi) - np.pi).max(axis=-1)
    return np.any(ok & (d < 1e-4), axis=1)


def prepare(chain: Chain, rng: np.random.Generator | None = None, n_poses: int = 24) -> GeneralSolver:
    """The chain's formulations, best first, with their determinants' degrees, from ``n_poses``
    poses FK(q) of uniform random q (``rng``; a fixed seed when None, so the choice is
    reproducible). A formulation is ranked by the share of those poses whose known q it recovers,
    then by the conditioning of Q (a special geometry can make a formulation fail: its
    determinant vanishes identically, or its roots lose the solutions)."""
    if chain.n != 6:
        raise ValueError(f"the general 6R method needs 6 joints, this chain has {chain.n}")
    rng = np.random.default_rng(20260) if rng is None else rng
    q = rng.uniform(-np.pi, np.pi, (n_poses, 6))
    phase = float(rng.uniform(0.0, 2 * np.pi))
    scores, lefts, degrees = [], [], []
    for form in FORMULATIONS:
        ch = chain.reversed() if form.reversed else chain
        CL = _left_coefficients(ch.X, form.f)
        qf = -q[:, ::-1] if form.reversed else q
        T = ch.fk(qf)
        M, _, _, rank = _matrices(ch.X, form.f, CL, T)
        dets = np.linalg.det(M[:, 0][:, None] + np.cos(_THETA)[None, :, None, None] * M[:, 1][:, None]
                             + np.sin(_THETA)[None, :, None, None] * M[:, 2][:, None])
        coef = np.abs(dets @ _DFT.T)  # (n, 25) k = -12..12
        k = np.abs(np.arange(-12, 13))
        deg = int(max(k[c > 1e-8 * c.max()].max() if c.max() > 0 else 0 for c in coef))
        theta, ok, status = _solve_formulation(ch, form.f, CL, max(deg, 1), phase, np.ascontiguousarray(T))
        found = _recovered(theta, ok, qf) & (status == 0)
        lefts.append(CL)
        degrees.append(max(deg, 1))
        scores.append((float(found.mean()), float(rank.min())))
    order = sorted(range(len(FORMULATIONS)), key=lambda i: scores[i], reverse=True)
    return GeneralSolver(chain=chain, order=tuple(FORMULATIONS[i] for i in order),
                         left=tuple(lefts[i] for i in order), degrees=tuple(degrees[i] for i in order),
                         phase=phase, recovered=tuple(scores[i][0] for i in order))


def candidates(solver: GeneralSolver, T: np.ndarray, max_tries: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate solutions (N, MAX_ROOTS, 6) rad, their validity (N, MAX_ROOTS) and the poses no
    formulation solved (N,) bool, for targets T (N, 4, 4) in the chain's base frame."""
    N = len(T)
    theta = np.zeros((N, MAX_ROOTS, 6))
    ok = np.zeros((N, MAX_ROOTS), dtype=bool)
    todo = np.arange(N)
    width = 1
    for k, form in enumerate(solver.order[:max_tries]):
        if not len(todo):
            break
        ch = solver.formulation_chain(k)
        Tk = inverse_transform(T[todo]) if form.reversed else T[todo]
        th, good, status = _solve_formulation(ch, form.f, solver.left[k], solver.degrees[k], solver.phase,
                                              np.ascontiguousarray(Tk))
        if form.reversed:
            th = -th[..., ::-1]
        done = status == 0
        w = th.shape[1]
        width = max(width, w)
        theta[todo[done], :w], ok[todo[done], :w] = th[done], good[done]
        todo = todo[~done]
    degenerate = np.zeros(N, dtype=bool)
    degenerate[todo] = True
    return theta[:, :width], ok[:, :width], degenerate
