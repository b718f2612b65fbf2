"""The arm held at any angle of its failed joint (capmap.capacity.self_motion.SelfMotion): where the joint
folds into the chain's base or tip, every target solved in one call on one arm, against the IK of the arm
built at each angle."""

import numpy as np
import pytest

from capmap.capacity.engine import LoadLimits
from capmap.capacity.self_motion import SelfMotion, self_motion_angles
from capmap.core import ik
from capmap.core.configuration import arm_configurations
from capmap.core.reduction import lock
from capmap.robots import load
from tests.scenario import ROOT, SSRMS_YAML, TASK_R

PANDA_YAML = ROOT / "config" / "robots" / "panda.yaml"


@pytest.fixture(scope="module")
def robot():
    return load(SSRMS_YAML)


def _sm(robot, joint: int) -> SelfMotion:
    lo, hi = np.rad2deg(robot.q_lower[joint - 1]), np.rad2deg(robot.q_upper[joint - 1])
    return SelfMotion.build(self_motion_angles(lo, hi, 0.5 * (lo + hi), 30), lambda a: lock(robot, joint, np.deg2rad(a)),
                            LoadLimits.uniform(7, 700, 200, 500).for_arm, lo, hi)


@pytest.mark.parametrize("joint, fold", [(1, 0), (7, -1), (4, None)])
def test_the_joint_folds_into_the_base_or_tip_only_at_the_chain_ends(robot, joint, fold):
    assert _sm(robot, joint).fold == fold


@pytest.mark.parametrize("joint", [1, 7, 4])
def test_one_call_finds_every_solution_the_arm_at_each_angle_finds(robot, joint):
    """Random reachable points, each at its own angle (grid and off-grid): the same solution sets as
    ik.solve on the arm built at that angle (to 1e-9 rad)."""
    sm = _sm(robot, joint)
    rng = np.random.default_rng(4)
    lo, hi = sm.lower_deg, sm.upper_deg
    angles = np.concatenate([sm.angles_deg[:5], rng.uniform(lo, hi, 25)])
    q = rng.uniform(np.maximum(robot.q_lower, -np.pi), np.minimum(robot.q_upper, np.pi), (len(angles), 7))
    q[:, joint - 1] = np.deg2rad(angles)
    arms = [lock(robot, joint, np.deg2rad(a)) for a in angles]
    points = np.array([arm.fk(qi[arm.active][None])[0, :3, 3] for arm, qi in zip(arms, q)])
    rows, sol = sm.solve(points, angles, TASK_R)
    n_total = 0
    for i, arm in enumerate(arms):
        ref = ik.solve(arm, points[i:i + 1], TASK_R)
        want = ref.q[0, :ref.n_solutions[0]]
        got = sol[rows == i]
        n_total += len(want)
        assert len(got) == len(want), i
        for w in want:  # each reference solution among the found ones (wrapped difference)
            d = np.abs((got - w + np.pi) % (2 * np.pi) - np.pi).max(axis=1)
            assert d.min() < 1e-9, (i, d.min())
    assert n_total > 20  # the points are reachable at the rotation for some angles: the test compares something


@pytest.mark.parametrize("joint", [1, 4])
def test_the_reach_bound_keeps_every_reachable_pose_and_drops_only_unreachable_ones(robot, joint):
    """Every pose of random joint angles is within reach (at its own rotation); every point the bound drops
    has no IK solution at any grid angle (the arm built there)."""
    sm = _sm(robot, joint)
    rng = np.random.default_rng(8)
    q = rng.uniform(np.maximum(robot.q_lower, -np.pi), np.minimum(robot.q_upper, np.pi), (2000, 7))
    T = sm.free_chain.fk(q)
    assert sm.within_reach(T[:, :3, 3], T[:, :3, :3]).all()
    box = rng.uniform(-40.0, 40.0, (400, 3))
    out = ~sm.within_reach(box, TASK_R)
    assert 50 < out.sum() < 400  # the bound drops some points and keeps others: the test says something
    for arm in sm.arms:
        assert not ik.solve(arm, box[out], TASK_R).n_solutions.any()


@pytest.mark.parametrize("robot_file, joint", [(SSRMS_YAML, 1), (SSRMS_YAML, 7), (PANDA_YAML, 1), (PANDA_YAML, 7),
                                               (SSRMS_YAML, 4)])
def test_postures_are_labelled_as_the_nearest_grid_arm_labels_them(robot_file, joint):
    """grid_configuration (one call on the first grid arm when the joint folds) against the labels of the arm
    at each posture's nearest grid angle, built for it: SSRMS (shoulder, elbow, wrist flags) and the Panda
    (the sign of det J), their first and last joints; SSRMS joint 4 (no fold: an arm per grid angle)."""
    robot = load(robot_file)
    sm = _sm(robot, joint)
    rng = np.random.default_rng(9)
    angles = rng.uniform(sm.lower_deg, sm.upper_deg, 400)
    q = rng.uniform(np.maximum(robot.q_lower, -np.pi), np.minimum(robot.q_upper, np.pi), (400, 7))
    q = np.delete(q, joint - 1, axis=1)
    nearest = np.argmin(np.abs((angles[:, None] - sm.angles_deg[None, :] + 180.0) % 360.0 - 180.0), axis=1)  # a turn
    want = np.array([arm_configurations(lock(robot, joint, np.deg2rad(sm.angles_deg[t]))).labels(qi[None])[0]
                     for t, qi in zip(nearest, q)])
    assert len(np.unique(want)) > 1  # the postures span several configurations: the test compares something
    np.testing.assert_array_equal(sm.grid_configuration(angles, q), want)
