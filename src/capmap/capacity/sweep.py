"""The direction sweep fused with the payload bound and the minimum (compiled with numba): for
each configuration, the smallest over directions of the largest payload every limit allows,
without materialising the (configurations, outputs, directions) arrays.

For configuration m, direction d and output k (see :func:`capmap.capacity.engine.affine_over_directions`):

    y0 = C[m, k] . phi[d]     (phi = [1, a u, v^2 features(u)]),   s = S[m, k] . (a u - g)
    bound_k = (L_k - sign(s) y0) / |s|   (0 if |y0| > L_k already, inf if s = 0),  clipped at 0

and the configuration's capacity is min_d min_k bound_k (the formulas of
:meth:`capmap.core.limits.AffineLimits.upper_from_zero`; equal to rounding). The velocity part
of y0 is even in u and the acceleration part odd, so u and -u share one evaluation.
Ties go to the first direction in pair order (u before -u) and the first output."""

from __future__ import annotations

import numba
import numpy as np

from capmap.capacity.directions import antipodal_pairs

__all__ = ["min_over_directions"]


_FAST = {"nsz", "contract", "reassoc"}  # vectorisable; infinities (s = 0) and NaN keep their meaning


@numba.njit(cache=True, inline="always", fastmath=_FAST, error_model="numpy")
def _bound(y0, s, lim):
    """The largest x >= 0 with |y0 + x s| <= lim (0 when already violated, inf when s = 0);
    branch-free so that the loop over outputs vectorises."""
    b = (lim - np.sign(s) * y0) / abs(s)  # s = 0: +inf (lim - 0 > 0 when not violated)
    b = 0.0 if abs(y0) > lim else b
    return 0.0 if b < 0.0 else b


@numba.njit(cache=True, inline="always")
def _first(values, target):
    for k in range(len(values)):
        if values[k] == target:
            return k
    return 0


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _sweep(C, S, phi, au, g, limit, pairs, cap, worst_dir, binding):
    """pairs (P, 2): direction d and its antipode (-1 when it has none in the set). The velocity
    terms are even in u and the acceleration terms odd: one evaluation of each serves u and -u."""
    M, _, K = C.shape  # C (M, 10, K), S (M, 3, K): outputs last, so the loops over them vectorise
    yv = np.empty(K)
    ya = np.empty(K)
    b1 = np.empty(K)
    b2 = np.empty(K)
    sa = np.empty(K)
    sg = np.empty(K)
    for m in range(M):
        Cm = C[m]
        Sm = S[m]
        for k in range(K):
            sg[k] = -(Sm[0, k] * g[0] + Sm[1, k] * g[1] + Sm[2, k] * g[2])
        best = np.inf
        bd = 0
        bk = 0
        for p in range(pairs.shape[0]):
            d = pairs[p, 0]
            e = pairs[p, 1]
            p1, p2, p3 = phi[d, 1], phi[d, 2], phi[d, 3]
            q4, q5, q6, q7, q8, q9 = phi[d, 4], phi[d, 5], phi[d, 6], phi[d, 7], phi[d, 8], phi[d, 9]
            u0, u1, u2 = au[d, 0], au[d, 1], au[d, 2]
            for k in range(K):
                ya[k] = Cm[1, k] * p1 + Cm[2, k] * p2 + Cm[3, k] * p3
                yv[k] = (Cm[0, k] + Cm[4, k] * q4 + Cm[5, k] * q5 + Cm[6, k] * q6 + Cm[7, k] * q7 + Cm[8, k] * q8
                         + Cm[9, k] * q9)
                sa[k] = Sm[0, k] * u0 + Sm[1, k] * u1 + Sm[2, k] * u2
            c1 = np.inf
            c2 = np.inf
            for k in range(K):  # min only (vectorised); the binding output is found when it matters
                b1[k] = _bound(yv[k] + ya[k], sa[k] + sg[k], limit[k])
                b2[k] = _bound(yv[k] - ya[k], -sa[k] + sg[k], limit[k])
                c1 = min(c1, b1[k])
                c2 = min(c2, b2[k])
            if c1 < best:
                best = c1
                bd = d
                bk = _first(b1, c1)
            if e >= 0 and c2 < best:
                best = c2
                bd = e
                bk = _first(b2, c2)
        cap[m] = best
        worst_dir[m] = bd
        binding[m] = bk


def min_over_directions(C: np.ndarray, S: np.ndarray, phi: np.ndarray, au: np.ndarray, gravity: np.ndarray,
                        limit: np.ndarray, pairs: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """C (M, n_out, 10), S (M, n_out, 3), phi (D, 10) = [1, a u, v^2 features(u)], au = a u (D, 3),
    gravity (3,), limit (n_out,) -> capacity (M,) kg, worst direction (M,), binding output at it
    (M,). ``pairs``: :func:`antipodal_pairs` of u (computed when not given)."""
    M = len(C)
    if pairs is None:
        pairs = antipodal_pairs(au / np.maximum(np.linalg.norm(au, axis=1, keepdims=True), 1e-300))
    cap, worst, binding = np.empty(M), np.empty(M, dtype=np.int64), np.empty(M, dtype=np.int64)
    _sweep(np.ascontiguousarray(np.swapaxes(C, 1, 2)), np.ascontiguousarray(np.swapaxes(S, 1, 2)),
           np.ascontiguousarray(phi), np.ascontiguousarray(au),
           np.asarray(gravity, dtype=float), np.ascontiguousarray(limit, dtype=float), pairs, cap, worst, binding)
    return cap, worst, binding
