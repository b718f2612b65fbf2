"""Torque-limited following: bounds against brute force, the 1-DOF analytic limit, torques
against the independent Newton-Euler, exact reproduction without limits, no limit crossed,
and TOPP-RA as the lower bound on the duration."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from capmap.core.limits import AffineLimits
from capmap.core.profiles import scurve
from capmap.core.reduction import free
from capmap.errors import CapmapError
from capmap.following.follower import FollowSettings, follow, follow_segment
from capmap.following.path import JointPath, line_path
from capmap.following.path_dynamics import PathDynamics, path_dynamics, prepare
from capmap.following.toppra_reference import ToppraSettings, time_optimal
from capmap.robots import load
from tests.reference.newton_euler import newton_euler
from tests.scenario import Q_INI_DEG, TASK_R, UR5_YAML, X_DES, X_INI

UR5 = UR5_YAML
UR5_Q0 = np.deg2rad([0, -68.75, 91.67, -108.86, -90, 0])
UR5_LIM = np.array([14, 150, 150, 28, 28, 28.0])


# --------------------------------------------------------------------------- admissible accelerations


@pytest.mark.parametrize("friction", [False, True])
@pytest.mark.parametrize("seed", range(20))
def test_admissible_path_accelerations_equal_brute_force(seed, friction):
    """[lo, hi] from the torque tables at a forward path speed vs a dense search over sdd of
    |a sdd + b sd^2 + c (+ F_v q' sd + F_c sign(q'), the drives' friction)| <= T."""
    rng = np.random.default_rng(seed)
    n = 6
    a, b, c = rng.normal(size=n), rng.normal(size=n), 0.3 * rng.normal(size=n)
    a[rng.random(n) < 0.15] = 0.0
    tau, sd = rng.uniform(0.5, 2.0, n), rng.uniform(0, 1.5)
    dq = rng.normal(size=n)
    coulomb, viscous = (rng.uniform(0, 0.4, n), rng.uniform(0, 0.5, n)) if friction else (np.zeros(n), np.zeros(n))
    pdyn = PathDynamics(np.zeros(1), a[None], b[None], c[None], dq[None], coulomb, viscous)
    (lo,), (hi,) = pdyn.sdd_interval(AffineLimits(tau, tuple(f"tau_j{k}_nm" for k in range(n))), np.array([sd]))
    x = np.linspace(-60, 60, 240001)
    ok = np.all(np.abs(np.outer(x, a) + b * sd**2 + c + viscous * dq * sd + coulomb * np.sign(dq)) <= tau, axis=1)
    if not ok.any():
        assert lo > hi or hi - lo < 1e-3
    else:
        assert lo == pytest.approx(max(x[ok].min(), -60), abs=1e-3) or lo < -60
        assert hi == pytest.approx(min(x[ok].max(), 60), abs=1e-3) or hi > 60


# --------------------------------------------------------------------------- 1-DOF analytic case


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory):
    """One revolute joint, horizontal axis (gravity along -y), point-like link of 4 kg at r = 0.5 m."""
    doc = {"name": "pendulum", "dh": {"convention": "modified", "rows": [[0, 0, 0, 0]]},
           "links": [{"mass_kg": 4.0, "com_m": [0.5, 0, 0], "inertia_kgm2": [1e-4, 1e-4, 1e-4]}],
           "joint_range_deg": [[-180, 180]], "gravity_mps2": [0, -9.81, 0]}
    path = tmp_path_factory.mktemp("robots") / "pendulum.yaml"
    path.write_text(yaml.safe_dump(doc))
    return free(load(path))


def test_one_dof_limited_acceleration_is_the_analytic_value(pendulum):
    m, r, g, Izz, T = 4.0, 0.5, 9.81, 1e-4, 25.0
    I_o = Izz + m * r**2
    L = 1.2  # rad: the joint path q(s) = s
    s = np.linspace(0, L, 2401)
    path = JointPath(s=s, q=s[:, None], dq=np.ones((len(s), 1)), ddq=np.zeros((len(s), 1)),
                        p=np.zeros((len(s), 3)))
    pdyn = path_dynamics(pendulum, path, payload_kg=0.0)
    assert np.allclose(pdyn.a[:, 0], I_o) and np.allclose(pdyn.b, 0) and np.allclose(pdyn.c[:, 0], m * g * r * np.cos(s))
    prep = prepare(pdyn, AffineLimits(np.array([T]), ("tau_j1_nm",)), v_max_mps=20.0)
    res = follow(prep, scurve(L, 20.0, 60.0, 2000.0), period_s=1e-3, catch_up_hz=5.0)
    up = res.limited & (res.sdd > 0)
    assert up.sum() > 50
    analytic = (T - m * g * r * np.cos(res.s[up])) / I_o  # largest admissible q'' at q = s
    assert np.allclose(res.sdd[up], analytic, rtol=1e-6)
    # everywhere (braking included) the applied acceleration is inside the analytic interval
    lo = (-T - m * g * r * np.cos(res.s)) / I_o
    hi = (T - m * g * r * np.cos(res.s)) / I_o
    assert np.all(res.sdd >= lo * (1 + 1e-6)) and np.all(res.sdd <= hi * (1 + 1e-6))  # table interpolation: ~1e-8
    assert res.s[-1] == pytest.approx(L, abs=1e-5) and res.s.max() <= L + 1e-5


def test_holding_impossible_is_a_one_line_error(pendulum):
    s = np.linspace(0, 0.5, 101)
    path = JointPath(s=s, q=s[:, None], dq=np.ones((101, 1)), ddq=np.zeros((101, 1)), p=np.zeros((101, 3)))
    with pytest.raises(CapmapError, match=r"tau_j1_nm: holding the path at rest at s = 0.0000 m needs 19.62 N m"):
        prepare(path_dynamics(pendulum, path, 0.0), AffineLimits(np.array([10.0]), ("tau_j1_nm",)), 1.0)


# --------------------------------------------------------------------------- torques along a Cartesian path


def test_path_torques_match_independent_newton_euler(scenario_arm):
    """a sdd + b sd^2 + c (payload appended to the last body) vs the textbook recursion with a payload."""
    arm = scenario_arm
    path = line_path(arm, X_INI, X_DES, TASK_R, np.deg2rad(Q_INI_DEG[1:]), ds_m=0.05)
    pdyn = path_dynamics(arm, path, payload_kg=1500.0)
    rng = np.random.default_rng(3)
    for i in rng.choice(len(path.s), 6, replace=False):
        sd, sdd = rng.uniform(0, 0.15), rng.uniform(-0.03, 0.03)
        q, dq, ddq = (arm.full_q(path.q[i]), arm.full_v(path.dq[i]), arm.full_v(path.ddq[i]))
        tau, acc, _, _ = newton_euler(q, dq * sd, dq * sdd + ddq * sd**2, arm.robot.gravity, 1500.0,
                                      arm.robot.base_com)
        u = (X_DES - X_INI) / np.linalg.norm(X_DES - X_INI)
        assert np.allclose(acc[:3], u * sdd, atol=1e-9) and np.allclose(acc[3:], 0, atol=1e-9)  # on the line
        assert np.allclose(pdyn.a[i] * sdd + pdyn.b[i] * sd**2 + pdyn.c[i], tau[1:], rtol=1e-9, atol=1e-7)


def _settings(tau):
    """The ground case: 2 kg, v 1 m/s, a 4 m/s^2, j 40 m/s^3, 1 ms period, 5 Hz catch-up."""
    return FollowSettings(2.0, tau, 1.0, 4.0, 40.0, 1e-3, 5.0)


@pytest.fixture(scope="module")
def ur5_line():
    arm = free(load(UR5))
    T0 = arm.fk(UR5_Q0[None])[0]
    return arm, T0[:3, 3], T0[:3, 3] + np.array([0, 0.5, 0]), T0[:3, :3]


def test_unlimited_follower_reproduces_the_command_exactly(ur5_line):
    arm, p0, p1, R = ur5_line
    seg = follow_segment(arm, p0, p1, R, UR5_Q0, _settings(UR5_LIM * 100))
    r = seg.result
    assert not r.limited.any()
    assert np.array_equal(r.s, r.s_cmd) and np.array_equal(r.sd, r.sd_cmd) and np.array_equal(r.sdd, r.sdd_cmd)
    assert r.duration_s == pytest.approx(seg.command.duration_s, abs=1.5e-3)
    assert np.allclose(seg.tau, seg.tau_cmd, rtol=1e-12, atol=1e-9)


def test_limited_follower_touches_but_never_crosses_the_limit(ur5_line):
    arm, p0, p1, R = ur5_line
    seg = follow_segment(arm, p0, p1, R, UR5_Q0, _settings(UR5_LIM))
    r = seg.result
    need = np.abs(seg.tau_cmd).max(axis=0) / UR5_LIM
    got = np.abs(seg.tau).max(axis=0) / UR5_LIM  # exact RNEA at the follower's states
    assert need[0] > 1.05  # the command alone would exceed the shoulder-pan limit
    assert 0.999 < got[0] <= 1 + 1e-4  # touches it, crosses it by less than 0.01 %
    assert np.all(got <= 1 + 1e-4) and not r.infeasible.any()
    assert np.all(np.diff(r.s) >= -1e-12) and r.s.max() <= seg.table.length_m + 1e-6  # no reversing, no overshoot
    assert abs(r.s[-1] - seg.table.length_m) < 1e-5 and r.duration_s > seg.command.duration_s
    assert seg.deviation_m.max() < 1e-5  # the path is kept: only the timing yields


def test_toppra_is_a_lower_bound_and_respects_the_limits(ur5_line):
    arm, p0, p1, R = ur5_line
    seg = follow_segment(arm, p0, p1, R, UR5_Q0, _settings(UR5_LIM))
    top = time_optimal(arm, seg.table, 2.0, seg.prepared.limits, ToppraSettings(1.0, 4.0))
    assert top.duration_s < seg.result.duration_s < 1.5 * top.duration_s
    assert (np.abs(top.tau).max(axis=0) / UR5_LIM).max() < 1.01
    assert top.sd.max() <= 1.0 + 1e-6 and top.s[-1] == pytest.approx(0.5, abs=1e-6)
