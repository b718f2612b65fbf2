"""The drives' friction model: the static band against a brute-force search over the friction torques
it allows, and the direction of motion on a path followed forward."""

from __future__ import annotations

import numpy as np

from capmap.core.drives import friction_torque, motor_torque, path_motion


def test_static_friction_gives_the_smallest_motor_torque_in_the_band():
    """At rest (motion 0) the friction torque can be anything in [-coulomb, coulomb]: the motor's torque is
    the smallest in magnitude of tau_rigid + f over that band (brute force on 20001 values of f)."""
    rng = np.random.default_rng(0)
    tau, coulomb = rng.normal(scale=5.0, size=200), rng.uniform(0.0, 6.0, 200)
    got = motor_torque(tau, np.zeros(200), np.zeros(200), coulomb, rng.uniform(0, 2, 200))
    f = np.linspace(-1, 1, 20001)[None, :] * coulomb[:, None]
    need = tau[:, None] + f
    best = need[np.arange(200), np.argmin(np.abs(need), axis=1)]
    assert np.allclose(got, best, atol=1e-3 * coulomb.max())  # the grid's step
    assert np.all(np.abs(got) <= np.abs(tau) + 1e-15)  # friction never makes holding harder


def test_moving_friction_opposes_the_motion():
    rng = np.random.default_rng(1)
    tau, qd = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    coulomb, viscous = np.array([1.0, 2.0, 0.5]), np.array([0.3, 0.0, 1.5])
    f = friction_torque(tau, qd, np.sign(qd), coulomb, viscous)
    assert np.allclose(f, viscous * qd + coulomb * np.sign(qd))
    assert np.all(f * qd > 0)  # dissipative: the motor works against it


def test_path_motion_is_the_path_direction_while_moving_or_starting_and_zero_at_rest():
    dq = np.array([[2.0, -1.0, 0.0]])
    assert np.array_equal(path_motion(dq, np.array([0.3]), np.array([-1.0])), [[1, -1, 0]])  # moving (braking)
    assert np.array_equal(path_motion(dq, np.array([0.0]), np.array([2.0])), [[1, -1, 0]])  # starting
    assert np.array_equal(path_motion(dq, np.array([0.0]), np.array([-2.0])), [[0, 0, 0]])  # stopping: static
    assert np.array_equal(path_motion(dq, np.array([0.0]), np.array([0.0])), [[0, 0, 0]])  # held
