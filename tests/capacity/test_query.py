"""The questions answered directly (capmap.capacity.query) against independent computations: the IK
branches of a random-restart solver, and each branch's capacity from Pinocchio's Jacobian and
classical acceleration (the joint motion), Craig's recursive Newton-Euler (the loads) and an LP (the
largest payload), over the same directions."""

import numpy as np
import pytest
import yaml

from capmap.capacity.directions import sphere
from capmap.capacity.engine import LoadLimits, Motion
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.query import line_query, point_query
from capmap.core.configuration import arm_configurations
from capmap.core.reduction import lock
from capmap.errors import CapmapError
from capmap.robots import load
from tests.reference.ik_oracle import DHArm, solve_all
from tests.reference.posture_capacity import posture_capacity
from tests.scenario import SSRMS_YAML, TASK_R, X_DES, X_INI

MOTION = Motion(0.15, 0.03)
DIRS = sphere(24)


@pytest.fixture(scope="module")
def question():
    robot = load(SSRMS_YAML)
    arm = lock(robot, 1, np.deg2rad(100))
    limits = LoadLimits.uniform(7, 700, 200, 500).for_arm(arm)
    return robot, CapacityProblem(arm, TASK_R, MOTION, limits, DIRS, labels=arm_configurations(arm))


def _reference_capacity(robot, arm, q_active: np.ndarray, limit: np.ndarray) -> float:
    """min over DIRS of the independent posture capacity (tests.reference.posture_capacity)."""
    return posture_capacity(robot, arm, q_active, DIRS.u, MOTION.v_max_mps, MOTION.a_max_mps2, limit)


@pytest.mark.parametrize("point", [X_INI, X_DES, np.array([1.5, 3.0, 3.0])])
def test_point_query_equals_an_independent_computation_on_every_configuration(question, point):
    robot, q = question
    arm = q.dyn.arm
    ans = point_query(q, point)
    # the branches: those of a random-restart solver on the DH arm, no more, no fewer
    oracle = solve_all(DHArm(yaml.safe_load(SSRMS_YAML.read_text()), 1, 100.0),
                       _pose(point)[None], 64, np.random.default_rng(5))[0]
    assert len(ans.configuration) == len(oracle) >= 4
    assert len(set(ans.configuration)) == len(ans.configuration)  # closed-form chain: one branch per configuration
    wrap = np.mod(ans.q_rad[:, None, :] - oracle[None] + np.pi, 2 * np.pi) - np.pi
    assert np.all(np.abs(wrap).max(axis=2).min(axis=1) < 1e-6)
    for k in range(len(ans.configuration)):
        expect = _reference_capacity(robot, arm, ans.q_rad[k], q.limits.limit)
        assert ans.capacity_kg[k] == pytest.approx(expect, rel=1e-7, abs=1e-6), ans.configuration[k]
    assert len(set(np.round(ans.capacity_kg, 3))) > 1  # the configurations differ (else this shows little)


def _pose(p):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = TASK_R, p
    return T


def test_line_query_on_a_configuration_and_bad_questions(question):
    _, q = question
    ans = line_query(q, X_INI, X_DES, 1500.0, 0.5, "S+E-W+")
    assert ans.configuration == "S+E-W+" and q.labels.names[q.labels.labels(ans.q_start_rad[None])[0]] == "S+E-W+"
    assert ans.verdict.length_m == pytest.approx(np.linalg.norm(X_DES - X_INI), rel=1e-12)
    with pytest.raises(CapmapError, match="not one of this arm's"):
        line_query(q, X_INI, X_DES, 1500.0, 0.5, "elbow-up")
    with pytest.raises(CapmapError, match="not reachable"):
        point_query(q, [100.0, 0, 0])
    with pytest.raises(CapmapError, match="distinct finite"):
        line_query(q, X_INI, X_INI, 1500.0, 0.5, "S+E-W+")


def _closed_boxes_holding(lower, shape, edge, p, tol):
    """Brute force over every voxel of the grid: those whose closed box holds p to within tol."""
    out = []
    for i in range(shape[0]):
        for j in range(shape[1]):
            for k in range(shape[2]):
                lo = np.asarray(lower) + edge * np.array([i, j, k])
                if np.all(p >= lo - tol) and np.all(p <= lo + edge + tol):
                    out.append((i, j, k))
    return sorted(out)


def test_a_point_touches_the_voxels_whose_closed_box_holds_it():
    """Inside one voxel, on a face (2), an edge (4), a corner (8), at the grid's border, outside:
    Grid.touching against a brute force over the grid's voxels."""
    from capmap.capacity.voxels import Grid

    grid = Grid(np.array([-1.5, 0.75, 2.25]), (4, 3, 5), 0.75)
    rng = np.random.default_rng(3)
    corners = grid.lower + 0.75 * rng.integers(0, [5, 4, 6], size=(40, 3))  # grid nodes, some on the border
    faces = corners + rng.uniform(0.01, 0.74, size=(40, 3)) * (rng.random((40, 3)) < 0.5)
    inside = grid.lower + rng.uniform(0, 1, size=(40, 3)) * 0.75 * np.array(grid.shape)
    outside = np.array([[-3.0, 1.0, 3.0], [0.0, 10.0, 3.0]])
    for p in np.vstack([corners, faces, inside, outside, corners + 4e-7]):
        got = sorted(map(tuple, grid.touching(p, 1e-6).tolist()))
        assert got == _closed_boxes_holding(grid.lower, grid.shape, 0.75, p, 1e-6), p
    assert len(grid.touching(grid.lower + 0.75 * np.array([1, 1, 1]))) == 8
    assert len(grid.touching(grid.lower + 0.75 * np.array([1, 1, 1]) + 2e-6)) == 1  # beyond the tolerance: inside one
