"""Manipulability and its gradient: against central differences, an analytic planar case, and
the null-space projection's defining properties."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.core.kinematics import Chain
from capmap.reconfig.loop import split_loop
from capmap.reconfig.redundancy import evaluate


def _m(chain, q, rows=None):
    _, J = chain.jacobian(q[None])
    J = J[0] if rows is None else J[0][rows]
    return np.sqrt(np.linalg.det(J @ J.T))


@pytest.mark.parametrize("unlock", ["arm1.P1", "arm2.P2"])
def test_gradient_of_m_equals_central_differences(platform, captured, unlock):
    chain = split_loop(platform, "arm1_arm2", unlock, captured).moving.chain
    rng = np.random.default_rng(3)
    for q in rng.uniform(-np.pi, np.pi, (8, chain.n)):
        ev = evaluate(chain, q)
        assert ev.m == pytest.approx(_m(chain, q), rel=1e-10)  # product of singular values = sqrt(det)
        h = 1e-6
        fd = np.array([(_m(chain, q + h * e) - _m(chain, q - h * e)) / (2 * h) for e in np.eye(chain.n)])
        assert np.allclose(ev.grad, fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())


def test_null_space_projection(platform, captured):
    chain = split_loop(platform, "arm1_arm2", "arm1.P1", captured).moving.chain
    ev = evaluate(chain, np.random.default_rng(4).uniform(-3, 3, chain.n))
    # SVD pseudo-inverse: |J J^+ - I| <= ~n eps cond(J) = 1.7e-13 (cond 127); measured 2.3e-15 to 1.4e-14 over the
    # 5 OpenBLAS kernels (Prescott, Sandybridge, Haswell, Zen, SkylakeX): margin 70. Likewise J N k below:
    # measured 3.3e-15 to 5.6e-15 (margin 180), J N grad m 1.3e-15 to 6.4e-15 of |grad m| (margin 1.5e4)
    assert np.allclose(ev.J @ ev.pinv, np.eye(6), atol=1e-12)
    assert np.allclose(ev.J @ ev.null_grad, 0, atol=1e-10 * np.abs(ev.grad).max())  # leaves the task still
    k = np.random.default_rng(5).normal(size=chain.n)
    assert np.allclose(ev.J @ ev.null(k), 0, atol=1e-12)
    # N grad m is the steepest ascent of m among task-preserving directions
    v = np.array([ev.null(x) for x in np.random.default_rng(6).normal(size=(200, chain.n))])
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    best = ev.grad @ ev.null_grad / np.linalg.norm(ev.null_grad)
    assert (v @ ev.grad).max() <= best + 1e-12


def _planar(lengths):
    """A planar chain of revolute joints about z with links along x."""
    X = [np.eye(4)]
    for length in lengths:
        T = np.eye(4)
        T[0, 3] = length
        X.append(T)
    return Chain(np.array(X))


def test_planar_three_link_with_a_one_dimensional_task_matches_the_analytic_gradient():
    """Task: the tip's x only (J is 1 x 3), m = |J|. Analytically, with phi_k = q_1 + ... + q_k,
    J_i = -sum_{k >= i} l_k sin phi_k, dJ_i/dq_j = -sum_{k >= max(i, j)} l_k cos phi_k,
    grad m = (dJ/dq)^T J / m, and the best task-preserving direction is grad m - J (J . grad m) / |J|^2."""
    lengths = np.array([1.0, 0.8, 0.6])
    chain = _planar(lengths)
    rng = np.random.default_rng(7)
    for q in rng.uniform(-np.pi, np.pi, (20, 3)):
        phi = np.cumsum(q)
        J = np.array([-(lengths[i:] * np.sin(phi[i:])).sum() for i in range(3)])
        dJ = np.array([[-(lengths[max(i, j):] * np.cos(phi[max(i, j):])).sum() for j in range(3)] for i in range(3)])
        m = np.linalg.norm(J)
        grad = dJ.T @ J / m
        direction = grad - J * (J @ grad) / (J @ J)
        ev = evaluate(chain, q, rows=np.array([0]))
        assert ev.m == pytest.approx(m, rel=1e-12)
        assert np.allclose(ev.grad, grad, atol=1e-12)
        assert np.allclose(ev.null_grad, direction, atol=1e-12)


def test_planar_null_space_ascent_reaches_the_brute_force_maximum():
    """Pure self-motion (x kept) along N grad m ends where m is largest over the self-motion set,
    found by brute force over a dense grid of that set."""
    lengths = np.array([1.0, 0.8, 0.6])
    chain = _planar(lengths)
    q = np.array([0.3, 0.9, -0.4])
    x0 = chain.fk(q[None])[0, 0, 3]
    for _ in range(4000):  # small steps of k = N grad m, then back onto x = x0 along J^+
        ev = evaluate(chain, q, rows=np.array([0]))
        q = q + 0.01 * ev.null_grad
        ev = evaluate(chain, q, rows=np.array([0]))
        q = q + ev.pinv[:, 0] * (x0 - ev.pose[0, 3])
    m_end = evaluate(chain, q, rows=np.array([0])).m
    # brute force: q1, q2 on a grid, q3 from x = x0 (both roots)
    g = np.linspace(-np.pi, np.pi, 721)
    q1, q2 = np.meshgrid(g, g, indexing="ij")
    c3 = (x0 - lengths[0] * np.cos(q1) - lengths[1] * np.cos(q1 + q2)) / lengths[2]
    ok = np.abs(c3) <= 1
    best = 0.0
    for sign in (1, -1):
        phi3 = sign * np.arccos(np.clip(c3, -1, 1))
        J = np.stack([-(lengths[0] * np.sin(q1) + lengths[1] * np.sin(q1 + q2) + lengths[2] * np.sin(phi3)),
                      -(lengths[1] * np.sin(q1 + q2) + lengths[2] * np.sin(phi3)), -lengths[2] * np.sin(phi3)])
        best = max(best, np.linalg.norm(J, axis=0)[ok].max())
    assert chain.fk(q[None])[0, 0, 3] == pytest.approx(x0, abs=1e-9)
    assert m_end == pytest.approx(best, rel=1e-3)
    assert np.linalg.norm(evaluate(chain, q, rows=np.array([0])).null_grad) < 1e-4
