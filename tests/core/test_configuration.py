"""Configuration labels (capmap.core.configuration) against independent computations: Pinocchio's
Jacobian determinant, the closed form's own branch choices, and motions that do or do not cross a
singular surface."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import capmap.core.ik.closed as ik_closed
from capmap.core import ik
from capmap.core.configuration import Aspects, ShoulderElbowWrist, arm_configurations
from capmap.core.reduction import free, lock
from capmap.core.tracking import track
from capmap.robots import load

SSRMS, UR5 = "config/robots/ssrms7.yaml", "config/robots/ur5.yaml"
# (robot, locked joint (0: none), angle deg): every closed-form case of the SSRMS, the UR5 as shipped,
# and a semi-analytical lock (aspects)
CASES = [(SSRMS, 1, 100), (SSRMS, 2, 124), (SSRMS, 6, 174), (SSRMS, 7, 57), (UR5, 0, 0), (SSRMS, 4, 130)]


def _arm(robot: str, joint: int, angle_deg: float):
    r = load(robot)
    return free(r) if joint == 0 else lock(r, joint, np.deg2rad(angle_deg))


def _det_pinocchio(arm, q: np.ndarray) -> np.ndarray:
    """det of Pinocchio's frame Jacobian (6, 6) of the reduced model at each q (M, 6)."""
    model = arm.reduced_model
    data = model.createData()
    return np.array([np.linalg.det(pin.computeFrameJacobian(model, data, qi, arm.reduced_ee_frame_id, pin.LOCAL))
                     for qi in q])


@pytest.mark.parametrize("robot,joint,angle", CASES)
def test_det_j_is_the_product_of_the_flags(robot, joint, angle):
    """Every singular surface is a sign change of exactly one flag: det J (Pinocchio) / prod(flags)
    is a nonzero constant on 2,000 random configurations (measured 0.5 in magnitude for every
    closed-form case, to 1e-11 relative; the bound 1e-6 leaves five orders of margin for rounding).
    For aspects the one flag is det J itself (the chain's own Jacobian)."""
    arm = _arm(robot, joint, angle)
    q = np.random.default_rng(joint).uniform(-np.pi, np.pi, (2000, 6))
    ratio = _det_pinocchio(arm, q) / np.prod(arm_configurations(arm).flags(q), axis=1)
    assert np.all(np.sign(ratio) == np.sign(ratio[0]))
    assert np.ptp(np.abs(ratio)) <= 1e-6 * np.abs(ratio).max()


@pytest.mark.parametrize("robot,joint,angle", CASES[:5])
def test_flags_are_the_closed_forms_branch_choices(robot, joint, angle):
    """Branch k = 4 i + 2 j + l of ik_closed.branches takes the root phi -+ delta of joint 0, 4 and
    2's equations: the labels of its (polished) raw branches are those choices, read from the
    angles alone."""
    arm = _arm(robot, joint, angle)
    labeller = arm_configurations(arm)
    rev = labeller.reversed
    chain = arm.chain.reversed() if rev else arm.chain
    T = chain.fk(np.random.default_rng(7).uniform(-np.pi, np.pi, (300, 6)))
    theta, ok = ik_closed.branches(chain, T)
    n, k = np.nonzero(ok)
    f = ik_closed.flags(chain, theta[n, k])
    clear = np.all(np.abs(f) > 1e-6 * np.abs(f).max(), axis=1)  # not within rounding of a singular surface
    bits = np.stack([(k >> 2) & 1, k & 1, (k >> 1) & 1], axis=1)  # shoulder (joint 0), elbow (2), wrist (4)
    assert clear.mean() > 0.99
    assert np.array_equal((f[clear] > 0), bits[clear] == 1)
    q = -theta[n, k][:, ::-1] if rev else theta[n, k]  # the arm's own angles
    labels = labeller.labels(q)
    # one IK solution per configuration at each pose: the labels of a pose's branches are distinct
    for pose in np.unique(n[clear])[:100]:
        mine = labels[(n == pose) & clear]
        assert len(np.unique(mine)) == len(mine)


def _check_segment(arm, labeller, a, b, n: int, depth: int) -> int:
    """The segment a -> b sampled at n points: each step changes the label iff det J changes sign,
    by one flag; a step where two flags flip at once (two surfaces between two samples) is
    resampled (``depth`` times at most). Returns the det J sign changes seen."""
    q = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
    det = _det_pinocchio(arm, q)
    labels = labeller.labels(q)
    crossed = np.sign(det[1:]) != np.sign(det[:-1])
    flipped = np.bitwise_xor(labels[1:], labels[:-1])
    several = (flipped & (flipped - 1)) != 0
    assert np.array_equal((flipped != 0) & ~several, crossed & ~several)
    count = int((crossed & ~several).sum())
    for i in np.flatnonzero(several):
        assert depth > 0, "two flags flip at one point of the motion"
        count += _check_segment(arm, labeller, q[i], q[i + 1], 200, depth - 1)
    return count


@pytest.mark.parametrize("robot,joint,angle", CASES)
def test_labels_change_exactly_where_a_motion_crosses_a_singular_surface(robot, joint, angle):
    """Straight joint-space motions, finely sampled: between two samples the label changes iff det J
    (Pinocchio) changes sign, and then (closed form) exactly one flag flips."""
    arm = _arm(robot, joint, angle)
    labeller = arm_configurations(arm)
    rng = np.random.default_rng(100 + joint)
    crossings = 0
    for _ in range(12):
        a, b = rng.uniform(-np.pi, np.pi, (2, 6))
        crossings += _check_segment(arm, labeller, a, b, 1500, depth=2)
    assert crossings >= 5  # the motions do cross singular surfaces


def test_labels_constant_along_a_tracked_cartesian_motion():
    """The default scenario's straight line (SSRMS, joint 1 locked at 100 deg), tracked on each IK branch
    at the start: up to where the tracker loses its branch, det J keeps its sign and so does the label."""
    arm = _arm(SSRMS, 1, 100)
    labeller = arm_configurations(arm)
    R = pin.rpy.rpyToMatrix(*np.deg2rad([90.0, 0.0, 90.0]))
    start, goal = np.array([0.3790, 4.8432, 1.8878]), np.array([2.6250, 1.8750, 4.8750])
    line = start + np.linspace(0.0, 1.0, 800)[:, None] * (goal - start)
    sol = ik.solve(arm, start[None], R)
    assert sol.n_solutions[0] == 8
    seen = set()
    for q0 in sol.q[0, :8]:
        tr = track(arm, line, R, q0)
        end = tr.failed_at if tr.failed_at >= 0 else len(line)
        q = tr.q[:end]
        assert end > 10
        det = _det_pinocchio(arm, q)
        assert np.all(np.sign(det) == np.sign(det[0]))
        labels = labeller.labels(q)
        assert np.all(labels == labels[0])
        seen.add(int(labels[0]))
    assert len(seen) == 8  # the eight branches at the start are the eight configurations


def test_general_chains_get_aspects():
    arm = _arm(SSRMS, 4, 130)
    labeller = arm_configurations(arm)
    assert isinstance(labeller, Aspects) and labeller.names == ("A-", "A+")
    assert isinstance(arm_configurations(_arm(SSRMS, 1, 100)), ShoulderElbowWrist)
