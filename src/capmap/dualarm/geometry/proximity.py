"""Which collision pairs are near, on the packed chain (:mod:`capmap.dualarm.geometry.chain`), compiled: every
pair's safety distance at many configurations with bounding-sphere and plane culling
(:func:`batch_distances`: the optimiser's pair filter, and the evaluation of a solution, exact for
each configuration's least distance and the pairs within a given distance). Tested against
Pinocchio's placements and the full evaluation in tests/dualarm/test_nodes.py.
"""

from __future__ import annotations

import numba
import numpy as np

from capmap.dualarm.geometry.broadphase import group_bound
from capmap.dualarm.geometry.chain import Packed, fk, groups_of, pair_table, place_primitives, plane_gap
from capmap.dualarm.geometry.collision import Pairs
from capmap.dualarm.geometry.distance import segpoint, segseg, segtri

__all__ = ["batch_distances", "near_pairs", "PairFilter"]

_jit = numba.njit(cache=True)  # plain calls (see capmap.dualarm.geometry.chain)
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
    row = np.int64(0)  # P[0], Q[0]: not a literal 0 (segseg and segtri compiled once more for it)
    if rows[n, 0] == 1:
        return segtri(A, rows[n, 1], B, rows[n, 1], V, rows[n, 2], P, Q, row) - rsum[n]
    return segseg(A, rows[n, 1], B, rows[n, 1], A, rows[n, 2], B, rows[n, 2], P, Q, row) - rsum[n]


@_jit
def _row(A, B, V, ctr, rad, rows, rsum, order, groups, spheres, cutoff, idx, val, P, Q, kept, lb):
    """The pairs whose group ball, bounding spheres and triangle plane do not put them above ``cutoff``:
    their rows n in idx and safety distances (m) in val (from 0); returns how many. kept (P,) bool: pairs
    not looked at; lb (G,): a group whose entry is above the cutoff is not looked at either; every other
    entry becomes a lower bound of the distances of its group's pairs not kept (inf: none). One call per
    configuration (a call per pair would pay numba's per-array argument overhead: the pair's tests are
    written out here)."""
    S = A.shape[0]
    m = 0
    for gi in range(groups.shape[0]):
        if lb[gi] > cutoff:
            continue
        if groups[gi, 2] > 0:
            x = group_bound(A, B, V, rows, order, groups, spheres, gi)
            if x > cutoff:
                lb[gi] = x - ROUNDING
                continue
        low = np.inf
        for t in range(groups[gi, 0], groups[gi, 1]):
            n = order[t]
            if kept[n]:
                continue
            a, b = rows[n, 1], rows[n, 2] + (S if rows[n, 0] == 1 else 0)
            dx, dy, dz = ctr[a, 0] - ctr[b, 0], ctr[a, 1] - ctr[b, 1], ctr[a, 2] - ctr[b, 2]
            x = np.sqrt(dx * dx + dy * dy + dz * dz) - rad[a] - rad[b] - rsum[n]
            if x <= cutoff:  # the first segment itself, not its ball, against the second primitive's ball
                x = segpoint(A, B, rows[n, 1], ctr[b, 0], ctr[b, 1], ctr[b, 2]) - rad[b] - rsum[n]
            if x <= cutoff and rows[n, 0] == 1:  # both ends on one side of the triangle's plane
                x = plane_gap(A, B, rows[n, 1], V, rows[n, 2]) - rsum[n]
            if x > cutoff:
                low = min(low, x)
                continue
            x = _pair_distance(A, B, V, rows, rsum, n, P, Q)
            idx[m], val[m] = n, x
            m += 1
            low = min(low, x)
        lb[gi] = low - ROUNDING
    return m


@_jit
def _grow(ok, on, od, count, need):
    """The entry arrays (k, n, distance) with their first ``count`` entries, room for ``need`` or twice as many."""
    cap = max(2 * ok.shape[0], need)
    ok2, on2, od2 = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
    ok2[:count], on2[:count], od2[:count] = ok[:count], on[:count], od[:count]
    return ok2, on2, od2


@_jit
def _subset(a, b):
    """Whether every True of the bool array a is True in b."""
    for i in range(a.shape[0]):
        if a[i] and not b[i]:
            return False
    return True


@_jit
def _carry(lever, movers, gm, q, q_ref, dm, lb):
    """lb (G,) valid at q_ref (nq,) made valid at q: less how far each group's moving primitives (rows gm (G,
    2) of ``lever``, -1: none) can have moved (a point of primitive e moves at most sum_i lever[e, i] |dq_i|,
    :func:`capmap.dualarm.geometry.chain.levers`); dm (S + T,): scratch, 0 but for ``movers``."""
    for e in movers:
        x = 0.0
        for i in range(q.shape[0]):
            x += lever[e, i] * abs(q[i] - q_ref[i])
        dm[e] = x
    for gi in range(lb.shape[0]):
        lb[gi] -= (dm[gm[gi, 0]] if gm[gi, 0] >= 0 else 0.0) + (dm[gm[gi, 1]] if gm[gi, 1] >= 0 else 0.0)


@_jit
def _place(chain_f, chain_i, q, R, p, ms, mt, mseg_f, mseg_j, mtri_f, mtri_j, mA, mB, mV, mctr, mrad, A, B, V, ctr, rad):
    """The moving segments ms and triangles mt (their rows mseg_f, ... and scratch mA, ...) placed at q into
    the world coordinates A, B, V and bounding spheres ctr, rad of all primitives (the static ones stay)."""
    S = A.shape[0]
    fk(chain_f, chain_i, q, R, p)
    place_primitives(mseg_f, mseg_j, mtri_f, mtri_j, R, p, mA, mB, mV)
    _bounding_spheres(mA, mB, mV, mctr, mrad)
    for i in range(len(ms)):
        A[ms[i]], B[ms[i]], ctr[ms[i]], rad[ms[i]] = mA[i], mB[i], mctr[i], mrad[i]
    for i in range(len(mt)):
        for k in range(3):  # element by element: a 2-D array assignment compiles numba's shape-error path (~3 s)
            for j in range(3):
                V[mt[i], k, j] = mV[i, k, j]
        ctr[S + mt[i]], rad[S + mt[i]] = mctr[len(ms) + i], mrad[len(ms) + i]


@_jit
def _scratch(chain_f, chain_i, seg_f, seg_j, tri_f, tri_j):
    """Placement scratch for :func:`_place`: (R, p, A, B, V, ctr, rad, ms, mt, mseg_f, mseg_j, mtri_f, mtri_j,
    mA, mB, mV, mctr, mrad), the static primitives (joint 0) placed once in A, B, V, ctr, rad."""
    nj, S, T = chain_f.shape[0], seg_f.shape[0], tri_f.shape[0]
    R, p = np.empty((nj, 3, 3)), np.empty((nj, 3))
    A, B, V = np.empty((S, 3)), np.empty((S, 3)), np.empty((T, 3, 3))
    ctr, rad = np.empty((S + T, 3)), np.empty(S + T)
    fk(chain_f, chain_i, np.zeros(chain_f.shape[0] - 1), R, p)  # any configuration: the moving ones are placed again
    place_primitives(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V)
    _bounding_spheres(A, B, V, ctr, rad)
    ms, mt = np.flatnonzero(seg_j != 0), np.flatnonzero(tri_j != 0)
    mA, mB, mV = np.empty((len(ms), 3)), np.empty((len(ms), 3)), np.empty((len(mt), 3, 3))
    mctr, mrad = np.empty((len(ms) + len(mt), 3)), np.empty(len(ms) + len(mt))
    return R, p, A, B, V, ctr, rad, ms, mt, seg_f[ms], seg_j[ms], tri_f[mt], tri_j[mt], mA, mB, mV, mctr, mrad


@numba.njit(cache=True)
def _batch(chain_f, chain_i, seg_f, seg_j, tri_f, tri_j, qs, rows, rsum, order, groups, spheres, cutoff, within, lever,
           movers, gm):
    """The pairs evaluated at each configuration qs[k], as (k, n, distance m) entries in configuration
    order: every pair that is not shown above ``cutoff``; with ``within`` >= 0 only those not shown
    above both ``within`` and the least distance at qs[k] (the previous configuration's nearest pair,
    evaluated first, bounds that least distance), the nearest always. What shows a pair above: its group's
    ball, its own bounding spheres and triangle plane, or its group's bound at the previous configuration
    less how far the group can have moved since (:func:`_carry`)."""
    NP = rows.shape[0]
    R, p, A, B, V, ctr, rad, ms, mt, mseg_f, mseg_j, mtri_f, mtri_j, mA, mB, mV, mctr, mrad = _scratch(
        chain_f, chain_i, seg_f, seg_j, tri_f, tri_j)
    P, Q = np.empty((1, 3)), np.empty((1, 3))
    idx, val = np.empty(NP + 1, np.int64), np.empty(NP + 1)
    kept, lb, dm = np.zeros(NP, np.bool_), np.full(groups.shape[0], -np.inf), np.zeros(lever.shape[0])
    cap = max(1024, 16 * qs.shape[0])
    ok, on, od = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
    # np.int64, not a literal: numba types a call first with a variable's first value's literal type and would
    # compile _grow and _pair_distance once more for it
    count = np.int64(0)
    nearest = np.int64(-1)
    for k in range(qs.shape[0]):
        _place(chain_f, chain_i, qs[k], R, p, ms, mt, mseg_f, mseg_j, mtri_f, mtri_j, mA, mB, mV, mctr, mrad, A, B, V,
               ctr, rad)
        cut, d0 = cutoff, np.nan
        if within >= 0.0 and nearest >= 0:
            d0 = _pair_distance(A, B, V, rows, rsum, nearest, P, Q)
            # the bounds are computed otherwise than the distances and may exceed them by rounding: a pair at
            # the threshold keeps its distance with ROUNDING to spare, and the nearest pair is always kept
            cut = min(cutoff, max(within, d0) + ROUNDING)
        if k:
            _carry(lever, movers, gm, qs[k], qs[k - 1], dm, lb)
        m = _row(A, B, V, ctr, rad, rows, rsum, order, groups, spheres, cut, idx, val, P, Q, kept, lb)
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
            nearest = np.int64(-1)
            best = np.inf
            for i in range(m):
                if val[i] < best or (val[i] == best and idx[i] < nearest):
                    best, nearest = val[i], idx[i]
        if count + m > ok.shape[0]:
            ok, on, od = _grow(ok, on, od, count, count + m)
        for i in range(m):
            ok[count], on[count], od[count] = k, idx[i], val[i]
            count += 1
    return ok[:count].copy(), on[:count].copy(), od[:count].copy()


@numba.njit(cache=True)
def _recheck(chain_f, chain_i, seg_f, seg_j, tri_f, tri_j, qs, rows, rsum, order, groups, spheres, cutoff, keep, lb,
             ref_q, lever, movers, gm):
    """The pairs not in ``keep`` (K, P) whose safety distance at qs[k] is below ``cutoff``, as (k, n, distance
    m) entries. lb (K, G), ref_q (K, nq): per configuration and group, a lower bound of the distance of the
    group's pairs not kept, valid at ref_q[k] (nan: none); a group whose bound, less how far its moving
    primitives (rows gm (G, 2) of ``lever``, -1: none) can have moved since, clears the cutoff is not looked
    at (nor one whose bound at the previous configuration, so carried, does, when that configuration kept no
    pair this one does not); both are updated to qs."""
    K, nq, G = qs.shape[0], qs.shape[1], groups.shape[0]
    R, p, A, B, V, ctr, rad, ms, mt, mseg_f, mseg_j, mtri_f, mtri_j, mA, mB, mV, mctr, mrad = _scratch(
        chain_f, chain_i, seg_f, seg_j, tri_f, tri_j)
    P, Q = np.empty((1, 3)), np.empty((1, 3))
    dm, lbk = np.zeros(lever.shape[0]), np.empty(G)
    idx, val = np.empty(rows.shape[0], np.int64), np.empty(rows.shape[0])
    ok, on, od = np.empty(1024, np.int64), np.empty(1024, np.int64), np.empty(1024)
    count = np.int64(0)  # (not a literal: _batch)
    nb = np.empty(G)
    for k in range(K):
        lbk[:] = lb[k]
        if not np.isnan(ref_q[k, 0]):
            _carry(lever, movers, gm, qs[k], ref_q[k], dm, lbk)
        if k > 0 and _subset(keep[k - 1], keep[k]):
            # the previous configuration's bounds (now at qs[k - 1]) cover every pair not kept here too: carried
            # to qs[k], they bound them as well, and the larger of two lower bounds is one
            nb[:] = lb[k - 1]
            _carry(lever, movers, gm, qs[k], qs[k - 1], dm, nb)
            for gi in range(G):
                lbk[gi] = max(lbk[gi], nb[gi])
        look = False
        for gi in range(G):
            look = look or lbk[gi] <= cutoff
        if look:
            _place(chain_f, chain_i, qs[k], R, p, ms, mt, mseg_f, mseg_j, mtri_f, mtri_j, mA, mB, mV, mctr, mrad, A, B, V,
                   ctr, rad)
            m = _row(A, B, V, ctr, rad, rows, rsum, order, groups, spheres, cutoff, idx, val, P, Q, keep[k], lbk)
            if count + m > ok.shape[0]:
                ok, on, od = _grow(ok, on, od, count, count + m)
            for i in range(m):
                if val[i] < cutoff:
                    ok[count], on[count], od[count] = k, idx[i], val[i]
                    count += 1
        for gi in range(G):
            lb[k, gi] = lbk[gi]  # (a group with a pair found now is looked at once more: then that pair is kept)
        for i in range(nq):
            ref_q[k, i] = qs[k, i]
    return ok[:count].copy(), on[:count].copy(), od[:count].copy()


def _movers(packed: Packed, rows: np.ndarray, order: np.ndarray, groups: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lever (S + T, nq) of every segment, then triangle (:func:`capmap.dualarm.geometry.chain.levers`), the rows
    of those that move, gm (G, 2): the rows of each group's moving primitives, -1: none)."""
    S, lever = len(packed.seg_f), packed.lever
    first = rows[order[groups[:, 0]]].reshape(-1, 3)
    second = np.where(first[:, 0] == 1, S + first[:, 2], first[:, 2])
    col = groups[:, 2]
    # the moving primitive of a group (col 1: the segment, col 2: the second, a triangle when kind 1), both of a pair
    gm = np.column_stack([np.where(col == 2, second, first[:, 1]), np.where(col == 0, second, -1)]).astype(np.int64)
    return lever, np.flatnonzero(lever.any(axis=1)).astype(np.int64), gm


class PairFilter:
    """The optimiser's pair filter over its outer iterations: which pairs come within ``cutoff`` m at K
    configurations that change a little from call to call. Each call returns the pairs newly within the
    cutoff; they join ``keep`` (K, P) bool, which is never looked at again. In between, each (configuration,
    pair group) keeps a lower bound of its other pairs' distances, less how far its moving primitives can
    have moved since (:func:`capmap.dualarm.geometry.chain.levers`), so a group far from the cutoff costs a
    comparison, not a test (the same pairs as :func:`near_pairs` with the same cutoff, tested against it in
    tests/dualarm/test_nodes.py)."""

    def __init__(self, packed: Packed, pairs: Pairs, K: int, cutoff: float):
        self.packed, self.cutoff = packed, float(cutoff)
        self.rows, self.rsum = pair_table(packed, pairs)
        self.order, self.groups, self.spheres = groups_of(packed, self.rows)
        self.lever, self.movers, self.gm = _movers(packed, self.rows, self.order, self.groups)
        self.lb = np.full((K, len(self.groups)), -np.inf)
        self.ref_q = np.full((K, packed.chain_f.shape[0] - 1), np.nan)
        self.keep = np.zeros((K, len(self.rows)), dtype=bool)

    def update(self, qs: np.ndarray) -> np.ndarray:
        """(K, P) bool: the pairs not kept before whose safety distance at qs (K, nq) is below the cutoff
        (they are kept from now on)."""
        pk = self.packed
        k, n, _ = _recheck(pk.chain_f, pk.chain_i, pk.seg_f, pk.seg_j, pk.tri_f, pk.tri_j,
                           np.ascontiguousarray(qs, dtype=float), self.rows, self.rsum, self.order, self.groups,
                           self.spheres, self.cutoff, self.keep, self.lb, self.ref_q, self.lever, self.movers, self.gm)
        new = np.zeros_like(self.keep)
        new[k, n] = True
        self.keep |= new
        return new


def near_pairs(packed: Packed, qs: np.ndarray, pairs: Pairs, cutoff: float = np.inf,
               within: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pair distances :func:`batch_distances` leaves finite, as entries: configuration k (E,), pair n
    (E,), safety distance m (E,), in configuration order."""
    rows, rsum = pair_table(packed, pairs)
    qs = np.ascontiguousarray(qs, dtype=float).reshape(-1, packed.chain_f.shape[0] - 1)
    order, groups, spheres = groups_of(packed, rows)
    return _batch(packed.chain_f, packed.chain_i, packed.seg_f, packed.seg_j, packed.tri_f, packed.tri_j, qs, rows, rsum,
                  order, groups, spheres, float(cutoff), -1.0 if within is None else float(within),
                  *_movers(packed, rows, order, groups))


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

