"""The healthy arm (capmap.capacity.baseline) against independent computations: each posture's capacity
from Pinocchio's Jacobian and classical acceleration, Craig's recursive Newton-Euler and an LP, maximised
over the angles and solutions by brute force; the branch and bound against evaluating every candidate;
the healthy value never below the locked arm's at any angle of the sweep, on any configuration."""

import numpy as np
import pinocchio as pin
import pytest

from capmap.capacity.baseline import healthy_capacity
from capmap.capacity.directions import Directions, exact, paper_grid, sphere
from capmap.capacity.engine import LoadLimits, Motion
from capmap.capacity.problem import CapacityProblem, point_capacity
from capmap.capacity.self_motion import HealthyProblem, Hint, SelfMotion, screening_subset, self_motion_angles
from capmap.core import ik
from capmap.core.configuration import arm_configurations
from capmap.core.reduction import lock
from capmap.errors import CapmapError
from capmap.robots import load
from tests.reference.posture_capacity import posture_capacity
from tests.scenario import SSRMS_YAML, TASK_R, X_DES, X_INI

MOTION = Motion(0.15, 0.03)
LIMITS = LoadLimits.uniform(7, 700, 200, 500)


def _subset(dirs: Directions, n: int) -> Directions:
    screen = screening_subset(dirs, n)
    assert all(any(np.array_equal(v, w) for w in dirs.u) for v in screen.u)  # a subset: its minimum bounds the set's
    return screen


@pytest.fixture(scope="module")
def robot():
    return load(SSRMS_YAML)


def _self_motion(robot, joint: int, through: float, step: float) -> SelfMotion:
    lo, hi = np.rad2deg(robot.q_lower[joint - 1]), np.rad2deg(robot.q_upper[joint - 1])
    return SelfMotion.build(self_motion_angles(lo, hi, through, step), lambda a: lock(robot, joint, np.deg2rad(a)),
                            LIMITS.for_arm)


def _hp(sm: SelfMotion, dirs: Directions, screen: Directions) -> HealthyProblem:
    """The healthy question of ``sm`` at the task orientation and motion over ``dirs``, screened by ``screen``."""
    return HealthyProblem(CapacityProblem(sm.arms[0], TASK_R, MOTION, sm.limits, dirs), sm, screen)


def test_angles_hold_the_failed_angle_one_turn_or_the_range():
    a = self_motion_angles(-270, 270, 100, 10)
    assert len(a) == 36 and np.any(np.isclose(a, 100))
    assert len(np.unique(np.round(np.mod(a, 360), 9))) == 36  # every angle mod 360 once
    assert np.all((a >= -270) & (a <= 270))
    b = self_motion_angles(-166, 166, 30, 20)  # a range under a turn: the grid inside it and both ends
    assert np.any(np.isclose(b, 30)) and b[0] == -166 and b[-1] == 166 and np.all(np.diff(b) > 0)
    assert np.allclose(np.diff(b[1:-1]), 20)
    assert len(self_motion_angles(-270, 270, 100, 7)) == 52  # 360/7 not whole: the last gap is shorter
    for bad in (0.0, -5.0, np.nan):
        with pytest.raises(CapmapError):
            self_motion_angles(-270, 270, 100, bad)
    with pytest.raises(CapmapError):
        self_motion_angles(-90, 90, 100, 10)


def _reference(robot, arm, q_active: np.ndarray, dirs: Directions, limit: np.ndarray) -> float:
    """The independent posture capacity (tests.reference.posture_capacity) over dirs; 0 at a singular posture."""
    J = pin.computeFrameJacobian(arm.reduced_model, arm.reduced_model.createData(), q_active, arm.reduced_ee_frame_id,
                                 pin.LOCAL_WORLD_ALIGNED)
    if abs(np.linalg.det(J)) < 1e-9:
        return 0.0
    return posture_capacity(robot, arm, q_active, dirs.u, MOTION.v_max_mps, MOTION.a_max_mps2, limit)


@pytest.mark.parametrize("joint, point", [(1, X_INI), (1, X_DES), (4, np.array([1.5, 3.0, 3.0]))])
def test_healthy_value_is_the_best_posture_by_brute_force(robot, joint, point):
    """The healthy value = max over the angles and every IK solution there of the posture's capacity,
    each computed independently (Pinocchio + Newton-Euler + LP) over the same directions."""
    dirs = sphere(24)
    sm = _self_motion(robot, joint, 100.0 if joint == 1 else 130.0, 60.0)
    got = healthy_capacity(_hp(sm, dirs, _subset(dirs, 6)), point[None])
    best = -np.inf
    for arm in sm.arms:
        sol = ik.solve(arm, point[None], TASK_R)
        for b in range(sol.n_solutions[0]):
            best = max(best, _reference(robot, arm, sol.q[0, b], dirs, LIMITS.for_arm(arm).limit))
    assert np.isfinite(best)
    assert got.capacity_kg[0] == pytest.approx(best, rel=1e-6, abs=1e-6)
    assert got.exact[0] and got.n_full[0] >= 1
    # the posture reported: the arm held at the reported angle, its joints there, at the pose
    arm = lock(robot, joint, np.deg2rad(got.angle_deg[0]))
    T = arm.fk(got.q_rad[:1])[0]
    np.testing.assert_allclose(T[:3, 3], point, atol=1e-7)
    np.testing.assert_allclose(T[:3, :3], TASK_R, atol=1e-7)


def _per_solution_max(sm: SelfMotion, points: np.ndarray, dirs: Directions) -> tuple[np.ndarray, np.ndarray]:
    """(N,) the max over every (angle, solution) of the solution's capacity, each solution evaluated on its
    own by point_capacity (no screening, no pruning); (N, T) the locked arm's all-branch value per angle."""
    best = np.full(len(points), -np.inf)
    locked = np.full((len(points), len(sm.arms)), np.nan)
    for t, arm in enumerate(sm.arms):  # each angle's own arm, dynamics and limits
        lim = LIMITS.for_arm(arm)
        sol = ik.solve(arm, points, TASK_R)
        p, b = np.nonzero(np.arange(sol.q.shape[1])[None, :] < sol.n_solutions[:, None])
        problem = CapacityProblem(arm, TASK_R, MOTION, lim, dirs)
        one = point_capacity(problem, sol.q[p, b][:, None, :], np.ones(len(p), dtype=int))
        np.maximum.at(best, p, one.capacity_kg)
        locked[:, t] = point_capacity(problem, sol.q, sol.n_solutions).capacity_kg
    return np.where(np.isfinite(best), best, np.nan), locked


@pytest.fixture(scope="module")
def sweep(robot):
    rng = np.random.default_rng(5)
    points = rng.uniform([-6, -6, -4], [6, 8, 8], (120, 3))
    dirs = paper_grid(30.0)
    sm = _self_motion(robot, 1, 100.0, 30.0)
    return sm, points, dirs


@pytest.mark.parametrize("n_screen", [1, 8, 40])
def test_branch_and_bound_equals_every_candidate_evaluated(sweep, n_screen):
    """Any screening subset (down to one direction) gives the exact maximum: pruning only drops
    candidates whose bound cannot beat the best found."""
    sm, points, dirs = sweep
    got = healthy_capacity(_hp(sm, dirs, _subset(dirs, n_screen)), points)
    ref, _ = _per_solution_max(sm, points, dirs)
    assert np.array_equal(np.isnan(got.capacity_kg), np.isnan(ref))
    ok = np.isfinite(ref)
    assert ok.sum() > 60
    np.testing.assert_allclose(got.capacity_kg[ok], ref[ok], rtol=1e-9, atol=1e-9)
    assert np.all(got.n_full[ok] <= got.n_candidates[ok])


@pytest.mark.parametrize("n_screen", [4, 16])
def test_on_the_whole_sphere_a_screen_of_its_start_directions_only_bounds(sweep, n_screen):
    """The whole sphere (the default set): its 16 start directions, even all of them, are a subset of the
    motion set whose minimum lies above the sphere's; the value is still every candidate's on the sphere."""
    sm, points, _ = sweep
    dirs = exact()
    got = healthy_capacity(_hp(sm, dirs, screening_subset(dirs, n_screen)), points[:40])
    ref, _ = _per_solution_max(sm, points[:40], dirs)
    ok = np.isfinite(ref)
    assert ok.sum() > 20 and np.array_equal(np.isnan(got.capacity_kg), np.isnan(ref))
    np.testing.assert_allclose(got.capacity_kg[ok], ref[ok], rtol=1e-9, atol=1e-9)


def test_a_ceiling_stops_only_points_at_or_above_it(sweep):
    sm, points, dirs = sweep
    exact = healthy_capacity(_hp(sm, dirs, _subset(dirs, 8)), points)
    ceiling = np.nan_to_num(exact.capacity_kg, nan=1.0) * np.where(np.arange(len(points)) % 2, 0.9, 1.1)
    got = healthy_capacity(_hp(sm, dirs, _subset(dirs, 8)), points, ceiling)
    below = np.isfinite(exact.capacity_kg) & (exact.capacity_kg < ceiling)
    np.testing.assert_allclose(got.capacity_kg[below], exact.capacity_kg[below], rtol=1e-12)
    above = np.isfinite(exact.capacity_kg) & ~below
    assert np.all(got.capacity_kg[above] >= ceiling[above]) and np.all(got.capacity_kg[above] <= exact.capacity_kg[above])
    assert np.all(got.exact[below]) and got.n_full.sum() <= exact.n_full.sum()


def test_healthy_never_below_the_locked_arm_at_any_swept_angle_on_any_configuration(sweep):
    sm, points, dirs = sweep
    got = healthy_capacity(_hp(sm, dirs, _subset(dirs, 8)), points)
    _, locked = _per_solution_max(sm, points, dirs)
    reach = np.isfinite(locked)
    assert reach.any(axis=1).sum() > 60
    assert np.all(got.capacity_kg[:, None][reach.any(axis=1)] >= np.nanmax(locked, axis=1)[reach.any(axis=1), None] - 1e-9)
    for t, arm in enumerate(sm.arms):  # per configuration too
        sol = ik.solve(arm, points, TASK_R)
        problem = CapacityProblem(arm, TASK_R, MOTION, LIMITS.for_arm(arm), dirs, labels=arm_configurations(arm))
        pc = point_capacity(problem, sol.q, sol.n_solutions)
        has = np.isfinite(pc.config_capacity_kg)
        assert np.all(np.repeat(got.capacity_kg[:, None], has.shape[1], axis=1)[has] >= pc.config_capacity_kg[has] - 1e-9)


def test_groups_need_only_their_least_value_exact(sweep):
    """With the points' voxels given, each voxel's least value is exact and attained; every other value
    is a lower bound of the point's own (a posture found) at or above that least value."""
    sm, points, dirs = sweep
    exact = healthy_capacity(_hp(sm, dirs, _subset(dirs, 8)), points)
    groups = np.random.default_rng(3).integers(0, 12, len(points))
    got = healthy_capacity(_hp(sm, dirs, _subset(dirs, 8)), points, groups=groups)
    assert got.n_full.sum() < exact.n_full.sum()
    for g in np.unique(groups):
        mine = (groups == g) & np.isfinite(exact.capacity_kg)
        if not mine.any():
            continue
        low = exact.capacity_kg[mine].min()
        assert got.capacity_kg[mine].min() == pytest.approx(low, rel=1e-12, abs=1e-12)
        assert np.all(got.capacity_kg[mine] <= exact.capacity_kg[mine] + 1e-9)
        assert np.all(got.capacity_kg[mine] >= low - 1e-9)
        assert np.all(got.exact[mine] | (got.capacity_kg[mine] >= low - 1e-9))


def test_hints_and_ceilings_keep_each_groups_least_value_below_its_ceiling_exact(sweep):
    sm, points, dirs = sweep
    exact = healthy_capacity(_hp(sm, dirs, _subset(dirs, 8)), points)
    rng = np.random.default_rng(4)
    groups = rng.integers(0, 12, len(points))
    low = {g: np.nanmin(exact.capacity_kg[groups == g], initial=np.inf) for g in np.unique(groups)}
    factor = {g: 1.05 if g % 2 else 0.95 for g in low}  # the group's least value below / above its ceiling
    ceiling = np.array([low[g] * factor[g] if np.isfinite(low[g]) else np.inf for g in groups])
    hint = Hint(rng.integers(-1, len(sm.angles_deg), len(points)), rng.integers(-1, 8, len(points)))
    got = healthy_capacity(_hp(sm, dirs, _subset(dirs, 8)), points, ceiling, groups, hint)
    assert np.array_equal(np.isnan(got.capacity_kg), np.isnan(exact.capacity_kg))
    fin = np.isfinite(exact.capacity_kg)
    assert np.all(got.capacity_kg[fin] <= exact.capacity_kg[fin] + 1e-9)  # a posture's value: never above the best
    for g in low:
        mine = (groups == g) & fin
        if not mine.any():
            continue
        if factor[g] > 1:
            assert got.capacity_kg[mine].min() == pytest.approx(low[g], rel=1e-12, abs=1e-12)
        else:
            assert np.all(got.capacity_kg[mine] >= ceiling[mine] - 1e-9)
    # the posture reported reaches the pose at the reported angle
    for i in np.flatnonzero(fin)[:10]:
        arm = sm.arms[int(np.searchsorted(sm.angles_deg, got.angle_deg[i]))]
        np.testing.assert_allclose(arm.fk(got.q_rad[i:i + 1])[0][:3, 3], points[i], atol=1e-7)
