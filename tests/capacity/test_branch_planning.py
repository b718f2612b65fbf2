"""Planning on the executed branch: A* over (voxel, IK branch) states against the state graph
built explicitly with the verification's tracker, Pinocchio's per-state loads and scipy's
Dijkstra (tests/reference/branch_graph.py); the plan executed by the verification stays on
the planned configurations; joint ranges; the report of a goal reachable only on another branch."""

from __future__ import annotations

import re

import numpy as np
import pytest
import yaml

from capmap.capacity.branch_moves import line_capacity, track_moves
from capmap.capacity.branch_planning import BranchProblem, plan_on_branch
from capmap.capacity.engine import LoadLimits, Motion, state_capacity
from capmap.capacity.plan_verify import branch_deviation_deg
from capmap.capacity.verification import judge, verify_path
from capmap.capacity.voxels import Grid
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import lock
from capmap.errors import NoPath
from capmap.robots import load
from tests.reference import branch_graph
from tests.scenario import SSRMS_YAML, TASK_R, X_INI

MOTION = Motion(0.15, 0.03)
LOWER = X_INI - 0.3
GRID = Grid(lower=LOWER, shape=(4, 3, 3), edge_m=0.75)
START = LOWER + 0.3  # off its voxel's centre
GOAL = LOWER + np.array([2.75, 1.9, 1.95])  # voxel (3, 2, 2), off centre


def _problem(arm):
    limits = LoadLimits.uniform(7, 700, 200, 500).for_arm(arm)
    return BranchProblem(ArmDynamics(arm), GRID, TASK_R, MOTION, limits, np.ones(GRID.n_voxels, dtype=bool))


def _length(pb, q0, M):
    try:
        return plan_on_branch(pb, START, GOAL, q0, M).length_m
    except NoPath:
        return np.inf


@pytest.fixture(scope="module")
def setting(scenario_arm):
    pb = _problem(scenario_arm)
    sol = ik.solve(scenario_arm, START[None], TASK_R)
    return pb, sol.q[0, :sol.n_solutions[0]]


@pytest.fixture(scope="module")
def reference(setting):
    pb, starts = setting
    return {k: branch_graph.build(pb.dyn, pb.limits, MOTION, TASK_R, GRID, START, GOAL, starts[k], pb.step_m)
            for k in (0,)}


def test_line_capacity_equals_the_per_state_pinocchio_loads(setting):
    pb, starts = setting
    rng = np.random.default_rng(3)
    u = rng.normal(size=(len(starts), 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    got = line_capacity(pb.dyn, starts, u, MOTION, pb.limits)
    ref = [min(state_capacity(pb.dyn, q, s * 0.15 * d, s * 0.03 * d, pb.limits)[0] for s in (1, -1))
           for q, d in zip(starts, u)]
    assert np.allclose(got, ref, rtol=1e-10)


def test_shortest_executable_path_equals_the_explicit_graph(setting, reference):
    pb, starts = setting
    kinds = set()
    for k, (n_nodes, moves) in reference.items():
        caps = np.unique([m[3] for m in moves])
        levels = {}
        for M in caps[::max(1, len(caps) // 40)]:  # every payload level where the reference path changes
            levels.setdefault(branch_graph.shortest(n_nodes, moves, M), M)
        for ref, M in levels.items():
            assert _length(pb, starts[k], M) == pytest.approx(ref, abs=1e-9), (k, M)
        finite = [r for r in levels if np.isfinite(r)]
        kinds |= {"no path" for r in levels if not np.isfinite(r)} | {"detour" for r in finite if r > min(finite) + 1e-6}
    assert kinds == {"no path", "detour"}  # the payloads probe both: the comparison can fail


def test_the_verification_executes_the_planned_configurations(setting, reference):
    pb, starts = setting
    n_nodes, moves = reference[0]
    lengths = {M: branch_graph.shortest(n_nodes, moves, M) for M in np.unique([m[3] for m in moves])}
    # the heaviest payload with a path (a detour here), less the rounding between the planner's batched
    # coefficients and the reference's Pinocchio loads (they agree to ~1e-12 relative: tests/core/test_batch_dynamics):
    # at the exact boundary either side may round below the other
    M = max(m for m, L in lengths.items() if np.isfinite(L)) * (1 - 1e-9)
    plan = plan_on_branch(pb, START, GOAL, starts[0], M)
    assert plan.waypoint_kind[0] == "start" and plan.waypoint_kind[-1] == "goal"
    assert np.all(plan.move_capacity_kg[1:] >= M)
    res = verify_path(pb.dyn, plan.waypoints, TASK_R, starts[0], MOTION, 0.1, pb.limits)
    _, verdict = judge(res, pb.dyn.arm, pb.limits, M)
    assert verdict.tracking == "ok" and verdict.joint_range == "ok"
    assert branch_deviation_deg(res, np.rad2deg(plan.q)) < 1e-9


def test_moves_leaving_a_joint_range_are_refused_as_the_reference_does(tmp_path, setting, reference):
    _, starts = setting
    doc = yaml.safe_load(SSRMS_YAML.read_text())
    q = np.rad2deg(starts[0])  # active joints 2..7
    # joint 3 may turn 360 deg but only 2 deg above its start: IK always has an angle inside the range (the turn
    # below), so only the continuous angle tells that the arm would pass its stop
    doc["joint_range_deg"][2] = [float(q[1]) - 358.0, float(q[1]) + 2.0]
    path = tmp_path / "narrow.yaml"
    path.write_text(yaml.safe_dump(doc))
    pb = _problem(lock(load(path), 1, np.deg2rad(100.0)))
    n_nodes, moves = branch_graph.build(pb.dyn, pb.limits, MOTION, TASK_R, GRID, START, GOAL, starts[0], pb.step_m)
    assert len(moves) < len(reference[0][1])  # the narrow range removes moves ...
    assert branch_graph.shortest(n_nodes, moves, 0.0) == np.inf  # ... and every way to the goal
    assert _length(pb, starts[0], 0.0) == np.inf


def test_a_goal_reachable_only_from_other_branches_is_reported(setting, reference):
    pb, starts = setting
    n_nodes, moves = reference[0]
    best = max(m for m in np.unique([m[3] for m in moves]) if np.isfinite(branch_graph.shortest(n_nodes, moves, m)))
    M = float(best) + 1.0  # just above what branch 1 can carry to the goal
    with pytest.raises(NoPath) as err:
        plan_on_branch(pb, START, GOAL, starts[0], M)
    named = re.search(r"IK branch(?:es)? ([\d, ]+) of", str(err.value).split(";")[-1])
    others = {int(x) for x in named.group(1).split(",")} if named else set()
    for k in range(1, len(starts)):
        assert np.isfinite(_length(pb, starts[k], M)) == (k + 1 in others), (k, str(err.value))


def test_tracking_keeps_a_joint_turning_past_180_deg(setting):
    pb, starts = setting
    q0 = np.array([3.0, 0.1, -0.2, 0.3, 0.4, 0.5])  # joint 2 at 171.9 deg, turning on by 3 deg per sample
    steps = q0 + np.deg2rad(3.0) * np.arange(1, 5)[:, None] * np.eye(6)[0]
    wrapped = np.mod(steps + np.pi, 2 * np.pi) - np.pi  # what IK lists: angles nearest 0
    far = wrapped + 1.0  # a second branch, far away
    sets = np.stack([wrapped, far], axis=1)[None]  # (1, S, K, n)
    ok, path = track_moves(pb, q0[None], sets, np.full((1, 4), 2))
    assert ok[0] and np.allclose(path[0], steps)  # continuous: 174.9 .. 183.9 deg, not -176
    ok, _ = track_moves(pb, q0[None], sets[:, :, ::-1], np.full((1, 4), 1))  # only the far branch listed
    assert not ok[0]
