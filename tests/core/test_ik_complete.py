"""Completeness of the IK for every locked joint of the SSRMS-type arm, against an independent
dense random-restart solver written from the DH rows (tests/reference/ik_oracle.py): at 200
poses per locked joint (4 lock angles x 50 poses), every branch the oracle finds is found,
and every branch found is an exact solution by the oracle's own forward kinematics."""

import numpy as np
import pytest
import yaml

from capmap.core.ik import COMPLETE_METHODS, method_for, solve
from capmap.core.reduction import lock
from tests.reference.ik_oracle import DHArm, solve_all
from tests.scenario import SSRMS_YAML

POSES, ANGLES_DEG, RESTARTS = 50, (-150.0, -40.0, 35.0, 125.0), 120


def _wrapped_distance(a, b):
    return np.abs(np.mod(a[:, None] - b[None] + np.pi, 2 * np.pi) - np.pi).max(-1)  # (len a, len b)


@pytest.mark.parametrize("joint", range(1, 8))
def test_every_branch_found(ssrms, joint):
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    rng = np.random.default_rng(100 + joint)
    found = oracle_found = extra = 0
    for angle in ANGLES_DEG:
        arm = lock(ssrms, joint, np.deg2rad(angle))
        assert method_for(arm.chain) in COMPLETE_METHODS
        oracle = DHArm(doc, joint, angle)
        T = oracle.fk(rng.uniform(-np.pi, np.pi, (POSES, 6)))  # reachable targets, independent FK
        sol = solve(arm, T[:, :3, 3], T[:, :3, :3])
        ref = solve_all(oracle, T, RESTARTS, rng)
        for i in range(POSES):
            mine = sol.q[i, : sol.n_solutions[i]]
            assert len(mine) >= 1
            # exact by the oracle's forward kinematics
            Tm = oracle.fk(mine)
            assert np.abs(Tm[:, :3, 3] - T[i, :3, 3]).max() < 1e-8 and np.abs(Tm[:, :3, :3] - T[i, :3, :3]).max() < 1e-8
            if len(ref[i]):
                d = _wrapped_distance(ref[i], mine)
                missed = d.min(axis=1) > 1e-5
                assert not missed.any(), (f"joint {joint} at {angle} deg, pose {i}: missed "
                                          f"{np.rad2deg(ref[i][missed]).round(3).tolist()}")
                extra += int((d.min(axis=0) > 1e-5).sum())
            found += len(mine)
            oracle_found += len(ref[i])
    print(f"joint {joint}: {found} branches found at {POSES * len(ANGLES_DEG)} poses; oracle ({RESTARTS} restarts) "
          f"{oracle_found}; found only by capmap (exact, checked): {extra}")
