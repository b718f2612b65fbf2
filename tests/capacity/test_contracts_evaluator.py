"""The Evaluator contract (capmap.capacity.evaluator), written once and run against every evaluator:
the locked arm's and the healthy arm's. Each value is checked against the Pinocchio reference path
(per posture: :func:`capmap.capacity.engine.coefficients_pinocchio`, 16 RNEA calls of Pinocchio, then the
least over the same directions; the healthy value the best such posture over every swept angle and
IK solution), not against the batched kernels the evaluators use. The two paths agree to ~1e-12
relative (the docstring of coefficients); the tolerance below, 1e-8 relative + 1e-6 kg, is four
orders above that and far below any capacity difference that matters."""

import numpy as np
import pytest

from capmap.capacity.baseline import healthy_capacity
from capmap.capacity.directions import grid_axes, sphere
from capmap.capacity.engine import LoadLimits, Motion, capacity_over_directions, coefficients_pinocchio
from capmap.capacity.evaluator import Evaluator, LockedEvaluator
from capmap.capacity.healthy_evaluator import HealthyEvaluator
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.self_motion import HealthyProblem, SelfMotion, screening_subset, self_motion_angles
from capmap.core import ik
from capmap.core.configuration import arm_configurations
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import lock
from capmap.robots import load
from tests.scenario import SSRMS_YAML, TASK_R, X_DES, X_INI

MOTION = Motion(0.15, 0.03)
LIMITS = LoadLimits.uniform(7, 700, 200, 500)
DIRS = sphere(24)
REL, ABS = 1e-8, 1e-6


def _posture_reference(arm, q: np.ndarray) -> np.ndarray:
    """Each posture's least capacity over DIRS (K,) kg by Pinocchio's per-configuration path."""
    dyn = ArmDynamics(arm)
    coef = coefficients_pinocchio(dyn, q)
    cap, _ = capacity_over_directions(coef, DIRS, MOTION, dyn.gravity, LIMITS.for_arm(arm))
    return cap.min(axis=1)


def _locked():
    arm = lock(load(SSRMS_YAML), 1, np.deg2rad(100))
    problem = CapacityProblem(arm, TASK_R, MOTION, LIMITS.for_arm(arm), DIRS, grid_axes(), arm_configurations(arm))

    def reference(points):
        out = np.full(len(points), np.nan)
        sol = ik.solve(arm, points, TASK_R)
        for i, n in enumerate(sol.n_solutions):
            if n:
                out[i] = _posture_reference(arm, sol.q[i, :n]).min()
        return out

    return LockedEvaluator(problem, chunk=3), reference  # a small chunk: the chunks' seams are in the test


def _healthy(levels: int = 0):
    """The healthy arm's evaluator over a 60 deg grid of joint 1, its best posture followed ``levels``
    levels between grid angles; the reference per point, one posture at a time (Pinocchio's path): the
    best over every angle and solution, then the angles half a step either side of it, each with the
    solution nearest its joints, the better kept, the step halved each level."""
    robot = load(SSRMS_YAML)
    lo, hi = np.rad2deg(robot.q_lower[0]), np.rad2deg(robot.q_upper[0])
    sm = SelfMotion.build(self_motion_angles(lo, hi, 100.0, 60.0), lambda a: lock(robot, 1, np.deg2rad(a)),
                          LIMITS.for_arm, lo, hi)

    def follow(point, value, angle, q):
        h = 30.0
        for _ in range(levels):
            best = (value, angle, q)
            for a in (angle - h, angle + h):
                a = a - 360.0 if a > hi else a + 360.0 if a < lo else a  # joint 1 turns through 540 deg
                arm = lock(robot, 1, np.deg2rad(a))
                sol = ik.solve(arm, point[None], TASK_R)
                n = sol.n_solutions[0]
                if n:
                    d = [np.linalg.norm(np.angle(np.exp(1j * (sol.q[0, b] - q)))) for b in range(n)]
                    qb = sol.q[0, int(np.argmin(d))]
                    v = _posture_reference(arm, qb[None])[0]
                    if v > best[0]:
                        best = (v, a, qb)
            value, angle, q = best
            h /= 2
        return value

    def reference(points):
        out = np.full(len(points), np.nan)
        for i, point in enumerate(points):
            best = (-np.inf, None, None)
            for a, arm in zip(sm.angles_deg, sm.arms):
                sol = ik.solve(arm, point[None], TASK_R)
                for b in range(sol.n_solutions[0]):
                    v = _posture_reference(arm, sol.q[0, b:b + 1])[0]
                    if v > best[0]:
                        best = (v, a, sol.q[0, b])
            if np.isfinite(best[0]):
                out[i] = follow(point, *best)
        return out

    hp = HealthyProblem(CapacityProblem(sm.arms[0], TASK_R, MOTION, sm.limits, DIRS), sm, screening_subset(DIRS, 6),
                        levels)
    return HealthyEvaluator(hp, n_voxels=4, chunk=3), reference


EVALUATORS = {"locked": _locked, "healthy": _healthy, "healthy, followed": lambda: _healthy(3)}


@pytest.fixture(scope="module", params=sorted(EVALUATORS))
def case(request):
    ev, reference = EVALUATORS[request.param]()
    rng = np.random.default_rng(5)
    points = np.concatenate([X_INI + rng.uniform(-0.4, 0.4, (5, 3)), X_DES + rng.uniform(-0.4, 0.4, (5, 3))])
    exact = reference(points)
    assert np.isfinite(exact).sum() >= 6  # enough reachable points for the contract to say something
    return request.param, ev, points, exact


def _close(got, want):
    return np.allclose(got, want, rtol=REL, atol=ABS, equal_nan=True)


def _a_posture_at_least_the_followed_best(ev, points, got, followed):
    """Each value at least the reference's (the grid's best posture followed) and a posture's own: the
    search's posture at that point (healthy_capacity, what the evaluator calls) meets the pose, and its
    capacity recomputed one posture at a time (Pinocchio's path) is the value."""
    assert np.array_equal(np.isnan(got), np.isnan(followed))
    reach = np.isfinite(got)
    assert np.all(got[reach] >= followed[reach] - ABS - REL * np.abs(followed[reach])), np.c_[got, followed]
    hc = healthy_capacity(ev.hp, points)
    assert _close(hc.capacity_kg, got)
    robot = load(SSRMS_YAML)
    for i in np.flatnonzero(reach):
        arm = lock(robot, 1, np.deg2rad(hc.angle_deg[i]))
        assert np.allclose(arm.fk(hc.q_rad[i][None])[0, :3, 3], points[i], atol=1e-8)
        assert _close(_posture_reference(arm, hc.q_rad[i][None]), hc.capacity_kg[i:i + 1])


def test_is_an_evaluator(case):
    _, ev, _, _ = case
    assert isinstance(ev, Evaluator) and isinstance(ev.pointwise, bool)


def test_every_value_exact_without_a_ceiling(case):
    name, ev, points, exact = case
    before = ev.n_evaluated
    res = ev.evaluate(points)
    if name == "healthy, followed":  # between grid angles the search also looks where a branch ends: at least the
        _a_posture_at_least_the_followed_best(ev, points, res.capacity_kg, exact)  # followed grid best, a posture's
    else:
        assert _close(res.capacity_kg, exact), np.c_[res.capacity_kg, exact]
    assert ev.n_evaluated - before == len(points)
    assert np.array_equal(res.n_branches > 0, np.isfinite(exact))


@pytest.mark.parametrize("scale", [0.5, 1.05, 1.5])  # every owner's ceiling below, just above, well above its least value
def test_least_of_each_owner_exact_below_its_ceiling(case, scale):
    _, ev, points, exact = case
    owner = np.arange(len(points)) % 4
    least = np.array([np.nanmin(exact[owner == g]) for g in range(4)])
    ceiling = scale * least[owner]
    res = ev.evaluate(points, ceiling, owner)
    got = np.where(np.isfinite(res.capacity_kg), res.capacity_kg, np.inf)
    for g in range(4):
        mine = owner == g
        if least[g] < ceiling[mine][0]:
            assert got[mine].min() == pytest.approx(least[g], rel=REL, abs=ABS)
        # no value below the exact least one, nor below the ceiling where it stopped
        assert np.all(got[mine] >= np.minimum(least[g], ceiling[mine]) * (1 - REL) - ABS)
    assert np.array_equal(np.isfinite(res.capacity_kg), np.isfinite(exact))


def test_axis_and_configuration_values_do_not_depend_on_the_ceiling(case):
    _, ev, points, exact = case
    alone = ev.evaluate(points)
    owner = np.arange(len(points)) % 4
    capped = ev.evaluate(points, np.zeros(len(points)), owner)
    for f in ("axis_capacity_kg", "config_capacity_kg", "config_axis_capacity_kg", "config_branches"):
        a, b = getattr(alone, f), getattr(capped, f)
        assert (a is None) == (b is None)
        if a is not None:
            assert np.array_equal(a, b, equal_nan=True), f
    if alone.config_capacity_kg is not None:  # the all-branch value is the least over the configurations
        assert _close(np.fmin.reduce(alone.config_capacity_kg, axis=1), exact)


def test_pointwise_means_a_value_needs_only_its_own_point(case):
    _, ev, points, exact = case
    if not ev.pointwise:
        pytest.skip("this evaluator prunes a point by its owner's other points: the refinement shares no point")
    together = ev.evaluate(points, np.full(len(points), np.inf), np.zeros(len(points), dtype=int)).capacity_kg
    one_by_one = np.array([ev.evaluate(points[i:i + 1], np.full(1, np.inf), np.zeros(1, dtype=int)).capacity_kg[0]
                           for i in range(len(points))])
    assert np.array_equal(together, one_by_one, equal_nan=True)
