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
higher degree than the chain's, marks the pose. :func:`candidates` solves every pose with the two
best formulations and joins their candidates (one formulation's roots can lose solutions another
keeps) and tries further formulations for a pose both leave unsolved; a pose none of them solves
is returned in ``degenerate`` (the caller falls back to a search there and says so). The ranking of
the formulations and the degrees of their determinants are found once per chain
(:func:`prepare`) from poses of a seeded generator.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from capmap.core.ik_general_kernels import back_substitute, polynomials
from capmap.core.kinematics import Chain, inverse_transform

__all__ = ["Formulation", "GeneralSolver", "prepare", "candidates", "quantities", "MAX_ROOTS"]

MAX_ROOTS = 48  # candidates per pose (24 roots of a degree-12 determinant, some shared by several solutions); more: degenerate
_SAMPLES = 25  # qa samples of the determinant: exact for degree <= 12
_RANK_TOL = 1e-9  # sigma_8 / sigma_1 of Q below this: Q is rank deficient (special geometry)
_REAL_TOL = 1e-2  # companion eigenvalues with |imag| <= this (relative) are candidates (then polished, checked)

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
    polynomials(M, _DFT, _THETA, _companion_map(degree, phase), degree, poly, status)
    status[rank < _RANK_TOL] = 3
    pose, x = _real_roots(poly, status == 0)
    qa, qb, qc = (np.zeros((N, MAX_ROOTS)) for _ in range(3))
    count = np.zeros(N, dtype=np.int64)
    back_substitute(M, pose, x, phase, qa, qb, qc, count)
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


UNION = 2  # formulations every pose is solved by (their candidates joined): one formulation's roots can lose
# solutions another keeps (measured: Baxter's left arm with joint 2 locked, 4 of 8 lost by the best-ranked one)


def candidates(solver: GeneralSolver, T: np.ndarray, max_tries: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate solutions (N, K, 6) rad, their validity (N, K) and the poses no formulation solved
    (N,) bool, for targets T (N, 4, 4) in the chain's base frame. Every pose is solved by the
    ``UNION`` best formulations that recover every test pose (the best one at least), their
    candidates joined; a pose they both leave unsolved tries the next formulations."""
    N = len(T)
    parts = []
    solved = np.zeros(N, dtype=bool)
    used = 0
    for k, form in enumerate(solver.order[:max_tries]):
        union = used < UNION and (k == 0 or solver.recovered[k] == 1.0)
        rows = np.arange(N) if union else np.flatnonzero(~solved)
        if not len(rows):
            break
        ch = solver.formulation_chain(k)
        Tk = inverse_transform(T[rows]) if form.reversed else T[rows]
        th, good, status = _solve_formulation(ch, form.f, solver.left[k], solver.degrees[k], solver.phase,
                                              np.ascontiguousarray(Tk))
        if form.reversed:
            th = -th[..., ::-1]
        done = status == 0
        theta = np.zeros((N,) + th.shape[1:])
        ok = np.zeros((N, th.shape[1]), dtype=bool)
        theta[rows[done]], ok[rows[done]] = th[done], good[done]
        parts.append((theta, ok))
        solved[rows[done]] = True
        used += union
    theta = np.concatenate([p[0] for p in parts], axis=1)
    ok = np.concatenate([p[1] for p in parts], axis=1)
    return theta, ok, ~solved
