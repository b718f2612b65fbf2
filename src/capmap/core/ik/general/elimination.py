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
degree D <= 12 in qa (8 for a general chain: at most 16 solutions); it is sampled at 2D + 3
equispaced qa (25 for D = 12), its Fourier coefficients are exact (the one harmonic above D
measures the rounding noise), and its real roots are the eigenvalues of a companion matrix (in x =
tan((qa - phase)/2), a seeded random phase, so that a root at x = infinity, qa = phase + 180 deg,
has probability zero; a formulation whose polynomial loses degree at a pose does not count as
having solved it, :mod:`capmap.core.ik.general.select`).
For each root the null vector of M(qa) gives qb, qc (from projective ratios, so qb = 180 deg is
no special case), the least-squares solution of Q gives qu, qv, and the orientation gives qf.

Degenerate cases are detected, never silently dropped: a rank-deficient Q or a determinant that
vanishes identically (special geometries, where some formulations fail), or a determinant of
higher degree than the chain's, marks the pose (:func:`solve_formulation`'s status). Which
formulations solve which poses, and how their candidates are joined, is
:mod:`capmap.core.ik.general.select`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from capmap.core.ik.general.back import back_substitute
from capmap.core.ik.general.kernels import finish_angles, polynomials
from capmap.core.ik.general.matrices import matrices
from capmap.core.ik.roots import RealRoots, real_roots
from capmap.core.kinematics import Chain, inverse_transform

__all__ = ["Formulation", "FORMULATIONS", "Solved", "solve_formulation", "left_coefficients", "degree_of",
           "companion_map", "sampling", "structural_roots", "in_cluster", "CLUSTER_TOL",
           "recovered", "quantities", "MAX_ROOTS"]

MAX_ROOTS = 48  # candidates per pose (24 roots of a degree-12 determinant, some shared by several solutions); more: degenerate
_SAMPLES = 25  # qa samples of the determinant: exact for degree <= 12
_RANK_TOL = 1e-9  # |R_88| / |R_11| of Q's pivoted QR below this: Q is rank deficient (special geometry)
CLUSTER_TOL = 1e-2  # rad: a root this close (|real part| + |imag part|) to a structural root is one of its cluster
PSEUDO = 10.0  # a dropped eigenvalue whose real part is a pseudo-zero below this ratio (RealRoots.pseudo) is a candidate too
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


def left_coefficients(X: np.ndarray, f: int) -> np.ndarray:
    V = quantities(_left(X, f, _G3[:, 0], _G3[:, 1], _G3[:, 2]))  # (27, 14)
    return np.moveaxis((_B3_INV @ V).reshape(3, 9, 14), 2, 1).copy()  # (3, 14, 9)


def _matrices(X: np.ndarray, f: int, CL: np.ndarray, T: np.ndarray):
    """Per pose: M (N, 3, 12, 12) (M(qa) = M0 + cos qa M1 + sin qa M2), the least-squares map of Q
    (N, 8, 14), the right-hand constant (N, 14), and |R_88| / |R_11| of Q's pivoted QR (N,) (compiled:
    :func:`capmap.core.ik.general.matrices.matrices`)."""
    N = len(T)
    A, B = _sides(X, f, _G2[:, 0], _G2[:, 1])  # (9, 4, 4)
    M, lstsq = np.empty((N, 3, 12, 12)), np.empty((N, 8, 14))
    const, rank = np.empty((N, 14)), np.empty(N)
    matrices(np.ascontiguousarray(inverse_transform(A)), np.ascontiguousarray(inverse_transform(B)), _B2_INV, _HH,
             np.ascontiguousarray(CL), np.ascontiguousarray(T, dtype=float), M, lstsq, const, rank)
    return M, lstsq, const, rank


@lru_cache(maxsize=None)
def companion_map(degree: int, phase: float) -> np.ndarray:
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


@lru_cache(maxsize=None)
def sampling(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """The qa samples (S,) rad and the DFT (S k, S n) for a determinant of the chain's degree D: S =
    2D + 3 (one harmonic above D, to check the degree; the chain's degree is the largest measured over
    random poses, so a pose's is no higher), 25 for D = 12 (the largest possible)."""
    S = min(2 * degree + 3, _SAMPLES)
    k = np.arange(S) - (S - 1) // 2
    return 2 * np.pi * np.arange(S) / S, np.exp(-2j * np.pi * np.outer(k, np.arange(S)) / S) / S


def _real_roots(poly: np.ndarray, usable: np.ndarray, noise: np.ndarray) -> RealRoots:
    """Real roots of the polynomials poly (N, 2D+1) (x^0 upward) of the ``usable`` poses (see
    :func:`capmap.core.ik.roots.real_roots`). Eigenvalues with |imag| <= _REAL_TOL (1 + |real|) are
    kept: near-double roots split into complex pairs of small imaginary part, and every candidate is
    polished and checked later."""
    return real_roots(poly, usable, _REAL_TOL, noise)


class Solved(NamedTuple):
    """One formulation on N poses: theta (N, K, 6) rad, ok (N, K), status (N,) (see
    :func:`solve_formulation`), real (N,): the eigenvalues the QR iteration found exactly real (not
    counting those of the structural roots' clusters), clustered (N,): the kept eigenvalues in those
    clusters (see :func:`structural_roots`), full
    (N,): the polynomial kept its full degree 2D (no root escaped toward x = infinity), doubt (N,):
    how close a dropped complex eigenvalue's error bound comes to the real axis (see
    :class:`capmap.core.ik.roots.RealRoots`)."""

    theta: np.ndarray
    ok: np.ndarray
    status: np.ndarray
    real: np.ndarray
    full: np.ndarray
    doubt: np.ndarray
    clustered: np.ndarray


def _polynomials(M: np.ndarray, degree: int, phase: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """det M(qa) of each pose as the polynomial (N, 2D+1) in x = tan((qa - phase) / 2), its status (N,)
    and noise (N,) (compiled: :func:`capmap.core.ik.general.kernels.polynomials`)."""
    N = len(M)
    poly, status, noise = np.zeros((N, 2 * degree + 1)), np.zeros(N, dtype=np.int64), np.full(N, np.inf)
    theta_s, dft = sampling(degree)
    polynomials(M, dft, theta_s, companion_map(degree, phase), degree, poly, status, noise)
    return poly, status, noise


def solve_formulation(chain: Chain, f: int, CL: np.ndarray, degree: int, phase: float, T: np.ndarray,
                      structural: np.ndarray | None = None) -> Solved:
    """One formulation on ``chain`` (its structural roots, rad: :func:`structural_roots`); status 0
    solved, 1 a determinant vanishing identically, 2 of too
    high a degree, 3 a rank-deficient Q, 4 more candidates than MAX_ROOTS, 5 a companion matrix
    whose QR iteration did not converge."""
    N = len(T)
    M, lstsq, const, rank = _matrices(chain.X, f, CL, T)
    poly, status, noise = _polynomials(M, degree, phase)
    status[rank < _RANK_TOL] = 3
    roots = _real_roots(poly, status == 0, noise)
    status[roots.failed] = 5
    angle = phase + 2 * np.arctan(roots.x + 1j * roots.imag)
    near, skip = _structural_clusters(angle, roots.pose, N, structural)
    qa, qb, qc = (np.zeros((N, MAX_ROOTS)) for _ in range(3))
    count = np.zeros(N, dtype=np.int64)
    split = roots.x + roots.imag  # a near-real pair z, conj z: candidates at Re z +- |Im z|, where a split double root lies
    doubtful = (roots.pseudo < PSEUDO) & ~in_cluster(phase + 2 * np.arctan(roots.dropped), structural)
    back_substitute(M, np.concatenate([roots.pose[~skip], roots.dropped_pose[doubtful]]),
                    np.concatenate([split[~skip], roots.dropped.real[doubtful]]),  # at Re z, where it was tested
                    phase, qa, qb, qc, count)
    status[count > MAX_ROOTS] = 4
    count = np.minimum(count, MAX_ROOTS)
    width = max(int(count.max(initial=0)), 1)
    qa, qb, qc = qa[:, :width], qb[:, :width], qc[:, :width]
    ok = (np.arange(width)[None] < count[:, None]) & (status == 0)[:, None]
    theta = np.zeros((N, width, 6))
    finish_angles(chain.X, f, CL, lstsq, const, T, qa, qb, qc, count, theta)
    real = np.bincount(roots.pose[(roots.imag == 0.0) & ~near], minlength=N)
    return Solved(theta, ok, status, real, roots.degree == 2 * degree, roots.doubt,
                  np.bincount(roots.pose[near], minlength=N))


def _structural_clusters(angle: np.ndarray, pose: np.ndarray, N: int,
                         structural: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """For kept roots at complex angles ``angle`` (R,) rad of poses ``pose`` (R,) of N: which lie in a
    structural root's cluster (R,) bool, and which of those are the structural roots themselves (R,)
    bool: their pose's clusters each hold exactly the root's multiplicity, so none is a true root
    (they give no solution, and are not back-substituted). A cluster holding more keeps all of its
    roots: a true one sits beside the structural ones."""
    if structural is None or not len(structural):
        none = np.zeros(angle.shape, dtype=bool)
        return none, none
    centres, multiplicity = np.unique(structural, return_counts=True)
    inside = _distance(angle, centres) < CLUSTER_TOL  # (R, C)
    near = inside.any(axis=1)
    if not near.any():
        return near, near
    counts = np.stack([np.bincount(pose[inside[:, c]], minlength=N) for c in range(len(centres))], axis=1)
    exact = np.all(counts == multiplicity, axis=1)
    return near, near & exact[pose]


def _distance(qa: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(..., C): |wrapped difference of qa's real part (..., rad, complex) and each centre (C,)| + |Im qa|."""
    d = np.abs(np.mod(qa.real[..., None] - centres + np.pi, 2 * np.pi) - np.pi)
    return d + np.abs(qa.imag)[..., None]


def in_cluster(qa: np.ndarray, structural: np.ndarray | None) -> np.ndarray:
    """(R,) bool: the angles qa (R,) rad (complex: a complex root's angle) within CLUSTER_TOL of a
    structural root (|difference of real parts| + |imaginary part|)."""
    qa = np.asarray(qa)
    if structural is None or not len(structural):
        return np.zeros(qa.shape, dtype=bool)
    return np.any(_distance(qa, np.unique(np.asarray(structural, dtype=float))) < CLUSTER_TOL, axis=-1)


def structural_roots(chain: Chain, f: int, CL: np.ndarray, degree: int, phase: float, T: np.ndarray) -> np.ndarray:
    """Structural roots of formulation f on ``chain`` (rad, each repeated by its multiplicity; empty
    when none): angles where det M(qa) vanishes at every pose of T (n, 4, 4), special geometry (the
    xArm7's formulation f4: 4 at q1 = 0 and 4 at 180 deg of its 16, so at most 8 solutions). An m-fold
    root is computed as m roots within ~eps^(1/m) (complex ones included), which give no solution and
    can hide a true root beside them; the multiplicity is the smallest count within CLUSTER_TOL over
    the poses, the location the mean over poses of each cluster's mean (accurate to rounding, unlike
    its members)."""
    M, _, _, _ = _matrices(chain.X, f, CL, np.ascontiguousarray(T))
    poly, status, _ = _polynomials(M, degree, phase)
    if (status != 0).any():
        return np.zeros(0)
    qa = [phase + 2 * np.arctan(np.roots(p[::-1]).astype(complex)) for p in poly]  # complex angles
    found: list[float] = []
    for r0 in qa[0]:
        near = [q[in_cluster(q, [r0.real])] for q in qa]
        m = min(len(c) for c in near)
        if not m or in_cluster(np.array([r0.real]), found).any():
            continue
        centres = [np.mean(np.exp(1j * c.real)) for c in near if len(c) == m]  # poses with no true root nearby
        found += [float(np.angle(np.mean(centres)))] * m
    return np.array(found) if len(found) < 2 * degree else np.zeros(0)


def recovered(theta: np.ndarray, ok: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(N,) bool: the known solution q (N, 6) is within 1e-4 rad of one of the candidates theta (N, K, 6)."""
    d = np.abs(np.mod(theta - q[:, None] + np.pi, 2 * np.pi) - np.pi).max(axis=-1)
    return np.any(ok & (d < 1e-4), axis=1)


def degree_of(chain: Chain, f: int, CL: np.ndarray, T: np.ndarray) -> int:
    """The degree (>= 1) of det M(qa) of formulation f on ``chain`` over the poses T (N, 4, 4): the
    highest Fourier coefficient above 1e-8 of the largest, at any pose."""
    M, _, _, _ = _matrices(chain.X, f, CL, T)
    dets = np.linalg.det(M[:, 0][:, None] + np.cos(_THETA)[None, :, None, None] * M[:, 1][:, None]
                         + np.sin(_THETA)[None, :, None, None] * M[:, 2][:, None])
    coef = np.abs(dets @ _DFT.T)  # (n, 25) k = -12..12
    k = np.abs(np.arange(-12, 13))
    return max(1, int(max(k[c > 1e-8 * c.max()].max() if c.max() > 0 else 0 for c in coef)))
