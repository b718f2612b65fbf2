"""A Pinocchio model of revolute joints packed into flat arrays, and compiled (numba) kinematics and
safety distances on it, for the node models and the pair filters (:mod:`capmap.dualarm.geometry.proximity`).

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

from capmap.dualarm.geometry.broadphase import BodyBalls, SegmentPrims, TrianglePrims, pair_groups, static_balls
from capmap.dualarm.geometry.collision import Pairs, Primitives
from capmap.dualarm.geometry.distance import segpoint, segseg, segtri

__all__ = ["Packed", "pack", "fk", "pair_table", "place_primitives", "plane_gap", "lower_bound", "distances",
           "groups_of", "joint_placements", "levers",
           "static_bound", "place_moving"]

_jit = numba.njit(cache=True)  # plain calls (numba's IR inlining, inline="always", compiles several times slower)


@dataclass(frozen=True, eq=False)
class Packed:
    """chain_f (nj, 15): placement R (9), p (3), axis (3); chain_i (nj, 2): parent, q index (-1 for
    the universe); moves (nj, nv) bool: the columns that move joint j's body; frame_f (3, 12): R,
    p of the left gripper, right gripper and panel frames in their joints; frame_j (3,);
    seg_f (S, 6): segment ends a, b (in their joint's frame, world for joint 0); seg_j (S,);
    seg_r (S,); tri_f (T, 17): vertices (9) in their joint's frame, then for :func:`static_bound` the
    centroid (3), reach (1), unit normal (3) and plane offset (1); tri_j (T,); tri_r (T,); seg_g (S,),
    tri_g (T,), balls (G, 4): the static primitives' bodies and their balls
    (:func:`capmap.dualarm.geometry.broadphase.static_balls`); reach (nj, nv):
    a bound on the distance from joint j's origin to the origin of column i's joint, in any configuration
    (the lengths of the placements between them), where column i moves joint j; lever (S + T, nv): every
    segment's, then triangle's :func:`levers`."""

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
    seg_g: np.ndarray
    tri_g: np.ndarray
    balls: np.ndarray
    reach: np.ndarray
    lever: np.ndarray


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
    seg = (np.ascontiguousarray(np.hstack([prims.seg_a, prims.seg_b]), dtype=float),
           prims.seg_joint.astype(np.int64), prims.seg_r.astype(float))
    tri = (np.ascontiguousarray(prims.tri_v.reshape(-1, 9), dtype=float), prims.tri_joint.astype(np.int64),
           prims.tri_r.astype(float))
    groups = static_balls(SegmentPrims(*seg, prims.seg_body), TrianglePrims(*tri, prims.tri_body))
    v = tri[0].reshape(-1, 3, 3)
    ctr = v.mean(axis=1)
    tri_reach = np.linalg.norm(v - ctr[:, None], axis=2).max(axis=1, initial=0.0)
    nrm = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    size = np.linalg.norm(nrm, axis=1)
    nrm = np.where(size[:, None] > 0, nrm / np.where(size > 0, size, 1.0)[:, None], 0.0)  # 0: no plane bound
    ext = np.column_stack([ctr, tri_reach, nrm, np.einsum("ij,ij->i", nrm, v[:, 0])])
    tri = (np.ascontiguousarray(np.hstack([tri[0], ext])),) + tri[1:]
    reach = np.zeros((nj, model.nv))
    for j in range(1, nj):
        length, l = 0.0, j
        while l > 0:  # up the chain: |o_l - o_parent(l)| = |placement translation of l|
            reach[j, chain_i[l, 1]] = length
            length += np.linalg.norm(chain_f[l, 9:12])
            l = chain_i[l, 0]
    return Packed(chain_f, chain_i, moves, frame_f, frame_j, *seg, *tri, groups.seg_g, groups.tri_g, groups.balls, reach,
                  _lever_table(seg[0], seg[1], tri[0], tri[1], moves, reach))


def pair_table(packed: Packed, pairs: Pairs) -> tuple[np.ndarray, np.ndarray]:
    """(P, 3) int rows (kind 0 segment-segment / 1 segment-triangle, first, second) and the sums of
    the two radii (P,), segment-segment pairs first (the order of :class:`Pairs`)."""
    ss, st = np.asarray(pairs.ss, dtype=np.int64).reshape(-1, 2), np.asarray(pairs.st, dtype=np.int64).reshape(-1, 2)
    rows = np.vstack([np.column_stack([np.zeros(len(ss), np.int64), ss]),
                      np.column_stack([np.ones(len(st), np.int64), st])]).astype(np.int64)
    rsum = np.concatenate([packed.seg_r[ss[:, 0]] + packed.seg_r[ss[:, 1]], packed.seg_r[st[:, 0]] + packed.tri_r[st[:, 1]]])
    return np.ascontiguousarray(rows), rsum


def levers(packed: Packed, seg: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(len(seg) + len(tri), nv): how far (m) a point of each of those segments, then triangles, moves per
    radian of each column, at most, in any configuration: the reach from its joint's origin to the column's
    joint plus its own extent from its joint's origin (a rotation dq about an axis through o moves X by at
    most |dq| |X - o|); 0 for a static primitive or a column that does not move it."""
    return np.ascontiguousarray(packed.lever[np.concatenate([seg, len(packed.seg_f) + np.asarray(tri, np.int64)])])


def _lever_table(seg_f: np.ndarray, seg_j: np.ndarray, tri_f: np.ndarray, tri_j: np.ndarray, moves: np.ndarray,
                 reach: np.ndarray) -> np.ndarray:
    """:func:`levers` of every segment, then every triangle (S + T, nv)."""
    far = np.concatenate([np.maximum(np.linalg.norm(seg_f[:, :3], axis=1), np.linalg.norm(seg_f[:, 3:6], axis=1)),
                          np.linalg.norm(tri_f[:, :9].reshape(-1, 3, 3), axis=2).max(axis=1, initial=0.0)])
    joint = np.concatenate([seg_j, tri_j])
    return np.where(moves[joint], reach[joint] + far[:, None], 0.0) * (joint > 0)[:, None]


def groups_of(packed: Packed, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pair rows' groups (order, groups, spheres) of :func:`capmap.dualarm.geometry.broadphase.pair_groups`."""
    pk = packed
    return pair_groups(rows, pk.seg_j, pk.seg_r, pk.tri_j, pk.tri_r, BodyBalls(pk.seg_g, pk.tri_g, pk.balls))


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
def joint_placements(chain_f, chain_i, qs, R, p):
    """World placements R (K, nj, 3, 3), p (K, nj, 3) of every joint at each configuration qs (K, nq)."""
    for k in range(qs.shape[0]):
        fk(chain_f, chain_i, qs[k], R[k], p[k])


@_jit
def place_primitives(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V):
    """World segment ends A, B (S, 3) and triangles V (T, 3, 3) at the joint placements R, p."""
    for s in range(seg_f.shape[0]):
        if seg_j[s] == 0:
            for i in range(3):
                A[s, i], B[s, i] = seg_f[s, i], seg_f[s, 3 + i]
    for t in range(tri_f.shape[0]):
        if tri_j[t] == 0:
            for k in range(3):
                for i in range(3):
                    V[t, k, i] = tri_f[t, 3 * k + i]
    place_moving(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V)


@_jit
def place_moving(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V):
    """World segment ends A, B (S, 3) and triangles V (T, 3, 3) of the moving primitives (joint > 0) at the
    joint placements R, p; the static ones' rows are left as they are."""
    for s in range(seg_f.shape[0]):
        j = seg_j[s]
        if j == 0:
            continue
        for i in range(3):
            A[s, i] = p[j, i] + R[j, i, 0] * seg_f[s, 0] + R[j, i, 1] * seg_f[s, 1] + R[j, i, 2] * seg_f[s, 2]
            B[s, i] = p[j, i] + R[j, i, 0] * seg_f[s, 3] + R[j, i, 1] * seg_f[s, 4] + R[j, i, 2] * seg_f[s, 5]
    for t in range(tri_f.shape[0]):
        j = tri_j[t]
        if j == 0:
            continue
        for k in range(3):
            for i in range(3):
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
def lower_bound(A, B, V, kind, a, b):
    """A lower bound (m) of the distance between primitives a and b of a pair row (kind 0: segments
    A[a] -> B[a] and A[b] -> B[b]; 1: segment a and triangle V[b]), at a few dozen flops: the distance
    from the first segment to the second primitive's centre less that primitive's reach from its
    centre, and for a triangle also :func:`plane_gap`."""
    if kind == 0:
        cx, cy, cz = 0.5 * (A[b, 0] + B[b, 0]), 0.5 * (A[b, 1] + B[b, 1]), 0.5 * (A[b, 2] + B[b, 2])
        reach = 0.5 * np.sqrt((B[b, 0] - A[b, 0]) ** 2 + (B[b, 1] - A[b, 1]) ** 2 + (B[b, 2] - A[b, 2]) ** 2)
        return segpoint(A, B, a, cx, cy, cz) - reach
    cx = (V[b, 0, 0] + V[b, 1, 0] + V[b, 2, 0]) / 3.0
    cy = (V[b, 0, 1] + V[b, 1, 1] + V[b, 2, 1]) / 3.0
    cz = (V[b, 0, 2] + V[b, 1, 2] + V[b, 2, 2]) / 3.0
    reach = 0.0
    for m in range(3):
        reach = max(reach, np.sqrt((V[b, m, 0] - cx) ** 2 + (V[b, m, 1] - cy) ** 2 + (V[b, m, 2] - cz) ** 2))
    return max(segpoint(A, B, a, cx, cy, cz) - reach, plane_gap(A, B, a, V, b))


@_jit
def static_bound(A, B, s, tri_f, t):
    """A lower bound (m) of the distance from segment A[s] -> B[s] to the static triangle tri_f[t] (world
    coordinates, with its centroid, reach, normal and offset): the larger of the distance to its centroid
    less its reach and, when both ends lie on one side of its plane, the nearer end's distance to it."""
    lb = segpoint(A, B, s, tri_f[t, 9], tri_f[t, 10], tri_f[t, 11]) - tri_f[t, 12]
    nx, ny, nz, off = tri_f[t, 13], tri_f[t, 14], tri_f[t, 15], tri_f[t, 16]
    if nx != 0.0 or ny != 0.0 or nz != 0.0:
        da = nx * A[s, 0] + ny * A[s, 1] + nz * A[s, 2] - off
        db = nx * B[s, 0] + ny * B[s, 1] + nz * B[s, 2] - off
        if da * db > 0.0:
            lb = max(lb, min(abs(da), abs(db)))
    return lb


@_jit
def distances(A, B, V, rows, rsum, d, P, Q):
    """Safety distances d (P,) of the pair rows (kind, first, second) with closest points P, Q."""
    for n in range(rows.shape[0]):
        if rows[n, 0] == 0:
            core = segseg(A, rows[n, 1], B, rows[n, 1], A, rows[n, 2], B, rows[n, 2], P, Q, n)
        else:
            core = segtri(A, rows[n, 1], B, rows[n, 1], V, rows[n, 2], P, Q, n)
        d[n] = core - rsum[n]
