"""The search contract (:mod:`capmap.capacity.search`), written once and run against every
implementation: the voxel-map A* (:class:`~capmap.capacity.planning.VoxelSearch`) with isotropic
and with direction-aware moves, and the A* over (voxel, IK branch) states
(:class:`~capmap.capacity.branch_planning.BranchSearch`).

Each implementation comes with its own graph built independently of the planners: the masked
26-neighbour voxel graph (tests/reference/dijkstra.py; the per-axis test written out here) and the
explicit (voxel, branch) state graph (tests/reference/branch_graph.py: the verification's tracker,
Pinocchio's per-state loads). The contract: at every payload the plan's length is the graph's
Dijkstra distance (scipy.sparse.csgraph) from the true start to the true goal; the waypoints run
from the true start through voxel centres of 26-neighbour voxels to the true goal; when the
distance is infinite the search says why in one line (NoPath) instead; a start outside the grid
is a CapmapError, not a missing path. The payloads probe both outcomes, so the comparison can fail.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from capmap.capacity.branch_planning import BranchProblem, BranchSearch
from capmap.capacity.engine import LoadLimits, Motion
from capmap.capacity.planning import VoxelSearch
from capmap.capacity.search import Outcome, PathPlan, Search, attempt
from capmap.capacity.voxels import Grid
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import lock
from capmap.errors import CapmapError, NoPath
from capmap.robots import load
from tests.reference import branch_graph
from tests.reference.dijkstra import dijkstra_cost
from tests.scenario import SSRMS_YAML, TASK_R, X_INI

IMPLEMENTATIONS = ("voxel_isotropic", "voxel_axis", "branch")
SEEDS = range(6)
AXES = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, 0, 1), (1, 0, -1), (1, -1, 0), (0, 1, 1), (0, 1, -1),
        (1, 1, 1), (1, 1, -1), (1, -1, 1), (1, -1, -1)]  # the 13 grid axes, written out


def _axis(d):
    return next(a for a, ax in enumerate(AXES) if ax == tuple(d) or ax == tuple(-v for v in d))


def _voxel_instances(directional: bool):
    """(search, grid, start_m, goal_m, [(payload, Dijkstra length or inf)]) on random maps."""
    out = []
    for seed in SEEDS:
        rng = np.random.default_rng(300 + seed)
        grid = Grid(lower=np.array([0.5, -1.0, 0.25]), shape=(7, 6, 5), edge_m=0.5)
        axis_cap = rng.uniform(0, 3000, grid.shape + (13,))
        axis_cap[rng.random(grid.shape) < 0.15] = np.nan  # voxels without a reachable point
        cap = axis_cap.min(axis=-1) if directional else rng.uniform(0, 3000, grid.shape)
        cap[np.isnan(axis_cap[..., 0])] = np.nan
        cells = np.argwhere(~np.isnan(cap))
        s, g = (tuple(int(v) for v in cells[i]) for i in rng.choice(len(cells), 2, replace=False))
        if directional:
            cap[s] = cap[g] = 3000.0  # endpoints that carry every payload in every direction (moves still per axis)
        start, goal = (grid.lower + (np.array(c) + rng.uniform(0.05, 0.95, 3)) * grid.edge_m for c in (s, g))
        legs = np.linalg.norm(start - grid.centres(np.array([s]))[0]) + np.linalg.norm(goal - grid.centres(np.array([g]))[0])
        levels = []
        for M in (0.0, 300.0, 800.0, 1500.0, 2500.0):
            if directional:
                carries = np.nan_to_num(axis_cap, nan=-np.inf) >= M
                edge_ok = functools.partial(lambda c, a, b, d: c[a][_axis(d)] and c[b][_axis(d)], carries)
                ends = cap[s] >= M and cap[g] >= M  # the endpoints carry it in every direction
                d = dijkstra_cost(carries.any(axis=-1), s, g, grid.edge_m, edge_ok) if ends else np.inf
            else:
                d = dijkstra_cost(np.nan_to_num(cap, nan=-np.inf) >= M, s, g, grid.edge_m)
            levels.append((M, legs + d))
        search = VoxelSearch(grid, cap.ravel(), axis_cap.reshape(-1, 13) if directional else None)
        out.append((search, grid, start, goal, levels))
    return out


def _branch_instances():
    """The branch search on the scenario's arm from two start branches, every payload level at which
    the explicit graph's shortest path changes."""
    arm = lock(load(SSRMS_YAML), 1, np.deg2rad(100.0))
    motion, lower = Motion(0.15, 0.03), X_INI - 0.3
    grid = Grid(lower=lower, shape=(4, 2, 2), edge_m=0.75)
    start, goal = lower + 0.3, lower + np.array([2.75, 1.15, 1.2])  # both off their voxels' centres
    limits = LoadLimits.uniform(7, 700, 200, 500).for_arm(arm)
    pb = BranchProblem(ArmDynamics(arm), grid, TASK_R, motion, limits, np.ones(grid.n_voxels, dtype=bool))
    sol = ik.solve(arm, start[None], TASK_R)
    out = []
    for k in (0, 3):
        q0 = sol.q[0, k]
        n_nodes, moves = branch_graph.build(pb.dyn, limits, motion, TASK_R, grid, start, goal, q0, pb.step_m)
        levels = {}
        for M in np.unique([0.0] + [m[3] for m in moves]):
            levels.setdefault(branch_graph.shortest(n_nodes, moves, M), M)
        out.append((BranchSearch(pb, q0), grid, start, goal, [(M, L) for L, M in levels.items()]))
    return out


@functools.cache
def _instances(impl: str):
    return _branch_instances() if impl == "branch" else _voxel_instances(impl == "voxel_axis")


def _check_plan(plan, grid, start, goal):
    """The shape of every plan: true start, 26-neighbour voxel centres, true goal; its length."""
    assert isinstance(plan, PathPlan)
    W = len(plan.waypoints)
    assert plan.waypoints.shape == (W, 3) and plan.waypoint_voxel.shape == (W, 3) and len(plan.waypoint_kind) == W
    assert plan.waypoint_kind[0] == "start" and plan.waypoint_kind[-1] == "goal"
    assert set(plan.waypoint_kind[1:-1]) <= {"voxel"}
    assert np.allclose(plan.waypoints[0], start, rtol=0, atol=1e-12) and np.allclose(plan.waypoints[-1], goal, rtol=0, atol=1e-12)
    assert np.array_equal(plan.waypoint_voxel[0], grid.index(start[None])[0])
    assert np.array_equal(plan.waypoint_voxel[-1], grid.index(goal[None])[0])
    assert np.abs(np.diff(plan.waypoint_voxel, axis=0)).max(initial=0) <= 1  # 26-neighbour moves
    assert np.allclose(plan.waypoints[1:-1], grid.centres(plan.waypoint_voxel[1:-1]), rtol=0, atol=1e-12)
    seg = np.linalg.norm(np.diff(plan.waypoints, axis=0), axis=1)
    assert np.all(seg > 1e-9)  # consecutive duplicates merged
    assert plan.length_m == pytest.approx(seg.sum(), rel=1e-12) and plan.expanded >= 1


@pytest.mark.parametrize("impl", IMPLEMENTATIONS)
def test_the_plan_is_the_shortest_path_of_the_graph(impl):
    outcomes = set()
    for search, grid, start, goal, levels in _instances(impl):
        assert isinstance(search, Search)
        for M, expect in levels:
            got = attempt(search, start, goal, M)
            assert isinstance(got, Outcome)
            if np.isinf(expect):
                assert got.plan is None and np.isinf(got.length_m), (impl, M, got.length_m)
                outcomes.add("no path")
                continue
            assert got.plan is not None, (impl, M, got.reason)
            _check_plan(got.plan, grid, start, goal)
            assert got.plan.length_m == pytest.approx(expect, rel=1e-9, abs=1e-9), (impl, M)
            straight = np.linalg.norm(goal - start)
            outcomes.add("path" if got.plan.length_m < min(L for _, L in levels) + 1e-9 else "detour")
            assert got.plan.length_m >= straight - 1e-12
    assert outcomes == {"path", "detour", "no path"}  # the payloads probe every outcome: the comparison can fail


@pytest.mark.parametrize("impl", IMPLEMENTATIONS)
def test_no_path_comes_with_a_one_line_reason(impl):
    search, grid, start, goal, levels = next(i for i in _instances(impl) if any(np.isinf(L) for _, L in i[4]))
    M = next(M for M, L in levels if np.isinf(L))
    got = attempt(search, start, goal, M)
    assert got.plan is None and got.reason and "\n" not in got.reason and "payload" in got.reason
    with pytest.raises(NoPath) as err:
        search.plan(start, goal, M)
    assert str(err.value) == got.reason


@pytest.mark.parametrize("impl", IMPLEMENTATIONS)
def test_a_goal_outside_the_grid_is_an_error_not_a_missing_path(impl):
    search, grid, start, goal, _ = _instances(impl)[0]
    outside = grid.lower + np.array(grid.shape) * grid.edge_m + 0.1  # beyond the far corner
    with pytest.raises(CapmapError) as err:
        search.plan(start, outside, 0.0)
    assert not isinstance(err.value, NoPath) and "goal" in str(err.value) and "outside the workspace grid" in str(err.value)


def test_every_search_is_covered():
    kinds = {(type(i[0]).__name__, getattr(i[0], "axis_capacity_kg", None) is not None)
             for impl in IMPLEMENTATIONS for i in _instances(impl)}
    assert kinds == {("VoxelSearch", False), ("VoxelSearch", True), ("BranchSearch", False)}
