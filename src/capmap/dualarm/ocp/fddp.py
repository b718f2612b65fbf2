"""Crocoddyl's FDDP, compiled with the node kernel inside it: one call solves the augmented problem, with
no Python callback per node (Crocoddyl calls a Python action model ~200,000 times per solve).

The algorithm is Crocoddyl 3.2's ``SolverFDDP`` step for step (src/core/solvers/fddp.cpp and ddp.cpp):
the same backward pass (gaps in the value function while infeasible, the regularisation ``preg`` on
Quu and Vxx, Cholesky of Quu), the same expected improvement (dg, dq, dv), the same line search over
alphas 1, 1/2, ..., 1/512 with its acceptance tests (th_acceptstep 0.1, th_acceptnegstep 2, th_grad
1e-12), the same regularisation schedule (reg_min 1e-9, reg_max 1e9, the given increase factor,
decrease 10, thresholds 0.5 and 0.01) and stop (|d0 + d1 / 2| < th_stop once feasible). The problem is the
one :class:`capmap.dualarm.ocp.compiled_nodes.CompiledNodeModel` states (linear dynamics x+ = Fx x + Fu u, Luu = dt
diag(w_control), Lxu = 0), its nodes packed flat by :func:`capmap.dualarm.ocp.packed_nodes.pack_nodes` and
evaluated through :func:`capmap.dualarm.ocp.packed_nodes.node_function`. tests/dualarm/test_fddp.py checks it step
for step against Crocoddyl's own solver on the same nodes, and tests/dualarm/test_nodes.py the whole AL solve
against Crocoddyl on the Pinocchio node models.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["fddp", "evaluate_nodes", "ALPHAS"]

ALPHAS = 0.5 ** np.arange(10)  # Crocoddyl's step lengths
REG_MIN, REG_MAX, REG_DEC, TH_ACCEPT, TH_ACCEPTNEG, TH_GRAD, TH_STEPDEC, TH_STEPINC = 1e-9, 1e9, 10.0, 0.1, 2.0, 1e-12, 0.5, 0.01
HUGE = 1e30  # Crocoddyl's raiseIfNaN: nan, inf or >= 1e30 fails a rollout or a backward pass
STOPPED = -1.0  # a trial stopped by its partial cost (_forward; a cost is >= 0)
VALUE, DIFF = np.False_, np.True_  # the node evaluation's diff, typed bool (a literal: one compile per value)
# _calc, _forward inlined in numba's IR (as plain calls the node half compiles no faster)
_wrapper = numba.njit(cache=True, inline="always")


@numba.njit(cache=True)
def evaluate_nodes(P, ev, xs):
    """Every node's equality values c and inequality values g at the states xs (N + 1, 2 nq), written into
    the packed nodes' c and g (flat, by node offsets eo, io); as in a calc, a pair with no multiplier whose
    lower bound clears the margin has that bound in g. ``ev``: the nodes' evaluation
    (:func:`capmap.dualarm.ocp.packed_nodes.node_function`)."""
    n2 = xs.shape[1]
    Lx, Lxx, Lu, xn = np.empty(n2), np.empty((n2, n2)).T, np.empty(n2 // 2), np.empty(n2)
    u0 = np.zeros(n2 // 2)
    for k in range(xs.shape[0]):
        ev(P, k, xs[k], u0, 1.0, VALUE, Lx, Lxx, Lu, xn)


@_wrapper
def _calc(P, ev, mu, cost, xnext, k, x, u):
    """Node k's cost at (x, u) into cost[k], its next state into xnext[k]."""
    Lx, Lxx, Lu = np.empty(0), np.empty((0, 0)).T, np.empty(0)
    cost[k] = ev(P, k, x, u, mu, VALUE, Lx, Lxx, Lu, xnext[k])
    return cost[k]


@numba.njit(cache=True)
def _huge(a):
    """Whether an entry of ``a`` is nan, inf or of magnitude >= HUGE."""
    for v in a.ravel():
        if not abs(v) < HUGE:
            return True
    return False


@numba.njit(cache=True)
def _chol_solve(A, L, B):
    """B <- A^-1 B by Cholesky (A symmetric); False when A is not positive definite (Eigen's LLT test)."""
    n = A.shape[0]
    for j in range(n):
        s = A[j, j]
        for p in range(j):
            s -= L[j, p] * L[j, p]
        if not s > 0.0:
            return False
        L[j, j] = np.sqrt(s)
        for i in range(j + 1, n):
            s = A[i, j]
            for p in range(j):
                s -= L[i, p] * L[j, p]
            L[i, j] = s / L[j, j]
    m = B.shape[1]
    for i in range(n):  # row by row, each column's sums in the same order as a column-by-column solve
        for p in range(i):
            for col in range(m):
                B[i, col] -= L[i, p] * B[p, col]
        for col in range(m):
            B[i, col] /= L[i, i]
    for i in range(n - 1, -1, -1):
        for p in range(i + 1, n):
            for col in range(m):
                B[i, col] -= L[p, i] * B[p, col]
        for col in range(m):
            B[i, col] /= L[i, i]
    return True


@numba.njit(cache=True)
def _backward(h, a, Luu, Lx, Lxx, Lu, fs, feasible, preg, Vx, Vxx, Qu, Quuk, K, k_):
    """Crocoddyl's backwardPass for the dynamics Fx = [[I, h I], [0, I]], Fu = [[a I], [h I]] (the products
    with Fx and Fu in closed form; Lxu = 0); False where Quu is not positive definite or a value of Vx,
    Vxx is nan, inf or >= HUGE."""
    N, n2 = Lx.shape[0] - 1, Lx.shape[1]
    n = n2 // 2
    for i in range(n2 * n2):  # element by element: a 2-D array assignment compiles numba's shape-error path (~3 s)
        Vxx[N, i // n2, i % n2] = Lxx[N, i // n2, i % n2]
    Vx[N] = Lx[N]
    for i in range(n2):
        Vxx[N, i, i] += preg
    if not feasible:
        Vx[N] += Vxx[N] @ fs[N]
    Qxx, Qxu, Quu, Qx = np.empty((n2, n2)), np.empty((n2, n)), np.empty((n, n)), np.empty(n2)
    L, Kt = np.zeros((n, n)), np.empty((n, n2 + 1))
    for t in range(N - 1, -1, -1):
        V, v = Vxx[t + 1], Vx[t + 1]
        for i in range(n):
            Qx[i] = Lx[t, i] + v[i]
            Qx[n + i] = Lx[t, n + i] + h * v[i] + v[n + i]
            Qu[t, i] = Lu[t, i] + a * v[i] + h * v[n + i]
            for j in range(n):
                A, Bq, Bv, D = V[i, j], V[i, n + j], V[n + i, j], V[n + i, n + j]
                Qxx[i, j] = Lxx[t, i, j] + A
                Qxx[i, n + j] = Lxx[t, i, n + j] + h * A + Bq
                Qxx[n + i, j] = Lxx[t, n + i, j] + h * A + Bv
                Qxx[n + i, n + j] = Lxx[t, n + i, n + j] + h * h * A + h * Bq + h * Bv + D
                top, bot = a * A + h * Bq, a * Bv + h * D  # V Fu
                Qxu[i, j] = top
                Qxu[n + i, j] = h * top + bot
                Quu[i, j] = Luu[t, i, j] + a * top + h * bot
        for i in range(n):
            Quu[i, i] += preg
            Kt[i, n2] = Qu[t, i]  # k solved with K, as the last column
            for j in range(n2):
                Kt[i, j] = Qxu[j, i]
        if not _chol_solve(Quu, L, Kt):
            return False
        for i in range(n):
            k_[t, i] = Kt[i, n2]
            for j in range(n2):
                K[t, i, j] = Kt[i, j]
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += Quu[i, j] * k_[t, j]
            Quuk[t, i] = s
        for i in range(n2):
            s = Qx[i]
            for r in range(n):
                s -= K[t, r, i] * Qu[t, r]
            Vx[t, i] = s
        M = Qxu @ K[t]
        for i in range(n2):
            for j in range(i, n2):
                Vxx[t, i, j] = Vxx[t, j, i] = 0.5 * ((Qxx[i, j] - M[i, j]) + (Qxx[j, i] - M[j, i]))
            Vxx[t, i, i] += preg
        if not feasible:
            Vx[t] += Vxx[t] @ fs[t]
        if _huge(Vx[t]) or _huge(Vxx[t]):
            return False
    return True


@_wrapper
def _forward(P, ev, x0, xs, us, fs, K, k_, alpha, feasible, mu, cost, xnext, xs_try, us_try, total0, limit):
    """Crocoddyl's FDDP forwardPass: the trial's cost, nan when the cost or a state is nan, inf or >= HUGE
    (the products written out: no allocation per node); STOPPED as soon as total0 - (the cost so far) <=
    limit (not nan): the trial's cost can only grow (every node's is >= 0), so its dV = total0 - cost would
    fail Crocoddyl's test dV > limit (rounding is monotone: the same outcome in floating point)."""
    N, n2, nu = xs.shape[0] - 1, xs.shape[1], us.shape[1]
    total = 0.0
    shift = not (feasible or alpha == 1.0)
    for t in range(N + 1):
        for i in range(n2):
            xn = x0[i] if t == 0 else xnext[t - 1, i]
            xs_try[t, i] = xn + fs[t, i] * (alpha - 1.0) if shift else xn
        if t < N:
            for r in range(nu):
                s = 0.0
                for i in range(n2):
                    s += K[t, r, i] * (xs_try[t, i] - xs[t, i])
                us_try[t, r] = us[t, r] - k_[t, r] * alpha - s
            total += _calc(P, ev, mu, cost, xnext, t, xs_try[t], us_try[t])
            if not abs(total) < HUGE or _huge(xnext[t]):
                return np.nan
            if total0 - total <= limit:
                return STOPPED
        else:
            total += _calc(P, ev, mu, cost, xnext, t, xs_try[t], np.zeros(nu))
            if not abs(total) < HUGE:
                return np.nan
    return total


@numba.njit(cache=True)
def fddp(P, ev, h, a, Luu, x0, xs, us, maxiter, feasible, mu, th_stop, reg_inc, alphas):
    """Crocoddyl's SolverFDDP.solve from xs (N + 1, 2 nq), us (N, nq) (both updated in place) on the packed
    nodes P at penalty mu; the dynamics Fx = [[I, h I], [0, I]], Fu = [[a I], [h I]] (h: the nodes'
    dt in s, a = dt^2 / 2 in s^2); Luu (N, nq, nq). Returns (converged, iterations as Crocoddyl's ``iter``,
    cost, trials not rolled out or stopped by their partial cost). ``ev``: the nodes' evaluation
    (:func:`capmap.dualarm.ocp.packed_nodes.node_function`)."""
    N, n2, nu = xs.shape[0] - 1, xs.shape[1], us.shape[1]
    cost, xnext = np.zeros(N + 1), np.zeros((N + 1, n2))
    Lx, LxxT, Lu = np.zeros((N + 1, n2)), np.zeros((N + 1, n2, n2)), np.zeros((N + 1, nu))
    Lxx = LxxT.transpose(0, 2, 1)  # node t's Lxx is LxxT[t].T: F-ordered for node_eval, read through this view
    Vx, Vxx = np.zeros((N + 1, n2)), np.zeros((N + 1, n2, n2))
    Qu, Quuk, K, k_ = np.zeros((N, nu)), np.zeros((N, nu)), np.zeros((N, nu, n2)), np.zeros((N, nu))
    fs = np.zeros((N + 1, n2))
    xs_try, us_try = np.zeros((N + 1, n2)), np.zeros((N, nu))
    xs_try[0] = x0
    u0 = np.zeros(nu)
    preg = REG_MIN
    was_feasible = False
    stopped = 0
    recalc = True
    total = 0.0
    d0 = d1 = 0.0
    for it in range(maxiter):
        while True:
            if recalc:
                if it == 0:
                    for t in range(N + 1):
                        _calc(P, ev, mu, cost, xnext, t, xs[t], us[t] if t < N else u0)
                for t in range(N + 1):
                    ev(P, t, xs[t], us[t] if t < N else u0, mu, DIFF, Lx[t], LxxT[t].T, Lu[t], xnext[t])
                total = 0.0
                for t in range(N + 1):  # in Crocoddyl's order
                    total += cost[t]
                fs[0] = x0 - xs[0]
                for t in range(N):
                    fs[t + 1] = xnext[t] - xs[t + 1]
            if _backward(h, a, Luu, Lx, Lxx, Lu, fs, feasible, preg, Vx, Vxx, Qu, Quuk, K, k_):
                break
            recalc = False
            preg = min(preg * reg_inc, REG_MAX)
            if preg == REG_MAX:
                return False, it, total, stopped
        dg, dq = 0.0, 0.0
        if not feasible:
            dg -= Vx[N] @ fs[N]
            dq += fs[N] @ (Vxx[N] @ fs[N])
        for t in range(N):
            dg += Qu[t] @ k_[t]
            dq -= k_[t] @ Quuk[t]
            if not feasible:
                dg -= Vx[t] @ fs[t]
                dq += fs[t] @ (Vxx[t] @ fs[t])
        recalc = False
        alpha = alphas[0]
        for alpha in alphas:
            # once feasible, a trial's expected improvement is known before its rollout (dv = 0) and every node's
            # cost is >= 0: a trial that cannot be accepted is not rolled out, or stops as soon as its partial cost
            # shows it (_forward); it sets d0, d1 as a completed one would (Crocoddyl's decisions, unless the
            # completed rollout would have overflowed: then Crocoddyl keeps the previous d0, d1)
            limit = np.nan
            if feasible:
                dVexp = alpha * ((dg + 0.0) + 0.5 * alpha * (dq - 0.0))
                if not dVexp >= 0.0:
                    d0, d1 = dg + 0.0, dq - 0.0
                    stopped += 1
                    continue
                if not abs(dg + 0.0) < TH_GRAD:
                    limit = TH_ACCEPT * dVexp
            trial = _forward(P, ev, x0, xs, us, fs, K, k_, alpha, feasible, mu, cost, xnext, xs_try, us_try, total, limit)
            if trial == STOPPED:
                d0, d1 = dg + 0.0, dq - 0.0
                stopped += 1
                continue
            if np.isnan(trial):
                continue
            dV = total - trial
            dv = 0.0
            if not feasible:  # the terminal node first, as Crocoddyl
                dv -= fs[N] @ (Vxx[N] @ (xs[N] - xs_try[N]))
                for t in range(N):
                    dv -= fs[t] @ (Vxx[t] @ (xs[t] - xs_try[t]))
            d0, d1 = dg + dv, dq - 2.0 * dv
            dVexp = alpha * (d0 + 0.5 * alpha * d1)
            if (dVexp >= 0.0 and (abs(d0) < TH_GRAD or dV > TH_ACCEPT * dVexp)) or (
                    dVexp < 0.0 and not feasible and dV > TH_ACCEPTNEG * dVexp):
                was_feasible = feasible
                for t in range(N + 1):  # element by element (_backward)
                    for i in range(n2):
                        xs[t, i] = xs_try[t, i]
                        if t < N and i < nu:
                            us[t, i] = us_try[t, i]
                feasible = was_feasible or alpha == 1.0
                total = trial
                recalc = True
                break
        if alpha > TH_STEPDEC:
            preg = max(preg / REG_DEC, REG_MIN)
        if alpha <= TH_STEPINC:
            preg = min(preg * reg_inc, REG_MAX)
            if preg == REG_MAX:
                return False, it, total, stopped
        if was_feasible and abs(d0 + 0.5 * d1) < th_stop:
            return True, it, total, stopped
    return False, maxiter, total, stopped
