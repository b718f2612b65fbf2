"""Improved A* against Dijkstra (scipy.sparse.csgraph) on the same masked 26-neighbour graph."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.capacity.planning import astar, capacity_penalty, plan
from capmap.capacity.voxels import Grid, capacity_volume
from capmap.errors import CapmapError, NoPath
from tests.reference.dijkstra import dijkstra_cost


def random_case(rng, shape=(7, 6, 5), p_unreachable=0.15):
    cap = rng.uniform(0, 3000, shape)
    cap[rng.random(shape) < p_unreachable] = np.nan
    return cap


@pytest.mark.parametrize("seed, p_unreachable", [(s, 0.15) for s in range(10)] + [(s, 0.8) for s in range(10)])
def test_astar_cost_equals_dijkstra_and_path_is_valid(seed, p_unreachable):
    rng = np.random.default_rng(seed)
    cap = random_case(rng, p_unreachable=p_unreachable)
    payload = rng.uniform(500, 1500)
    pen = capacity_penalty(cap, payload)
    ok = np.isfinite(pen)
    cells = np.argwhere(ok)
    s, g = (tuple(cells[i]) for i in rng.choice(len(cells), 2, replace=False))
    edge = 0.75
    res = astar(pen, s, g, edge)
    expect = dijkstra_cost(ok, s, g, edge)
    if np.isinf(expect):
        assert len(res.path) == 0 and np.isinf(res.cost_m)
        return
    assert res.cost_m == pytest.approx(expect, rel=1e-12)
    path = res.path
    assert tuple(path[0]) == s and tuple(path[-1]) == g
    steps = np.diff(path, axis=0)
    assert np.abs(steps).max() <= 1 and (np.abs(steps).sum(axis=1) > 0).all()  # 26-neighbour moves
    assert np.all(np.nan_to_num(cap[tuple(path.T)], nan=-1) >= payload)  # no voxel below M_task
    assert edge * np.linalg.norm(steps, axis=1).sum() == pytest.approx(res.cost_m, rel=1e-12)


def test_astar_expands_fewer_voxels_than_the_grid_on_open_space():
    pen = np.zeros((20, 20, 20))
    res = astar(pen, (0, 0, 0), (19, 19, 19), 1.0)
    assert res.cost_m == pytest.approx(19 * np.sqrt(3))
    assert res.expanded == 20  # the straight diagonal: the heuristic is exact here


def _grid_case():
    grid = Grid(lower=np.zeros(3), shape=(4, 4, 4), edge_m=1.0)
    cap = np.full(grid.shape, 2000.0)
    return grid, cap


def test_plan_waypoints_are_true_start_voxel_centres_true_goal():
    grid, cap = _grid_case()
    cap[1:3, :, :] = 100.0  # a weak slab at x in [1, 3) ...
    cap[1:3, 3, 3] = 2500.0  # ... with one strong tunnel at the far corner
    start, goal = np.array([0.2, 0.3, 0.4]), np.array([3.5, 0.5, 0.5])
    p = plan(grid, cap.ravel(), start, goal, 1500)
    assert np.allclose(p.waypoints[0], start) and p.waypoint_kind[0] == "start"
    assert p.waypoint_kind[-1] == "goal" and np.allclose(p.waypoints[-1], goal)  # goal = its voxel centre: merged
    mid = p.waypoints[1:-1]
    assert np.allclose(mid, grid.centres(p.voxel_path)[: len(mid)])
    assert all(tuple(v) in {(1, 3, 3), (2, 3, 3)} for v in p.voxel_path if 1 <= v[0] <= 2)
    assert np.isclose(p.cost_m, dijkstra_cost(cap >= 1500, tuple(p.voxel_path[0]), tuple(p.voxel_path[-1]), 1.0))


@pytest.mark.parametrize("where, change, expect, exc", [
    ("start", lambda c: None, "task.start_m = [-1, 0.5, 0.5] is outside the workspace grid", CapmapError),
    ("goal_weak", lambda c: c.__setitem__((3, 0, 0), 900.0),
     "task.goal_m = [3.5, 0.5, 0.5] lies in voxel (3, 0, 0) whose capacity 900.0 kg is below task.payload_kg = 1500", NoPath),
    ("start_unreachable", lambda c: c.__setitem__((0, 0, 0), np.nan),
     "task.start_m = [0.5, 0.5, 0.5] lies in voxel (0, 0, 0), which has no point reachable", CapmapError),
    ("wall", lambda c: c.__setitem__((slice(1, 3), slice(None), slice(None)), 100.0),
     "no path from the start voxel (0, 0, 0) to the goal voxel (3, 0, 0)", NoPath),
])
def test_plan_errors_name_the_problem(where, change, expect, exc):
    grid, cap = _grid_case()
    change(cap)
    start = np.array([-1.0, 0.5, 0.5]) if where == "start" else np.array([0.5, 0.5, 0.5])
    with pytest.raises(exc) as err:
        plan(grid, cap.ravel(), start, np.array([3.5, 0.5, 0.5]), 1500)
    keys = {"start": "task.start_m", "goal": "task.goal_m", "payload": "task.payload_kg"}
    assert expect in err.value.in_terms(**keys)  # re-worded with the config keys by the stage
    own = expect
    for role, key in keys.items():
        own = own.replace(key, role)
    assert own in str(err.value)  # in its own terms
    assert "\n" not in str(err.value)


def test_capacity_volume_counts_voxels_carrying_each_payload():
    rng = np.random.default_rng(4)
    cap = rng.uniform(0, 100, 500)
    cap[rng.random(500) < 0.2] = np.nan  # unreachable voxels
    payloads = np.array([-1.0, 0.0, 12.5, cap[~np.isnan(cap)][7], 99.9, 150.0])
    brute = [sum(1 for c in cap if c == c and c >= m) * 0.5**3 for m in payloads]  # written out, NaN != NaN
    assert np.allclose(capacity_volume(cap, 0.5, payloads), brute)


@pytest.mark.parametrize("seed", range(4))
def test_direction_aware_astar_equals_dijkstra_on_axis_capacities(seed):
    """Per-axis capacities: A* with direction-aware moves against scipy's Dijkstra on a graph
    whose edges are built independently (the axis of an offset found by brute force over the
    13 axes written out here)."""
    rng = np.random.default_rng(100 + seed)
    shape, edge, M = (7, 6, 5), 0.5, 1000.0
    grid = Grid(lower=np.zeros(3), shape=shape, edge_m=edge)
    axis_cap = rng.uniform(0, 2500, grid.shape + (13,))
    iso = axis_cap.min(axis=-1)
    s, g = (0, 0, 0), (6, 5, 4)
    iso[s], iso[g] = 2000.0, 2000.0  # endpoints carry M in every direction
    axes = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, 0, 1), (1, 0, -1), (1, -1, 0), (0, 1, 1), (0, 1, -1),
            (1, 1, 1), (1, 1, -1), (1, -1, 1), (1, -1, -1)]

    def axis(d):
        return next(a for a, ax in enumerate(axes) if ax == tuple(d) or ax == tuple(-v for v in d))

    def edge_ok(a, b, d):
        return axis_cap[a][axis(d)] >= M and axis_cap[b][axis(d)] >= M

    expect = dijkstra_cost(np.ones(shape, dtype=bool), s, g, edge, edge_ok)
    start_m, goal_m = grid.centres(np.array([s]))[0], grid.centres(np.array([g]))[0]
    if np.isinf(expect):
        with pytest.raises(NoPath):
            plan(grid, iso.ravel(), start_m, goal_m, M, axis_cap.reshape(-1, 13))
        return
    p = plan(grid, iso.ravel(), start_m, goal_m, M, axis_cap.reshape(-1, 13))
    assert np.isclose(p.cost_m, expect)
    for a, b in zip(p.voxel_path[:-1], p.voxel_path[1:]):
        assert edge_ok(tuple(a), tuple(b), tuple(b - a))
    # the isotropic map (worst axis everywhere) is never better than direction-aware moves
    try:
        iso_cost = plan(grid, iso.ravel(), start_m, goal_m, M).cost_m
    except NoPath:
        iso_cost = np.inf
    assert iso_cost >= p.cost_m - 1e-12
