"""Real roots of many small polynomials, compiled (numba): each polynomial's companion matrix,
balanced (EISPACK ``balanc``) and reduced by the Francis double-shift QR iteration (EISPACK
``hqr``, as in Numerical Recipes). The companion matrix is already upper Hessenberg, so the
Hessenberg reduction LAPACK's ``dgeev`` performs is skipped: about half the time of
``numpy.linalg.eigvals`` on a 16 x 16 companion, with the same accuracy (tests/core/test_ik_compiled.py
compares both on polynomials whose coefficients span six decades)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

__all__ = ["real_roots", "RealRoots"]

_MAX_DEGREE = 24


class RealRoots(NamedTuple):
    """pose (R,) int and x (R,): the kept eigenvalues' rows and real parts; imag (R,): their imaginary
    parts (exactly 0 where the QR iteration found a real eigenvalue); error (R,): a first-order bound
    on each one's error, noise max|p_j| sum_j |z|^j / |p'(z)|; degree (N,): each polynomial's
    effective degree; doubt (N,): over the eigenvalues z not kept (complex), the largest ratio of the
    same bound to |Im z|: above ~0.1 the error could carry z (and its conjugate) to the real axis,
    i.e. a real root may have been lost; failed (N,) bool: rows whose QR iteration did not converge.
    dropped_pose (D,) int, dropped (D,) complex: the eigenvalues not kept; pseudo (D,): each one's
    real part as a pseudo-zero, |p(x)| / (noise sum_j |p_j| |x|^j) at x = Re z (below 1, x is a root
    of a polynomial whose coefficients each differ from p's by at most their noise share: in a
    crowd of roots, where first-order bounds fail, the pair z, conj(z) may be a real root that
    rounding moved off the axis; inf where the noise is unknown)."""

    pose: np.ndarray
    x: np.ndarray
    imag: np.ndarray
    error: np.ndarray
    degree: np.ndarray
    doubt: np.ndarray
    failed: np.ndarray
    dropped_pose: np.ndarray
    dropped: np.ndarray
    pseudo: np.ndarray


@numba.njit(cache=True)
def _balance(a, n):
    """Diagonal similarity scaling of a[:n, :n] in place (EISPACK balanc, radix 2)."""
    done = False
    while not done:
        done = True
        for i in range(n):
            r = 0.0
            c = 0.0
            for j in range(n):
                if j != i:
                    c += abs(a[j, i])
                    r += abs(a[i, j])
            if c > 0.0 and r > 0.0:
                g = r / 2.0
                f = 1.0
                s = c + r
                while c < g:
                    f *= 2.0
                    c *= 4.0
                g = r * 2.0
                while c > g:
                    f /= 2.0
                    c /= 4.0
                if (c + r) / f < 0.95 * s:
                    done = False
                    g = 1.0 / f
                    for j in range(n):
                        a[i, j] *= g
                    for j in range(n):
                        a[j, i] *= f


@numba.njit(cache=True)
def _hqr(a, n, wr, wi):
    """Eigenvalues (wr + i wi) of the upper Hessenberg a[:n, :n] (overwritten) by the Francis
    double-shift QR iteration (EISPACK hqr); returns False when an eigenvalue took more than 60
    iterations."""
    anorm = 0.0
    for i in range(n):
        for j in range(max(i - 1, 0), n):
            anorm += abs(a[i, j])
    nn = n - 1
    t = 0.0
    while nn >= 0:
        its = 0
        while True:
            l = 0
            for ll in range(nn, 0, -1):
                s = abs(a[ll - 1, ll - 1]) + abs(a[ll, ll])
                if s == 0.0:
                    s = anorm
                if abs(a[ll, ll - 1]) + s == s:
                    a[ll, ll - 1] = 0.0
                    l = ll
                    break
            x = a[nn, nn]
            if l == nn:
                wr[nn] = x + t
                wi[nn] = 0.0
                nn -= 1
                break
            y = a[nn - 1, nn - 1]
            w = a[nn, nn - 1] * a[nn - 1, nn]
            if l == nn - 1:
                p = 0.5 * (y - x)
                q = p * p + w
                z = math.sqrt(abs(q))
                x += t
                if q >= 0.0:
                    z = p + (z if p >= 0.0 else -z)
                    wr[nn - 1] = wr[nn] = x + z
                    if z != 0.0:
                        wr[nn] = x - w / z
                    wi[nn - 1] = wi[nn] = 0.0
                else:
                    wr[nn - 1] = wr[nn] = x + p
                    wi[nn - 1] = -z
                    wi[nn] = z
                nn -= 2
                break
            if its == 60:
                return False
            if its == 10 or its == 20 or its == 40:  # exceptional shifts
                t += x
                for i in range(nn + 1):
                    a[i, i] -= x
                s = abs(a[nn, nn - 1]) + abs(a[nn - 1, nn - 2])
                x = y = 0.75 * s
                w = -0.4375 * s * s
            its += 1
            m = nn - 2
            while True:
                z = a[m, m]
                r = x - z
                s = y - z
                p = (r * s - w) / a[m + 1, m] + a[m, m + 1]
                q = a[m + 1, m + 1] - z - r - s
                r = a[m + 2, m + 1]
                s = abs(p) + abs(q) + abs(r)
                p /= s
                q /= s
                r /= s
                if m == l:
                    break
                u = abs(a[m, m - 1]) * (abs(q) + abs(r))
                v = abs(p) * (abs(a[m - 1, m - 1]) + abs(z) + abs(a[m + 1, m + 1]))
                if u + v == v:
                    break
                m -= 1
            for i in range(m + 2, nn + 1):
                a[i, i - 2] = 0.0
                if i != m + 2:
                    a[i, i - 3] = 0.0
            for k in range(m, nn):
                if k != m:
                    p = a[k, k - 1]
                    q = a[k + 1, k - 1]
                    r = a[k + 2, k - 1] if k != nn - 1 else 0.0
                    x = abs(p) + abs(q) + abs(r)
                    if x != 0.0:
                        p /= x
                        q /= x
                        r /= x
                s = math.sqrt(p * p + q * q + r * r)
                if p < 0.0:
                    s = -s
                if s != 0.0:
                    if k == m:
                        if l != m:
                            a[k, k - 1] = -a[k, k - 1]
                    else:
                        a[k, k - 1] = -s * x
                    p += s
                    x = p / s
                    y = q / s
                    z = r / s
                    q /= p
                    r /= p
                    for j in range(k, nn + 1):
                        p = a[k, j] + q * a[k + 1, j]
                        if k != nn - 1:
                            p += r * a[k + 2, j]
                            a[k + 2, j] -= p * z
                        a[k + 1, j] -= p * y
                        a[k, j] -= p * x
                    mmin = nn if nn < k + 3 else k + 3
                    for i in range(l, mmin + 1):
                        p = x * a[i, k] + y * a[i, k + 1]
                        if k != nn - 1:
                            p += z * a[i, k + 2]
                            a[i, k + 2] -= p * r
                        a[i, k + 1] -= p * q
                        a[i, k] -= p
            if l >= nn - 1:
                break
    return True


@numba.njit(cache=True)
def _count_roots(poly, noise, usable, real_tol, pose_out, x_out, imag_out, error_out, degree_out, doubt_out, pseudo_out):
    """Per usable row of poly (N, n+1) (x^0 upward): its effective degree (trailing coefficients
    below 1e-14 of the largest are zero), the eigenvalues of its companion matrix, and those with
    |imag| <= real_tol (1 + |real|) written to pose_out, x_out, imag_out, their error bounds (see
    :class:`RealRoots`) to error_out; the effective degrees to
    degree_out, and to doubt_out the largest ratio, over the eigenvalues not kept, of a first-order
    bound on its error to its distance from the real axis (see :class:`RealRoots`); the eigenvalues
    not kept to the end of pose_out, x_out, imag_out (backward from the last slot), their pseudo-zero
    ratios to pseudo_out there; returns (count kept, count dropped, failed rows)."""
    N, n1 = poly.shape
    a = np.empty((_MAX_DEGREE, _MAX_DEGREE))
    wr, wi = np.empty(_MAX_DEGREE), np.empty(_MAX_DEGREE)
    m, failed, dropped = 0, 0, 0
    top = len(pose_out) - 1
    for r in range(N):
        if not usable[r]:
            continue
        scale = 0.0
        for k in range(n1):
            scale = max(scale, abs(poly[r, k]))
        deg = 0
        for k in range(n1 - 1, -1, -1):
            if abs(poly[r, k]) > 1e-14 * scale:
                deg = k
                break
        degree_out[r] = deg
        if deg == 0:
            continue
        for i in range(deg):
            for j in range(deg):
                a[i, j] = 0.0
        for j in range(deg):
            a[0, j] = -poly[r, deg - 1 - j] / poly[r, deg]
        for i in range(1, deg):
            a[i, i - 1] = 1.0
        _balance(a, deg)
        if not _hqr(a, deg, wr, wi):
            usable[r] = False
            failed += 1
            continue
        doubt = 0.0
        for k in range(deg):
            z = complex(wr[k], wi[k])
            dp = 0j  # p'(z) by Horner
            for j in range(deg, 0, -1):
                dp = dp * z + j * poly[r, j]
            size, zk = 0.0, 1.0  # sum_j |z|^j
            for j in range(deg + 1):
                size += zk
                zk *= abs(z)
            err = noise[r] * scale * size / max(abs(dp), 1e-300)
            if abs(wi[k]) <= real_tol * (1.0 + abs(wr[k])):
                pose_out[m] = r
                x_out[m] = wr[k]
                imag_out[m] = wi[k]
                error_out[m] = err
                m += 1
            else:
                doubt = max(doubt, err / abs(wi[k]))
                x, px, size = wr[k], 0.0, 0.0  # p(x) and sum_j |p_j| |x|^j by Horner
                for j in range(deg, -1, -1):
                    px = px * x + poly[r, j]
                    size = size * abs(x) + abs(poly[r, j])
                slot = top - dropped
                pose_out[slot], x_out[slot], imag_out[slot] = r, wr[k], wi[k]
                pseudo_out[slot] = abs(px) / (noise[r] * size) if noise[r] < np.inf else np.inf  # unknown noise: no test
                dropped += 1
        doubt_out[r] = doubt
    return m, dropped, failed


def real_roots(poly: np.ndarray, usable: np.ndarray, real_tol: float, noise: np.ndarray | None = None) -> RealRoots:
    """The real roots of the ``usable`` polynomials poly (N, n+1) (x^0 upward, n <= 24): the
    eigenvalues of their companion matrices with |imag| <= real_tol (1 + |real|) (near-double roots
    split into complex pairs of small imaginary part; the caller polishes and checks every one).
    ``noise`` (N,): the coefficients' relative error (default 1e-15)."""
    poly = np.ascontiguousarray(poly, dtype=float)
    if poly.shape[1] - 1 > _MAX_DEGREE:
        raise ValueError(f"polynomials of degree {poly.shape[1] - 1} > {_MAX_DEGREE}")
    live = np.ascontiguousarray(usable, dtype=np.bool_).copy()
    pose = np.empty(len(poly) * (poly.shape[1] - 1), dtype=np.int64)
    x, imag, error = np.empty(len(pose)), np.empty(len(pose)), np.empty(len(pose))
    degree = np.zeros(len(poly), dtype=np.int64)
    noise = np.full(len(poly), 1e-15) if noise is None else np.maximum(np.asarray(noise, dtype=float), 1e-15)
    doubt = np.full(len(poly), np.inf)
    pseudo = np.empty(len(pose))
    m, d, _ = _count_roots(poly, noise, live, real_tol, pose, x, imag, error, degree, doubt, pseudo)
    tail = slice(len(pose) - d, len(pose))
    return RealRoots(pose[:m], x[:m], imag[:m], error[:m], degree, doubt, usable & ~live,
                     pose[tail], x[tail] + 1j * imag[tail], pseudo[tail])
