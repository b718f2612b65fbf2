"""Which collision pairs are near, on the packed chain (:mod:`capmap.dualarm.chain`), compiled: every
pair's safety distance at many configurations with bounding-sphere and plane culling
(:func:`batch_distances`; exact for each configuration's least distance and the pairs within a
distance), and the incremental re-check of the pairs within the optimiser's filter as the motion
changes (:class:`PairRecheck`, on a motion bound from the chain's offsets: :func:`motion_reach`).
Tested against Pinocchio's placements and the full evaluation in tests/dualarm/test_nodes.py.
"""

from __future__ import annotations

import numba
import numpy as np

from capmap.dualarm.chain import Packed, fk, pair_table, place_primitives, plane_gap
from capmap.dualarm.collision import Pairs
from capmap.dualarm.distance import segseg, segtri

__all__ = ["batch_distances", "motion_reach", "PairRecheck"]

_jit = numba.njit(cache=True)  # plain calls (see capmap.dualarm.chain)


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
def _row(A, B, V, ctr, rad, rows, rsum, cutoff, every, need, out, low, P, Q):
    """For each pair row n (``every``, or those with need[n]): out[n] its safety distance (m) and
    low[n] the same; or, when the bounding spheres or the triangle's plane put it above ``cutoff``,
    out[n] = inf and low[n] that lower bound. One call per configuration (a call per pair would pay
    numba's per-array argument overhead)."""
    S = A.shape[0]
    for n in range(rows.shape[0]):
        if not every and not need[n]:
            out[n] = np.inf
            continue
        a, b = rows[n, 1], rows[n, 2] + (S if rows[n, 0] == 1 else 0)
        dx, dy, dz = ctr[a, 0] - ctr[b, 0], ctr[a, 1] - ctr[b, 1], ctr[a, 2] - ctr[b, 2]
        low[n] = np.sqrt(dx * dx + dy * dy + dz * dz) - rad[a] - rad[b] - rsum[n]
        if low[n] <= cutoff and rows[n, 0] == 1:  # both ends on one side of the triangle's plane
            low[n] = max(low[n], plane_gap(A, B, rows[n, 1], V, rows[n, 2]) - rsum[n])
        if low[n] > cutoff:
            out[n] = np.inf
            continue
        if rows[n, 0] == 1:
            out[n] = segtri(A, rows[n, 1], B, rows[n, 1], V, rows[n, 2], P, Q, 0) - rsum[n]
        else:
            out[n] = segseg(A, rows[n, 1], B, rows[n, 1], A, rows[n, 2], B, rows[n, 2], P, Q, 0) - rsum[n]
        low[n] = out[n]


@numba.njit(cache=True)
def _batch(chain_f, chain_i, seg_f, seg_j, tri_f, tri_j, qs, rows, rsum, cutoff, within, out):
    """out[k, n]: pair n's safety distance at qs[k], or inf when it is above ``cutoff``; with
    ``within`` >= 0 also inf when it is above both ``within`` and the least distance at qs[k] (the
    previous configuration's nearest pair, evaluated first, bounds that least distance)."""
    nj, S, T = chain_f.shape[0], seg_f.shape[0], tri_f.shape[0]
    R, p = np.empty((nj, 3, 3)), np.empty((nj, 3))
    A, B, V = np.empty((S, 3)), np.empty((S, 3)), np.empty((T, 3, 3))
    ctr, rad = np.empty((S + T, 3)), np.empty(S + T)
    P, Q = np.empty((1, 3)), np.empty((1, 3))
    low, none = np.empty(rows.shape[0]), np.empty(0, np.bool_)
    nearest = -1
    for k in range(qs.shape[0]):
        fk(chain_f, chain_i, qs[k], R, p)
        place_primitives(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V)
        _bounding_spheres(A, B, V, ctr, rad)
        cut = cutoff
        if within >= 0.0 and nearest >= 0:
            cut = min(cutoff, max(within, _pair_distance(A, B, V, rows, rsum, nearest, P, Q)))
        _row(A, B, V, ctr, rad, rows, rsum, cut, True, none, out[k], low, P, Q)
        if within >= 0.0:
            n = np.argmin(out[k])
            nearest = n if np.isfinite(out[k, n]) else -1


@numba.njit(cache=True)
def _recheck(chain_f, chain_i, seg_f, seg_j, tri_f, tri_j, reach, horizon, qs, rows, rsum, cutoff, q_ref, watch, nwatch,
             low_ref, up_ref, near):
    """near[k, n]: is pair n within ``cutoff`` at qs[k]? From node k's reference configuration
    q_ref[k] a point has moved by at most g = sum_c |q - q_ref|_c reach[c] (:func:`motion_reach`, its
    largest per joint), so a pair's distance has changed by at most 2 g. While 2 g <= ``horizon`` only
    the node's watch list (watch[k, :nwatch[k]]: the pairs whose lower bound low_ref at the reference
    was within cutoff + horizon; up_ref their distance there, or inf when only the bound is known) is
    looked at: near when
    up_ref + 2 g < cutoff, far when low_ref - 2 g > cutoff, else evaluated. Beyond, every pair is
    evaluated and the node's reference, watch list and bounds are reset (in place)."""
    nj, S, T = chain_f.shape[0], seg_f.shape[0], tri_f.shape[0]
    nv, npair = qs.shape[1], rows.shape[0]
    R, p = np.empty((nj, 3, 3)), np.empty((nj, 3))
    A, B, V = np.empty((S, 3)), np.empty((S, 3)), np.empty((T, 3, 3))
    ctr, rad = np.empty((S + T, 3)), np.empty(S + T)
    P, Q = np.empty((1, 3)), np.empty((1, 3))
    need, low, d = np.zeros(npair, np.bool_), np.empty(npair), np.empty(npair)
    for k in range(qs.shape[0]):
        g = 0.0
        for c in range(nv):
            g += abs(qs[k, c] - q_ref[k, c]) * reach[c]
        near[k, :] = False
        if nwatch[k] >= 0 and 2.0 * g <= horizon:
            count = 0
            for m in range(nwatch[k]):
                n = watch[k, m]
                if up_ref[k, m] + 2.0 * g < cutoff:
                    near[k, n] = True
                elif low_ref[k, m] - 2.0 * g <= cutoff:
                    need[n] = True
                    count += 1
            if count:
                fk(chain_f, chain_i, qs[k], R, p)
                place_primitives(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V)
                _bounding_spheres(A, B, V, ctr, rad)
                _row(A, B, V, ctr, rad, rows, rsum, cutoff, False, need, d, low, P, Q)
                for m in range(nwatch[k]):
                    n = watch[k, m]
                    if need[n]:
                        near[k, n] = d[n] < cutoff
                        need[n] = False
            continue
        fk(chain_f, chain_i, qs[k], R, p)
        place_primitives(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V)
        _bounding_spheres(A, B, V, ctr, rad)
        _row(A, B, V, ctr, rad, rows, rsum, cutoff, True, need, d, low, P, Q)  # low: a bound where d is inf
        m = 0
        for n in range(npair):
            near[k, n] = d[n] < cutoff
            if low[n] <= cutoff + horizon:
                watch[k, m], low_ref[k, m], up_ref[k, m] = n, low[n], d[n]
                m += 1
        nwatch[k] = m
        q_ref[k, :] = qs[k]


def motion_reach(packed: Packed) -> np.ndarray:
    """(S + T, nv) m/rad: how far any point of each primitive (segments, then triangles) moves per
    radian of each joint, at any configuration. A point X moves at |w_i x (X - o_i)| <= |X - o_i| per
    unit rate of joint i (o_i on its axis), and |X - o_i| is at most the offsets of the joints from i
    down to X's own joint plus X's distance from that joint's origin (triangle inequality); zero for
    the joints that do not carry it. Along q -> q + dq every point of primitive i therefore moves at
    most |dq| . reach[i], so a pair's distance drops by at most the two primitives' sum."""
    seg, tri = packed.seg_f.reshape(-1, 2, 3), packed.tri_f.reshape(-1, 3, 3)
    local = np.concatenate([np.linalg.norm(seg, axis=2).max(axis=1, initial=0.0),
                            np.linalg.norm(tri, axis=2).max(axis=1, initial=0.0)])
    joint = np.concatenate([packed.seg_j, packed.tri_j])
    offset = np.linalg.norm(packed.chain_f[:, 9:12], axis=1)
    out = np.zeros((len(joint), packed.moves.shape[1]))
    for j in np.unique(joint[joint > 0]):
        rows, acc, m = joint == j, 0.0, int(j)
        while m > 0:
            out[rows, packed.chain_i[m, 1]] = acc + local[rows]
            acc += offset[m]
            m = int(packed.chain_i[m, 0])
    return out


def batch_distances(packed: Packed, qs: np.ndarray, pairs: Pairs, cutoff: float = np.inf,
                    within: float | None = None) -> np.ndarray:
    """Safety distances (K, P) m of every pair at every configuration qs (K, nq); inf for a pair whose
    distance is above ``cutoff`` m (bounding spheres or a triangle's plane show it); with ``within``
    m, inf also for the pairs above both ``within`` and the configuration's least distance, which
    stays exact (each row's minimum and every pair within ``within`` are exact)."""
    rows, rsum = pair_table(packed, pairs)
    qs = np.ascontiguousarray(qs, dtype=float).reshape(-1, packed.chain_f.shape[0] - 1)
    out = np.empty((len(qs), len(rows)))
    _batch(packed.chain_f, packed.chain_i, packed.seg_f, packed.seg_j, packed.tri_f, packed.tri_j, qs, rows, rsum,
           float(cutoff), -1.0 if within is None else float(within), out)
    return out


class PairRecheck:
    """Which candidate pairs are within ``cutoff`` m at each of K nodes, checked again as the motion
    changes (:func:`_recheck`): a node evaluates only the pairs of its watch list that the motion
    since its reference configuration can have brought within the cutoff, until that motion could
    close ``horizon`` m, when every pair is evaluated again. Exact: a pair it skips is farther than
    the cutoff (tests/dualarm/test_nodes.py, against the full evaluation)."""

    def __init__(self, packed: Packed, pairs: Pairs, cutoff: float, horizon: float = 0.05):
        self.packed, self.cutoff, self.horizon = packed, float(cutoff), float(horizon)
        self.rows, self.rsum = pair_table(packed, pairs)
        self.reach = motion_reach(packed).max(axis=0, initial=0.0)
        self.q_ref = None

    def near(self, qs: np.ndarray) -> np.ndarray:
        """(K, P) bool: the pairs within the cutoff at the configurations qs (K, nq)."""
        pk = self.packed
        qs = np.ascontiguousarray(qs, dtype=float)
        K, npair = len(qs), len(self.rows)
        if self.q_ref is None or self.q_ref.shape != qs.shape:
            self.q_ref, self.nwatch = qs.copy(), np.full(K, -1, np.int64)
            self.watch, self.low_ref = np.empty((K, npair), np.int64), np.empty((K, npair))
            self.up_ref = np.empty((K, npair))
        near = np.empty((K, npair), np.bool_)
        _recheck(pk.chain_f, pk.chain_i, pk.seg_f, pk.seg_j, pk.tri_f, pk.tri_j, self.reach, self.horizon, qs,
                 self.rows, self.rsum, self.cutoff, self.q_ref, self.watch, self.nwatch, self.low_ref, self.up_ref, near)
        return near
