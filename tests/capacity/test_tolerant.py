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
    """Sweeps on one set of voxels: random capacities, some locks not reaching some voxels."""
    ijk = np.stack(np.unravel_index(rng.choice(5 * 5 * 5, voxels, replace=False), (5, 5, 5)), axis=1)
    rows = []
    for j in joints:
        for a in angles:
            cap = rng.uniform(0, 5000, voxels)
            cap[rng.random(voxels) < unreached] = np.nan
            rows.append(pd.DataFrame({"joint": j, "angle_deg": a, "i": ijk[:, 0], "j": ijk[:, 1], "k": ijk[:, 2],
                                      "x_m": ijk[:, 0] + 0.5, "y_m": ijk[:, 1] + 0.5, "z_m": ijk[:, 2] + 0.5,
                                      "capacity_kg": cap}))
    return pd.concat(rows, ignore_index=True).sample(frac=1.0, random_state=1, ignore_index=True)  # any order


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_minimum_over_every_joint_and_angle_by_a_plain_loop(seed):
    sweeps = _random_sweeps(np.random.default_rng(seed))
    tol = failure_tolerant(sweeps)
    assert list(tol[["i", "j", "k"]].itertuples(index=False)) == sorted(tol[["i", "j", "k"]].itertuples(index=False))
    for r in tol.itertuples():
        mine = sweeps[(sweeps.i == r.i) & (sweeps.j == r.j) & (sweeps.k == r.k)]
        values = mine.capacity_kg.to_numpy()
        if np.isnan(values).any():  # some lock leaves it: no guarantee, and that lock binds
            assert np.isnan(r.tolerant_capacity_kg) and not r.reachable_every_failure
            b = mine[(mine.joint == r.binding_joint) & (mine.angle_deg == r.binding_angle_deg)]
            assert b.capacity_kg.isna().all()
        else:
            assert r.reachable_every_failure and r.tolerant_capacity_kg == values.min()
            b = mine[(mine.joint == r.binding_joint) & (mine.angle_deg == r.binding_angle_deg)]
            assert b.capacity_kg.iloc[0] == values.min()
        for j, g in mine.groupby("joint"):
            per = getattr(r, f"tolerant_j{j}_capacity_kg")
            assert (np.isnan(per) if g.capacity_kg.isna().any() else per == g.capacity_kg.min())
        assert r.healthy_capacity_kg == np.nanmax(values) if np.isfinite(values).any() else np.isnan(r.healthy_capacity_kg)
        assert r.n_locks == 12 and r.n_locks_reaching == np.isfinite(values).sum()
        # the sweep at twice the step: every other angle of each joint (-90 and 45 deg here)
        coarse = mine[mine.angle_deg.isin([-90.0, 45.0])].capacity_kg.to_numpy()
        ref = np.nan if np.isnan(coarse).any() else coarse.min()
        assert (np.isnan(r.tolerant_capacity_double_step_kg) and np.isnan(ref)) or r.tolerant_capacity_double_step_kg == ref


def test_a_lock_leaving_out_a_voxel_and_sweeps_on_other_voxels():
    sweeps = _random_sweeps(np.random.default_rng(5), unreached=0.0)
    assert failure_tolerant(sweeps).reachable_every_failure.all()
    with pytest.raises(CapmapError, match="not on one set of voxels"):
        failure_tolerant(sweeps.iloc[1:])
    reach = lock_reach(sweeps)
    assert len(reach) == 12 and (reach.n_reached == 40).all()


def test_summary_volumes_count_the_voxels_carrying_each_payload():
    tol = failure_tolerant(_random_sweeps(np.random.default_rng(3), unreached=0.02))
    s = tolerance_summary(tol, 0.5, (1000.0, 2500.0))
    any_joint = s[s.scope == "any joint"].set_index("payload_kg")
    for m in (1000.0, 2500.0):
        assert any_joint.volume_m3[m] == pytest.approx((tol.tolerant_capacity_kg >= m).sum() * 0.125)
        h = s[(s.scope == "healthy") & (s.payload_kg == m)].volume_m3.iloc[0]
        assert h == pytest.approx((tol.healthy_capacity_kg >= m).sum() * 0.125) and h >= any_joint.volume_m3[m]
    assert set(s.scope) == {"healthy", "joint 1", "joint 2", "joint 3", "any joint"}


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
    points = rng.uniform([-2.0, 0.0, -1.0], [4.0, 6.0, 5.0], (24, 3))
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
        per_lock = np.array([np.nanmin(v) if np.isfinite(v).any() else np.nan for v in mine])
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
