import numpy as np
import pytest
import yaml

from capmap.core.ik import RESIDUAL_TOL, MultiStartNewton, SemiAnalytic, method_for, solve, wrap_to_range
from capmap.core.reduction import free, lock
from capmap.robots import load
from tests.scenario import Q_INI_DEG, SSRMS_YAML, TASK_R, X_DES, X_INI


def _pin_residual(robot, arm, q_act, position, R):
    """Residual by the full robot's Pinocchio FK (independent of the chain used by the solver)."""
    T = robot.fk(np.insert(q_act, arm.locked_joint - 1, arm.locked_angle_rad, axis=-1))
    dp = np.linalg.norm(T[..., :3, 3] - position, axis=-1)
    cos = np.clip((np.trace(np.swapaxes(T[..., :3, :3], -1, -2) @ R, axis1=-2, axis2=-1) - 1) / 2, -1, 1)
    return dp, np.arccos(cos)


def _distinct(q):
    d = np.abs(np.mod(q[:, None] - q[None] + np.pi, 2 * np.pi) - np.pi).max(-1)
    return np.all(d[~np.eye(len(q), dtype=bool)] > 1e-6)


def test_scenario_uses_closed_form(scenario_arm):
    assert method_for(scenario_arm.chain) == "closed_form"


def test_all_eight_at_x_des(ssrms, scenario_arm):
    sol = solve(scenario_arm, X_DES[None], TASK_R)
    assert sol.n_solutions[0] == 8
    q = sol.q[0]
    dp, dr = _pin_residual(ssrms, scenario_arm, q, X_DES, TASK_R)
    assert dp.max() <= RESIDUAL_TOL and dr.max() <= 1e-7  # arccos loses precision near 0: 1e-7 rad ~ 1e-14 in cos
    assert _distinct(q)


def test_q_ini_is_one_branch_at_x_ini(scenario_arm):
    sol = solve(scenario_arm, X_INI[None], TASK_R)
    q = np.rad2deg(sol.q[0, : sol.n_solutions[0]])
    err = np.abs(np.mod(q - Q_INI_DEG[1:] + 180, 360) - 180).max(axis=1)
    assert err.min() < 0.6


def test_random_reachable_poses_recover_generating_configuration(ssrms, scenario_arm):
    rng = np.random.default_rng(7)
    q_true = rng.uniform(-np.pi, np.pi, (3000, 6))
    T = ssrms.fk(scenario_arm.full_q(q_true))  # targets from the full Pinocchio model
    sol = solve(scenario_arm, T[:, :3, 3], T[:, :3, :3])
    assert sol.n_solutions.max() <= 8 and sol.n_solutions.min() >= 1
    d = np.abs(np.mod(sol.q - q_true[:, None] + np.pi, 2 * np.pi) - np.pi).max(-1)
    assert np.all(np.nanmin(d, axis=1) < 1e-6)
    # every returned solution reaches its target (Pinocchio FK), and solutions are distinct
    for i in range(0, 3000, 150):
        q = sol.q[i, : sol.n_solutions[i]]
        dp, _ = _pin_residual(ssrms, scenario_arm, q, T[i, :3, 3], T[i, :3, :3])
        assert dp.max() <= RESIDUAL_TOL
        assert _distinct(q)


def test_solution_counts_are_even_for_generic_points(scenario_arm):
    # real solutions of this polynomial system come in pairs away from singular boundaries
    rng = np.random.default_rng(8)
    T = scenario_arm.fk(rng.uniform(-np.pi, np.pi, (2000, 6)))
    n = solve(scenario_arm, T[:, :3, 3], T[:, :3, :3]).n_solutions
    assert np.mean(n % 2 == 0) > 0.99


def test_unreachable_point_has_no_solution(scenario_arm):
    sol = solve(scenario_arm, np.array([[50.0, 0, 0], [0, 0, 0.6]]), TASK_R)
    assert sol.n_solutions[0] == 0
    assert np.all(np.isnan(sol.q[0]))


@pytest.mark.parametrize("joint, method", [(2, "closed_form"), (6, "closed_form_reversed"), (7, "closed_form_reversed")])
def test_other_locks_closed_form(ssrms, joint, method):
    arm = lock(ssrms, joint, 0.4)
    assert method_for(arm.chain) == method
    rng = np.random.default_rng(joint)
    q_true = rng.uniform(-np.pi, np.pi, (300, 6))
    T = arm.fk(q_true)
    sol = solve(arm, T[:, :3, 3], T[:, :3, :3])
    d = np.abs(np.mod(sol.q - q_true[:, None] + np.pi, 2 * np.pi) - np.pi).max(-1)
    assert np.all(np.nanmin(d, axis=1) < 1e-6)
    dp, _ = _pin_residual(ssrms, arm, sol.q[0, : sol.n_solutions[0]], T[0, :3, 3], T[0, :3, :3])
    assert dp.max() <= RESIDUAL_TOL


@pytest.mark.parametrize("joint", [3, 4, 5])
def test_middle_locks_use_the_semi_analytical_method(ssrms, joint):
    chain = lock(ssrms, joint, 0.4).chain
    assert method_for(chain) == "semi_analytic"
    assert SemiAnalytic().applies(chain)


def test_general_chain_gets_every_branch(tmp_path):
    """A chain with no closed form or search (joints 3, 4, 5 no longer parallel) is solved by the
    general 6R method: every solution exact by Pinocchio, the sampled configuration among them, and
    every solution a 256-start Newton search finds among them (an independent, incomplete oracle)."""
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    doc["dh"]["rows"][3][0] = 10
    doc["dh"]["rows"][4][0] = 170
    (tmp_path / "r.yaml").write_text(yaml.safe_dump(doc))
    arm = lock(load(tmp_path / "r.yaml"), 1, 0.9)
    assert method_for(arm.chain) == "general_6r"
    rng = np.random.default_rng(11)
    q_true = rng.uniform(-np.pi, np.pi, (8, 6))
    T = arm.fk(q_true)
    sol = solve(arm, T[:, :3, 3], T[:, :3, :3])
    starts = MultiStartNewton().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    for i in range(len(T)):
        q = sol.q[i, : sol.n_solutions[i]]
        dp, _ = _pin_residual(arm.robot, arm, q, T[i, :3, 3], T[i, :3, :3])
        assert dp.max() <= RESIDUAL_TOL and _distinct(q)
        wrapped = np.mod(q - q_true[i] + np.pi, 2 * np.pi) - np.pi
        assert np.abs(wrapped).max(axis=1).min() < 1e-6
        for s in starts.q[i, : starts.n_solutions[i]]:
            assert (np.abs(np.mod(q - s + np.pi, 2 * np.pi) - np.pi).max(axis=1) < 1e-6).any()


def test_numeric_fallback_for_seven_joints(ssrms, caplog):
    """More than 6 free joints: only the multi-start search applies; it warns that the map may overstate."""
    arm = free(ssrms)
    assert method_for(arm.chain) == "numeric"
    T = arm.fk(np.random.default_rng(2).uniform(-np.pi, np.pi, (3, 7)))
    with caplog.at_level("WARNING", logger="capmap.core.ik"):
        sol = solve(arm, T[:, :3, 3], T[:, :3, :3])
    assert "may overstate" in caplog.text
    assert np.all(sol.n_solutions >= 1)


def test_solutions_respect_joint_ranges(tmp_path):
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    doc["joint_range_deg"][3] = [-90, 90]  # joint 4
    (tmp_path / "r.yaml").write_text(yaml.safe_dump(doc))
    arm = lock(load(tmp_path / "r.yaml"), 1, np.deg2rad(100))
    full = solve(lock(load(SSRMS_YAML), 1, np.deg2rad(100)), X_DES[None], TASK_R)
    limited = solve(arm, X_DES[None], TASK_R)
    q_full = full.q[0, : full.n_solutions[0]]
    expected = np.sum(np.abs(q_full[:, 2]) <= np.pi / 2)  # joint 4 is active index 2
    assert limited.n_solutions[0] == expected < 8
    assert np.all(np.abs(limited.q[0, : limited.n_solutions[0], 2]) <= np.pi / 2 + 1e-12)


def test_wrap_to_range():
    lo, hi = np.array([-np.pi, 0.0, -4.0]), np.array([np.pi, 2 * np.pi, 4.0])
    q, ok = wrap_to_range(np.array([[3 * np.pi / 2, -0.5, 3.5]]), lo, hi)
    assert np.allclose(q, [[-np.pi / 2, 2 * np.pi - 0.5, 3.5 - 2 * np.pi]]) and ok.all()  # nearest 0 of 3.5 and 3.5-2pi
    _, ok = wrap_to_range(np.array([[0.0, 0.0, 0.0]]), np.array([1.0, 0, 0]), np.array([2.0, 1, 1]))
    assert not ok[0, 0]
