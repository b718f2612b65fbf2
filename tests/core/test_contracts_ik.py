"""The IK contract (:class:`capmap.core.ik.IKMethod`), written once and run against every
implementation in :data:`capmap.core.ik.METHODS` on every test arm it applies to: the SSRMS with
joints 1, 3, 4 and 7 locked and the UR5 (URDF), the same reachable poses for every method.

The reference is the independent random-restart oracle of tests/reference/ik_oracle.py: from the
robot file's DH rows for the SSRMS, and from the robot's own Pinocchio model (the URDF; no capmap
chain or IK code) for the UR5, whose file has no DH rows. Every method must return exact solutions
(by the oracle's forward kinematics), distinct, inside the joint ranges, in the documented shapes.
A complete method (``complete`` True: closed form, semi-analytical search, each also reversed) must
find every branch the oracle finds. The multi-start Newton fallback is NOT complete, so it is held
only to "every returned solution exact" and "a subset of the oracle's branches" (and of the complete
method's branches at the same poses), with at least one at every target: it may miss branches, it
must not invent any.
"""

from __future__ import annotations

import functools

import numpy as np
import pinocchio as pin
import pytest
import yaml

from capmap.core import ik
from capmap.core.reduction import free, lock
from capmap.robots import load
from tests.reference.ik_oracle import DHArm, solve_all
from tests.scenario import SSRMS_YAML, UR5_YAML

POSES = 10  # per arm, the same for every method
RESTARTS = 400  # of the oracle per pose (at 150 it misses a branch of the SSRMS with joint 4 locked that both methods find)
SAME = 1e-5  # rad: two solutions are one branch (wrapped, max over joints)
EXACT = 1e-8  # m and rotation-matrix entries, by the oracle's FK
# name: (robot file, locked joint (0: none), lock angle deg)
ARMS = {"ssrms_j1": (SSRMS_YAML, 1, 100.0), "ssrms_j3": (SSRMS_YAML, 3, -150.0), "ssrms_j4": (SSRMS_YAML, 4, 35.0),
        "ssrms_j7": (SSRMS_YAML, 7, 60.0), "ur5": (UR5_YAML, 0, 0.0)}


class PinocchioArm:
    """The oracle's arm interface (``active``, ``fk``, ``jacobian``: tool pose (M, 4, 4) and
    world-aligned Jacobian (M, 6, n) [v; w] of the tool point) from the robot's Pinocchio model."""

    def __init__(self, robot):
        self.model, self.data, self.frame = robot.model, robot.model.createData(), robot.ee_frame_id
        self.active = list(range(robot.model.nq))

    def jacobian(self, q):
        T, J = [], []
        for qi in np.atleast_2d(q):
            J.append(pin.computeFrameJacobian(self.model, self.data, qi, self.frame, pin.LOCAL_WORLD_ALIGNED))
            pin.updateFramePlacement(self.model, self.data, self.frame)
            T.append(self.data.oMf[self.frame].homogeneous.copy())
        return np.array(T), np.array(J)

    def fk(self, q):
        return self.jacobian(q)[0]


@functools.cache
def _arm(name: str):
    path, joint, angle_deg = ARMS[name]
    robot = load(path)
    if joint:
        return lock(robot, joint, np.deg2rad(angle_deg)), DHArm(yaml.safe_load(path.read_text()), joint, angle_deg)
    return free(robot), PinocchioArm(robot)


def _admissible(q, arm):
    """Oracle solutions (K, n) in (-pi, pi] that have a representative (2 pi k shifts) inside the joint ranges."""
    shifted = q[..., None] + 2 * np.pi * np.arange(-2, 3)
    inside = (shifted >= arm.q_lower[:, None] - 1e-12) & (shifted <= arm.q_upper[:, None] + 1e-12)
    return q[np.all(inside.any(-1), axis=-1)]


@functools.cache
def _poses(name: str):
    """Reachable targets (N, 4, 4) by the oracle's FK, and the oracle's admissible branches per target."""
    arm, oracle = _arm(name)
    rng = np.random.default_rng(sum(map(ord, name)))
    T = oracle.fk(rng.uniform(-np.pi, np.pi, (POSES, arm.n_active)))
    return T, [_admissible(r, arm) for r in solve_all(oracle, T, RESTARTS, rng)]


@functools.cache
def _solved(name: str, method_name: str):
    arm, _ = _arm(name)
    T, _ = _poses(name)
    return next(m for m in ik.METHODS if m.name == method_name).solve(arm, T[:, :3, 3], T[:, :3, :3])


def _distance(a, b):
    """Wrapped max-joint distance (len a, len b) rad."""
    return np.abs(np.mod(a[:, None] - b[None] + np.pi, 2 * np.pi) - np.pi).max(-1, initial=0.0)


PAIRS = [(name, m.name) for name in ARMS for m in ik.METHODS if m.applies(_arm(name)[0].chain)]


def test_every_method_meets_the_contract_somewhere():
    assert {m for _, m in PAIRS} == {m.name for m in ik.METHODS}
    assert all(isinstance(m, ik.IKMethod) for m in ik.METHODS)
    assert ik.COMPLETE_METHODS == tuple(m.name for m in ik.METHODS if m.complete)
    assert not next(m for m in ik.METHODS if m.name == "numeric").complete


@pytest.mark.parametrize("name, method_name", PAIRS)
def test_method_against_the_oracle(name, method_name):
    arm, oracle = _arm(name)
    method = next(m for m in ik.METHODS if m.name == method_name)
    T, ref = _poses(name)
    sol = _solved(name, method_name)
    N, K, n = sol.q.shape
    assert (N, n) == (POSES, arm.n_active) and sol.n_solutions.shape == (N,) and sol.method == method.name
    complete = ik.method_of(arm.chain)  # the method ik.solve dispatches to on this arm: complete here
    assert complete.complete
    missed = invented = extra = 0
    for i in range(N):
        k = int(sol.n_solutions[i])
        assert k >= 1  # every target is reachable (the FK of a configuration): a method finds at least one branch
        mine = sol.q[i, :k]
        assert np.all(np.isfinite(mine)) and np.all(np.isnan(sol.q[i, k:]))
        assert np.all((mine >= arm.q_lower - 1e-12) & (mine <= arm.q_upper + 1e-12))
        d_self = _distance(mine, mine)
        assert np.all(d_self[~np.eye(k, dtype=bool)] > 1e-6)  # distinct
        Tm = oracle.fk(mine)  # every returned solution exact by the oracle's own forward kinematics
        assert np.abs(Tm[:, :3, 3] - T[i, :3, 3]).max(initial=0) < EXACT
        assert np.abs(Tm[:, :3, :3] - T[i, :3, :3]).max(initial=0) < EXACT
        d = _distance(ref[i], mine)  # (oracle, mine)
        if method.complete:
            missed += int((d.min(axis=1, initial=np.inf) > SAME).sum())  # every oracle branch found
            extra += int((d.min(axis=0, initial=np.inf) > SAME).sum())  # found only here: exact (checked above)
        else:
            invented += int((d.min(axis=0, initial=np.inf) > SAME).sum())  # a subset of the oracle
            full = _solved(name, complete.name)
            d_full = _distance(full.q[i, :full.n_solutions[i]], mine)
            invented += int((d_full.min(axis=0, initial=np.inf) > SAME).sum())  # and of the complete method
    assert sum(map(len, ref)) >= POSES  # the oracle did find branches to compare with
    assert missed == 0, f"{method.name} on {name}: {missed} oracle branches missed"
    assert invented == 0, f"{method.name} on {name}: {invented} solutions outside the oracle's branches"
    print(f"{name} {method.name}: {int(sol.n_solutions.sum())} solutions at {N} poses, oracle {sum(map(len, ref))}, "
          f"found only by {method.name} (exact): {extra}")


@pytest.mark.parametrize("name, method_name", PAIRS)
def test_an_unreachable_target_has_no_solution(name, method_name):
    arm, _ = _arm(name)
    method = next(m for m in ik.METHODS if m.name == method_name)
    sol = method.solve(arm, np.array([[50.0, 0.0, 0.0]]), np.eye(3))
    assert sol.n_solutions.tolist() == [0] and np.all(np.isnan(sol.q)) and sol.q.shape[2] == arm.n_active


def test_a_method_refuses_a_chain_it_does_not_apply_to():
    arm, _ = _arm("ssrms_j4")
    closed = next(m for m in ik.METHODS if m.name == "closed_form")
    assert not closed.applies(arm.chain)
    with pytest.raises(ValueError, match="does not apply"):
        closed.solve(arm, np.zeros((1, 3)), np.eye(3))


def test_solve_dispatches_to_the_first_method_that_applies():
    for name in ARMS:
        arm, _ = _arm(name)
        first = next(m for m in ik.METHODS if m.applies(arm.chain))
        assert ik.method_of(arm.chain) is first and ik.method_for(arm.chain) == first.name
        T, _ = _poses(name)
        via, direct = ik.solve(arm, T[:, :3, 3], T[:, :3, :3]), _solved(name, first.name)
        assert via.method == direct.method and np.array_equal(via.n_solutions, direct.n_solutions)
        assert np.array_equal(via.q, direct.q, equal_nan=True)
