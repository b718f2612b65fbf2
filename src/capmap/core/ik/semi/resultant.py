"""Every IK solution of a chain ``0 | 1 | 2 3 parallel | 4 5 intersecting`` (the SSRMS-type arm with
joint 3, 4 or 5 locked) as the real roots of one polynomial in joint 0, batched over poses.

The semi-analytical method (:mod:`capmap.core.ik.semi.search`) follows Xu, She and Xu (Acta Astronautica
105, 2014): for a fixed q0 joints 1, 4, 5 are closed forms and one residual is left, searched over
q0. Here that residual is eliminated exactly. In the frame of joint 2 (z along the parallel axes),
with P' the wrist point (where axes 4 and 5 meet) and w the axis of joint 5, both bilinear in
(cos q0, sin q0) x (cos q1, sin q1), and phi the summed angle of the parallel pair:

    E1:  P'_z = h                                       (the wrist point's height on the parallel axes)
    A:   a1 cos phi + a2 sin phi = a3                   (axis 4 at its fixed angle to axis 5)
    B:   b1 cos phi + b2 sin phi = b3                   (the planar 2R reaches the wrist point)

A and B have a common solution on the unit circle iff
F = (a3 b2 - a2 b3)^2 + (a1 b3 - a3 b1)^2 - (a1 b2 - a2 b1)^2 = 0. E1 is linear in (cos q1, sin q1):
its two roots q1+-(q0) (complex where E1 has no real root), and the resultant of E1 and F in q1,

    P(q0) = rho^4 F(q0, q1+) F(q0, q1-),    rho^2 = (the E1 coefficients of cos q1, sin q1)^2 summed,

is a trigonometric polynomial in q0 (degree 8 on the SSRMS: at most 16 roots; the chain's degree is
measured once from seeded poses, :func:`prepare`). P is sampled at 2D + 3 angles (one harmonic above D
measures the rounding noise), its real roots are the eigenvalues of a companion matrix (in x =
tan((q0 - phase)/2), a seeded phase, as in :mod:`capmap.core.ik.general.elimination`), and at every root the
closed forms of the semi-analytical kernel (:mod:`capmap.core.ik.semi.kernels`) give joints 1-5 on the
branches whose residual vanishes there. No search, no grid: a pose costs one companion matrix.

Where the chain has the shape from its tip as well (every SSRMS middle lock), the direction whose
roots are better conditioned on seeded poses is used (:func:`prepare`).

A pose is degenerate when P is (numerically) zero for every q0, has a harmonic above D (its
samples are not accurate: rho near 0 at a sample), loses degree (a root toward x = infinity), its
QR iteration fails, a root's error bound exceeds ``_MAX_WINDOW``, or a complex eigenvalue's error
bound reaches the real axis (``doubt`` > 0.1,
:class:`capmap.core.ik.roots.RealRoots`): those poses are solved by the 1-D search, complete as well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np

import capmap.core.ik.semi.kernels as ik_kernels
import capmap.core.ik.semi.search as ik_semi
from capmap.core.ik.general.elimination import companion_map, sampling
from capmap.core.ik.roots import real_roots
from capmap.core.kinematics import Chain, inverse_transform

__all__ = ["SemiPolynomial", "prepare", "candidates", "polynomial_samples"]

_REAL_TOL = 1e-2  # companion eigenvalues with |imag| <= this (1 + |real|) are candidates (then checked)
_DEGREE_TOL = 1e-9  # a harmonic above D larger than this x the largest: the samples are not accurate
_ZERO_TOL = 1e-12  # max |P| below this x its terms' scale: P vanishes identically (a continuum)
_DOUBT = 0.1  # a dropped complex root whose error bound reaches this fraction of |imag|: search the pose
_PAIR_DOUBT = 1e-3  # a kept complex pair whose error bound reaches this fraction of |imag|: search around it
_BRANCH_TOL = 1e-4  # at a root: the branch of least residual, and others below this x the chain's length
_FOLD_SLACK = 1e-3  # a root this close past the fold of joint 1 or 4 (where two branches meet) keeps them
_WINDOW = 1e-3  # rad: half-width of the search around a root known only approximately
_ROOT_SPREAD = 1e-5  # rad: a root whose error bound exceeds this is searched around (clusters of 3 or more)
_MAX_WINDOW = 5e-3  # rad: a pose with a root known to worse than this gets the full search
_WINDOW_POINTS = 8  # samples of each branch across a window (then the search's refinement)
_PREP_POSES = 32
_SCORE_POSES = 128  # seeded poses on which the two directions of a reversible chain are compared


@dataclass(frozen=True)
class SemiPolynomial:
    """Per chain: the packed constants of :func:`polynomial_samples` (``k``) and of the semi-analytical
    kernel (``c``), the degree D of P in q0, the phase of the substitution (rad), the chain's length
    scale (m), and ``reversed``: ``chain`` is the inverse of the caller's chain (solved from its tip)."""

    chain: Chain
    k: np.ndarray
    c: np.ndarray
    degree: int
    phase: float
    length: float
    reversed: bool = False


def _constants(chain: Chain, semi: ik_kernels.SemiConstants) -> tuple[np.ndarray, float]:
    X = chain.X
    u = (np.linalg.inv(X[6]) @ np.array([0.0, 0.0, semi.s_star, 1.0]))[:3]
    S = np.diag([1.0, semi.sigma, semi.sigma])  # Rz(q2) R3 Rz(q3) = Rz(phi) S
    v, m = S @ X[4][:3, 2], S @ semi.wc
    t3 = X[3][:3, 3]
    k = np.concatenate([X[0].ravel(), X[1].ravel(), X[2].ravel(), u, X[6][2, :3], v, m,
                        [semi.h, X[5][2, 2], m[0] ** 2 + m[1] ** 2 - t3[0] ** 2 - t3[1] ** 2]])
    length = 1.0 + float(np.abs(X[:, :3, 3]).sum())
    return k, length


@numba.njit(cache=True)
def polynomial_samples(k, T, theta, out, scale):
    """P(q0) (see the module docstring) for poses T (N, 4, 4) at angles theta (S,) rad -> out (N, S);
    scale (N, S): the same product taken over the terms' magnitudes (for the identically-zero test)."""
    X0, X1, X2 = k[0:16].reshape(4, 4), k[16:32].reshape(4, 4), k[32:48].reshape(4, 4)
    u, z6, v, m = k[48:51], k[51:54], k[54:57], k[57:60]
    h, kappa, mt = k[60], k[61], k[62]
    n1x, n1y, n1z = X2[0, 2], X2[1, 2], X2[2, 2]
    hc = h + n1x * X2[0, 3] + n1y * X2[1, 3] + n1z * X2[2, 3]
    R0 = np.empty((3, 3))
    P, z5, r, y = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    for n in range(T.shape[0]):
        for i in range(3):
            P[i] = T[n, i, 0] * u[0] + T[n, i, 1] * u[1] + T[n, i, 2] * u[2] + T[n, i, 3]
            z5[i] = T[n, i, 0] * z6[0] + T[n, i, 1] * z6[1] + T[n, i, 2] * z6[2]
        for s in range(len(theta)):
            c0, s0 = math.cos(theta[s]), math.sin(theta[s])
            for i in range(3):  # R0 = X0 Rz(q0) X1, t0 = X0 Rz(q0) t1 + t0
                a0, a1 = c0 * X0[i, 0] + s0 * X0[i, 1], -s0 * X0[i, 0] + c0 * X0[i, 1]
                for j in range(3):
                    R0[i, j] = a0 * X1[0, j] + a1 * X1[1, j] + X0[i, 2] * X1[2, j]
                r[i] = P[i] - (a0 * X1[0, 3] + a1 * X1[1, 3] + X0[i, 2] * X1[2, 3] + X0[i, 3])
            p0, p1, p2 = r[0], r[1], r[2]
            for i in range(3):
                r[i] = R0[0, i] * p0 + R0[1, i] * p1 + R0[2, i] * p2
                y[i] = R0[0, i] * z5[0] + R0[1, i] * z5[1] + R0[2, i] * z5[2]
            A = n1x * r[0] + n1y * r[1]
            B = n1x * r[1] - n1y * r[0]
            C = hc - n1z * r[2]
            rho2 = A * A + B * B
            root = np.sqrt(complex(rho2 - C * C))
            value, size = 1.0 + 0j, 1.0
            for sgn in (1.0, -1.0):
                c1 = (A * C - sgn * B * root) / rho2
                s1 = (B * C + sgn * A * root) / rho2
                g0, g1 = c1 * r[0] + s1 * r[1] - X2[0, 3], -s1 * r[0] + c1 * r[1] - X2[1, 3]
                g2 = r[2] - X2[2, 3]
                e0, e1 = c1 * y[0] + s1 * y[1], -s1 * y[0] + c1 * y[1]
                px = X2[0, 0] * g0 + X2[1, 0] * g1 + X2[2, 0] * g2  # P' = R2^T (Rz(q1)^T r - t2)
                py = X2[0, 1] * g0 + X2[1, 1] * g1 + X2[2, 1] * g2
                wx = X2[0, 0] * e0 + X2[1, 0] * e1 + X2[2, 0] * y[2]
                wy = X2[0, 1] * e0 + X2[1, 1] * e1 + X2[2, 1] * y[2]
                wz = X2[0, 2] * e0 + X2[1, 2] * e1 + X2[2, 2] * y[2]
                a1, a2, a3 = wx * v[0] + wy * v[1], wy * v[0] - wx * v[1], kappa - wz * v[2]
                b1, b2 = px * m[0] + py * m[1], py * m[0] - px * m[1]
                b3 = 0.5 * (px * px + py * py + mt)
                f1, f2, f3 = a3 * b2 - a2 * b3, a1 * b3 - a3 * b1, a1 * b2 - a2 * b1
                value *= f1 * f1 + f2 * f2 - f3 * f3
                t1 = abs(a3 * b2) + abs(a2 * b3)
                t2 = abs(a1 * b3) + abs(a3 * b1)
                t3 = abs(a1 * b2) + abs(a2 * b1)
                size *= t1 * t1 + t2 * t2 + t3 * t3
            out[n, s] = (value * rho2 * rho2).real
            scale[n, s] = size * rho2 * rho2


def _polynomials(solver: SemiPolynomial, T: np.ndarray, degree: int):
    """poly (N, 2D+1) in x (x^0 upward), status (N,) (0 usable, 1 identically zero, 2 a harmonic above D
    or a sample not finite), noise (N,) for a degree-``degree`` sampling."""
    theta, dft = sampling(degree)
    N = len(T)
    vals, scale = np.empty((N, len(theta))), np.empty((N, len(theta)))
    polynomial_samples(solver.k, np.ascontiguousarray(T, dtype=float), theta, vals, scale)
    finite = np.isfinite(vals).all(axis=1) & np.isfinite(scale).all(axis=1)  # rho = 0 exactly at a sample
    vals[~finite], scale[~finite] = 0.0, 1.0
    coef = vals @ dft.T  # (N, S) harmonics -(S-1)/2 ..
    c = (len(theta) - 1) // 2
    big = np.abs(coef).max(axis=1)
    high = np.abs(np.concatenate([coef[:, : c - degree], coef[:, c + degree + 1:]], axis=1)).max(axis=1, initial=0.0)
    status = np.where(big <= _ZERO_TOL * scale.max(axis=1), 1, np.where(high > _DEGREE_TOL * big, 2, 0))
    status[~finite] = 2
    poly = (coef[:, c - degree: c + degree + 1] @ companion_map(degree, solver.phase).T).real
    return poly, status, np.where(big > 0, high / np.where(big > 0, big, 1.0), np.inf)


def prepare(chain: Chain, reversible: bool = False, seed: int = 0) -> SemiPolynomial:
    """The solver of ``chain``; ``reversible``: the chain has the shape from its tip as well, and the
    direction whose polynomial has fewer ill-conditioned roots on ``_SCORE_POSES`` seeded poses is
    taken (the SSRMS with joint 3 locked at 98 deg: 0.43 roots per pose known to worse than 1e-5 rad
    on the chain, none on its inverse; with joint 5 locked the other way round)."""
    direct = _prepare(chain, seed)
    if not reversible:
        return direct
    inverse = _prepare(chain.reversed(), seed, reversed=True)
    T = chain.fk(np.random.default_rng(seed + 1).uniform(-np.pi, np.pi, (_SCORE_POSES, 6)))
    return min((direct, inverse), key=lambda s: _ill_conditioned(s, inverse_transform(T) if s.reversed else T))


def _ill_conditioned(solver: SemiPolynomial, T: np.ndarray) -> int:
    """How many real roots of the poses T are known to worse than ``_ROOT_SPREAD`` (plus degenerate poses)."""
    poly, status, noise = _polynomials(solver, T, solver.degree)
    found = real_roots(poly, status == 0, _REAL_TOL, noise)
    real = found.imag == 0
    spread = 2 * found.error[real] / (1 + found.x[real] ** 2)
    return int((spread > _ROOT_SPREAD).sum() + (status != 0).sum())


def _prepare(chain: Chain, seed: int, reversed: bool = False) -> SemiPolynomial:
    """The chain's constants, its degree D (the highest harmonic of P above 1e-9 of the largest over
    ``_PREP_POSES`` seeded poses, sampled at 25 angles) and a seeded phase."""
    rng = np.random.default_rng(seed)
    semi = ik_kernels.SemiConstants.of(chain.X)
    k, length = _constants(chain, semi)
    phase = float(rng.uniform(-np.pi, np.pi))
    T = chain.fk(rng.uniform(-np.pi, np.pi, (_PREP_POSES, 6)))
    theta, dft = sampling(12)
    vals, scale = np.empty((len(T), len(theta))), np.empty((len(T), len(theta)))
    polynomial_samples(k, T, theta, vals, scale)
    coef = np.abs(vals @ dft.T)
    harmonic = np.abs(np.arange(len(theta)) - (len(theta) - 1) // 2)
    degree = max(1, max(int(harmonic[row > 1e-9 * row.max()].max()) for row in coef if row.max() > 0))
    return SemiPolynomial(chain, k, semi.packed(chain.X), degree, phase, length, reversed)


class Roots(NamedTuple):
    """Candidates theta (N, K, 6) rad, ok (N, K), and the poses (N,) bool left to the search."""

    theta: np.ndarray
    ok: np.ndarray
    degenerate: np.ndarray


def roots(solver: SemiPolynomial, T: np.ndarray) -> Roots:
    """The real roots of P for every pose T (N, 4, 4) and the kernel's branches that vanish there.
    A root where no branch vanishes to ``_BRANCH_TOL`` or whose error bound exceeds ``_ROOT_SPREAD``
    (solutions close together beside a fold, each root known to ~1e-5 rad only, so that the branch of
    least residual at a root can be a neighbour's), and every complex pair kept as a candidate, are
    searched in a window around it (:func:`capmap.core.ik.semi.search.search_windows`)."""
    N, D = len(T), solver.degree
    poly, status, noise = _polynomials(solver, T, D)
    found = real_roots(poly, status == 0, _REAL_TOL, noise)
    degenerate = (status != 0) | found.failed | (found.degree != 2 * D) | (found.doubt > _DOUBT)
    # the real roots, and one of each complex pair whose error bound could reach the real axis
    kept = (found.imag == 0) | ((found.imag > 0) & (found.error > _PAIR_DOUBT * found.imag))
    spread = 2 * (np.abs(found.imag) + found.error) / (1 + found.x ** 2)  # rad: how far the root may be off
    degenerate[found.pose[kept & (spread > _MAX_WINDOW)]] = True  # wider than a window: the full search
    keep = ~degenerate[found.pose] & kept
    pose, x, imag, spread = found.pose[keep], found.x[keep], found.imag[keep], spread[keep]
    q0 = solver.phase + 2 * np.arctan(x)
    M = len(pose)
    ok, f, Tp = np.empty((M, 4), dtype=bool), np.empty((M, 4)), np.ascontiguousarray(T[pose])
    ik_kernels.residuals(solver.c, Tp, np.ascontiguousarray(q0), ok, f, _FOLD_SLACK)
    f = np.where(ok, np.abs(f), np.inf)
    tight = f <= _BRANCH_TOL * solver.length
    row, branch = np.nonzero(ok & (tight | (f == f.min(axis=1, keepdims=True))))
    theta = np.empty((len(row), 6))
    ik_kernels.branch_angles(solver.c, np.ascontiguousarray(Tp[row]), np.ascontiguousarray(q0[row]), branch, theta,
                             _FOLD_SLACK)
    rows = [(pose[row], theta)]
    loose = (imag != 0) | ~tight.any(axis=1) | (spread > _ROOT_SPREAD)
    if loose.any():
        half = _WINDOW + 4 * spread[loose]  # rad
        wt, wok, _ = ik_semi.search_windows(solver.chain, T, pose[loose], q0[loose] - half, q0[loose] + half, _WINDOW_POINTS)
        n, k = np.nonzero(wok)
        rows.append((n, wt[n, k]))
    pose, theta = np.concatenate([r[0] for r in rows]), np.concatenate([r[1] for r in rows])
    out, ok, _ = ik_semi._pack(pose, theta, np.ones(len(pose), dtype=bool), np.zeros(len(pose), dtype=bool), N)
    return Roots(out, ok, degenerate)


def candidates(solver: SemiPolynomial, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Candidate solutions (N, K, 6) rad and validity (N, K) for targets T (N, 4, 4) of the caller's
    chain: the polynomial's roots, and the 1-D search (:func:`capmap.core.ik.semi.search.candidates`) on its
    degenerate poses (on the inverse chain where the solver is ``reversed``, the angles mapped back)."""
    T = np.ascontiguousarray(inverse_transform(T) if solver.reversed else T, dtype=float)
    theta, ok, degenerate = roots(solver, T)
    if degenerate.any():
        extra, extra_ok = ik_semi.candidates(solver.chain, T[degenerate])
        pad = np.zeros((len(T), extra.shape[1], 6))
        pad_ok = np.zeros((len(T), extra.shape[1]), dtype=bool)
        pad[degenerate], pad_ok[degenerate] = extra, extra_ok
        theta, ok = np.concatenate([theta, pad], axis=1), np.concatenate([ok, pad_ok], axis=1)
    return (-theta[..., ::-1], ok) if solver.reversed else (theta, ok)
