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
         PlanTask(2000.0, (2.0, 4.0, 3.0), (-1.0, 5.0, 1.0), tuple(Q_INI_DEG), name="aside")]


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
        for r in tasks_at_lock(_problem(robot, a), full_grid(vox, grid), grid, TASKS, AdviceSettings(DT)):
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


def _brute_force(robot, sweep, grid):
    """Per angle: the worst task's margin [%] and the worst line margin [%], by the brute force above."""
    out = {}
    for a, vox in sweep.groupby("angle_deg", sort=True):
        problem = _problem(robot, a)
        full = full_grid(vox, grid)
        cap, axis = full.capacity_kg.to_numpy(), full[AXIS_COLUMNS].to_numpy()
        margins, lines = [], []
        for task in TASKS:
            m = task.payload_kg
            lines.append(100 * (_line_least(cap, grid, task.start_m, task.goal_m) - m) / m)
            q0 = _start(problem.arm, task)
            if q0 is None:
                margins.append(-100.0)
                continue
            carried = [_carries(problem, np.array([task.start_m, task.goal_m]), q0, m)]
            for payload in (m, 0.0):
                try:
                    p = planning.plan(grid, cap, np.asarray(task.start_m), np.asarray(task.goal_m), payload, axis)
                except NoPath:
                    continue
                except CapmapError:  # the start or goal voxel unreached on this map: no plan at all
                    break
                carried.append(_carries(problem, p.waypoints, q0, m))
                break
            margins.append(100 * (max(carried) - m) / m)
        out[a] = (min(margins), min(lines))
    return out


def test_recommended_angle_equals_a_brute_force_over_the_angles(swept):
    robot, sweep, grid, rows = swept
    assert list(rows.columns) == ADVICE_TASK_COLUMNS
    brute = _brute_force(robot, sweep, grid)
    per_angle = rows.groupby("angle_deg").agg(worst=("margin_pct", "min"), line=("line_margin_pct", "min"))
    for a, (worst, line) in brute.items():
        assert per_angle.worst[a] == pytest.approx(worst, abs=1e-6)
        assert per_angle.line[a] == pytest.approx(line, abs=1e-6)
    top = max(brute.values())
    best = [a for a, v in brute.items() if np.isclose(v[0], top[0]) and np.isclose(v[1], top[1])]
    best = min(best, key=lambda a: abs(a - 100.0))  # ties: nearest the angle the joint stands at
    got = recommend(rows, 100.0)
    assert got.angle_deg == best and got.worst_margin_pct == pytest.approx(brute[best][0], abs=1e-6)
    assert len(set(np.round([v[0] for v in brute.values()], 6))) > 1  # the angle matters: not a flat sweep


def test_each_row_is_its_better_verified_path(swept):
    _, _, _, rows = swept
    ran = rows[rows.direct_note != "start not reachable"]
    assert len(ran) > 0
    best = np.maximum(ran.direct_capacity_kg, ran.planned_capacity_kg)
    np.testing.assert_allclose(ran.capacity_kg, best)
    np.testing.assert_allclose(rows.margin_pct, 100 * (rows.capacity_kg - rows.payload_kg) / rows.payload_kg)
    assert (rows.feasible == (rows.capacity_kg >= rows.payload_kg)).all()


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
                          "line_margin_pct": 0.0, "feasible": True} for a, t in product(angles, ("a", "b"))])
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
                         "line_margin_pct": 0.0, "feasible": True})
    assert neighbours_worst(rows, 100.0) == 9.0 and neighbours_worst(rows, -80.0) == -7.0
    assert neighbours_worst(rows, 270.0) == -8.0
    part = rows[rows.angle_deg <= 0]  # under a turn: the ends have one neighbour
    assert neighbours_worst(part, -80.0) == -7.0 and neighbours_worst(part, 0.0) == -1.0
