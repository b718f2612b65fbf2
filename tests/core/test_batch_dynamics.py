"""The batched Newton-Euler coefficients (numba) against the per-configuration Pinocchio
computation (ArmDynamics.coefficients) and the independent textbook Newton-Euler of
tests/reference, over random and near-singular configurations of the SSRMS (space, and on the
ground with gravity and an offset base centre of mass), the UR5 (URDF) and a locked middle joint."""

import numpy as np
import pytest

from capmap.config.robot_file import load
from capmap.core.batch_dynamics import BatchDynamics
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import free, lock
from tests.reference.newton_euler import newton_euler
from tests.scenario import SSRMS_YAML, UR5_YAML

KEYS = ("c0", "L", "Q", "S")


def _arms(gravity_robot_yaml):
    return {"ssrms_j1": lock(load(SSRMS_YAML), 1, np.deg2rad(100)),
            "ssrms_j4": lock(load(SSRMS_YAML), 4, np.deg2rad(40)),
            "ground_j1": lock(load(gravity_robot_yaml), 1, np.deg2rad(100)),
            "ur5": free(load(UR5_YAML))}


def _near_singular(dyn, rng, n):
    """Badly conditioned configurations: Jacobian condition numbers between 1e2 and 1e4, the worst
    of many random ones. (Beyond that both computations lose ~cond^2 x eps to rounding, Q being
    quadratic in J^-1: at cond 1e5-1e6 the two differ by 1-2e-12 of |Q|, neither being more exact.)"""
    qa = rng.uniform(-np.pi, np.pi, (4000, dyn.arm.n_active))
    cond = np.array([np.linalg.cond(dyn.ee_jacobian(dyn.arm.full_q(q))) for q in qa])
    pick = np.flatnonzero((cond > 1e2) & (cond < 1e4))
    pick = pick[np.argsort(cond[pick])[-n:]]
    return qa[pick], cond[pick]


@pytest.mark.parametrize("name", ["ssrms_j1", "ssrms_j4", "ground_j1", "ur5"])
def test_batch_equals_pinocchio_per_configuration(gravity_robot_yaml, name):
    arm = _arms(gravity_robot_yaml)[name]
    dyn, bd = ArmDynamics(arm), BatchDynamics(arm)
    rng = np.random.default_rng(5)
    near, cond = _near_singular(dyn, rng, 10)
    assert len(near) >= 5 and cond.max() > 1e3  # the batch does include badly conditioned states
    qa = np.concatenate([rng.uniform(-np.pi, np.pi, (60, arm.n_active)), near])
    mine = dict(zip(KEYS + ("singular",), bd.coefficients(qa)))
    worst = {"random": 0.0, "near-singular": 0.0}
    for i, q in enumerate(qa):
        ref = dyn.coefficients(q)
        assert mine["singular"][i] == ref["singular"]
        scale = max(np.abs(ref[k]).max() for k in KEYS)
        kind = "random" if i < 60 else "near-singular"
        worst[kind] = max(worst[kind], max(np.abs(mine[k][i] - ref[k]).max() for k in KEYS) / scale)
    print(name, {k: f"{v:.1e}" for k, v in worst.items()})
    # random states to 1e-12 of the largest coefficient; badly conditioned ones (cond 1e2-1e4) to
    # 1e-11: the polarisation Q = Z(a+b) - Z(a) - Z(b) cancels large terms, amplified by J^-1
    assert worst["random"] <= 1e-12 and worst["near-singular"] <= 1e-11


def test_an_exactly_singular_configuration_is_flagged():
    arm = lock(load(SSRMS_YAML), 1, np.deg2rad(100))
    qa = np.zeros((1, 6))  # stretched: the SSRMS at zero angles is singular
    dyn = ArmDynamics(arm)
    assert dyn.coefficients(qa[0])["singular"]
    *_, singular = BatchDynamics(arm).coefficients(qa)
    assert singular[0]


def test_batch_polynomial_equals_independent_newton_euler(gravity_robot_yaml):
    robot = load(gravity_robot_yaml)
    arm = lock(robot, 1, np.deg2rad(100))
    dyn = ArmDynamics(arm)
    rng = np.random.default_rng(6)
    qa = rng.uniform(-np.pi, np.pi, (8, 6))
    c0, L, Q, S, _ = BatchDynamics(arm).coefficients(qa)
    for i in range(len(qa)):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        v, a, m = 0.15, 0.03, 800.0
        phi = np.array([u[0] ** 2, u[1] ** 2, u[2] ** 2, u[0] * u[1], u[0] * u[2], u[1] * u[2]])
        y = c0[i] + a * L[i] @ u + v**2 * Q[i] @ phi + m * S[i] @ (a * u - robot.gravity)
        q, qd, qdd = dyn.motion(qa[i], v * u, a * u)
        tau, _, bf, bm = newton_euler(q, qd, qdd, robot.gravity, payload_kg=m, base_com=robot.base_com,
                                      path=gravity_robot_yaml)
        expect = np.concatenate([tau[1:], bf, bm])
        assert np.allclose(y, expect, rtol=1e-9, atol=1e-9 * np.abs(expect).max())
