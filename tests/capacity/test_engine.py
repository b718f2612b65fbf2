import numpy as np
import pytest

from capmap.capacity.directions import paper_grid, sphere
from capmap.capacity.engine import (
    LoadLimits,
    Motion,
    capacity_over_directions,
    coefficients,
    state_capacity,
)
from capmap.capacity.problem import CapacityProblem, point_capacity
from capmap.core.dynamics import ArmDynamics
from capmap.core.ik import solve
from capmap.core.limits import AffineLimits
from capmap.core.reduction import lock
from capmap.errors import CapmapError
from capmap.robots import load
from tests.reference.lp import lp_capacity
from tests.reference.newton_euler import newton_euler
from tests.scenario import SSRMS_YAML, TASK_R, X_DES

LIMITS = LoadLimits.uniform(7, 700, 200, 500)
# on the ground the 5 m links' own weight needs ~10^4 N m: scale the limits so states are non-trivial
GROUND_LIMITS = LoadLimits.uniform(7, 60000, 20000, 120000)
MOTION = Motion(0.15, 0.03)


@pytest.fixture(scope="module", params=["space", "ground"])
def setup(request, gravity_robot_yaml):
    robot = load(SSRMS_YAML if request.param == "space" else gravity_robot_yaml)
    arm = lock(robot, 1, np.deg2rad(100))
    return robot, arm, ArmDynamics(arm), (LIMITS if request.param == "space" else GROUND_LIMITS).for_arm(arm)


def test_capacity_matches_linprog_on_newton_euler_states(setup):
    # y0 and s from the independent recursion, the maximum from an LP
    robot, arm, dyn, limits = setup
    limit = limits.limit
    rng = np.random.default_rng(0)
    n_pos = 0
    for _ in range(60):
        qa = rng.uniform(-np.pi, np.pi, 6)
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        q, qd, qdd = dyn.motion(qa, 0.15 * u, 0.03 * u)
        t0, acc, f0, m0 = newton_euler(q, qd, qdd, robot.gravity, 0.0, robot.base_com)
        t1, _, f1, m1 = newton_euler(q, qd, qdd, robot.gravity, 1.0, robot.base_com)
        y0 = np.concatenate([t0[1:], f0, m0])
        s = np.concatenate([t1[1:], f1, m1]) - y0
        expect = lp_capacity(y0, s, limit)
        got, name = state_capacity(dyn, qa, 0.15 * u, 0.03 * u, limits)
        assert got == pytest.approx(expect, rel=1e-7, abs=1e-6)
        n_pos += got > 0
    assert n_pos > 10  # the comparison covered non-trivial states


def test_batch_over_directions_equals_one_state(setup):
    robot, arm, dyn, limits = setup
    rng = np.random.default_rng(1)
    q = rng.uniform(-np.pi, np.pi, (4, 6))
    dirs = sphere(40)
    coef = coefficients(dyn, q)
    cap, binding = capacity_over_directions(coef, dirs, MOTION, robot.gravity, limits)
    assert np.mean(cap > 0) > 0.3
    names = ("tau_j2_nm", "tau_j3_nm", "tau_j4_nm", "tau_j5_nm", "tau_j6_nm", "tau_j7_nm",
             "base_fx_n", "base_fy_n", "base_fz_n", "base_mx_nm", "base_my_nm", "base_mz_nm")
    for b in range(4):
        for d in range(40):
            c1, n1 = state_capacity(dyn, q[b], 0.15 * dirs.u[d], 0.03 * dirs.u[d], limits)
            assert cap[b, d] == pytest.approx(c1, rel=1e-9, abs=1e-9)
            if c1 > 0:
                assert names[binding[b, d]] == n1


def test_point_capacity_is_min_over_branches_and_directions(scenario_arm):
    dyn = ArmDynamics(scenario_arm)
    limits = LIMITS.for_arm(scenario_arm)
    sol = solve(scenario_arm, X_DES[None], TASK_R)
    dirs = paper_grid(30)
    pc = point_capacity(CapacityProblem(dyn.arm, TASK_R, MOTION, limits, dirs), sol.q, sol.n_solutions)
    brute = min(state_capacity(dyn, sol.q[0, k], 0.15 * u, 0.03 * u, limits)[0]
                for k in range(sol.n_solutions[0]) for u in dirs.u)
    assert pc.capacity_kg[0] == pytest.approx(brute, rel=1e-9)
    k, d = pc.branch[0], pc.direction[0]
    c, name = state_capacity(dyn, sol.q[0, k], 0.15 * dirs.u[d], 0.03 * dirs.u[d], limits)
    assert c == pytest.approx(pc.capacity_kg[0], rel=1e-9) and name == pc.names[pc.binding[0]]
    assert pc.n_states[0] == 8 * len(dirs)


def test_unreachable_point_is_nan(scenario_arm):
    sol = solve(scenario_arm, np.array([[40.0, 0, 0]]), TASK_R)
    pc = point_capacity(CapacityProblem(scenario_arm, TASK_R, MOTION, LIMITS.for_arm(scenario_arm), sphere(10)), sol.q,
                        sol.n_solutions)
    assert np.isnan(pc.capacity_kg[0]) and pc.binding[0] == -1


def test_capacity_is_monotone_in_the_limits(scenario_arm):
    dyn = ArmDynamics(scenario_arm)
    q = solve(scenario_arm, X_DES[None], TASK_R).q[0, :1]
    coef = coefficients(dyn, q)
    dirs = sphere(50)
    base = LIMITS.for_arm(scenario_arm)
    wider = AffineLimits(base.limit * 1.5, base.names)
    c1, _ = capacity_over_directions(coef, dirs, MOTION, np.zeros(3), base)
    c2, _ = capacity_over_directions(coef, dirs, MOTION, np.zeros(3), wider)
    assert np.all(c2 >= c1) and np.any(c2 > c1)


def test_zero_motion_in_space_is_unbounded(scenario_arm):
    dyn = ArmDynamics(scenario_arm)
    c, _ = state_capacity(dyn, np.full(6, 0.3), np.zeros(3), np.zeros(3), LIMITS.for_arm(scenario_arm))
    assert c == np.inf


def test_limits_validation(scenario_arm):
    with pytest.raises(CapmapError, match="tau_j3_nm"):
        LoadLimits(np.array([700, 700, 0, 700, 700, 700, 700.0]), np.full(3, 200.0), np.full(3, 500.0)).for_arm(
            scenario_arm)
    with pytest.raises(CapmapError, match="has 6 entries"):
        LoadLimits(np.full(6, 700.0), np.full(3, 200.0), np.full(3, 500.0)).for_arm(scenario_arm)
