"""The lock-angle advice (capmap.capacity.advice) against an independent brute force over the lock
angles of the SSRMS-type arm's joint 1 on a coarse map: at each angle each task starts on the IK
solution nearest its start configuration (every solution and whole turn tried), its direct line and the
A* path on that lock's map are verified carrying its payload, the worst task's margin is taken, and the
best angle chosen; the advice must agree. And the healthy reference is never below a locked arm's."""

from itertools import product

import numpy as np
import pandas as pd
import pytest

from capmap.capacity import planning
from capmap.capacity.advice import (
    ADVICE_TASK_COLUMNS,
    AdviceSettings,
    convergence,
    full_grid,
    healthy_lines,
    neighbours_worst,
    recommend,
    tasks_at_lock,
)
from capmap.capacity.directions import grid_axes, sphere
from capmap.capacity.engine import LoadLimits, Motion
from capmap.capacity.healthy_map import healthy_samples
from capmap.capacity.lock_sweep import lock_angles, lock_sweep
from capmap.capacity.problem import CapacityProblem
from capmap.capacity.tables import AXIS_COLUMNS
from capmap.capacity.verification import judge, verify_path
from capmap.capacity.voxels import Grid
from capmap.config.capacity import SamplingConfig
from capmap.config.jobs import PlanTask
from capmap.core import ik
from capmap.core.reduction import lock
from capmap.errors import CapmapError, NoPath
from capmap.robots import load
from tests.scenario import Q_INI_DEG, SSRMS_YAML, TASK_R, X_DES, X_INI

MOTION = Motion(0.15, 0.03)
LIMITS = LoadLimits.uniform(7, 700, 200, 500)
DT = 0.5
EDGE = 2.5
TASKS = [PlanTask(1500.0, tuple(X_INI), tuple(X_DES), tuple(Q_INI_DEG)),
         PlanTask(4000.0, tuple(X_INI), tuple(X_DES), tuple(Q_INI_DEG)),
         PlanTask(2000.0, (2.0, 4.0, 3.0), (-1.0, 5.0, 1.0), tuple(Q_INI_DEG), name="aside"),
         PlanTask(0.0, (2.0, 4.0, 3.0), (-1.0, 5.0, 1.0), tuple(Q_INI_DEG), name="reach")]
# the run's own planned path of a task (here a detour over the line's midpoint), verified at every angle too
RUN_PLANS = [np.array([X_INI, 0.5 * (X_INI + X_DES) + [0.0, 0.0, 1.0], X_DES]), None, None, None]


def _problem(robot, angle: float) -> CapacityProblem:
    arm = lock(robot, 1, np.deg2rad(angle))
    return CapacityProblem(arm, TASK_R, MOTION, LIMITS.for_arm(arm), sphere(12), grid_axes())


@pytest.fixture(scope="module")
def swept():
    robot = load(SSRMS_YAML)
    points, _ = healthy_samples(robot, SamplingConfig("voxel_fill", 300, 7, 0), EDGE)
    angles = lock_angles(robot, 1, 100.0, 45.0)
    sweep = lock_sweep(lambda a: _problem(robot, a), 1, angles, points, EDGE)
    grid = Grid.covering(points, EDGE)
    rows = []
    for a, vox in sweep.groupby("angle_deg", sort=True):
        for r in tasks_at_lock(_problem(robot, a), full_grid(vox, grid), grid, TASKS, AdviceSettings(DT), RUN_PLANS):
            rows.append({"joint": 1, "angle_deg": a, **r})
    return robot, sweep, grid, pd.DataFrame(rows)


def _start(arm, task) -> np.ndarray | None:
    """Brute force: every IK solution at the start, each joint shifted by -1, 0 or +1 turn within its range,
    the one nearest the task's start configuration (largest joint difference)."""
    sol = ik.solve(arm, np.asarray(task.start_m)[None], TASK_R)
    ref = np.deg2rad(np.asarray(task.q_start_deg))[arm.active]
    best, best_off = None, np.inf
    for b in range(sol.n_solutions[0]):
        q = sol.q[0, b]
        cand = []
        for c in range(len(q)):
            shifts = [q[c] + k * 2 * np.pi for k in (-1, 0, 1)]
            ok = [s for s in shifts if arm.q_lower[c] - 1e-12 <= s <= arm.q_upper[c] + 1e-12] or [q[c]]
            cand.append(min(ok, key=lambda s, c=c: abs(s - ref[c])))
        cand = np.array(cand)
        off = np.abs(cand - ref).max()
        if off < best_off:
            best, best_off = cand, off
    return best


def _carries(problem, waypoints, q0, payload) -> float:
    res = verify_path(problem.dyn, waypoints, problem.rotation, q0, problem.motion, DT, problem.limits)
    _, v = judge(res, problem.arm, problem.limits, payload)
    return v.capacity_kg if v.tracking == "ok" and v.joint_range == "ok" else 0.0


def _line_least(cap: np.ndarray, grid: Grid, a, b) -> float:
    """Least map capacity on the segment a -> b, sampled densely (unreached voxels 0 kg)."""
    p = np.asarray(a) + np.linspace(0, 1, 2001)[:, None] * (np.asarray(b) - np.asarray(a))
    idx = grid.index(p)
    c = cap[np.unique(grid.flat(idx[idx[:, 0] >= 0]))]
    return float(np.nan_to_num(c, nan=0.0).min())


def _plan(grid, cap, axis, task, payload):
    return planning.plan(grid, cap, np.asarray(task.start_m), np.asarray(task.goal_m), payload, axis).waypoints


def _widest(grid, cap, axis, task):
    """The path for the largest payload any path on the map carries (bisected to 1 % of the task's)."""
    try:
        wp = _plan(grid, cap, axis, task, 0.0)
    except CapmapError:  # no path at all, or the start or goal voxel unreached: no plan
        return None
    lo, hi = 0.0, task.payload_kg
    while hi - lo > 0.01 * task.payload_kg:
        mid = 0.5 * (lo + hi)
        try:
            wp, lo = _plan(grid, cap, axis, task, mid), mid
        except NoPath:
            hi = mid
    return wp


def _brute_force(robot, sweep, grid):
    """Per angle: the worst task's margin [%] and the mean map capacity over the tasks' lines, by the brute
    force above."""
    out = {}
    for a, vox in sweep.groupby("angle_deg", sort=True):
        problem = _problem(robot, a)
        full = full_grid(vox, grid)
        cap, axis = full.capacity_kg.to_numpy(), full[AXIS_COLUMNS].to_numpy()
        margins, region = [], set()
        for task, known in zip(TASKS, RUN_PLANS):
            m = task.payload_kg
            p = np.asarray(task.start_m) + np.linspace(0, 1, 2001)[:, None] * (np.asarray(task.goal_m) - task.start_m)
            idx = grid.index(p)
            region |= set(grid.flat(idx[idx[:, 0] >= 0]).tolist())
            q0 = _start(problem.arm, task)
            if q0 is None:
                margins.append(-100.0)
                continue
            paths = [np.array([task.start_m, task.goal_m]), known]
            try:
                paths.append(_plan(grid, cap, axis, task, m))
            except NoPath:
                paths.append(_widest(grid, cap, axis, task))
            except CapmapError:
                pass
            carried = [_carries(problem, wp, q0, m) for wp in paths if wp is not None]
            best = max(carried)
            margins.append(100 * (best - m) / m if m > 0 else (0.0 if best >= 0 and any(
                c >= 0 and _executable(problem, wp, q0) for c, wp in zip(carried, [w for w in paths if w is not None]))
                else -100.0))
        out[a] = (min(margins), float(np.mean(np.nan_to_num(cap[sorted(region)], nan=0.0))))
    return out


def _executable(problem, waypoints, q0) -> bool:
    res = verify_path(problem.dyn, waypoints, problem.rotation, q0, problem.motion, DT, problem.limits)
    _, v = judge(res, problem.arm, problem.limits, 0.0)
    return v.tracking == "ok" and v.joint_range == "ok"


def test_recommended_angle_equals_a_brute_force_over_the_angles(swept):
    robot, sweep, grid, rows = swept
    assert list(rows.columns) == ADVICE_TASK_COLUMNS
    brute = _brute_force(robot, sweep, grid)
    per_angle = rows.groupby("angle_deg").agg(worst=("margin_pct", "min"), region=("region_capacity_kg", "first"))
    for a, (worst, region) in brute.items():
        assert per_angle.worst[a] == pytest.approx(worst, abs=1e-6)
        assert per_angle.region[a] == pytest.approx(region, rel=1e-12)
    top = max(brute.values())
    best = [a for a, v in brute.items() if v == top]
    best = min(best, key=lambda a: abs(a - 100.0))  # ties: nearest the angle the joint stands at
    got = recommend(rows, 100.0)
    assert got.angle_deg == best and got.worst_margin_pct == pytest.approx(brute[best][0], abs=1e-6)
    assert len(set(np.round([v[0] for v in brute.values()], 6))) > 1  # the angle matters: not a flat sweep


def test_ties_go_to_the_task_region_then_to_the_angle_nearest_where_the_joint_stands():
    def rows(worst, region):
        return pd.DataFrame({"angle_deg": [0.0, 60.0, 120.0, 180.0], "task": "a", "payload_kg": 1.0,
                             "margin_pct": worst, "line_margin_pct": 0.0, "region_capacity_kg": region,
                             "feasible": True})
    assert recommend(rows([5.0, 5.0, 5.0, 1.0], [10.0, 30.0, 20.0, 99.0]), 170.0).angle_deg == 60.0
    assert recommend(rows([5.0, 5.0, 5.0, 1.0], [10.0, 30.0, 30.0, 99.0]), 170.0).angle_deg == 120.0
    assert recommend(rows([5.0, 5.0, 5.0, 1.0], [10.0, 30.0, 30.0, 99.0]), 0.0).angle_deg == 60.0
    assert recommend(rows([-100.0, 2.0, -3.0, 1.0], [10.0, 0.0, 30.0, 99.0]), 0.0).angle_deg == 60.0


def test_each_row_is_its_best_verified_path(swept):
    _, _, _, rows = swept
    ran = rows[rows.direct_note != "start not reachable"]
    assert len(ran) > 0 and ran.run_plan_capacity_kg[ran.payload_kg == 1500].notna().all()
    best = np.fmax(np.maximum(ran.direct_capacity_kg, ran.planned_capacity_kg), ran.run_plan_capacity_kg)
    np.testing.assert_allclose(ran.capacity_kg, best)
    paid = rows.payload_kg > 0
    np.testing.assert_allclose(rows.margin_pct[paid], 100 * (rows.capacity_kg - rows.payload_kg)[paid] / rows.payload_kg[paid])
    assert (rows.feasible[paid] == (rows.capacity_kg >= rows.payload_kg)[paid]).all()
    reach = rows[~paid]  # a 0 kg task: 0 % where a path is executable, -100 % where none is
    assert set(reach.margin_pct) <= {0.0, -100.0} and (reach.margin_pct == np.where(reach.feasible, 0.0, -100.0)).all()
    widest = rows[rows.planned_note.str.contains("the widest carries")]
    assert len(widest) and (widest.planned_payload_kg < widest.payload_kg).all()


def test_healthy_reference_is_never_below_a_locked_arm(swept):
    _, sweep, grid, rows = swept
    h = healthy_lines(sweep, grid, TASKS).set_index(["task", "payload_kg"])
    for (task, m), g in rows.groupby(["task", "payload_kg"]):
        assert (g.line_capacity_kg <= h.line_capacity_kg[(task, m)] + 1e-9).all()
        assert h.line_capacity_kg[(task, m)] == pytest.approx(g.line_capacity_kg.max())  # joint 1's own sweep


def test_convergence_takes_every_other_and_every_fourth_angle():
    angles = np.arange(-80.0, 280.0, 10.0)
    rng = np.random.default_rng(0)
    rows = pd.DataFrame([{"angle_deg": a, "task": t, "payload_kg": 1000.0, "margin_pct": rng.uniform(-50, 50),
                          "line_margin_pct": 0.0, "region_capacity_kg": 0.0, "feasible": True}
                         for a, t in product(angles, ("a", "b"))])
    conv = convergence(rows, 100.0, 10.0)
    assert list(conv.step_deg) == [40.0, 20.0, 10.0] and list(conv.n_angles) == [9, 18, 36]
    for r in conv.itertuples():
        keep = angles[np.rint((angles - 100.0) / 10.0).astype(int) % int(r.step_deg / 10) == 0]
        worst = rows[rows.angle_deg.isin(keep)].groupby("angle_deg").margin_pct.min()
        assert r.recommended_angle_deg == worst.idxmax() and r.worst_margin_pct == worst.max()
        assert 100.0 in keep


def test_neighbours_worst_takes_the_swept_angles_either_side_a_turn_round():
    angles = np.arange(-80.0, 280.0, 10.0)  # one turn: -80 and 270 are neighbours
    rows = pd.DataFrame({"angle_deg": angles, "task": "a", "payload_kg": 1.0, "margin_pct": angles / 10,
                         "line_margin_pct": 0.0, "region_capacity_kg": 0.0, "feasible": True})
    assert neighbours_worst(rows, 100.0) == 9.0 and neighbours_worst(rows, -80.0) == -7.0
    assert neighbours_worst(rows, 270.0) == -8.0
    part = rows[rows.angle_deg <= 0]  # under a turn: the ends have one neighbour
    assert neighbours_worst(part, -80.0) == -7.0 and neighbours_worst(part, 0.0) == -1.0
