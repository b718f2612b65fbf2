"""Verification along a path: continuous-branch tracking, exact joint rates, loads and segment
capacities, against forward kinematics, finite differences and the independent Newton-Euler."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.capacity.engine import LoadLimits, Motion
from capmap.capacity.verification import verify_path
from capmap.core.dynamics import ArmDynamics
from capmap.core.tracking import range_excursions
from tests.reference.newton_euler import craig_fk, newton_euler
from tests.scenario import Q_INI_DEG, TASK_R, X_DES, X_INI

LIMITS = LoadLimits.uniform(7, 700, 200, 500)
Q_INI = np.deg2rad(Q_INI_DEG[1:])


@pytest.fixture(scope="module")
def direct(scenario_arm):
    dyn = ArmDynamics(scenario_arm)
    return dyn, verify_path(dyn, np.array([X_INI, X_DES]), TASK_R, Q_INI, Motion(0.15, 0.03), 0.25,
                            LIMITS.for_arm(scenario_arm))


def _full(arm, qa):
    return arm.full_q(qa)


def test_tracking_reaches_every_sample_at_the_task_pose(direct, scenario_arm):
    _, res = direct
    tr, tl = res.tracking, res.timeline
    assert tr.ok and tr.start_offset_rad < np.deg2rad(0.6)
    for i in range(0, len(tl), 7):
        R, p = craig_fk(_full(scenario_arm, tr.q[i]))
        assert np.allclose(p, tl.p[i], atol=1e-8) and np.allclose(R, TASK_R, atol=1e-8)
    assert np.abs(np.diff(tr.q, axis=0)).max() < np.deg2rad(2)  # one continuous branch


def test_joint_rates_match_finite_differences_of_the_tracked_path(direct):
    _, res = direct
    tl, q, ld = res.timeline, res.tracking.q, res.loads
    for ph in range(3):
        rows = np.flatnonzero(tl.phase == ph)
        t = tl.t_s[rows]
        dq = (q[rows][2:] - q[rows][:-2]) / (t[2:] - t[:-2])[:, None]
        scale = np.abs(ld.qd[rows]).max()
        assert np.abs(dq - ld.qd[rows][1:-1]).max() < 1e-3 * scale  # O(dt^2) central differences
        dqd = (ld.qd[rows][2:] - ld.qd[rows][:-2]) / (t[2:] - t[:-2])[:, None]
        assert np.abs(dqd - ld.qdd[rows][1:-1]).max() < 2e-3 * np.abs(ld.qdd[rows]).max() + 1e-9


def test_loads_at_payload_match_independent_newton_euler(direct, scenario_arm):
    dyn, res = direct
    tl, ld = res.timeline, res.loads
    robot = scenario_arm.robot
    y = ld.at(1500.0)
    for i in np.linspace(0, len(tl) - 1, 9).astype(int):
        q = _full(scenario_arm, res.tracking.q[i])
        qd, qdd = scenario_arm.full_v(ld.qd[i]), scenario_arm.full_v(ld.qdd[i])
        tau, acc, bf, bm = newton_euler(q, qd, qdd, robot.gravity, 1500.0, robot.base_com)
        assert np.allclose(acc[:3], tl.a[i], atol=1e-9) and np.allclose(acc[3:], 0, atol=1e-9)
        expect = np.concatenate([tau[1:], bf, bm])
        assert np.allclose(y[i], expect, rtol=1e-9, atol=1e-8)


def test_segment_capacity_is_the_largest_payload_within_all_limits(direct, scenario_arm):
    """Bisection on payload with the independent Newton-Euler at every sample of the line."""
    _, res = direct
    ld, arm = res.loads, scenario_arm
    robot = arm.robot
    lim = LIMITS.for_arm(arm).limit
    cap = res.segment_capacity_kg[0]

    def worst_ratio(m):
        r = 0.0
        for i in range(len(res.timeline)):
            q = _full(arm, res.tracking.q[i])
            tau, _, bf, bm = newton_euler(q, arm.full_v(ld.qd[i]), arm.full_v(ld.qdd[i]), robot.gravity, m,
                                          robot.base_com)
            r = max(r, np.max(np.abs(np.concatenate([tau[1:], bf, bm])) / lim))
        return r

    assert 1000 < cap < 10000
    assert worst_ratio(cap * (1 - 1e-6)) <= 1.0
    assert worst_ratio(cap * (1 + 1e-6)) > 1.0


def test_q_ini_branch_turns_joint_2_past_180_within_its_270_deg_range(direct, scenario_arm):
    """On q_ini's branch joint 2 ends beyond +180 deg (182.9): inside the SSRMS's +-270 deg (no
    excursion flagged), tracked continuously (not wrapped), and its wrapped value is an IK branch."""
    _, res = direct
    q = res.tracking.q
    assert range_excursions(res.tracking.in_range) == []
    assert np.pi < q[-1, 0] < np.deg2rad(270) and np.all(np.abs(q[-1, 1:]) <= np.pi)
    wrapped = q[-1].copy()
    wrapped[0] -= 2 * np.pi
    R, p = craig_fk(_full(scenario_arm, wrapped))
    assert np.allclose(p, X_DES, atol=1e-8)
