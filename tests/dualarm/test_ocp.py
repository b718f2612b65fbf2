"""Node models: the task constraints' Jacobians and the augmented cost's gradient against finite
differences, at every kind of node; the dynamics exact for constant acceleration."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.dualarm.ocp.assembly import warm_start
from capmap.dualarm.ocp.crocoddyl_nodes import Context, NodeModel
from capmap.dualarm.ocp.settings import Weights
from capmap.dualarm.ocp.solver import initial_guess, node_pairs

W = Weights(control=np.full(14, 1.0), velocity=1.0, panel=0.01, margin_m=0.005)


@pytest.fixture(scope="module")
def small(robot, make_assembly):
    asm = make_assembly(40, 0.25, 28)
    qs = warm_start(asm)
    xs, us = initial_guess(qs, asm.task.dt)
    ctx = Context(asm.model, asm.task, asm.collision, W, robot.q_lower, robot.q_upper, robot.v_max, mu=1e3)
    keep = node_pairs(asm, qs, 0.15)
    return asm, ctx, xs, us, keep


@pytest.mark.parametrize("k", [0, 10, 28, 33, 40])  # transfer, pre-insertion, insertion, terminal
def test_constraint_jacobians_and_cost_gradient_equal_finite_differences(small, k):
    asm, ctx, xs, us, keep = small
    m = NodeModel(ctx, k, asm.pairs.subset(keep[k]))
    rng = np.random.default_rng(k)
    m.lam_eq = rng.normal(size=m.m_eq)
    m.lam_in = np.abs(rng.normal(size=m.n_in))  # some inequality terms active
    d = m.createData()
    x = xs[k] + 1e-3 * rng.normal(size=28)
    u = None if k == 40 else us[k]
    h = 1e-6
    fd = np.zeros(28)
    for i in range(28):
        e = np.zeros(28)
        e[i] = h
        costs = []
        for s in (1, -1):
            m.calc(d, x + s * e, u) if u is not None else m.calc(d, x + s * e)
            costs.append(d.cost)
        fd[i] = (costs[0] - costs[1]) / (2 * h)
    (m.calcDiff(d, x, u) if u is not None else m.calcDiff(d, x))
    assert np.allclose(d.Lx, fd, rtol=1e-5, atol=1e-6 * max(1.0, np.abs(fd).max()))
    # the equality Jacobians
    pd = d.pin
    m._kinematics(pd, x[:14], True)
    c, C = m.equalities(pd, x[:14], x[14:], True)
    for i in range(28):
        e = np.zeros(28)
        e[i] = h
        vals = []
        for s in (1, -1):
            y = x + s * e
            m._kinematics(pd, y[:14], False)
            vals.append(m.equalities(pd, y[:14], y[14:], False)[0])
        assert np.allclose(C[:, i], (vals[0] - vals[1]) / (2 * h), atol=1e-7)


def test_dynamics_are_exact_for_constant_acceleration(small):
    asm, ctx, xs, us, keep = small
    m = NodeModel(ctx, 5, asm.pairs.subset(keep[5]))
    d = m.createData()
    x, u = xs[5], us[5]
    m.calc(d, x, u)
    dt = asm.task.dt
    # integrate q'' = u exactly over dt in 1000 small Euler steps
    q, v = x[:14].copy(), x[14:].copy()
    for _ in range(1000):
        q += v * dt / 1000 + 0.5 * u * (dt / 1000) ** 2
        v += u * dt / 1000
    assert np.allclose(d.xnext, np.concatenate([q, v]), atol=1e-12)
