"""Continuous-branch tracking: error terms, range excursions, leaving the workspace."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.core.tracking import range_excursions, start_branch, track
from capmap.errors import CapmapError
from tests.scenario import Q_INI_DEG, TASK_R, X_DES, X_INI

Q_INI = np.deg2rad(Q_INI_DEG[1:])


def test_range_excursions_runs():
    ok = np.ones((10, 2), dtype=bool)
    ok[2:4, 1] = False
    ok[7:, 1] = False
    ok[5, 0] = False
    assert range_excursions(ok) == [(1, 2, 3), (0, 5, 5), (1, 7, 9)]


def test_wrong_start_configuration_is_a_one_line_error_in_own_terms(scenario_arm):
    with pytest.raises(CapmapError) as err:
        track(scenario_arm, np.array([X_INI, X_DES]), TASK_R, Q_INI + np.deg2rad(10))
    msg = str(err.value)
    assert "\n" not in msg and "the start configuration is 10.54 deg from the nearest of the 8 IK solutions" in msg
    assert err.value.in_terms(q_ini="task.q_ini_deg", start="task.start_m").startswith(
        "task.q_ini_deg is 10.54 deg from the nearest of the 8 IK solutions at task.start_m")


def test_start_branch_is_the_nearest_exact_solution(scenario_arm):
    q, off = start_branch(scenario_arm, X_INI, TASK_R, Q_INI)
    assert off < np.deg2rad(0.6) and np.abs(q - Q_INI).max() == pytest.approx(off)
    T = scenario_arm.fk(q[None])[0]
    assert np.allclose(T[:3, 3], X_INI, atol=1e-9) and np.allclose(T[:3, :3], TASK_R, atol=1e-9)


def test_leaving_the_workspace_stops_tracking(scenario_arm):
    far = X_INI + 30 * (X_DES - X_INI) / np.linalg.norm(X_DES - X_INI)
    tr = track(scenario_arm, np.linspace(X_INI, far, 2000), TASK_R, Q_INI)
    # the elbow straightens at the reach boundary: the branch merges with another (singular)
    assert not tr.ok and "branch lost" in tr.failure and 0 < tr.failed_at < 2000
    assert np.isnan(tr.q[tr.failed_at:]).all() and not np.isnan(tr.q[: tr.failed_at]).any()
    tr = track(scenario_arm, np.array([X_INI, far]), TASK_R, Q_INI)
    assert tr.failed_at == 1 and "no IK solution" in tr.failure
