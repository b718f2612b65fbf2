import numpy as np
import pytest
from conftest import SSRMS_YAML, TASK_R, X_DES, newton_euler
from scipy.optimize import linprog

from capmap.capacity import (
    Limits,
    Motion,
    capacity_from_affine,
    capacity_over_directions,
    coefficients,
    point_capacity,
    state_capacity,
)
from capmap.directions import paper_grid, sphere
from capmap.dynamics import ArmDynamics
from capmap.errors import CapmapError
from capmap.ik import solve
from capmap.locking import lock
from capmap.robot import load

LIMITS = Limits.uniform(7, 700, 200, 500)
# on the ground the 5 m links' own weight needs ~10^4 N m: scale the limits so states are non-trivial
GROUND_LIMITS = Limits.uniform(7, 60000, 20000, 120000)
MOTION = Motion(0.15, 0.03)


@pytest.fixture(scope="module", params=["space", "ground"])
def setup(request, gravity_robot_yaml):
    robot = load(SSRMS_YAML if request.param == "space" else gravity_robot_yaml)
    arm = lock(robot, 1, np.deg2rad(100))
    return robot, arm, ArmDynamics(arm), (LIMITS if request.param == "space" else GROUND_LIMITS)


def _lp_capacity(y0, s, limit):
    """max m s.t. -L <= y0 + m s <= L, m >= 0 (scipy HiGHS); 0 if infeasible at m = 0."""
    if np.any(np.abs(y0) > limit):
        return 0.0
    res = linprog(c=[-1.0], A_ub=np.concatenate([s, -s])[:, None], b_ub=np.concatenate([limit - y0, limit + y0]),
                  bounds=[(0, None)], method="highs")
    return np.inf if res.status == 3 else res.x[0]


def test_capacity_matches_linprog_on_newton_euler_states(setup):
    # y0 and s from the independent recursion, the maximum from an LP
    robot, arm, dyn, limits = setup
    limit = limits.vector(arm)
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
        expect = _lp_capacity(y0, s, limit)
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
    cap, binding = capacity_over_directions(coef, dirs, MOTION, robot.gravity, limits.vector(arm))
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
    sol = solve(scenario_arm, X_DES[None], TASK_R)
    dirs = paper_grid(30)
    pc = point_capacity(dyn, sol.q, sol.n_solutions, dirs, MOTION, LIMITS)
    brute = min(state_capacity(dyn, sol.q[0, k], 0.15 * u, 0.03 * u, LIMITS)[0]
                for k in range(sol.n_solutions[0]) for u in dirs.u)
    assert pc.capacity_kg[0] == pytest.approx(brute, rel=1e-9)
    k, d = pc.branch[0], pc.direction[0]
    c, name = state_capacity(dyn, sol.q[0, k], 0.15 * dirs.u[d], 0.03 * dirs.u[d], LIMITS)
    assert c == pytest.approx(pc.capacity_kg[0], rel=1e-9) and name == pc.names[pc.binding[0]]
    assert pc.n_states[0] == 8 * len(dirs)


def test_unreachable_point_is_nan(scenario_arm):
    dyn = ArmDynamics(scenario_arm)
    sol = solve(scenario_arm, np.array([[40.0, 0, 0]]), TASK_R)
    pc = point_capacity(dyn, sol.q, sol.n_solutions, sphere(10), MOTION, LIMITS)
    assert np.isnan(pc.capacity_kg[0]) and pc.binding[0] == -1


def test_capacity_is_monotone_in_the_limits(scenario_arm):
    dyn = ArmDynamics(scenario_arm)
    q = solve(scenario_arm, X_DES[None], TASK_R).q[0, :1]
    coef = coefficients(dyn, q)
    dirs = sphere(50)
    base = LIMITS.vector(scenario_arm)
    c1, _ = capacity_over_directions(coef, dirs, MOTION, np.zeros(3), base)
    c2, _ = capacity_over_directions(coef, dirs, MOTION, np.zeros(3), base * 1.5)
    assert np.all(c2 >= c1) and np.any(c2 > c1)


def test_violation_without_payload_gives_zero():
    y0 = np.array([[800.0, 0.0], [100.0, 0.0]])
    s = np.array([[-10.0, 1.0], [1.0, 1.0]])
    cap, b = capacity_from_affine(y0, s, np.array([700.0, 50.0]))
    assert cap[0] == 0 and b[0] == 0  # |800| > 700 even though the payload would pull it back
    assert cap[1] == pytest.approx(50.0) and b[1] == 1  # second output binds: 0 + 50 * 1 = 50


def test_zero_motion_in_space_is_unbounded(scenario_arm):
    dyn = ArmDynamics(scenario_arm)
    c, _ = state_capacity(dyn, np.full(6, 0.3), np.zeros(3), np.zeros(3), LIMITS)
    assert c == np.inf


def test_limits_validation(scenario_arm):
    with pytest.raises(CapmapError, match="tau_j3_nm"):
        Limits(np.array([700, 700, 0, 700, 700, 700, 700.0]), np.full(3, 200.0), np.full(3, 500.0)).vector(scenario_arm)
    with pytest.raises(CapmapError, match="has 6 entries"):
        Limits(np.full(6, 700.0), np.full(3, 200.0), np.full(3, 500.0)).vector(scenario_arm)
