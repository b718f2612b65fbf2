"""The failure-tolerant map (capmap.capacity.tolerant) against independent computations: on random
sweeps, the minimum over every (joint, angle) by a plain loop; on the SSRMS-type arm, the value of
random voxels against each lock's capacity at the voxel's points computed independently (every IK
solution, each posture's capacity from Pinocchio's Jacobian, Craig's Newton-Euler and an LP)."""

import numpy as np
import pandas as pd
import pinocchio as pin
import pytest

from capmap.capacity.directions import grid_axes, sphere
from capmap.capacity.engine import LoadLimits, Motion
from capmap.capacity.lock_sweep import SWEEP_COLUMNS, lock_angles, lock_sweep
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.tolerant import failure_tolerant, lock_reach, tolerance_summary
from capmap.capacity.voxels import Grid
from capmap.core import ik
from capmap.core.reduction import lock
from capmap.errors import CapmapError
from capmap.robots import load
from tests.reference.posture_capacity import posture_capacity
from tests.scenario import SSRMS_YAML, TASK_R

MOTION = Motion(0.15, 0.03)
LIMITS = LoadLimits.uniform(7, 700, 200, 500)


def _random_sweeps(rng, joints=(1, 2, 3), angles=(-90.0, 0.0, 45.0, 170.0), voxels=40, unreached=0.1):
    """Sweeps on one set of voxels of 2 points each: random capacities, some locks reaching one point or none."""
    ijk = np.stack(np.unravel_index(rng.choice(5 * 5 * 5, voxels, replace=False), (5, 5, 5)), axis=1)
    rows = []
    for j in joints:
        for a in angles:
            cap = rng.uniform(0, 5000, voxels)
            n_reach = np.where(rng.random(voxels) < unreached, rng.integers(0, 2, voxels), 2)
            cap[n_reach == 0] = np.nan
            rows.append(pd.DataFrame({"joint": j, "angle_deg": a, "i": ijk[:, 0], "j": ijk[:, 1], "k": ijk[:, 2],
                                      "x_m": ijk[:, 0] + 0.5, "y_m": ijk[:, 1] + 0.5, "z_m": ijk[:, 2] + 0.5,
                                      "n_points": 2, "n_reachable": n_reach, "capacity_kg": cap}))
    return pd.concat(rows, ignore_index=True).sample(frac=1.0, random_state=1)  # any order, any index


def _whole(mine: pd.DataFrame) -> np.ndarray:
    """Per row: its capacity where the lock reaches both points of the voxel, else NaN (by hand)."""
    return np.array([c if n == 2 else np.nan for c, n in zip(mine.capacity_kg, mine.n_reachable)])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_minimum_over_every_joint_and_angle_by_a_plain_loop(seed):
    sweeps = _random_sweeps(np.random.default_rng(seed))
    tol = failure_tolerant(sweeps)
    reach = lock_reach(sweeps)
    rank = {(r.joint, r.angle_deg): n for n, r in enumerate(reach.itertuples())}
    assert list(tol[["i", "j", "k"]].itertuples(index=False)) == sorted(tol[["i", "j", "k"]].itertuples(index=False))
    for r in tol.itertuples():
        mine = sweeps[(sweeps.i == r.i) & (sweeps.j == r.j) & (sweeps.k == r.k)]
        values = _whole(mine)
        lock = (r.binding_joint, r.binding_angle_deg)
        if np.isnan(values).any():  # some lock leaves it (wholly or in part): no guarantee
            assert np.isnan(r.tolerant_capacity_kg) and not r.reachable_every_failure
            leaving = [(j, a) for j, a, v in zip(mine.joint, mine.angle_deg, values) if np.isnan(v)]
            if np.isfinite(values).any():  # the lock leaving it that reaches the fewest voxels binds
                assert lock == min(leaving, key=rank.get)
            else:
                assert r.binding_joint == -1 and np.isnan(r.binding_angle_deg)
        else:
            assert r.reachable_every_failure and r.tolerant_capacity_kg == values.min()
            assert values[[(j, a) == lock for j, a in zip(mine.joint, mine.angle_deg)]][0] == values.min()
        for j, g in mine.groupby("joint"):
            per, v = getattr(r, f"tolerant_j{j}_capacity_kg"), _whole(g)
            assert np.isnan(per) if np.isnan(v).any() else per == v.min()
        best = np.nanmax(values) if np.isfinite(values).any() else np.nan
        assert r.healthy_capacity_kg == best or (np.isnan(best) and np.isnan(r.healthy_capacity_kg))
        assert r.n_locks == 12 and r.n_locks_reaching == np.isfinite(values).sum()
        # the sweep at twice the step: every other angle of each joint (-90 and 45 deg here)
        coarse = values[mine.angle_deg.isin([-90.0, 45.0]).to_numpy()]
        ref = np.nan if np.isnan(coarse).any() else coarse.min()
        assert (np.isnan(r.tolerant_capacity_double_step_kg) and np.isnan(ref)) or r.tolerant_capacity_double_step_kg == ref


def test_a_lock_leaving_out_a_voxel_and_sweeps_on_other_voxels():
    sweeps = _random_sweeps(np.random.default_rng(5), unreached=0.0)
    assert failure_tolerant(sweeps).reachable_every_failure.all()
    with pytest.raises(CapmapError, match="not on one set of voxels"):
        failure_tolerant(sweeps.iloc[1:])
    reach = lock_reach(sweeps)
    assert len(reach) == 12 and (reach.n_reached == 40).all()


def test_summary_volumes_and_the_step_drop_per_scope():
    tol = failure_tolerant(_random_sweeps(np.random.default_rng(3), unreached=0.02))
    s = tolerance_summary(tol, 0.5, (1000.0, 2500.0))
    assert set(s.scope) == {"healthy", "joint 1", "joint 2", "joint 3", "any joint"}
    for scope, col in (("any joint", "tolerant_capacity"), ("joint 2", "tolerant_j2_capacity")):
        rows = s[s.scope == scope].set_index("payload_kg")
        for m in (1000.0, 2500.0):
            assert rows.volume_m3[m] == pytest.approx((tol[f"{col}_kg"] >= m).sum() * 0.125)
            assert rows.volume_double_step_m3[m] == pytest.approx((tol[f"{col}_double_step_kg"] >= m).sum() * 0.125)
            assert rows.volume_double_step_m3[m] >= rows.volume_m3[m]  # more angles can only lower the minimum
        ok = tol[f"{col}_kg"].notna() & tol[f"{col}_double_step_kg"].gt(0)
        drop = ((tol[f"{col}_double_step_kg"] - tol[f"{col}_kg"]) / tol[f"{col}_double_step_kg"])[ok].max()
        assert rows.double_step_drop_max_rel.iloc[0] == pytest.approx(drop)
    h = s[(s.scope == "healthy") & (s.payload_kg == 1000.0)].volume_m3.iloc[0]
    assert h == pytest.approx((tol.healthy_capacity_kg >= 1000.0).sum() * 0.125)
    empty = tol.assign(tolerant_capacity_kg=np.nan, tolerant_capacity_double_step_kg=np.nan)
    e = tolerance_summary(empty, 0.5, (1000.0,))
    assert np.isnan(e[e.scope == "any joint"].double_step_drop_max_rel.iloc[0])  # nothing to compare: no 0 %


def _independent(robot, joint: int, angle: float, points: np.ndarray, dirs) -> np.ndarray:
    """(N,) the least over every IK solution at each point of its posture capacity (independent: Pinocchio +
    Newton-Euler + LP) with ``joint`` locked at ``angle`` deg; NaN where the arm does not reach the point."""
    arm = lock(robot, joint, np.deg2rad(angle))
    limit = LIMITS.for_arm(arm).limit
    sol = ik.solve(arm, points, TASK_R)
    out = np.full(len(points), np.nan)
    for p in range(len(points)):
        for b in range(sol.n_solutions[p]):
            q = sol.q[p, b]
            J = pin.computeFrameJacobian(arm.reduced_model, arm.reduced_model.createData(), q,
                                         arm.reduced_ee_frame_id, pin.LOCAL_WORLD_ALIGNED)
            c = 0.0 if abs(np.linalg.det(J)) < 1e-9 else posture_capacity(
                robot, arm, q, dirs.u, MOTION.v_max_mps, MOTION.a_max_mps2, limit)
            out[p] = np.fmin(out[p], c)
    return out


@pytest.mark.slow  # ~30 s of LPs; the plain loop above checks the minimum itself in the quick suite
def test_every_voxel_equals_the_minimum_over_independently_computed_locked_maps():
    """Joints 1, 3 and 7 each locked at two angles, the sweeps on one set of points; at every voxel the
    failure-tolerant value equals the least, over the six locks, of each lock's voxel value computed
    independently (the least over the voxel's points the lock reaches; none reached: no guarantee)."""
    robot = load(SSRMS_YAML)
    dirs = sphere(4)
    rng = np.random.default_rng(11)
    edge = 2.0
    points = rng.uniform([-2.0, 0.0, -1.0], [4.0, 6.0, 5.0], (24, 3))  # a lock reaching part of a voxel leaves it
    sweeps, locks = [], []
    for joint, through in ((1, 100.0), (3, 98.0), (7, 57.0)):
        angles = lock_angles(robot, joint, through, 180.0)
        assert len(angles) == 2
        locks += [(joint, float(a)) for a in angles]
        sweeps.append(lock_sweep(lambda a, j=joint: CapacityProblem(
            lock(robot, j, np.deg2rad(a)), TASK_R, MOTION, LIMITS.for_arm(lock(robot, j, np.deg2rad(a))), dirs,
            grid_axes()), joint, angles, points, edge))
    sweeps = pd.concat(sweeps, ignore_index=True)
    assert list(sweeps.columns) == SWEEP_COLUMNS
    tol = failure_tolerant(sweeps)
    per_point = np.array([_independent(robot, j, a, points, dirs) for j, a in locks])  # (locks, N)
    flat = Grid.covering(points, edge).flat(Grid.covering(points, edge).index(points))
    grid = Grid.covering(points, edge)
    assert len(tol) == len(np.unique(flat))
    for r in tol.itertuples():
        mine = per_point[:, flat == grid.flat(np.array([r.i, r.j, r.k]))]
        per_lock = np.array([np.min(v) if np.isfinite(v).all() else np.nan for v in mine])
        if np.isnan(per_lock).any():
            assert np.isnan(r.tolerant_capacity_kg) and not r.reachable_every_failure
        else:
            assert r.tolerant_capacity_kg == pytest.approx(per_lock.min(), rel=1e-6, abs=1e-6)
        for j in (1, 3, 7):
            sub = per_lock[[n for n, (jj, _) in enumerate(locks) if jj == j]]
            got = getattr(r, f"tolerant_j{j}_capacity_kg")
            assert np.isnan(got) if np.isnan(sub).any() else got == pytest.approx(sub.min(), rel=1e-6, abs=1e-6)
    guaranteed = tol[tol.reachable_every_failure]
    assert len(guaranteed) >= 3 and guaranteed.binding_joint.nunique() >= 2  # more than one joint decides somewhere
