"""The optimal control problem, one Crocoddyl action model per node, on Pinocchio's own calls (the
reference; :mod:`.nodes` evaluates the same model compiled, and the solver uses that one).

State x = [q; v] (2 nq), control u = joint accelerations (nq), exact for a constant
acceleration over a step: q+ = q + dt v + dt^2 u / 2, v+ = v + dt u (so the motion between
nodes is the piecewise-quadratic q(t) that is re-checked on a finer grid afterwards).

Cost per running node (scaled by dt): u^T W_u u / 2 (input energy) + w_v |v|^2 / 2 (the
joint path's length, squared) + w_ee |log6(M_ref^-1 M_P)|^2 / 2 (the panel's distance from
its reference path); at the last node the panel term only.

Constraints (:mod:`.task` equalities; inequalities: safety distances >= margin on the
node's collision pairs, joint position and velocity limits) enter either as augmented-
Lagrangian terms (``mode='al'``: mu |c + lambda/mu|^2 / 2 for equalities, mu max(0,
lambda/mu - g)^2 / 2 for g >= 0, Gauss-Newton Hessians; scaled by dt on running nodes like
the other running costs, so the effective penalty there is mu dt) or, for the equality-only check with
mim-solvers CSQP (``mode='constrained'``), as the model's constraint rows g = c with bounds 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import crocoddyl
import numpy as np
import pinocchio as pin

from capmap.dualarm.geometry.collision import CollisionModel, Pairs
from capmap.dualarm.ocp.settings import Weights
from capmap.dualarm.ocp.task import AssemblyTask, node_constraints

__all__ = ["Context", "NodeModel", "NodeData", "equality_size"]

LOCAL = pin.ReferenceFrame.LOCAL


@dataclass
class Context:
    """Shared by every node: the model, task, collision model, weights, joint limits, the
    penalty mu (the augmented-Lagrangian loop changes it) and, when the model packs, the packed
    chain of the compiled node models."""

    model: pin.Model
    task: AssemblyTask
    collision: CollisionModel
    weights: Weights
    q_lower: np.ndarray
    q_upper: np.ndarray
    v_max: np.ndarray
    mu: float = 100.0
    with_limits: bool = True
    packed: object = None  # the chain packed for the compiled node models (chain.Packed), or None
    counters: dict = field(default_factory=lambda: {"calc": 0, "calcDiff": 0})


def equality_size(task: AssemblyTask, k: int, nv: int) -> int:
    """Rows of node k's equality constraints."""
    if k < task.n_transfer:
        return 6 + 2
    if k == task.n_transfer:
        return 6 + 6
    if k < task.N:
        return 6 + 5
    return 6 + 6 + nv


class NodeData(crocoddyl.ActionDataAbstract):
    """Crocoddyl's node data plus the node's own Pinocchio data."""

    def __init__(self, am: "NodeModel"):
        crocoddyl.ActionDataAbstract.__init__(self, am)
        self.pin = am.ctx.model.createData()


class NodeModel(crocoddyl.ActionModelAbstract):
    """Node k of the problem (terminal when k = N); ``pairs``: its collision pairs; ``mode``: 'al' or
    'constrained' (see the module docstring). Multipliers lam_eq, lam_in live on the node."""

    def __init__(self, ctx: Context, k: int, pairs: Pairs, mode: str = "al"):
        nq = ctx.model.nq
        self.ctx, self.k, self.pairs, self.mode = ctx, k, pairs, mode
        self.terminal = k == ctx.task.N
        self.m_eq = equality_size(ctx.task, k, nq)
        ng = self.m_eq if mode == "constrained" else 0
        crocoddyl.ActionModelAbstract.__init__(self, crocoddyl.StateVector(2 * nq), nq, 1, ng, 0)
        if ng:
            self.g_lb, self.g_ub = np.zeros(ng), np.zeros(ng)
        self.n_in = (len(pairs) + (4 * nq if ctx.with_limits else 0)) if mode == "al" else 0
        self.lam_eq, self.lam_in = np.zeros(self.m_eq), np.zeros(self.n_in)
        dt = ctx.task.dt
        I, Z = np.eye(nq), np.zeros((nq, nq))
        self.Fx = np.block([[I, dt * I], [Z, I]])
        self.Fu = np.vstack([0.5 * dt * dt * I, dt * I])
        self._G_limits = np.block([[I, Z], [-I, Z], [Z, I], [Z, -I]])  # d(limit rows)/dx, constant
        self.scale = 1.0 if self.terminal else dt  # the penalty terms weigh like the running costs

    def createData(self):
        return NodeData(self)

    def values(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Equality values c (m,) and inequality values g (p,) at the state x (2 nq,)."""
        nq = self.ctx.model.nq
        pd = self.ctx.model.createData()
        q, v = x[:nq], x[nq:]
        self._kinematics(pd, q, jac=False)
        return self.equalities(pd, q, v, False)[0], self.inequalities(pd, q, v, False)[0]

    # ------------------------------------------------------------------ pieces
    def _kinematics(self, pd, q, jac):
        m = self.ctx.model
        if jac:
            pin.computeJointJacobians(m, pd, q)
        else:
            pin.forwardKinematics(m, pd, q)
        pin.updateFramePlacements(m, pd)

    def equalities(self, pd, q, v, jac):
        """Stacked equality values (m,) and Jacobians by x (m, 2 nq) (None unless jac)."""
        parts = node_constraints(self.ctx.task, self.k, self.ctx.model, pd, v, jac)
        c = np.concatenate([p.value for p in parts])
        if not jac:
            return c, None
        nq = len(q)
        rows = []
        for p in parts:
            blk = np.zeros((len(p.value), 2 * nq))
            if p.on_velocity:
                blk[:, nq:] = np.eye(nq)
            else:
                blk[:, :nq] = p.jac
            rows.append(blk)
        return c, np.vstack(rows)

    def inequalities(self, pd, q, v, jac):
        """g >= 0: safety distances minus the margin, then q - lower, upper - q, v + v_max, v_max - v;
        values (p,) and Jacobians by x (p, 2 nq) (None unless jac)."""
        ctx = self.ctx
        ev = ctx.collision.evaluate(pd, self.pairs, gradient=jac)
        parts = [ev.distance - ctx.weights.margin_m]
        if ctx.with_limits:
            parts += [q - ctx.q_lower, ctx.q_upper - q, v + ctx.v_max, ctx.v_max - v]
        g = np.concatenate(parts)
        if not jac:
            return g, None
        nq = len(q)
        G = np.zeros((len(g), 2 * nq))
        n = len(ev.distance)
        G[:n, :nq] = ev.gradient
        if ctx.with_limits:
            G[n:] = self._G_limits
        return g, G

    def _panel_error(self, pd, jac):
        err = self.ctx.task.reference[self.k].actInv(pd.oMf[self.ctx.task.panel])
        r = pin.log6(err).vector
        if not jac:
            return r, None
        return r, pin.Jlog6(err) @ pin.getFrameJacobian(self.ctx.model, pd, self.ctx.task.panel, LOCAL)

    # ------------------------------------------------------------------ crocoddyl
    def calc(self, data, x, u=None):
        ctx, nq = self.ctx, self.ctx.model.nq
        ctx.counters["calc"] += 1
        q, v = x[:nq], x[nq:]
        pd = data.pin
        self._kinematics(pd, q, jac=False)
        w = ctx.weights
        r_ee, _ = self._panel_error(pd, False)
        cost = 0.5 * w.panel * (r_ee @ r_ee)
        if self.terminal or u is None:
            data.xnext[:] = x
        else:
            dt = ctx.task.dt
            data.xnext[:] = self.Fx @ x + self.Fu @ u
            cost = dt * (cost + 0.5 * (u * w.control) @ u + 0.5 * w.velocity * (v @ v))
        c, _ = self.equalities(pd, q, v, False)
        if self.mode == "constrained":
            data.g[:] = c
        else:
            mu = ctx.mu
            e = c + self.lam_eq / mu
            g, _ = self.inequalities(pd, q, v, False)
            s = np.maximum(self.lam_in / mu - g, 0.0)
            cost += self.scale * 0.5 * mu * (e @ e + s @ s)
        data.cost = cost

    def calcDiff(self, data, x, u=None):
        ctx, nq = self.ctx, self.ctx.model.nq
        ctx.counters["calcDiff"] += 1
        q, v = x[:nq], x[nq:]
        pd = data.pin
        self._kinematics(pd, q, jac=True)
        w = ctx.weights
        r_ee, J_ee = self._panel_error(pd, True)
        Lx = np.zeros(2 * nq)
        Lxx = np.zeros((2 * nq, 2 * nq))
        Lx[:nq] = w.panel * (J_ee.T @ r_ee)
        Lxx[:nq, :nq] = w.panel * (J_ee.T @ J_ee)
        if self.terminal or u is None:
            data.Lu[:] = 0.0
            data.Luu[:] = 0.0
        else:
            dt = ctx.task.dt
            Lx *= dt
            Lxx *= dt
            Lx[nq:] += dt * w.velocity * v
            Lxx[nq:, nq:] += dt * w.velocity * np.eye(nq)
            data.Lu[:] = dt * w.control * u
            data.Luu[:] = dt * np.diag(w.control)
            data.Fx[:] = self.Fx
            data.Fu[:] = self.Fu
        data.Lxu[:] = 0.0
        c, C = self.equalities(pd, q, v, True)
        if self.mode == "constrained":
            data.Gx[:] = C
            data.Gu[:] = 0.0
        else:
            mu = self.scale * ctx.mu
            e = c + self.lam_eq / ctx.mu
            Lx += mu * (C.T @ e)
            Lxx += mu * (C.T @ C)
            g, G = self.inequalities(pd, q, v, True)
            s = self.lam_in / ctx.mu - g
            active = s > 0
            if active.any():
                Ga = G[active]
                Lx -= mu * (Ga.T @ s[active])
                Lxx += mu * (Ga.T @ Ga)
        data.Lx[:] = Lx
        data.Lxx[:] = Lxx
