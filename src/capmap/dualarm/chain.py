"""A Pinocchio model of revolute joints packed into flat arrays, and compiled (numba) kinematics and
safety distances on it, for the node models and the pair filter.

Joint j: parent, placement in its parent (R, p), unit axis in its own frame, its q index; the
placement of joint j in the world is oMi[parent] * placement * Rot(axis, q). Column i of the
world Jacobian (the joint with q index i): angular w_i = R_j axis_j, and a point X carried by a
body that joint moves has velocity w_i x (X - o_j). Frames: left gripper, right gripper, panel
(their joint and placement in it). Only 1-dof revolute joints (Pinocchio's RX/RY/RZ and
revolute-unaligned) are packed; :func:`pack` says why not otherwise (the node models then stay
on Pinocchio's own calls). Tested against Pinocchio in tests/dualarm/test_nodes.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import pinocchio as pin

from capmap.dualarm.collision import Pairs, Primitives
from capmap.dualarm.distance import segseg, segtri

__all__ = ["Packed", "pack", "fk", "pair_table", "distances", "batch_distances", "motion_reach", "PairRecheck"]

_jit = numba.njit(cache=True)  # plain calls (numba's IR inlining, inline="always", compiles several times slower)


@dataclass(frozen=True, eq=False)
class Packed:
    """chain_f (nj, 15): placement R (9), p (3), axis (3); chain_i (nj, 2): parent, q index (-1 for
    the universe); moves (nj, nv) bool: the columns that move joint j's body; frame_f (3, 12): R,
    p of the left gripper, right gripper and panel frames in their joints; frame_j (3,);
    seg_f (S, 6): segment ends a, b (in their joint's frame, world for joint 0); seg_j (S,);
    seg_r (S,); tri_f (T, 9); tri_j (T,); tri_r (T,)."""

    chain_f: np.ndarray
    chain_i: np.ndarray
    moves: np.ndarray
    frame_f: np.ndarray
    frame_j: np.ndarray
    seg_f: np.ndarray
    seg_j: np.ndarray
    seg_r: np.ndarray
    tri_f: np.ndarray
    tri_j: np.ndarray
    tri_r: np.ndarray


def pack(model: pin.Model, frames: tuple[int, int, int], prims: Primitives) -> Packed | str:
    """The packed chain, or a sentence saying which joint cannot be packed."""
    nj = model.njoints
    if model.nq != model.nv or model.nq != nj - 1:
        return f"the model has {model.nq} configuration and {model.nv} velocity variables for {nj - 1} joints"
    data = model.createData()
    q0 = pin.neutral(model)
    pin.computeJointJacobians(model, data, q0)
    chain_f, chain_i = np.zeros((nj, 15)), np.full((nj, 2), -1, dtype=np.int64)
    chain_f[0, :9] = np.eye(3).ravel()
    for j in range(1, nj):
        jm = model.joints[j]
        if jm.nq != 1 or jm.nv != 1:
            return f"joint {model.names[j]!r} ({jm.shortname()}) is not a 1-dof joint"
        col = np.asarray(data.J).reshape(6, -1)[:, jm.idx_v]  # (eigenpy gives a 1-dof model's J as (6,))
        R0, o0 = data.oMi[j].rotation, data.oMi[j].translation
        w = col[3:]
        if abs(np.linalg.norm(w) - 1.0) > 1e-9 or np.linalg.norm(col[:3] - np.cross(o0, w)) > 1e-9:
            return f"joint {model.names[j]!r} ({jm.shortname()}) is not a revolute joint"
        M = model.jointPlacements[j]
        chain_f[j] = np.concatenate([M.rotation.ravel(), M.translation, R0.T @ w])
        chain_i[j] = (model.parents[j], jm.idx_q)
    moves = np.zeros((nj, model.nv), dtype=np.bool_)
    for j in range(1, nj):
        for i in model.supports[j][1:]:
            moves[j, model.joints[i].idx_v] = True
    frame_f = np.array([np.concatenate([model.frames[f].placement.rotation.ravel(), model.frames[f].placement.translation])
                        for f in frames])
    frame_j = np.array([model.frames[f].parentJoint for f in frames], dtype=np.int64)
    return Packed(chain_f, chain_i, moves, frame_f, frame_j,
                  np.ascontiguousarray(np.hstack([prims.seg_a, prims.seg_b]), dtype=float),
                  prims.seg_joint.astype(np.int64), prims.seg_r.astype(float),
                  np.ascontiguousarray(prims.tri_v.reshape(-1, 9), dtype=float), prims.tri_joint.astype(np.int64),
                  prims.tri_r.astype(float))


def pair_table(packed: Packed, pairs: Pairs) -> tuple[np.ndarray, np.ndarray]:
    """(P, 3) int rows (kind 0 segment-segment / 1 segment-triangle, first, second) and the sums of
    the two radii (P,), segment-segment pairs first (the order of :class:`Pairs`)."""
    ss, st = np.asarray(pairs.ss, dtype=np.int64).reshape(-1, 2), np.asarray(pairs.st, dtype=np.int64).reshape(-1, 2)
    rows = np.vstack([np.column_stack([np.zeros(len(ss), np.int64), ss]),
                      np.column_stack([np.ones(len(st), np.int64), st])]).astype(np.int64)
    rsum = np.concatenate([packed.seg_r[ss[:, 0]] + packed.seg_r[ss[:, 1]], packed.seg_r[st[:, 0]] + packed.tri_r[st[:, 1]]])
    return np.ascontiguousarray(rows), rsum


@_jit
def fk(chain_f, chain_i, q, R, p):
    """World placements R (nj, 3, 3), p (nj, 3) of every joint at q (joint 0: the world)."""
    R[0, :, :] = 0.0
    for i in range(3):
        R[0, i, i] = 1.0
        p[0, i] = 0.0
    for j in range(1, chain_f.shape[0]):
        par, iq = chain_i[j, 0], chain_i[j, 1]
        ax, ay, az = chain_f[j, 12], chain_f[j, 13], chain_f[j, 14]
        c, s = np.cos(q[iq]), np.sin(q[iq])
        v = 1.0 - c
        # Rot(axis, q), Rodrigues
        m00, m01, m02 = c + v * ax * ax, v * ax * ay - s * az, v * ax * az + s * ay
        m10, m11, m12 = v * ax * ay + s * az, c + v * ay * ay, v * ay * az - s * ax
        m20, m21, m22 = v * ax * az - s * ay, v * ay * az + s * ax, c + v * az * az
        for r in range(3):
            # row r of R[par] @ placement
            a0 = R[par, r, 0] * chain_f[j, 0] + R[par, r, 1] * chain_f[j, 3] + R[par, r, 2] * chain_f[j, 6]
            a1 = R[par, r, 0] * chain_f[j, 1] + R[par, r, 1] * chain_f[j, 4] + R[par, r, 2] * chain_f[j, 7]
            a2 = R[par, r, 0] * chain_f[j, 2] + R[par, r, 1] * chain_f[j, 5] + R[par, r, 2] * chain_f[j, 8]
            R[j, r, 0] = a0 * m00 + a1 * m10 + a2 * m20
            R[j, r, 1] = a0 * m01 + a1 * m11 + a2 * m21
            R[j, r, 2] = a0 * m02 + a1 * m12 + a2 * m22
            p[j, r] = p[par, r] + R[par, r, 0] * chain_f[j, 9] + R[par, r, 1] * chain_f[j, 10] + R[par, r, 2] * chain_f[j, 11]


@_jit
def place_primitives(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V):
    """World segment ends A, B (S, 3) and triangles V (T, 3, 3) at the joint placements R, p."""
    for s in range(seg_f.shape[0]):
        j = seg_j[s]
        for i in range(3):
            if j == 0:
                A[s, i], B[s, i] = seg_f[s, i], seg_f[s, 3 + i]
            else:
                A[s, i] = p[j, i] + R[j, i, 0] * seg_f[s, 0] + R[j, i, 1] * seg_f[s, 1] + R[j, i, 2] * seg_f[s, 2]
                B[s, i] = p[j, i] + R[j, i, 0] * seg_f[s, 3] + R[j, i, 1] * seg_f[s, 4] + R[j, i, 2] * seg_f[s, 5]
    for t in range(tri_f.shape[0]):
        j = tri_j[t]
        for k in range(3):
            for i in range(3):
                if j == 0:
                    V[t, k, i] = tri_f[t, 3 * k + i]
                else:
                    V[t, k, i] = (p[j, i] + R[j, i, 0] * tri_f[t, 3 * k] + R[j, i, 1] * tri_f[t, 3 * k + 1]
                                  + R[j, i, 2] * tri_f[t, 3 * k + 2])


@_jit
def plane_gap(A, B, s, V, t):
    """A lower bound (m) of the distance from segment A[s] -> B[s] to triangle V[t]: the nearer end's
    distance to the triangle's plane when both ends are on one side of it, else 0."""
    e1x, e1y, e1z = V[t, 1, 0] - V[t, 0, 0], V[t, 1, 1] - V[t, 0, 1], V[t, 1, 2] - V[t, 0, 2]
    e2x, e2y, e2z = V[t, 2, 0] - V[t, 0, 0], V[t, 2, 1] - V[t, 0, 1], V[t, 2, 2] - V[t, 0, 2]
    nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
    nn = np.sqrt(nx * nx + ny * ny + nz * nz)
    if nn == 0.0:
        return 0.0
    da = (nx * (A[s, 0] - V[t, 0, 0]) + ny * (A[s, 1] - V[t, 0, 1]) + nz * (A[s, 2] - V[t, 0, 2])) / nn
    db = (nx * (B[s, 0] - V[t, 0, 0]) + ny * (B[s, 1] - V[t, 0, 1]) + nz * (B[s, 2] - V[t, 0, 2])) / nn
    return min(abs(da), abs(db)) if da * db > 0.0 else 0.0


@_jit
def _point_segment(A, B, s, x, y, z):
    """Distance (m) from the point (x, y, z) to segment A[s] -> B[s]."""
    dx, dy, dz = B[s, 0] - A[s, 0], B[s, 1] - A[s, 1], B[s, 2] - A[s, 2]
    ex, ey, ez = x - A[s, 0], y - A[s, 1], z - A[s, 2]
    L2 = dx * dx + dy * dy + dz * dz
    t = 0.0 if L2 == 0.0 else min(max((ex * dx + ey * dy + ez * dz) / L2, 0.0), 1.0)
    ex, ey, ez = ex - t * dx, ey - t * dy, ez - t * dz
    return np.sqrt(ex * ex + ey * ey + ez * ez)


@_jit
def lower_bound(A, B, V, kind, a, b):
    """A lower bound (m) of the distance between primitives a and b of a pair row (kind 0: segments
    A[a] -> B[a] and A[b] -> B[b]; 1: segment a and triangle V[b]), at a few dozen flops: the distance
    from the first segment to the second primitive's centre less that primitive's reach from its
    centre, and for a triangle also :func:`plane_gap`."""
    if kind == 0:
        cx, cy, cz = 0.5 * (A[b, 0] + B[b, 0]), 0.5 * (A[b, 1] + B[b, 1]), 0.5 * (A[b, 2] + B[b, 2])
        reach = 0.5 * np.sqrt((B[b, 0] - A[b, 0]) ** 2 + (B[b, 1] - A[b, 1]) ** 2 + (B[b, 2] - A[b, 2]) ** 2)
        return _point_segment(A, B, a, cx, cy, cz) - reach
    cx = (V[b, 0, 0] + V[b, 1, 0] + V[b, 2, 0]) / 3.0
    cy = (V[b, 0, 1] + V[b, 1, 1] + V[b, 2, 1]) / 3.0
    cz = (V[b, 0, 2] + V[b, 1, 2] + V[b, 2, 2]) / 3.0
    reach = 0.0
    for m in range(3):
        reach = max(reach, np.sqrt((V[b, m, 0] - cx) ** 2 + (V[b, m, 1] - cy) ** 2 + (V[b, m, 2] - cz) ** 2))
    return max(_point_segment(A, B, a, cx, cy, cz) - reach, plane_gap(A, B, a, V, b))


@_jit
def distances(A, B, V, rows, rsum, d, P, Q):
    """Safety distances d (P,) of the pair rows (kind, first, second) with closest points P, Q."""
    for n in range(rows.shape[0]):
        if rows[n, 0] == 0:
            core = segseg(A, rows[n, 1], B, rows[n, 1], A, rows[n, 2], B, rows[n, 2], P, Q, n)
        else:
            core = segtri(A, rows[n, 1], B, rows[n, 1], V, rows[n, 2], P, Q, n)
        d[n] = core - rsum[n]


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
