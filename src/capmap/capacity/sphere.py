"""The exact minimum of the capacity over the continuous sphere of motion directions (compiled
with numba), in place of a direction grid's minimum (which overstates it by up to ~0.6 % for the
paper's 10-degree grid).

For one configuration, output k and a unit motion direction u (see
:func:`capmap.capacity.engine.affine_over_directions`):

    y(u) = c0 + a cL.u + u' Qv u        (Qv = v^2 Q, the velocity terms; y = y0 of the payload-free state)
    t(u) = a S.u - S.g                  (the payload's coefficient: y(m) = y(u) + m t(u))

and the output allows m <= (L - sign(t) y) / |t|, or nothing at all where |y(u)| > L. Written with
sigma = sign(t) fixed, the bound is the ratio N/D of N = L - sigma y (a quadratic on the sphere) over
D = sigma t (affine), on the cap where D > 0. So

1. the configuration's capacity is 0 exactly when some output has max over the sphere of |y| > L:
   the minimum of L - sigma y over the sphere, for both signs; and otherwise
2. it is min over (k, sigma) of min over {D > 0} of N/D, a fractional programme solved exactly by
   Dinkelbach's method: lambda is below that minimum iff min over the sphere of G = N - lambda D
   is >= 0 (where D <= 0, G = N + lambda |D| >= 0 already), and while it is not, the minimiser u
   gives a smaller lambda = N(u)/D(u) (superlinear convergence).

Both steps are quadratic minimisations on the unit sphere, a trust-region subproblem with an
equality constraint, solved globally: eigen-decomposition of the 3x3 quadratic form (Jacobi
rotations), then the secular equation for the multiplier mu <= the least eigenvalue (Newton with
bisection), the hard case included. The Lagrangian dual at mu bounds the minimum from below, so a
certificate "G >= 0 everywhere" never rests on a local minimum; every capacity reported is the bound
at an actual direction u, so it is never below the exact minimum by more than rounding. A cheap
bound (G >= c - |b| - |Qv|_F) skips the subproblem for outputs far from binding; a small antipodal
start set gives Dinkelbach's first lambda.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["START_DIRECTIONS", "min_over_sphere", "start_directions"]

START_DIRECTIONS = 8  # antipodal pairs of the start set (Fibonacci lattice): only the first lambda depends on it

_jit = numba.njit(cache=True, error_model="numpy")
_REL = 1e-12  # certificates hold to this fraction of the terms' size (rounding of a few flops on 3x3 forms)


def start_directions(n_pairs: int = START_DIRECTIONS) -> np.ndarray:
    """(2 n_pairs, 3) unit directions: a Fibonacci half-set and its antipodes (pair p is rows p and p + n)."""
    i = np.arange(n_pairs) + 0.5
    beta = np.arccos(1 - i / n_pairs)  # the upper hemisphere
    alpha = np.mod(np.pi * (1 + 5**0.5) * i, 2 * np.pi)
    u = np.stack([np.sin(beta) * np.cos(alpha), np.sin(beta) * np.sin(alpha), np.cos(beta)], axis=1)
    return np.concatenate([u, -u])


@_jit
def _y(c, a, v2, x0, x1, x2):
    """The payload-free output y(u) of coefficients c (10,) along u = (x0, x1, x2)."""
    return (c[0] + a * (c[1] * x0 + c[2] * x1 + c[3] * x2)
            + v2 * (c[4] * x0 * x0 + c[5] * x1 * x1 + c[6] * x2 * x2 + c[7] * x0 * x1 + c[8] * x0 * x2 + c[9] * x1 * x2))


@_jit
def _eig3(Q, w, V, A):
    """Symmetric Q (3, 3) -> eigenvalues w (3,) and eigenvectors V (3, 3) (columns), cyclic Jacobi;
    A (3, 3) workspace."""
    for i in range(3):  # (element by element: an array assignment compiles numba's shape-mismatch error, ~3 s)
        for j in range(3):
            A[i, j] = Q[i, j]
            V[i, j] = 1.0 if i == j else 0.0
    for _ in range(30):
        off = A[0, 1] ** 2 + A[0, 2] ** 2 + A[1, 2] ** 2
        diag = A[0, 0] ** 2 + A[1, 1] ** 2 + A[2, 2] ** 2
        if off <= 1e-36 * diag or off == 0.0:
            break
        for p, q in ((0, 1), (0, 2), (1, 2)):
            apq = A[p, q]
            if apq == 0.0:
                continue
            theta = (A[q, q] - A[p, p]) / (2.0 * apq)
            t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
            c = 1.0 / np.sqrt(t * t + 1.0)
            s = t * c
            for r in range(3):  # A <- A J, then J' A
                arp, arq = A[r, p], A[r, q]
                A[r, p] = c * arp - s * arq
                A[r, q] = s * arp + c * arq
            for r in range(3):
                apr, aqr = A[p, r], A[q, r]
                A[p, r] = c * apr - s * aqr
                A[q, r] = s * apr + c * aqr
            for r in range(3):
                vrp, vrq = V[r, p], V[r, q]
                V[r, p] = c * vrp - s * vrq
                V[r, q] = s * vrp + c * vrq
    for i in range(3):
        w[i] = A[i, i]


@_jit
def _trs(c, b, d, V, u, be, x):
    """min over |u| = 1 of c + b.u + u' A u, A = V diag(d) V' (3x3): writes the minimiser u (3,) and
    returns (its value, a lower bound of the minimum: the Lagrangian dual); be, x (3,) workspace."""
    for i in range(3):
        be[i] = V[0, i] * b[0] + V[1, i] * b[1] + V[2, i] * b[2]
    i1 = 0
    for i in range(1, 3):
        if d[i] < d[i1]:
            i1 = i
    d1 = d[i1]
    nb = np.sqrt(be[0] ** 2 + be[1] ** 2 + be[2] ** 2)
    scale = abs(d[0]) + abs(d[1]) + abs(d[2]) + nb
    tol_d = 1e-13 * scale
    free2 = 0.0  # the linear term on the least eigenvalue's eigenspace
    rest = 0.0  # |x|^2 of the other components at mu = d1
    for i in range(3):
        if d[i] - d1 <= tol_d:
            free2 += be[i] ** 2
        else:
            rest += be[i] ** 2 / (4.0 * (d[i] - d1) ** 2)
    slack = 0.0  # what the dual bound leaves out
    if np.sqrt(free2) <= 1e-13 * scale and rest <= 1.0:
        # hard case: mu = d1, the rest of the unit norm on the least eigenvector
        mu = d1
        placed = False
        for i in range(3):
            if d[i] - d1 > tol_d:
                x[i] = -be[i] / (2.0 * (d[i] - d1))
            else:
                x[i] = 0.0
        for i in range(3):
            if d[i] - d1 <= tol_d and not placed:
                x[i] = np.sqrt(max(1.0 - rest, 0.0)) * (-1.0 if be[i] > 0.0 else 1.0)
                placed = True
        dual = c + mu
        for i in range(3):
            if d[i] - d1 > tol_d:
                dual -= be[i] ** 2 / (4.0 * (d[i] - mu))
        slack = np.sqrt(free2)
    else:
        # secular equation phi(mu) = sum be_i^2 / (4 (d_i - mu)^2) = 1 on (d1 - |be|/2, d1)
        lo = d1 - 0.5 * nb - tol_d
        hi = d1
        mu = lo
        for _ in range(100):
            phi = 0.0
            dphi = 0.0
            for i in range(3):
                r = d[i] - mu
                phi += be[i] ** 2 / (4.0 * r * r)
                dphi += be[i] ** 2 / (2.0 * r * r * r)
            if phi < 1.0:
                lo = mu
            else:
                hi = mu
            # Newton on 1/sqrt(phi) - 1 (near linear in mu by the least eigenvalue's term)
            g = 1.0 / np.sqrt(phi) - 1.0
            dg = -0.5 * dphi / (phi * np.sqrt(phi))
            newton = mu - g / dg if dg != 0.0 else 0.5 * (lo + hi)
            if abs(newton - mu) <= 1e-15 * (abs(mu) + scale):
                break  # converged to rounding at mu (any mu < d1 keeps the dual a valid lower bound)
            step = newton if lo < newton < hi else 0.5 * (lo + hi)
            if hi - lo <= 1e-16 * (abs(mu) + scale) or step == mu:
                break
            mu = step
        if not mu < d1:
            mu = 0.5 * (lo + hi)
        dual = c + mu
        for i in range(3):
            x[i] = -be[i] / (2.0 * (d[i] - mu))
            dual -= be[i] ** 2 / (4.0 * (d[i] - mu))
        n = np.sqrt(x[0] ** 2 + x[1] ** 2 + x[2] ** 2)
        for i in range(3):
            x[i] /= n
    for j in range(3):
        u[j] = V[j, 0] * x[0] + V[j, 1] * x[1] + V[j, 2] * x[2]
    n = np.sqrt(u[0] ** 2 + u[1] ** 2 + u[2] ** 2)
    val = c
    for j in range(3):
        u[j] /= n
        val += b[j] * u[j]
    for k in range(3):  # u' A u = sum_k d_k (V_k . u)^2
        z = V[0, k] * u[0] + V[1, k] * u[1] + V[2, k] * u[2]
        val += d[k] * z * z
    return val, dual - slack


@_jit
def _sphere(C, S, U, a, v2, g, limit, cap, worst_u, binding, n_sub):
    """C (M, K, 10), S (M, K, 3) coefficients; U (2P, 3) start directions (pairs p, p + P);
    a = a_max, v2 = v_max^2; g (3,); limit (K,). Writes cap (M,), worst_u (M, 3), binding (M,),
    n_sub (M,) the subproblems solved."""
    M, K, _ = C.shape
    P2 = U.shape[0]
    Qv = np.empty((K, 3, 3))
    qf = np.empty(K)  # |Qv|_F: the quadratic term's bound
    w = np.empty((K, 3))
    V = np.empty((K, 3, 3))
    have = np.zeros(K, dtype=np.bool_)
    b = np.empty(3)
    u = np.empty(3)
    be = np.empty(3)
    x = np.empty(3)
    dd = np.empty(3)
    A = np.empty((3, 3))
    for m in range(M):
        # the form of each output
        for k in range(K):
            c = C[m, k]
            Qv[k, 0, 0] = v2 * c[4]
            Qv[k, 1, 1] = v2 * c[5]
            Qv[k, 2, 2] = v2 * c[6]
            Qv[k, 0, 1] = Qv[k, 1, 0] = 0.5 * v2 * c[7]
            Qv[k, 0, 2] = Qv[k, 2, 0] = 0.5 * v2 * c[8]
            Qv[k, 1, 2] = Qv[k, 2, 1] = 0.5 * v2 * c[9]
            f = 0.0
            for i in range(3):
                for j in range(3):
                    f += Qv[k, i, j] ** 2
            qf[k] = np.sqrt(f)
            have[k] = False
        # the start: the least bound over the start set
        lam = np.inf
        kb = 0
        ub0, ub1, ub2 = U[0, 0], U[0, 1], U[0, 2]
        for k in range(K):
            c = C[m, k]
            s = S[m, k]
            lim = limit[k]
            sg = s[0] * g[0] + s[1] * g[1] + s[2] * g[2]
            for p in range(P2):
                x0, x1, x2 = U[p, 0], U[p, 1], U[p, 2]
                y = _y(c, a, v2, x0, x1, x2)
                t = a * (s[0] * x0 + s[1] * x1 + s[2] * x2) - sg
                if lim - abs(y) < 0.0:
                    r = 0.0
                elif t > 0.0:
                    r = (lim - y) / t
                elif t < 0.0:
                    r = (lim + y) / -t
                else:
                    r = np.inf
                r = 0.0 if r < 0.0 else r
                if r < lam:
                    lam, kb, ub0, ub1, ub2 = r, k, x0, x1, x2
        nsub = 0
        # 1. is some output violated with no payload somewhere on the sphere?
        if lam > 0.0:
            for k in range(K):
                c = C[m, k]
                lim = limit[k]
                cl = a * np.sqrt(c[1] ** 2 + c[2] ** 2 + c[3] ** 2)
                done = False
                for sigma in (1.0, -1.0):
                    c0 = lim - sigma * c[0]
                    if c0 - cl - qf[k] >= 0.0:
                        continue
                    if not have[k]:
                        _eig3(Qv[k], w[k], V[k], A)
                        have[k] = True
                    for i in range(3):
                        b[i] = -sigma * a * c[i + 1]
                    for i in range(3):
                        dd[i] = -sigma * w[k, i]
                    val, low = _trs(c0, b, dd, V[k], u, be, x)
                    nsub += 1
                    if val < 0.0:  # |y(u)| > L: nothing can be carried along u
                        lam, kb, ub0, ub1, ub2 = 0.0, k, u[0], u[1], u[2]
                        done = True
                        break
                if done:
                    break
        # 2. Dinkelbach per (output, sign), the start's binding output first
        if lam > 0.0:
            k0 = kb
            for kk in range(K):
                k = k0 if kk == 0 else (kk - 1 if kk - 1 < k0 else kk)
                c = C[m, k]
                s = S[m, k]
                lim = limit[k]
                sg = s[0] * g[0] + s[1] * g[1] + s[2] * g[2]
                for sigma in (1.0, -1.0):
                    for _ in range(60):
                        c0 = lim - sigma * c[0] + lam * sigma * sg
                        nb2 = 0.0
                        for i in range(3):
                            b[i] = -sigma * a * (c[i + 1] + lam * s[i])
                            nb2 += b[i] * b[i]
                        scale = abs(lim) + abs(c[0]) + lam * abs(sg) + np.sqrt(nb2) + qf[k]
                        if c0 - np.sqrt(nb2) - qf[k] >= 0.0:
                            break
                        if not have[k]:
                            _eig3(Qv[k], w[k], V[k], A)
                            have[k] = True
                        dmin = np.inf
                        for i in range(3):
                            dd[i] = -sigma * w[k, i]
                            dmin = min(dmin, dd[i])
                        if c0 - np.sqrt(nb2) + dmin >= _REL * scale:
                            break  # G >= c - |b| + the least eigenvalue >= 0: lambda is below this minimum
                        val, low = _trs(c0, b, dd, V[k], u, be, x)
                        nsub += 1
                        if low >= -_REL * scale or val >= 0.0:
                            break  # lambda <= this (output, sign)'s minimum (to the dual's rounding)
                        # the minimiser's own bound: N - lambda D < 0 there, so N < 0 (|y| > L: nothing can be
                        # carried along u) unless D > 0, and then N / D < lambda
                        y = _y(c, a, v2, u[0], u[1], u[2])
                        den = sigma * (a * (s[0] * u[0] + s[1] * u[1] + s[2] * u[2]) - sg)
                        num = lim - sigma * y
                        r = num / den if den > 0.0 and num >= 0.0 else 0.0
                        if not r < lam:
                            break
                        lam, kb, ub0, ub1, ub2 = r, k, u[0], u[1], u[2]
        cap[m] = lam
        worst_u[m, 0] = ub0
        worst_u[m, 1] = ub1
        worst_u[m, 2] = ub2
        binding[m] = kb
        n_sub[m] = nsub


def min_over_sphere(C: np.ndarray, S: np.ndarray, a_max: float, v_max: float, gravity: np.ndarray, limit: np.ndarray,
                    start: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The exact minimum over all unit motion directions of the capacity of M configurations.

    C (M, n_out, 10), S (M, n_out, 3): the coefficients (:meth:`Coefficients.stacked`, ``S``);
    a_max m/s^2, v_max m/s; gravity (3,) m/s^2; limit (n_out,). ``start``: (2P, 3) start directions in
    antipodal pairs (default :func:`start_directions`). Returns capacity (M,) kg, the worst direction
    (M, 3) (a unit vector), the binding output (M,) and the subproblems solved (M,)."""
    M = len(C)
    U = start_directions() if start is None else np.ascontiguousarray(start, dtype=float)
    cap = np.empty(M)
    worst = np.empty((M, 3))
    binding = np.empty(M, dtype=np.int64)
    n_sub = np.empty(M, dtype=np.int64)
    if M:
        _sphere(np.ascontiguousarray(C, dtype=float), np.ascontiguousarray(S, dtype=float), U, float(a_max),
                float(v_max) ** 2, np.asarray(gravity, dtype=float), np.ascontiguousarray(limit, dtype=float), cap,
                worst, binding, n_sub)
    return cap, worst, binding, n_sub
