"""Which collision pairs are near, on the packed chain (:mod:`capmap.dualarm.chain`), compiled: every
pair's safety distance at many configurations with bounding-sphere and plane culling
(:func:`batch_distances`: the optimiser's pair filter, and the evaluation of a solution, exact for
each configuration's least distance and the pairs within a given distance). Tested against
Pinocchio's placements and the full evaluation in tests/dualarm/test_nodes.py.
"""

from __future__ import annotations

import numba
import numpy as np

from capmap.dualarm.broadphase import group_bound
from capmap.dualarm.chain import Packed, fk, groups_of, pair_table, place_primitives, plane_gap
from capmap.dualarm.collision import Pairs
from capmap.dualarm.distance import segpoint, segseg, segtri

__all__ = ["batch_distances", "near_pairs"]

_jit = numba.njit(cache=True)  # plain calls (see capmap.dualarm.chain)
ROUNDING = 1e-9  # m: how far a lower bound may exceed the distance it bounds by rounding (~1e-15 here)


@_jit
def _bounding_spheres(A, B, V, ctr, rad):
    """Centres ctr (S + T, 3) and radii rad (S + T,) of spheres around the segments, then the triangles."""
    S, T = A.shape[0], V.shape[0]
    for s in range(S):
        r2 = 0.0
        for i in range(3):
            ctr[s, i] = 0.5 * (A[s, i] + B[s, i])
            r2 += (0.5 * (B[s, i] - A[s, i])) ** 2
        rad[s] = np.sqrt(r2)
    for t in range(T):
        for i in range(3):
            ctr[S + t, i] = (V[t, 0, i] + V[t, 1, i] + V[t, 2, i]) / 3.0
        r = 0.0
        for m in range(3):
            r = max(r, np.sqrt((V[t, m, 0] - ctr[S + t, 0]) ** 2 + (V[t, m, 1] - ctr[S + t, 1]) ** 2
                               + (V[t, m, 2] - ctr[S + t, 2]) ** 2))
        rad[S + t] = r


@_jit
def _pair_distance(A, B, V, rows, rsum, n, P, Q):
    """Pair row n's safety distance (m)."""
    if rows[n, 0] == 1:
        return segtri(A, rows[n, 1], B, rows[n, 1], V, rows[n, 2], P, Q, 0) - rsum[n]
    return segseg(A, rows[n, 1], B, rows[n, 1], A, rows[n, 2], B, rows[n, 2], P, Q, 0) - rsum[n]


@_jit
def _row(A, B, V, ctr, rad, rows, rsum, order, groups, spheres, cutoff, idx, val, P, Q):
    """The pairs whose group ball, bounding spheres and triangle plane do not put them above ``cutoff``:
    their rows n in idx and safety distances (m) in val (from 0); returns how many. One call per
    configuration (a call per pair would pay numba's per-array argument overhead)."""
    S = A.shape[0]
    m = 0
    for gi in range(groups.shape[0]):
        if groups[gi, 2] > 0 and group_bound(A, B, V, rows, order, groups, spheres, gi) > cutoff:
            continue
        for t in range(groups[gi, 0], groups[gi, 1]):
            n = order[t]
            a, b = rows[n, 1], rows[n, 2] + (S if rows[n, 0] == 1 else 0)
            dx, dy, dz = ctr[a, 0] - ctr[b, 0], ctr[a, 1] - ctr[b, 1], ctr[a, 2] - ctr[b, 2]
            if np.sqrt(dx * dx + dy * dy + dz * dz) - rad[a] - rad[b] - rsum[n] > cutoff:
                continue
            if segpoint(A, B, rows[n, 1], ctr[b, 0], ctr[b, 1], ctr[b, 2]) - rad[b] - rsum[n] > cutoff:
                continue  # the first segment itself, not its ball, far from the second primitive's ball
            if rows[n, 0] == 1 and plane_gap(A, B, rows[n, 1], V, rows[n, 2]) - rsum[n] > cutoff:
                continue  # both ends on one side of the triangle's plane, farther than the cutoff
            idx[m], val[m] = n, _pair_distance(A, B, V, rows, rsum, n, P, Q)
            m += 1
    return m


@numba.njit(cache=True)
def _batch(chain_f, chain_i, seg_f, seg_j, tri_f, tri_j, qs, rows, rsum, order, groups, spheres, cutoff, within):
    """The pairs evaluated at each configuration qs[k], as (k, n, distance m) entries in configuration
    order: every pair that is not shown above ``cutoff``; with ``within`` >= 0 only those not shown
    above both ``within`` and the least distance at qs[k] (the previous configuration's nearest pair,
    evaluated first, bounds that least distance), the nearest always."""
    nj, S, T, NP = chain_f.shape[0], seg_f.shape[0], tri_f.shape[0], rows.shape[0]
    R, p = np.empty((nj, 3, 3)), np.empty((nj, 3))
    A, B, V = np.empty((S, 3)), np.empty((S, 3)), np.empty((T, 3, 3))
    ctr, rad = np.empty((S + T, 3)), np.empty(S + T)
    P, Q = np.empty((1, 3)), np.empty((1, 3))
    # the static primitives (joint 0) are placed once; each configuration places the moving ones
    ms, mt = np.flatnonzero(seg_j != 0), np.flatnonzero(tri_j != 0)
    mseg_f, mseg_j, mtri_f, mtri_j = seg_f[ms], seg_j[ms], tri_f[mt], tri_j[mt]
    mA, mB, mV = np.empty((len(ms), 3)), np.empty((len(ms), 3)), np.empty((len(mt), 3, 3))
    mctr, mrad = np.empty((len(ms) + len(mt), 3)), np.empty(len(ms) + len(mt))
    if qs.shape[0]:
        fk(chain_f, chain_i, qs[0], R, p)
        place_primitives(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V)
        _bounding_spheres(A, B, V, ctr, rad)
    idx, val = np.empty(NP + 1, np.int64), np.empty(NP + 1)
    cap = max(1024, 16 * qs.shape[0])
    ok, on, od = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
    count = 0
    nearest = -1
    for k in range(qs.shape[0]):
        fk(chain_f, chain_i, qs[k], R, p)
        place_primitives(mseg_f, mseg_j, mtri_f, mtri_j, R, p, mA, mB, mV)
        _bounding_spheres(mA, mB, mV, mctr, mrad)
        for i in range(len(ms)):
            A[ms[i]], B[ms[i]], ctr[ms[i]], rad[ms[i]] = mA[i], mB[i], mctr[i], mrad[i]
        for i in range(len(mt)):
            V[mt[i]], ctr[S + mt[i]], rad[S + mt[i]] = mV[i], mctr[len(ms) + i], mrad[len(ms) + i]
        cut, d0 = cutoff, np.nan
        if within >= 0.0 and nearest >= 0:
            d0 = _pair_distance(A, B, V, rows, rsum, nearest, P, Q)
            # the bounds are computed otherwise than the distances and may exceed them by rounding: a pair at
            # the threshold keeps its distance with ROUNDING to spare, and the nearest pair is always kept
            cut = min(cutoff, max(within, d0) + ROUNDING)
        m = _row(A, B, V, ctr, rad, rows, rsum, order, groups, spheres, cut, idx, val, P, Q)
        if d0 <= cutoff:  # (d0 is nan unless the nearest pair was evaluated: False)
            found = False
            for i in range(m):
                if idx[i] == nearest:
                    found = True
                    break
            if not found:
                idx[m], val[m] = nearest, d0
                m += 1
        if within >= 0.0:
            nearest = -1
            best = np.inf
            for i in range(m):
                if val[i] < best or (val[i] == best and idx[i] < nearest):
                    best, nearest = val[i], idx[i]
        if count + m > cap:
            cap = max(2 * cap, count + m)
            ok2, on2, od2 = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
            ok2[:count], on2[:count], od2[:count] = ok[:count], on[:count], od[:count]
            ok, on, od = ok2, on2, od2
        for i in range(m):
            ok[count], on[count], od[count] = k, idx[i], val[i]
            count += 1
    return ok[:count].copy(), on[:count].copy(), od[:count].copy()


def near_pairs(packed: Packed, qs: np.ndarray, pairs: Pairs, cutoff: float = np.inf,
               within: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pair distances :func:`batch_distances` leaves finite, as entries: configuration k (E,), pair n
    (E,), safety distance m (E,), in configuration order."""
    rows, rsum = pair_table(packed, pairs)
    qs = np.ascontiguousarray(qs, dtype=float).reshape(-1, packed.chain_f.shape[0] - 1)
    return _batch(packed.chain_f, packed.chain_i, packed.seg_f, packed.seg_j, packed.tri_f, packed.tri_j, qs, rows, rsum,
                  *groups_of(packed, rows), float(cutoff), -1.0 if within is None else float(within))


def batch_distances(packed: Packed, qs: np.ndarray, pairs: Pairs, cutoff: float = np.inf,
                    within: float | None = None) -> np.ndarray:
    """Safety distances (K, P) m of every pair at every configuration qs (K, nq); inf for a pair whose
    distance is above ``cutoff`` m (bounding spheres or a triangle's plane show it); with ``within``
    m, inf also for the pairs above both ``within`` and the configuration's least distance, which
    stays exact (each row's minimum and every pair within ``within`` are exact)."""
    k, n, d = near_pairs(packed, qs, pairs, cutoff, within)
    out = np.full((len(np.asarray(qs).reshape(-1, packed.chain_f.shape[0] - 1)), len(pairs)), np.inf)
    out[k, n] = d
    return out

