"""Between the healthy arm's grid angles (capmap.capacity.angle_search): the compiled branch following
against the numpy Newton steps, and the intervals marked for a finer search against their definition
on hand-made grids."""

from types import SimpleNamespace

import numpy as np
import pytest

from capmap.capacity.angle_search import EDGE_NEAR, FINER, FINER_BESIDE, edge_intervals, follow
from capmap.capacity.engine import LoadLimits
from capmap.capacity.self_motion import SelfMotion, self_motion_angles
from capmap.core.kinematics import pose_error
from capmap.core.reduction import lock
from capmap.robots import load
from tests.scenario import SSRMS_YAML, TASK_R


@pytest.mark.parametrize("joint", [1, 7])
def test_compiled_following_meets_the_pose_on_the_same_branch_as_the_numpy_steps(joint):
    robot = load(SSRMS_YAML)
    lo, hi = np.rad2deg(robot.q_lower[joint - 1]), np.rad2deg(robot.q_upper[joint - 1])
    sm = SelfMotion.build(self_motion_angles(lo, hi, 0.0, 30), lambda a: lock(robot, joint, np.deg2rad(a)),
                          LoadLimits.uniform(7, 700, 200, 500).for_arm, lo, hi)
    assert sm.fold is not None
    rng = np.random.default_rng(2)
    q = rng.uniform(np.maximum(robot.q_lower, -np.pi), np.minimum(robot.q_upper, np.pi), (200, 7))
    t = rng.integers(0, len(sm.angles_deg), 200)
    rows, start = sm.solve(sm.free_chain.fk(q)[:, :3, 3], sm.angles_deg[t], TASK_R)  # postures at the task rotation
    points, t = sm.free_chain.fk(q)[rows, :3, 3], t[rows]
    to = sm.into_range(sm.angles_deg[t] + rng.choice([-5.0, -2.5, 1.25, 5.0], len(rows)))
    rows_c, q_c = follow(sm, TASK_R, points, to, start)
    sm.__dict__["fold"] = None  # the numpy steps
    rows_n, q_n = follow(sm, TASK_R, points, to, start)
    both, ic, i_n = np.intersect1d(rows_c, rows_n, return_indices=True)
    assert len(both) > 100 and len(np.setdiff1d(rows_n, rows_c)) <= 0.02 * len(rows_n)
    assert np.abs((q_c[ic] - q_n[i_n] + np.pi) % (2 * np.pi) - np.pi).max() < 1e-8
    arm = sm.arms[0]
    full = np.zeros((len(rows_c), 7))
    full[:, arm.active], full[:, joint - 1] = q_c, np.deg2rad(to[rows_c])  # the pose met at the new angle
    target = np.broadcast_to(np.eye(4), (len(rows_c), 4, 4)).copy()
    target[:, :3, :3], target[:, :3, 3] = TASK_R, points[rows_c]
    assert np.linalg.norm(pose_error(sm.free_chain.fk(full), target), axis=1).max() < 1e-9


def _marks(values: np.ndarray, turns: bool = True) -> np.ndarray:
    """edge_intervals of one point whose grid holds, per angle, the postures values[t] (a list; none: [])."""
    pt, tt, v = [], [], []
    for t, vs in enumerate(values):
        for x in vs:
            pt.append(0)
            tt.append(t)
            v.append(x)
    sm = SimpleNamespace(angles_deg=np.arange(len(values)) * 10.0, turns=turns)
    return edge_intervals(sm, np.array(pt, dtype=int), np.array(tt, dtype=int), np.array(v, dtype=float), 1)[0]


def test_intervals_at_an_edge_near_the_best_are_split_finest_those_beside_less():
    near, far = 100.0 * (1 - EDGE_NEAR / 2), 100.0 * (1 - 2 * EDGE_NEAR)
    # a branch ends between angles 3 and 4, its value near the best; everything else smooth
    marks = _marks([[100, 50], [99, 50], [98, 50], [near, 50], [50], [50], [50], [50]], turns=False)
    assert marks[3] == FINER and marks[2] == FINER_BESIDE and marks[4] == 0  # beside, but far below the best
    assert marks[0] == marks[1] == marks[5] == marks[6] == 0 and marks[7] == 0  # no turn: no last interval
    # the same edge far below the best: not searched
    assert not _marks([[100, 50], [99, 50], [98, 50], [far, 50], [50], [50]], turns=False)[3]
    # a posture reaching 0 kg is an edge too; round a turn the last interval counts
    m = _marks([[near], [100], [100], [100], [100], [0.0]])
    assert m[4] == FINER and m[5] == FINER and m[3] == FINER_BESIDE and m[0] == FINER_BESIDE


def test_a_plateau_of_zero_is_searched_wherever_a_posture_is():
    m = _marks([[0.0], [0.0, 0.0], [], [], [0.0], [0.0]], turns=False)
    assert list(m) == [FINER, FINER, 0, FINER, FINER, 0]
