"""The direction sweep fused with the payload bound and the minimum (compiled with numba): for
each configuration, the smallest over directions of the largest payload every limit allows,
without materialising the (configurations, outputs, directions) arrays.

For configuration m, direction d and output k (see :func:`capmap.capacity.engine.affine_over_directions`):

    y0 = C[m, k] . phi[d]     (phi = [1, a u, v^2 features(u)]),   s = S[m, k] . (a u - g)
    bound_k = (L_k - sign(s) y0) / |s|   (0 if |y0| > L_k already, inf if s = 0),  clipped at 0

and the configuration's capacity is min_d min_k bound_k (the formulas of
:meth:`capmap.core.limits.AffineLimits.upper_from_zero`; equal to rounding). The velocity part
of y0 is even in u and the acceleration part odd, so u and -u share one evaluation.
Ties go to the first direction in pair order (u before -u) and the first output.

Loop order: outputs outside, direction pairs inside (contiguous feature rows), written
branch-free so that LLVM vectorises the inner loop (4 pairs per AVX2 instruction): about 12 us
per configuration for 614 directions and 12 outputs, against 23 us with the outputs inside."""

from __future__ import annotations

import numba
import numpy as np

from capmap.capacity.directions import antipodal_pairs

__all__ = ["min_over_directions", "min_per_pair"]


_FAST = {"nsz", "contract", "reassoc", "arcp"}  # vectorisable; infinities (s = 0) and NaN keep their meaning


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _sweep(C, S, A, F, other, g, limit, want_pairs, cap, worst_p, worst_side, binding, per_pair):
    """C (M, K, 10), S (M, K, 3); A (3, P) = a u of each pair's first direction, F (6, P) its
    v^2 features; other (P,) 1.0 where -u is in the set (else its bound is ignored). Outputs:
    cap, worst pair, side (0: u, 1: -u), binding output (M,); per_pair (M, P) = min over both
    sides and all outputs when want_pairs."""
    M, K, _ = C.shape
    P = A.shape[1]
    B1 = np.empty((K, P))  # bound of output k along u (B1) and -u (B2) of pair p
    B2 = np.empty((K, P))
    mk = np.empty(K)
    A0, A1, A2 = A[0], A[1], A[2]
    F0, F1, F2, F3, F4, F5 = F[0], F[1], F[2], F[3], F[4], F[5]
    for m in range(M):
        for k in range(K):
            c = C[m, k]
            s = S[m, k]
            c0, c1, c2, c3, c4, c5, c6, c7, c8, c9 = c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9]
            s0, s1, s2 = s[0], s[1], s[2]
            sg = -(s0 * g[0] + s1 * g[1] + s2 * g[2])
            lim = limit[k]
            b1k = B1[k]
            b2k = B2[k]
            for p in range(P):
                ya = c1 * A0[p] + c2 * A1[p] + c3 * A2[p]  # odd in u
                yv = c0 + c4 * F0[p] + c5 * F1[p] + c6 * F2[p] + c7 * F3[p] + c8 * F4[p] + c9 * F5[p]  # even
                sa = s0 * A0[p] + s1 * A1[p] + s2 * A2[p]
                y1 = yv + ya
                t1 = sa + sg
                y2 = yv - ya
                t2 = sg - sa
                # largest x >= 0 with |y + x t| <= lim: (lim - sign(t) y) / |t|; 0 if violated; inf if t = 0
                n1 = lim - y1 if t1 > 0.0 else (lim + y1 if t1 < 0.0 else lim)
                n2 = lim - y2 if t2 > 0.0 else (lim + y2 if t2 < 0.0 else lim)
                r1 = n1 / abs(t1)
                r2 = n2 / abs(t2)
                r1 = r1 if lim - abs(y1) >= 0.0 else 0.0
                r2 = r2 if lim - abs(y2) >= 0.0 else 0.0
                b1k[p] = 0.0 if r1 < 0.0 else r1
                b2k[p] = (0.0 if r2 < 0.0 else r2) if other[p] > 0.0 else np.inf
            lo = np.inf
            for p in range(P):
                lo = b1k[p] if b1k[p] < lo else lo
                lo = b2k[p] if b2k[p] < lo else lo
            mk[k] = lo
        best = np.inf
        for k in range(K):
            best = mk[k] if mk[k] < best else best
        # the minimiser: first pair, then u before -u, then first output
        fp, fs, kb = P, 2, 0
        for k in range(K):
            if mk[k] == best:
                for p in range(min(fp + 1, P)):
                    if B1[k, p] == best:
                        side = 0
                    elif B2[k, p] == best:
                        side = 1
                    else:
                        continue
                    if p < fp or (p == fp and side < fs):
                        fp, fs, kb = p, side, k
                    break
        if fp == P:  # NaN everywhere
            fp, fs = 0, 0
        cap[m] = best
        worst_p[m] = fp
        worst_side[m] = fs
        binding[m] = kb
        if want_pairs:
            row = per_pair[m]
            for p in range(P):
                row[p] = min(B1[0, p], B2[0, p])
            for k in range(1, K):
                for p in range(P):
                    row[p] = min(row[p], min(B1[k, p], B2[k, p]))


def _prepare(phi, au, pairs):
    d = pairs[:, 0]
    return (np.ascontiguousarray(np.asarray(au, dtype=float)[d].T), np.ascontiguousarray(np.asarray(phi, dtype=float)[d, 4:10].T),
            (pairs[:, 1] >= 0).astype(float))


def _run(C, S, phi, au, gravity, limit, pairs, want_pairs):
    M = len(C)
    if pairs is None:
        pairs = antipodal_pairs(au / np.maximum(np.linalg.norm(au, axis=1, keepdims=True), 1e-300))
    A, F, other = _prepare(phi, au, pairs)
    cap = np.empty(M)
    wp, ws, binding = (np.empty(M, dtype=np.int64) for _ in range(3))
    per_pair = np.empty((M, len(pairs)) if want_pairs else (0, len(pairs)))
    _sweep(np.ascontiguousarray(C, dtype=float), np.ascontiguousarray(S, dtype=float), A, F, other,
           np.asarray(gravity, dtype=float), np.ascontiguousarray(limit, dtype=float), want_pairs,
           cap, wp, ws, binding, per_pair)
    worst = np.where(ws == 0, pairs[wp, 0], pairs[wp, 1])
    return cap, worst, binding, per_pair, pairs


def min_over_directions(C: np.ndarray, S: np.ndarray, phi: np.ndarray, au: np.ndarray, gravity: np.ndarray,
                        limit: np.ndarray, pairs: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """C (M, n_out, 10), S (M, n_out, 3), phi (D, 10) = [1, a u, v^2 features(u)], au = a u (D, 3),
    gravity (3,), limit (n_out,) -> capacity (M,) kg, worst direction (M,), binding output at it
    (M,). ``pairs``: :func:`antipodal_pairs` of u (computed when not given)."""
    cap, worst, binding, _, _ = _run(C, S, phi, au, gravity, limit, pairs, False)
    return cap, worst, binding


def min_per_pair(C: np.ndarray, S: np.ndarray, phi: np.ndarray, au: np.ndarray, gravity: np.ndarray,
                 limit: np.ndarray, pairs: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """As :func:`min_over_directions`, but per antipodal pair: (M, P) kg, the capacity along the
    line of u (moving along u or -u), and the pairs (P, 2) used."""
    _, _, _, per_pair, pairs = _run(C, S, phi, au, gravity, limit, pairs, True)
    return per_pair, pairs
