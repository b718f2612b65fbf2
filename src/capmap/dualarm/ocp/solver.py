"""Augmented-Lagrangian constrained DDP: an outer loop of multiplier and penalty updates around
Crocoddyl's FDDP.

Outer iteration: solve the augmented problem (FDDP from the previous solution, accurate relative to
the violation it starts from, tight once that is near the tolerance: :func:`inner_stop`) -> measure
the violation (largest equality residual; largest shortfall of an inequality) -> lambda_eq <-
lambda_eq + mu c, lambda_in <- max(0, lambda_in - mu g) -> mu <- 10 mu when the violation has not
dropped ``decrease`` times. Collision pairs are filtered per node by their distance on the warm
start; after each outer iteration the candidate pairs not yet in a node's set are re-checked on the
solution and any within ``filter_m`` joins it (a :class:`capmap.dualarm.geometry.proximity.PairFilter`: a
group of pairs whose last bound, less how far the node has moved since, clears ``filter_m`` is not
looked at).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import crocoddyl
import mim_solvers  # after crocoddyl: it needs crocoddyl's libraries loaded
import numpy as np
import pinocchio as pin

from capmap.dualarm.geometry.chain import pack
from capmap.dualarm.geometry.collision import Pairs
from capmap.dualarm.geometry.proximity import PairFilter
from capmap.dualarm.ocp.assembly import Assembly
from capmap.dualarm.ocp.compiled_nodes import CompiledNodeModel
from capmap.dualarm.ocp.crocoddyl_nodes import Context, NodeModel
from capmap.dualarm.ocp.fddp import ALPHAS, evaluate_nodes, fddp
from capmap.dualarm.ocp.packed_nodes import C_VALUES, EQ_AT, G_VALUES, IN_AT, LAM_EQ, LAM_IN, node_function, pack_nodes
from capmap.dualarm.ocp.settings import ALSettings, SolveOptions, StopRule, Weights

__all__ = ["OuterStats", "Solution", "CSQPResult", "solve", "solve_csqp", "equality_cost", "initial_guess", "node_pairs",
           "all_distances", "context", "node_model", "inner_stop"]

NO_PAIRS = Pairs(np.zeros((0, 2), int), np.zeros((0, 2), int))


def context(asm: Assembly, weights: Weights, limits: tuple[np.ndarray, np.ndarray, np.ndarray], compiled: bool = True,
            log=None, **kw) -> Context:
    """The nodes' shared context; with ``compiled`` the chain packed for :class:`CompiledNodeModel`
    (when the model packs: else Pinocchio's node models, said through ``log``)."""
    packed = None
    if compiled:
        t = asm.task
        packed = pack(asm.model, (t.left, t.right, t.panel), asm.collision.prims)
        if isinstance(packed, str):
            if log:
                log(f"node models on Pinocchio's calls, not compiled: {packed}")
            packed = None
    return Context(asm.model, asm.task, asm.collision, weights, *limits, packed=packed, **kw)


def node_model(ctx: Context, k: int, pairs: Pairs, mode: str = "al"):
    """Node k's action model: compiled when the context has the packed chain."""
    if ctx.packed is not None:
        return CompiledNodeModel(ctx, k, pairs, mode, ctx.packed)
    return NodeModel(ctx, k, pairs, mode)


@dataclass(frozen=True)
class OuterStats:
    """One outer iteration: its penalty, FDDP iterations, cost, equality and inequality violation,
    collision pairs in use, pairs added by the re-check, wall time."""

    outer: int
    mu: float
    inner_iterations: int
    cost: float
    eq_violation: float
    in_violation: float
    pairs: int
    added_pairs: int
    time_s: float


@dataclass(frozen=True)
class Solution:
    """xs (N + 1, 2 nq), us (N, nq); per outer iteration statistics; converged; a message."""

    xs: np.ndarray
    us: np.ndarray
    stats: tuple[OuterStats, ...]
    converged: bool
    message: str


REG_INCREASE = 1e3  # Crocoddyl FDDP's regularisation factor after a rejected step (its default: 10); see solve()
INEXACT = 0.01  # far from the tolerance, an inner solve stops once accurate to this fraction of the violation
EXACT_WITHIN = 100.0  # ... unless the violation is within this many tolerances: then FDDP's own tight stop


def inner_stop(st: ALSettings, mu: float, violation: float) -> float:
    """FDDP's stop threshold (on its expected improvement |d0 + d1 / 2|) at penalty mu from a point whose violation
    is ``violation`` (m or rad): the penalty cost mu / 2 (INEXACT violation)^2, at least ``st.inner_stop``, which
    applies alone within EXACT_WITHIN tolerances. The inexact augmented Lagrangian (Conn, Gould and Toint;
    Bertsekas 1982, 2.5): the multiplier update is only as good as c, so an inner solve need only be accurate
    relative to the violation; FDDP's last iterations far from the tolerance (expected improvement 1e-7 .. 1e-10,
    violation 1e-2 .. 1e-5) do not change the next outer iteration. Default problem: 91 -> 69 FDDP iterations,
    the same outer iterations, penalties and active pairs, solution within 2.1e-7 rad. INEXACT = 0.03 at every
    outer iteration ended at mu_max short of the tolerance, hence the exact ones near the end."""
    if violation <= EXACT_WITHIN * st.tolerance:
        return st.inner_stop
    return max(st.inner_stop, 0.5 * mu * (INEXACT * violation) ** 2)


def initial_guess(qs: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """States (N + 1, 2 nq) and controls (N, nq) from a joint path: central-difference velocities
    (zero at both ends), accelerations as their forward differences."""
    v = np.zeros_like(qs)
    v[1:-1] = (qs[2:] - qs[:-2]) / (2 * dt)
    return np.hstack([qs, v]), np.diff(v, axis=0) / dt


def all_distances(asm: Assembly, qs: np.ndarray, pairs: Pairs) -> np.ndarray:
    """Safety distances (K, P) of every pair at every configuration (K, nq)."""
    data = asm.model.createData()
    out = np.empty((len(qs), len(pairs)))
    for k, q in enumerate(qs):
        pin.forwardKinematics(asm.model, data, q)
        out[k] = asm.collision.evaluate(data, pairs).distance
    return out


def node_pairs(asm: Assembly, qs: np.ndarray, filter_m: float) -> np.ndarray:
    """(K, P) bool: per node, which candidate pairs are within filter_m (safety distance) on the path qs (K, nq),
    on Pinocchio's placements (the compiled filter: :class:`capmap.dualarm.geometry.proximity.PairFilter`)."""
    return all_distances(asm, qs, asm.pairs) < filter_m


class _ReferenceFilter:
    """:class:`capmap.dualarm.geometry.proximity.PairFilter`'s interface on Pinocchio's placements (every candidate pair
    at every call)."""

    def __init__(self, asm: Assembly, K: int, cutoff: float):
        self.asm, self.cutoff = asm, cutoff
        self.keep = np.zeros((K, len(asm.pairs)), dtype=bool)

    def update(self, qs: np.ndarray) -> np.ndarray:
        new = node_pairs(self.asm, qs, self.cutoff) & ~self.keep
        self.keep |= new
        return new


class _CrocoddylInner:
    """The inner solve by Crocoddyl's SolverFDDP on Python action models (the Pinocchio reference); the
    same interface as :class:`_CompiledInner`: replace a node's model, solve from a guess, the nodes'
    constraint values."""

    def __init__(self, models: list, x0: np.ndarray, st: ALSettings):
        self.models = models
        self.problem = crocoddyl.ShootingProblem(x0.copy(), models[:-1], models[-1])
        self.solver = crocoddyl.SolverFDDP(self.problem)
        self.solver.th_stop = st.inner_stop
        self.solver.reg_incFactor = REG_INCREASE

    def replace(self, k: int, m) -> None:
        self.models[k] = m
        if k < len(self.models) - 1:
            self.problem.updateModel(k, m)
        else:
            self.problem.terminalModel = m

    def solve(self, xs: np.ndarray, us: np.ndarray, maxiter: int, feasible: bool, mu: float, stop: float):
        self.solver.th_stop = stop
        self.solver.solve(list(xs), list(us), maxiter, feasible)
        return np.array(self.solver.xs), np.array(self.solver.us), int(self.solver.iter), float(self.solver.cost)

    def violations(self, xs: np.ndarray) -> tuple[float, float]:
        """The largest equality residual and inequality shortfall at xs; the values are kept for
        :meth:`update`."""
        self.cs, self.gs = zip(*(m.values(x) for m, x in zip(self.models, xs)))
        return (max(float(np.abs(c).max()) for c in self.cs),
                max(float(np.maximum(-g, 0).max(initial=0.0)) for g in self.gs))

    def update(self, mu: float, keep_in: np.ndarray) -> None:
        """lambda_eq <- lambda_eq + mu c, lambda_in <- max(0, lambda_in - mu g) at the values of the last
        :meth:`violations`, but the inequality multipliers of the nodes ``keep_in`` (their pairs are about
        to change)."""
        keep = set(map(int, keep_in))
        for k, (m, c, g) in enumerate(zip(self.models, self.cs, self.gs)):
            m.lam_eq = m.lam_eq + mu * c
            if k not in keep:
                m.lam_in = np.maximum(m.lam_in - mu * g, 0.0)


class _CompiledInner:
    """The inner solve by the compiled FDDP (:func:`capmap.dualarm.ocp.fddp.fddp`, Crocoddyl's algorithm) on the
    compiled node models packed flat: no Python call per node."""

    def __init__(self, models: list, x0: np.ndarray, st: ALSettings):
        self.models, self.x0, self.st = models, x0.copy(), st
        first, nq = models[0], models[0].Fu.shape[1]
        self.h, self.a = first.Fx[0, nq], first.Fu[0, 0]
        I, Z = np.eye(nq), np.zeros((nq, nq))
        Fx, Fu = np.block([[I, self.h * I], [Z, I]]), np.vstack([self.a * I, self.h * I])
        assert all(np.array_equal(m.Fx, Fx) and np.array_equal(m.Fu, Fu) for m in models)  # what fddp() is written for
        Luu = first.ctx.task.dt * np.diag(first.lim[0])
        self.Luu = np.ascontiguousarray(np.broadcast_to(Luu, (len(models) - 1, nq, nq)))
        self.packed = None

    def replace(self, k: int, m) -> None:
        self.models[k], self.packed = m, None

    def _pack(self):
        if self.packed is None:
            P = self.packed = pack_nodes(self.models)
            eo, io = P[EQ_AT], P[IN_AT]
            for k, m in enumerate(self.models):  # the nodes' multipliers become views of the packed ones
                m.lam_eq, m.lam_in = P[LAM_EQ][eo[k]:eo[k + 1]], P[LAM_IN][io[k]:io[k + 1]]
        return self.packed

    def solve(self, xs: np.ndarray, us: np.ndarray, maxiter: int, feasible: bool, mu: float, stop: float):
        xs, us, P = np.array(xs, dtype=float), np.array(us, dtype=float), self._pack()
        with node_function(P) as ev:
            res = fddp(P, ev, self.h, self.a, self.Luu, self.x0, xs, us, maxiter, feasible, mu, stop, REG_INCREASE, ALPHAS)
        return xs, us, int(res[1]), float(res[2])  # (converged, iterations, cost, trials stopped)

    def violations(self, xs: np.ndarray) -> tuple[float, float]:
        """As :meth:`_CrocoddylInner.violations`; a pair with no multiplier whose lower bound clears the margin
        has that bound as its value (its shortfall and its multiplier's update are 0 either way)."""
        with node_function(P := self._pack()) as ev:
            evaluate_nodes(P, ev, np.ascontiguousarray(xs, dtype=float))
        return float(np.abs(P[C_VALUES]).max(initial=0.0)), float(np.maximum(-P[G_VALUES], 0).max(initial=0.0))

    def update(self, mu: float, keep_in: np.ndarray) -> None:
        """As :meth:`_CrocoddylInner.update`, on the packed multipliers (the nodes' are views of them)."""
        P = self._pack()
        P[LAM_EQ][:] += mu * P[C_VALUES]
        new = np.maximum(P[LAM_IN] - mu * P[G_VALUES], 0.0)
        io = P[IN_AT]
        for k in keep_in:
            new[io[k]:io[k + 1]] = P[LAM_IN][io[k]:io[k + 1]]
        P[LAM_IN][:] = new


def solve(asm: Assembly, weights: Weights, limits: tuple[np.ndarray, np.ndarray, np.ndarray], settings: ALSettings,
          xs0: np.ndarray, us0: np.ndarray, options: SolveOptions = SolveOptions()) -> Solution:
    """The augmented-Lagrangian loop (module docstring) from the initial guess xs0 (N + 1, 2 nq), us0 (N, nq) within
    ``limits`` (q lower, q upper rad, v max rad/s, each (nq,)); ``options``: its log, the equality-only problem
    (``inequalities=False``), Pinocchio's node models and Crocoddyl's FDDP (``compiled=False``: the reference)."""
    st, log, inequalities, compiled = settings, options.log, options.inequalities, options.compiled
    ctx = context(asm, weights, limits, compiled, log, mu=float(st.mu0), with_limits=inequalities)
    if not inequalities:
        asm = replace(asm, pairs=NO_PAIRS)
    N, nq = asm.task.N, asm.model.nq
    watch = (PairFilter(ctx.packed, asm.pairs, N + 1, st.filter_m) if ctx.packed is not None
             else _ReferenceFilter(asm, N + 1, st.filter_m))
    watch.update(xs0[:, :nq])
    keep = watch.keep
    models = [node_model(ctx, k, asm.pairs.subset(keep[k])) for k in range(N + 1)]
    # after a multiplier update the full step is often rejected until the regularisation has grown enough: by
    # Crocoddyl's x10 per rejected line search (10 trial rollouts each) that took ~8 rejections per outer iteration
    # on the default problem (46 of 132 iterations); x1000 reaches it in ~3: 118 -> 91 FDDP iterations, solve
    # 8.1 -> 6.3 s, the same solution (errors, margin, active pairs equal to 1e-12)
    inner = (_CompiledInner if ctx.packed is not None else _CrocoddylInner)(models, xs0[0], st)
    xs, us = np.array(xs0, dtype=float), np.array(us0, dtype=float)
    stats, prev, converged, message = [], np.inf, False, ""
    feasible = False
    start = max(inner.violations(xs))  # the initial guess's (the inner stop's scale before the first outer iteration)
    for outer in range(st.max_outer):
        t0 = time.perf_counter()
        xs, us, iters, cost = inner.solve(xs, us, st.max_inner, feasible, ctx.mu,
                                          inner_stop(st, ctx.mu, min(start, prev)))
        feasible = True
        eq, ineq = inner.violations(xs)
        new = watch.update(xs[:, :nq])  # every candidate pair re-checked on the solution: those that came near join
        grown, added = np.flatnonzero(new.any(axis=1)), int(new.sum())
        violation = max(eq, ineq)
        converged = violation < st.tolerance and added == 0
        if not converged:
            inner.update(ctx.mu, grown)
            for k in map(int, grown):  # the grown nodes keep their inequality multipliers, moved to their new places
                old = models[k]
                m = node_model(ctx, k, asm.pairs.subset(keep[k]))
                m.lam_eq = old.lam_eq.copy()
                m.lam_in[:len(m.pairs)] = _carry(old.pairs, m.pairs, old.lam_in[:len(old.pairs)])
                m.lam_in[len(m.pairs):] = old.lam_in[len(old.pairs):]
                inner.replace(k, m)
        stats.append(OuterStats(outer, ctx.mu, iters, cost, eq, ineq, int(keep.sum()), added, time.perf_counter() - t0))
        if log:
            log(f"outer {outer}: mu {ctx.mu:.0e}, {iters} FDDP iterations, cost {cost:.6g}, equality "
                f"violation {eq:.2e}, inequality {ineq:.2e}, {added} pairs added ({time.perf_counter() - t0:.1f} s)")
        if converged:
            break
        if violation > prev / st.decrease:
            if ctx.mu >= st.mu_max:
                message = f"the penalty reached mu = {st.mu_max:g} with the violation at {violation:.2e}"
                break
            ctx.mu = min(ctx.mu * st.mu_factor, st.mu_max)
        prev = min(prev, violation)
    else:
        message = f"{st.max_outer} outer iterations without reaching the tolerance {st.tolerance:g}"
    return Solution(xs, us, tuple(stats), converged, message)


def _pair_keys(p: Pairs) -> np.ndarray:
    """One integer per pair of ``p`` (its kind and two primitive indices), in its order."""
    ss, st = np.asarray(p.ss, np.int64).reshape(-1, 2), np.asarray(p.st, np.int64).reshape(-1, 2)
    return np.concatenate([(ss[:, 0] << 21) + ss[:, 1], (1 << 42) + (st[:, 0] << 21) + st[:, 1]])


def _carry(old: Pairs, new: Pairs, lam: np.ndarray) -> np.ndarray:
    """Multipliers of the old pair set moved to their places in the new (a superset)."""
    keys = _pair_keys(new)
    order = np.argsort(keys, kind="stable")
    out = np.zeros(len(new))
    out[order[np.searchsorted(keys[order], _pair_keys(old))]] = lam
    return out


@dataclass(frozen=True)
class CSQPResult:
    """xs (N + 1, 2 nq), us (N, nq); SQP iterations; converged (KKT residual below the tolerance)."""

    xs: np.ndarray
    us: np.ndarray
    iterations: int
    converged: bool


def solve_csqp(asm: Assembly, weights: Weights, limits: tuple[np.ndarray, np.ndarray, np.ndarray], xs0: np.ndarray,
               us0: np.ndarray, stop: StopRule, compiled: bool = True) -> CSQPResult:
    """The equality-only problem (the same costs; the task constraints as the nodes' constraint rows, bounds 0;
    no collisions or limits) by mim-solvers' CSQP from xs0 (N + 1, 2 nq), us0 (N, nq); ``stop``: SQP iterations
    at most, and the KKT residual that ends them."""
    ctx = context(asm, weights, limits, compiled, with_limits=False)
    models = [node_model(ctx, k, NO_PAIRS, mode="constrained") for k in range(asm.task.N + 1)]
    problem = crocoddyl.ShootingProblem(xs0[0].copy(), models[:-1], models[-1])
    csqp = mim_solvers.SolverCSQP(problem)
    csqp.max_qp_iters, csqp.eps_abs, csqp.eps_rel = 1000, 1e-9, 0.0
    csqp.reset_rho = True  # without it the ADMM penalty carried over stalls the KKT residual near 3e-4
    csqp.termination_tolerance = stop.tolerance
    converged = csqp.solve(list(xs0), list(us0), stop.iterations, False)
    return CSQPResult(np.array(csqp.xs), np.array(csqp.us), int(csqp.iter), bool(converged))


def equality_cost(asm: Assembly, weights: Weights, xs: np.ndarray, us: np.ndarray) -> float:
    """The cost of a trajectory without any constraint term (the objective both solvers share)."""
    unused = np.zeros(asm.model.nq)  # no limits in the objective
    ctx = Context(asm.model, asm.task, asm.collision, weights, unused, unused, unused, with_limits=False)
    total = 0.0
    for k, x in enumerate(xs):
        m = NodeModel(ctx, k, NO_PAIRS, mode="constrained")
        d = m.createData()
        m.calc(d, x, us[k]) if k < len(us) else m.calc(d, x)
        total += float(d.cost)
    return total
