"""The batched Newton-Euler coefficients (numba) against the per-configuration Pinocchio
computation (ArmDynamics.coefficients) and the independent textbook Newton-Euler of
tests/reference, over random and near-singular configurations of the SSRMS (space, and on the
ground with gravity and an offset base centre of mass), the UR5 (URDF) and a locked middle joint."""

from dataclasses import replace

import numpy as np
import pytest

from capmap.core.batch_dynamics import BatchDynamics
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import free, lock
from capmap.core.robot import Drive, build_robot
from capmap.robots import load
from tests.reference.newton_euler import newton_euler
from tests.scenario import SSRMS_YAML, UR5_YAML

KEYS = ("c0", "L", "Q", "S")
K_BOUND = 8.0  # see _tolerance


def _arms(gravity_robot_yaml):
    return {"ssrms_j1": lock(load(SSRMS_YAML), 1, np.deg2rad(100)),
            "ssrms_j4": lock(load(SSRMS_YAML), 4, np.deg2rad(40)),
            "ground_j1": lock(load(gravity_robot_yaml), 1, np.deg2rad(100)),
            "ur5": free(load(UR5_YAML)),
            "ssrms_j4_drives": lock(_with_armature(load(SSRMS_YAML), np.linspace(50.0, 5.0, 7)), 4, np.deg2rad(40))}


def _near_singular(dyn, rng, n):
    """Badly conditioned configurations: Jacobian condition numbers between 1e2 and 1e4, the worst
    of many random ones (the bound of _tolerance holds beyond: checked to cond 2.7e6)."""
    qa = rng.uniform(-np.pi, np.pi, (4000, dyn.arm.n_active))
    cond = np.array([np.linalg.cond(dyn.ee_jacobian(dyn.arm.full_q(q))) for q in qa])
    pick = np.flatnonzero((cond > 1e2) & (cond < 1e4))
    pick = pick[np.argsort(cond[pick])[-n:]]
    return qa[pick], cond[pick]


def _tolerance(dyn, q_active, scale):
    """Bound on |batch - per-configuration| for one configuration: K eps cond(J) max(T, scale).

    Both computations invert J (numba's and numpy's LAPACK, each on the machine's BLAS kernel); a
    backward-stable inverse is exact for some J + dJ with |dJ| <= c n eps |J|, so every quantity
    built from J^-1 (the columns A of J^-1 that give qd, and J^-1 Jdot w in qdd) carries a relative
    error of at most c n eps cond(J), to first order: p = 1, J^-1 entering each term a bounded number
    of times (<= 3) and not raising the power of cond. The error is relative to the size of the terms,
    not of the result: Z(w) = C(q, w) w + M(q) qdd(w) of the polarisation is the difference of
    two terms T that nearly cancel (T up to 130 x the largest coefficient for ssrms_j4, 3-10 x for the
    others), which is why a bound on the coefficients' scale alone fails (1.7e-12 > 1e-12 on some
    Xeons). So |error| <= 2 (two computations) x 3 x c n eps cond(J) max(T, scale) ~ 36 c eps cond max(T, scale).
    K = 8: measured max |error| / (eps cond max(T, scale)) over the test's 70 configurations of each arm
    is 0.77 (0.55-0.77 over the OpenBLAS kernels Prescott, Sandybridge, Haswell, Zen, SkylakeX), and 1.2 over
    300 more random and 40 near-singular ones up to cond 2.7e6 (flat in cond, confirming p = 1):
    margin 6.7, and below the first-order worst case. The tolerance is 5e-14 to 2e-12 of scale at the median
    configuration (tighter than the former flat 1e-12), at most 1.5e-10 at the worst conditioned."""
    q = dyn.arm.full_q(q_active)
    J = dyn.ee_jacobian(q)
    Jinv = np.linalg.inv(J)
    A = [dyn.arm.full_v(Jinv[:, i]) for i in range(3)]
    zero = np.zeros_like(A[0])
    T = scale
    for idx in [(0,), (1,), (2,), (0, 1), (0, 2), (1, 2)]:  # the polarisation's Z(w), w = sum of columns
        w = sum(A[i] for i in idx)
        qdd = dyn.arm.full_v(-Jinv @ dyn.drift(q, w))
        T = max(T, np.abs(dyn.outputs(q, w, zero, gravity=False)).max(), np.abs(dyn.outputs(q, zero, qdd, gravity=False)).max())
    return K_BOUND * np.finfo(float).eps * np.linalg.cond(J) * T


@pytest.mark.parametrize("name", ["ssrms_j1", "ssrms_j4", "ground_j1", "ur5", "ssrms_j4_drives"])
def test_batch_equals_pinocchio_per_configuration(gravity_robot_yaml, name):
    arm = _arms(gravity_robot_yaml)[name]
    dyn, bd = ArmDynamics(arm), BatchDynamics(arm)
    rng = np.random.default_rng(5)
    near, cond = _near_singular(dyn, rng, 10)
    assert len(near) >= 5 and cond.max() > 1e3  # the batch does include badly conditioned states
    qa = np.concatenate([rng.uniform(-np.pi, np.pi, (60, arm.n_active)), near])
    mine = vars(bd.coefficients(qa))  # the Coefficients fields by name
    worst = {"random": 0.0, "near-singular": 0.0}  # |error| / tolerance
    for i, q in enumerate(qa):
        ref = vars(dyn.coefficients(q))
        assert mine["singular"][i] == ref["singular"]
        scale = max(np.abs(ref[k]).max() for k in KEYS)
        kind = "random" if i < 60 else "near-singular"
        worst[kind] = max(worst[kind], max(np.abs(mine[k][i] - ref[k]).max() for k in KEYS) / _tolerance(dyn, q, scale))
    print(name, {k: f"{v:.2f} of K eps cond(J) max(T, scale)" for k, v in worst.items()})
    assert worst["random"] <= 1 and worst["near-singular"] <= 1  # per configuration, see _tolerance


def test_an_exactly_singular_configuration_is_flagged():
    arm = lock(load(SSRMS_YAML), 1, np.deg2rad(100))
    qa = np.zeros((1, 6))  # stretched: the SSRMS at zero angles is singular
    dyn = ArmDynamics(arm)
    assert dyn.coefficients(qa[0]).singular
    assert BatchDynamics(arm).coefficients(qa).singular[0]


def _with_armature(robot, armature):
    """The robot rebuilt with drives of reflected rotor inertia ``armature`` (n,) kg m^2."""
    desc = replace(robot.description, drives=tuple(Drive(i, armature_kgm2=float(a)) for i, a in enumerate(armature)))
    return build_robot(desc)


@pytest.mark.parametrize("armature", [False, True])
def test_batch_polynomial_equals_independent_newton_euler(gravity_robot_yaml, armature):
    """c0 + a L u + v^2 Q phi + m S (a u - g) against the textbook Newton-Euler of tests/reference, plus
    with drives the rotor torques armature_j qdd_j added by hand (that reference has no drives)."""
    robot = load(gravity_robot_yaml)
    arm_ref = lock(robot, 1, np.deg2rad(100))  # the motion (qd, qdd) does not depend on the drives
    Ia = np.linspace(5.0, 0.5, robot.n_joints) if armature else np.zeros(robot.n_joints)  # of the order of the links'
    robot = _with_armature(robot, Ia)
    arm = lock(robot, 1, np.deg2rad(100))
    rng = np.random.default_rng(6)
    qa = rng.uniform(-np.pi, np.pi, (8, 6))
    co = BatchDynamics(arm).coefficients(qa)
    c0, L, Q, S = co.c0, co.L, co.Q, co.S
    for i in range(len(qa)):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        v, a, m = 0.15, 0.03, 800.0
        phi = np.array([u[0] ** 2, u[1] ** 2, u[2] ** 2, u[0] * u[1], u[0] * u[2], u[1] * u[2]])
        y = c0[i] + a * L[i] @ u + v**2 * Q[i] @ phi + m * S[i] @ (a * u - robot.gravity)
        q, qd, qdd = ArmDynamics(arm_ref).motion(qa[i], v * u, a * u)
        tau, _, bf, bm = newton_euler(q, qd, qdd, robot.gravity, payload_kg=m, base_com=robot.base_com,
                                      path=gravity_robot_yaml)
        expect = np.concatenate([(tau + Ia * qdd)[1:], bf, bm])
        assert np.allclose(y, expect, rtol=1e-9, atol=1e-9 * np.abs(expect).max())
