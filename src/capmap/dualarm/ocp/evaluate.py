"""What a solution achieved, measured independently of the optimiser's own bookkeeping: the task
constraints and every candidate collision pair at every node, and the safety distances on a
finer time grid of the motion actually executed (constant acceleration over each step, so
q(t) = q_k + v_k tau + u_k tau^2 / 2 is exact between nodes)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from capmap.dualarm.geometry.chain import pack
from capmap.dualarm.geometry.proximity import near_pairs
from capmap.dualarm.ocp.assembly import Assembly
from capmap.dualarm.ocp.task import node_constraints

__all__ = ["NodeErrors", "node_errors", "fine_grid", "Safety", "safety", "active_pairs"]


@dataclass(frozen=True)
class NodeErrors:
    """Per node (K,): closed-chain position (m) and rotation (rad) errors; the path error (m, rad)
    of the constraint the node carries (vertical axis: rad only; pose: both; on the axis: m
    and the orientation: rad)."""

    closed_chain_pos: np.ndarray
    closed_chain_rot: np.ndarray
    path_pos: np.ndarray
    path_rot: np.ndarray


def node_errors(asm: Assembly, xs: np.ndarray, nodes: np.ndarray | None = None) -> NodeErrors:
    """Task-constraint errors at states xs (K, 2 nq) (node indices ``nodes``, default 0..K-1)."""
    model, task = asm.model, asm.task
    data = model.createData()
    nq = model.nq
    nodes = np.arange(len(xs)) if nodes is None else nodes
    out = np.zeros((len(xs), 4))
    for i, (k, x) in enumerate(zip(nodes, xs)):
        pin.forwardKinematics(model, data, x[:nq])
        pin.updateFramePlacements(model, data)
        for c in node_constraints(task, int(k), model, data, x[nq:]):
            v = c.value
            if c.name == "closed_chain":
                out[i, 0], out[i, 1] = np.linalg.norm(v[:3]), np.linalg.norm(v[3:])
            elif c.name in ("pre_insertion", "final"):
                out[i, 2], out[i, 3] = np.linalg.norm(v[:3]), np.linalg.norm(v[3:])
            elif c.name == "on_axis":
                out[i, 2] = np.linalg.norm(v)
            elif c.name in ("orientation", "vertical"):
                out[i, 3] = np.linalg.norm(v) if c.name == "orientation" else float(np.arcsin(min(np.linalg.norm(v), 1.0)))
    return NodeErrors(*out.T)


def fine_grid(xs: np.ndarray, us: np.ndarray, dt: float, factor: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times (M,), configurations (M, nq) and the node index just before each, ``factor`` samples per
    step plus the last node: the exact motion under constant accelerations."""
    nq = us.shape[1]
    tau = np.arange(factor) * dt / factor
    q = xs[:-1, None, :nq] + xs[:-1, None, nq:] * tau[:, None] + 0.5 * us[:, None, :] * (tau**2)[:, None]
    t = (np.arange(len(us))[:, None] * dt + tau).ravel()
    node = np.repeat(np.arange(len(us)), factor)
    return np.append(t, len(us) * dt), np.vstack([q.reshape(-1, nq), xs[-1, :nq]]), np.append(node, len(us))


@dataclass(frozen=True)
class Safety:
    """distance (M, P): safety distances at every configuration of the candidate pairs :func:`safety`
    evaluated somewhere (inf where it shows one above its cutoff, or above both ``within_m`` and the
    least; a pair it never evaluates is left out); names (P,) 'a vs b' of the bodies of each pair."""

    distance: np.ndarray
    names: np.ndarray

    @property
    def min_distance(self) -> np.ndarray:
        """(M,) the smallest safety distance at each configuration."""
        return self.distance.min(axis=1)

    @property
    def min_pair(self) -> np.ndarray:
        """(M,) the body pair attaining it."""
        return self.names[self.distance.argmin(axis=1)]


def safety(asm: Assembly, qs: np.ndarray, cutoff_m: float = 0.2, within_m: float | None = None) -> Safety:
    """Every candidate pair at every configuration qs (M, nq): with the chain packed
    (:func:`capmap.dualarm.geometry.proximity.batch_distances`, equal to Pinocchio's placements to 1e-12 in the tests),
    a pair whose distance is above ``cutoff_m`` gets inf, and with ``within_m`` also one above both
    ``within_m`` and the configuration's least distance (the least distance, its pair and every pair
    within ``within_m`` stay exact); else on Pinocchio's kinematics, every pair exactly."""
    t = asm.task
    packed = pack(asm.model, (t.left, t.right, t.panel), asm.collision.prims)
    if not isinstance(packed, str):
        # only the pairs evaluated somewhere are kept (a pair left out would be an inf column)
        k, n, d = near_pairs(packed, qs, asm.pairs, cutoff=cutoff_m, within=within_m)
        cols = np.unique(n) if len(n) or not len(asm.pairs) else np.zeros(1, np.int64)
        D = np.full((len(qs), len(cols)), np.inf)
        D[k, np.searchsorted(cols, n)] = d
        P = asm.collision.prims
        i, kk, tt = asm.pairs.ss, asm.pairs.st[:, 0], asm.pairs.st[:, 1]
        first, second = np.concatenate([P.seg_body[i[:, 0]], P.seg_body[kk]]), np.concatenate([P.seg_body[i[:, 1]],
                                                                                                P.tri_body[tt]])
        names = np.array([f"{a} vs {b}" for a, b in zip(first[cols], second[cols])], dtype=object)
        return Safety(D, names)
    data = asm.model.createData()
    D = np.empty((len(qs), len(asm.pairs)))
    names = None
    for k, q in enumerate(qs):
        pin.forwardKinematics(asm.model, data, q)
        ev = asm.collision.evaluate(data, asm.pairs)
        D[k] = ev.distance
        if names is None:
            names = np.array([f"{a} vs {b}" for a, b in zip(ev.first, ev.second)], dtype=object)
    return Safety(D, names)


def active_pairs(s: Safety, times: np.ndarray, within_m: float) -> list[tuple[str, float, float, float, float]]:
    """Body pairs that come within ``within_m``: (name, smallest distance m, its time, first and last
    time within it), nearest first; each body pair once (its closest primitive pair)."""
    per_body: dict[str, np.ndarray] = {}
    for p in np.flatnonzero(s.distance.min(axis=0) <= within_m):
        col = s.distance[:, p]
        name = s.names[p]
        per_body[name] = col if name not in per_body else np.minimum(per_body[name], col)
    out = []
    for name, col in per_body.items():
        near = np.flatnonzero(col <= within_m)
        out.append((name, float(col.min()), float(times[col.argmin()]), float(times[near[0]]), float(times[near[-1]])))
    return sorted(out, key=lambda r: r[1])
