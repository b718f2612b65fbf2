"""The collision model on the robot: distances against coal with the same capsules placed by
Pinocchio, gradients against finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from tests.reference.coal_shapes import capsule, distance


def test_robot_capsule_pairs_equal_coal(robot, make_assembly):
    asm = make_assembly(40, 0.25, 28)
    model, data = asm.model, asm.model.createData()
    caps = {c.name: c for c in robot.capsules}
    rng = np.random.default_rng(0)
    checked = 0
    for _ in range(5):
        q = rng.uniform(robot.q_lower, robot.q_upper)
        pin.forwardKinematics(model, data, q)
        ev = asm.collision.evaluate(data, asm.pairs)
        for i, (a, b) in enumerate(zip(ev.first, ev.second)):
            if a not in caps or b not in caps or i >= len(asm.pairs.ss):
                continue
            shapes = []
            for c in (caps[a], caps[b]):
                M = data.oMi[model.getJointId(c.joint)] if c.joint != "universe" else pin.SE3.Identity()
                shapes.append(capsule(M.act(c.a), M.act(c.b), c.r))
            assert ev.distance[i] == pytest.approx(distance(*shapes[0], *shapes[1]), abs=1e-9) or \
                ev.distance[i] < 0
            checked += 1
    assert checked > 100


def test_gradients_equal_finite_differences(robot, make_assembly):
    """At random configurations, for pairs whose distance is smooth there (central differences
    at two step sizes agree), the analytic gradient matches."""
    asm = make_assembly(40, 0.25, 28)
    model, data = asm.model, asm.model.createData()
    rng = np.random.default_rng(1)
    n_ok = 0
    for _ in range(3):
        q = rng.uniform(robot.q_lower, robot.q_upper)
        pin.computeJointJacobians(model, data, q)
        ev = asm.collision.evaluate(data, asm.pairs, gradient=True)

        def dist(x):
            pin.forwardKinematics(model, data, x)
            return asm.collision.evaluate(data, asm.pairs).distance

        fd = np.zeros_like(ev.gradient)
        fd2 = np.zeros_like(ev.gradient)
        for i in range(model.nq):
            e = np.zeros(model.nq)
            e[i] = 1e-6
            fd[:, i] = (dist(q + e) - dist(q - e)) / 2e-6
            fd2[:, i] = (dist(q + 2 * e) - dist(q - 2 * e)) / 4e-6
        smooth = (np.abs(fd - fd2).max(axis=1) < 1e-6) & (ev.distance > 0)  # separated volumes, no kink
        assert np.allclose(ev.gradient[smooth], fd[smooth], atol=2e-6)
        n_ok += int(smooth.sum())
    assert n_ok > 300
