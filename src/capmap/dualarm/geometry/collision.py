"""The collision model: swept-sphere primitives on the robot's joints, on the held panel and in
the environment, the pairs to check, and their safety distances and q-gradients.

Primitives are segments and triangles, each with a radius and the joint it rides on (joint
0: static). Two volumes' safety distance is the distance of their cores minus both radii.
A pair is segment-segment or segment-triangle; a triangle-triangle contact (the panel
against a face of the environment) is covered exactly by the panel's edges against the
face and the face's edges against the panel (the closest points of two triangles lie on an
edge of one of them).

The gradient of a pair's distance: with closest points P (first) and Q (second) and
n = (P - Q) / |P - Q|, dd/dq_i = n . (v_i + w_i x P) - n . (v_i + w_i x Q), each term only for
the joints i that move the body the point rides on, (v_i; w_i) being joint i's column of
Pinocchio's world Jacobian (its twist at the world origin).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
import pinocchio as pin

from capmap.dualarm.geometry.distance import segseg, segtri

__all__ = ["Primitives", "Pairs", "CollisionModel", "Evaluation"]

@dataclass(frozen=True)
class Primitives:
    """Segments: joint (S,), a, b (S, 3) in that joint's frame, radius (S,), body (S,) names;
    triangles: joint (T,), v (T, 3, 3), radius (T,), body (T,)."""

    seg_joint: np.ndarray
    seg_a: np.ndarray
    seg_b: np.ndarray
    seg_r: np.ndarray
    seg_body: np.ndarray
    tri_joint: np.ndarray
    tri_v: np.ndarray
    tri_r: np.ndarray
    tri_body: np.ndarray

    @staticmethod
    def concat(parts: list["Primitives"]) -> "Primitives":
        return Primitives(*(np.concatenate([getattr(p, f) for p in parts]) for f in Primitives.__dataclass_fields__))

    @staticmethod
    def empty() -> "Primitives":
        z = np.zeros
        return Primitives(z(0, int), z((0, 3)), z((0, 3)), z(0), z(0, dtype=object), z(0, int), z((0, 3, 3)), z(0),
                          z(0, dtype=object))


@dataclass(frozen=True)
class Pairs:
    """Pairs to check: ss (P1, 2) segment-segment and st (P2, 2) segment-triangle indices."""

    ss: np.ndarray
    st: np.ndarray

    def __len__(self) -> int:
        return len(self.ss) + len(self.st)

    def subset(self, keep: np.ndarray) -> "Pairs":
        """The pairs flagged in keep (len(self),): segment-segment first, then segment-triangle."""
        keep = np.asarray(keep, dtype=bool)
        return Pairs(self.ss[keep[:len(self.ss)]], self.st[keep[len(self.ss):]])


@dataclass(frozen=True)
class Evaluation:
    """Per pair: safety distance (P,) m, closest points p, q (P, 3), and names of the two bodies."""

    distance: np.ndarray
    p: np.ndarray
    q: np.ndarray
    first: np.ndarray
    second: np.ndarray
    gradient: np.ndarray | None = field(default=None)


@numba.njit(cache=True)
def _pair_gradients(P, Q, ja, jb, J, moves, G):
    """G[n] = dd_n/dq for closest points P, Q (n, 3) on joints ja, jb: J (6, nv) world Jacobian,
    moves (njoints, nv): which joints move each joint's body."""
    for n in range(len(P)):
        dx, dy, dz = P[n, 0] - Q[n, 0], P[n, 1] - Q[n, 1], P[n, 2] - Q[n, 2]
        norm = np.sqrt(dx * dx + dy * dy + dz * dz)
        if norm == 0.0:
            G[n, :] = 0.0
            continue
        nx, ny, nz = dx / norm, dy / norm, dz / norm
        for side in range(2):
            jj, X, sign = (ja[n], P, 1.0) if side == 0 else (jb[n], Q, -1.0)
            if jj == 0:
                continue
            # (X x n) . w + n . v per column
            cx = X[n, 1] * nz - X[n, 2] * ny
            cy = X[n, 2] * nx - X[n, 0] * nz
            cz = X[n, 0] * ny - X[n, 1] * nx
            for i in range(J.shape[1]):
                if moves[jj, i]:
                    G[n, i] += sign * (nx * J[0, i] + ny * J[1, i] + nz * J[2, i] + cx * J[3, i] + cy * J[4, i]
                                       + cz * J[5, i])


@numba.njit(cache=True)
def _pair_distances(a, b, v, ss, st, d, P, Q):
    """Core distances and closest points of segment-segment pairs ss then segment-triangle pairs st."""
    for n in range(len(ss)):
        d[n] = segseg(a, ss[n, 0], b, ss[n, 0], a, ss[n, 1], b, ss[n, 1], P, Q, n)
    m = len(ss)
    for n in range(len(st)):
        d[m + n] = segtri(a, st[n, 0], b, st[n, 0], v, st[n, 1], P, Q, m + n)


class CollisionModel:
    """Primitives on a Pinocchio model, with the world placement of its joints taken from ``data``.
    Static primitives (joint 0) are placed once."""

    def __init__(self, model: pin.Model, prims: Primitives):
        self.model, self.prims = model, prims
        self._seg_moving = np.flatnonzero(prims.seg_joint > 0)
        self._tri_moving = np.flatnonzero(prims.tri_joint > 0)
        self._a, self._b, self._v = prims.seg_a.copy(), prims.seg_b.copy(), prims.tri_v.copy()
        self._moves = np.zeros((model.njoints, model.nv), dtype=bool)  # joints that move each joint's body
        for j in range(1, model.njoints):
            for i in model.supports[j][1:]:
                self._moves[j, model.joints[i].idx_v:model.joints[i].idx_v + model.joints[i].nv] = True

    def _world(self, data: pin.Data) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        H = np.array([M.homogeneous for M in data.oMi])  # (njoints, 4, 4): one call per joint
        R, t = H[:, :3, :3], H[:, :3, 3]
        P = self.prims
        i, k = self._seg_moving, self._tri_moving
        ji, jk = P.seg_joint[i], P.tri_joint[k]
        self._a[i] = np.einsum("sij,sj->si", R[ji], P.seg_a[i]) + t[ji]
        self._b[i] = np.einsum("sij,sj->si", R[ji], P.seg_b[i]) + t[ji]
        self._v[k] = np.einsum("tij,tkj->tki", R[jk], P.tri_v[k]) + t[jk][:, None]
        return self._a, self._b, self._v, t

    def evaluate(self, data: pin.Data, pairs: Pairs, gradient: bool = False) -> Evaluation:
        """Safety distances (and with ``gradient``, their q-gradients (P, nv): needs
        ``pin.computeJointJacobians`` done on ``data``) of the pairs at the placements in ``data``."""
        P = self.prims
        a, b, v, origins = self._world(data)
        n = len(pairs)
        core, p, q = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
        _pair_distances(a, b, v, pairs.ss, pairs.st, core, p, q)
        i, j = pairs.ss[:, 0], pairs.ss[:, 1]
        k, t = pairs.st[:, 0], pairs.st[:, 1]
        dist = core - np.concatenate([P.seg_r[i] + P.seg_r[j], P.seg_r[k] + P.tri_r[t]])
        ja = np.concatenate([P.seg_joint[i], P.seg_joint[k]])
        jb = np.concatenate([P.seg_joint[j], P.tri_joint[t]])
        grad = None
        if gradient:  # needs pin.computeJointJacobians (data.J: the world Jacobian)
            grad = np.zeros((n, self.model.nv))
            _pair_gradients(p, q, ja, jb, np.asarray(data.J), self._moves, grad)
        first = np.concatenate([P.seg_body[i], P.seg_body[k]])
        second = np.concatenate([P.seg_body[j], P.tri_body[t]])
        return Evaluation(dist, p, q, first, second, grad)
