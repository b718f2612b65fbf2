"""The node model compiled: one numba call (:func:`capmap.dualarm.ocp.node_kernel.node_eval`) per Crocoddyl
``calc`` / ``calcDiff``.

The same problem as :class:`capmap.dualarm.ocp.crocoddyl_nodes.NodeModel` (its module docstring: costs,
equalities of :mod:`.task`, safety-distance and joint-limit inequalities, augmented-Lagrangian
terms or CSQP constraint rows) evaluated on the packed chain of :mod:`.chain`: forward
kinematics, the three frames and their local Jacobians, the logarithms of :mod:`.lie`, the pair
distances of :mod:`.distance` and their gradients, and the Gauss-Newton assembly of Lx, Lxx, Lu,
all in one compiled function writing straight into Crocoddyl's data. The Pinocchio model
(``ocp.NodeModel``) stays the reference: tests/dualarm/test_nodes.py runs the contract on both
and compares them, with finite differences of the compiled gradient.
"""

from __future__ import annotations

import crocoddyl
import numpy as np
import pinocchio as pin

from capmap.dualarm.geometry.chain import Packed, groups_of, joint_placements, levers, pack, pair_table
from capmap.dualarm.geometry.collision import CollisionModel, Pairs, Primitives
from capmap.dualarm.geometry.distance import point_triangle, segment_segment, segment_triangle
from capmap.dualarm.geometry.proximity import PairFilter, batch_distances
from capmap.dualarm.ocp.crocoddyl_nodes import Context, equality_size
from capmap.dualarm.ocp.fddp import ALPHAS, evaluate_nodes, fddp
from capmap.dualarm.ocp.node_kernel import node_eval
from capmap.dualarm.ocp.packed_nodes import node_function, pack_nodes
from capmap.dualarm.ocp.settings import Weights
from capmap.dualarm.ocp.task import AssemblyTask
from capmap.dualarm.scene.unknown import near_boxes
from capmap.dualarm.scene.unobserved import _bound_gaps, _cube_distances

__all__ = ["CompiledNodeModel", "node_kind", "node_targets", "warm_up_nodes", "warm_up_geometry"]

# node kinds (task.py): transfer (vertical), pre-insertion pose, insertion (axis + orientation), final
TRANSFER, PRE, INSERTION, FINAL = 0, 1, 2, 3


def node_kind(task, k: int) -> int:
    """The kind of node k's task constraint."""
    if k < task.n_transfer:
        return TRANSFER
    if k == task.n_transfer:
        return PRE
    return INSERTION if k < task.N else FINAL


def _inv(M: pin.SE3) -> np.ndarray:
    Mi = M.inverse()
    return np.concatenate([Mi.rotation.ravel(), Mi.translation])


def node_targets(task, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(targets (3, 12): the inverses of the closed chain's reference, node k's panel reference and
    the pre-insertion (kind PRE) or final pose, as R (9), p (3); axis (3, 3): the insertion axis'
    point and its two directions across)."""
    third = task.pre if k == task.n_transfer else task.final
    tg = np.array([_inv(task.rel_ref), _inv(task.reference[k]), _inv(third)])
    return tg, np.vstack([task.axis_point, task.axis_across])


def _compact(pk: Packed, rows: np.ndarray):
    """(seg_f, seg_j, tri_f, tri_j, A, B, V, rows, lever) with only the primitives that ``rows`` (P, 3) name,
    renumbered (a node places the few its pairs use, not the whole scene's), their world coordinates
    (segment ends A, B (S, 3), triangles V (T, 3, 3)) where static, and their levers (S + T, nv): how far
    a point of each moves per radian of each column, at most."""
    seg = np.unique(np.concatenate([rows[:, 1], rows[rows[:, 0] == 0, 2]])).astype(np.int64)
    tri = np.unique(rows[rows[:, 0] == 1, 2]).astype(np.int64)
    seg_new, tri_new = np.zeros(len(pk.seg_f), np.int64), np.zeros(len(pk.tri_f), np.int64)
    seg_new[seg], tri_new[tri] = np.arange(len(seg)), np.arange(len(tri))
    out = rows.copy()
    out[:, 1] = seg_new[rows[:, 1]]
    ss = rows[:, 0] == 0
    out[ss, 2], out[~ss, 2] = seg_new[rows[ss, 2]], tri_new[rows[~ss, 2]]
    c = np.ascontiguousarray
    seg_f, seg_j, tri_f, tri_j = c(pk.seg_f[seg]), c(pk.seg_j[seg]), c(pk.tri_f[tri]), c(pk.tri_j[tri])
    # world coordinates: the static primitives' (their joint-0 coordinates), the moving ones' written by each call
    Aw, Bw, Vw = c(seg_f[:, :3] * (seg_j == 0)[:, None]), c(seg_f[:, 3:6] * (seg_j == 0)[:, None]), c(
        tri_f[:, :9].reshape(-1, 3, 3) * (tri_j == 0)[:, None, None])
    return seg_f, seg_j, tri_f, tri_j, Aw, Bw, Vw, c(out), levers(pk, seg, tri)


class CompiledNodeModel(crocoddyl.ActionModelAbstract):
    """Node k of the problem on the packed chain ``packed`` (same arguments and meaning as
    :class:`capmap.dualarm.ocp.crocoddyl_nodes.NodeModel`; multipliers lam_eq, lam_in on the node)."""

    def __init__(self, ctx: Context, k: int, pairs: Pairs, mode: str = "al", packed: Packed | None = None):
        nq = ctx.model.nq
        self.ctx, self.k, self.pairs, self.mode, self.packed = ctx, k, pairs, mode, packed
        task = ctx.task
        self.terminal = k == task.N
        self.m_eq = equality_size(task, k, nq)
        ng = self.m_eq if mode == "constrained" else 0
        crocoddyl.ActionModelAbstract.__init__(self, crocoddyl.StateVector(2 * nq), nq, 1, ng, 0)
        if ng:
            self.g_lb, self.g_ub = np.zeros(ng), np.zeros(ng)
        self.n_in = len(pairs) + (4 * nq if ctx.with_limits else 0)
        self.lam_eq, self.lam_in = np.zeros(self.m_eq), np.zeros(self.n_in if mode == "al" else 0)
        self.rows, self.rsum = pair_table(packed, pairs)
        self.kind = node_kind(task, k)
        self.tg, self.axis = node_targets(task, k)
        w, dt = ctx.weights, task.dt
        self.par = np.array([dt, w.velocity, w.panel, w.margin_m, 1.0 if self.terminal else dt,
                             0.0 if self.terminal else 1.0, 1.0 if ctx.with_limits else 0.0,
                             1.0 if mode == "al" else 0.0, 1.0])
        self.lim = np.vstack([np.broadcast_to(np.asarray(w.control, float), (nq,)), ctx.q_lower, ctx.q_upper, ctx.v_max])
        I, Z = np.eye(nq), np.zeros((nq, nq))
        self.Fx = np.block([[I, dt * I], [Z, I]])
        self.Fu = np.vstack([0.5 * dt * dt * I, dt * I])
        self._u0 = np.zeros(nq)
        self._vdata = None
        pk = packed
        seg_f, seg_j, tri_f, tri_j, Aw, Bw, Vw, rows, lever = _compact(pk, self.rows)
        # the pairs' lower bounds at the last calcDiff's configuration ref_q (nan: none yet), for calc
        self.ref_lb, self.ref_q = np.full(len(rows), -np.inf), np.full(nq, np.nan)
        self._static = (pk.chain_f, pk.chain_i, pk.moves, pk.frame_f, pk.frame_j, seg_f, seg_j, tri_f, tri_j, Aw, Bw, Vw,
                        lever, self.ref_lb, self.ref_q, rows, self.rsum, *groups_of(pk, self.rows), self.kind, self.tg,
                        self.axis, self.par, self.lim)
        exact = self.par.copy()
        exact[8] = 0.0  # values(): every pair's exact distance
        self._static_exact = self._static[:-2] + (exact, self.lim)

    def createData(self):
        d = crocoddyl.ActionDataAbstract(self)
        nq = self.ctx.model.nq
        d.Lxu[:] = 0.0
        if not self.terminal:
            d.Fx[:] = self.Fx
            d.Fu[:] = self.Fu
            d.Luu[:] = self.ctx.task.dt * np.diag(self.lim[0])
        else:
            d.Luu[:] = 0.0
        # work arrays of this node, then views into the data (eigenpy returns the data's own memory)
        d.c, d.C = np.empty(self.m_eq), np.empty((self.m_eq, 2 * nq))
        d.gv = np.empty(len(self.pairs) + (4 * nq if self.ctx.with_limits else 0))
        d.out = (d.c, d.C, d.gv, d.Lx, d.Lxx, d.Lu, d.xnext)
        return d

    def _eval(self, d, x, u, diff, exact=False):
        return node_eval(*(self._static_exact if exact else self._static), self.lam_eq,
                         self.lam_in if self.mode == "al" else d.gv, x, self._u0 if u is None else u, self.ctx.mu, diff,
                         *d.out)

    def values(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Equality values c (m,) and inequality values g (p,) at the state x (2 nq,)."""
        if self._vdata is None:
            self._vdata = self.createData()
        d = self._vdata
        self._eval(d, np.ascontiguousarray(x, dtype=float), None, False, exact=True)
        return d.c.copy(), d.gv.copy()

    def calc(self, data, x, u=None):
        self.ctx.counters["calc"] += 1
        data.cost = self._eval(data, x, u, False)
        if self.mode == "constrained":
            data.g[:] = data.c

    def calcDiff(self, data, x, u=None):
        self.ctx.counters["calcDiff"] += 1
        self._eval(data, x, u, True)
        if self.mode == "constrained":
            data.Gx[:] = data.C
            data.Gu[:] = 0.0


def _toy() -> tuple:
    """A two-joint chain with one capsule pair and a triangle, the argument types of a real run: (model,
    the packed chain, its primitives, the pair list, the node context, x, u)."""
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "a")
    j2 = model.addJoint(j1, pin.JointModelRX(), pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.5])), "b")
    frames = tuple(model.addFrame(pin.Frame(n, j2, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME)) for n in "lrp")
    z = np.zeros
    obj = np.array(["x"], dtype=object)
    prims = Primitives(np.array([j2, 0]), np.array([[0, 0, 0], [1.0, 0, 0]]), np.array([[0, 0, 0.3], [1.0, 1, 0]]),
                       np.array([0.05, 0.05]), np.repeat(obj, 2), np.array([0]),
                       np.array([[[2.0, 0, 0], [2, 1, 0], [2, 0, 1]]]), np.array([0.01]), obj)
    packed = pack(model, frames, prims)
    I = pin.SE3.Identity()
    task = AssemblyTask(3, 0.1, 1, frames[0], frames[1], frames[2], I, I, I, z(3), np.eye(3)[:2], (I,) * 4)
    ctx = Context(model, task, None, Weights(np.ones(2), 1.0, 1.0, 0.0), np.full(2, -3.0), np.full(2, 3.0),
                  np.ones(2), packed=packed)
    pairs = Pairs(np.array([[0, 1]]), np.array([[0, 0]]))
    return model, packed, prims, pairs, ctx, np.full(4, 0.1), np.full(2, 0.1)


def warm_up_nodes() -> None:
    """Compile (or load from numba's cache) the node kernel and the compiled FDDP (with the distances they
    call), on :func:`_toy`'s chain with Crocoddyl's own data arrays."""
    model, packed, prims, pairs, ctx, x, u = _toy()
    models = {}
    for mode in ("al", "constrained"):
        for k in range(4):
            m = CompiledNodeModel(ctx, k, pairs, mode, packed)
            d = m.createData()
            (m.calc(d, x), m.calcDiff(d, x)) if k == 3 else (m.calc(d, x, u), m.calcDiff(d, x, u))
            models.setdefault(mode, []).append(m)
    P = pack_nodes(models["al"])  # the compiled FDDP (capmap.dualarm.ocp.solver), the argument types of a real run
    xs, us = np.tile(x, (4, 1)), np.tile(u, (3, 1))
    Luu = np.ascontiguousarray(np.broadcast_to(np.eye(2), (3, 2, 2)))
    with node_function(P) as ev:
        fddp(P, ev, 0.1, 0.005, Luu, x.copy(), xs, us, 2, False, 100.0, 1e-9, 1e3, ALPHAS)
        evaluate_nodes(P, ev, xs)


def warm_up_geometry() -> None:
    """Compile (or load) the rest of the family's kernels: the batch distances, the pair filters, the
    unknown-space checks, the chain's placements and the collision model's distances and gradients
    (:func:`_toy`'s chain)."""
    p = np.random.default_rng(0).normal(size=(4, 3))
    segment_segment(p, p + 1, p + 2, p + 3)
    point_triangle(p, p + 1, p + 2, p + 3)
    segment_triangle(p, p + 1, p + 2, p + 3, p + 4)
    model, packed, prims, pairs, ctx, x, u = _toy()
    batch_distances(packed, np.zeros((2, 2)), pairs, cutoff=0.1, within=0.01)
    PairFilter(packed, pairs, 2, 0.1).update(np.zeros((2, 2)))
    _cube_distances(np.zeros((1, 3)), np.zeros(1, np.int64), np.ones(1, np.int64), np.zeros((1, 3), np.int64),
                    np.ones((2, 2, 2), dtype=bool), np.zeros(3), 0.02)  # the unknown-space check
    _bound_gaps(np.zeros((2, 3)), np.ones(1), np.zeros(1), np.zeros(3), 0.02, np.ones((2, 2, 2)), 0.3)
    near_boxes(np.zeros((1, 2, 3)), np.zeros((1, 3)), np.zeros(1), 0.1)
    joint_placements(packed.chain_f, packed.chain_i, np.zeros((2, 2)), np.empty((2, 3, 3, 3)), np.empty((2, 3, 3)))
    data = model.createData()  # the Pinocchio-side evaluation (key poses, the independent check)
    pin.computeJointJacobians(model, data, x[:2])
    CollisionModel(model, prims).evaluate(data, pairs, gradient=True)
