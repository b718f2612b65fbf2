"""Improved A* on the voxel capacity grid (the spec's step 8).

Moves go to any of the 26 neighbours of a voxel; a move's cost g is the distance
between the voxel centres (edge * 1, sqrt 2 or sqrt 3), the heuristic h is the straight
distance to the goal voxel's centre (admissible and consistent, so the first time the
goal is popped its cost is optimal), and the capacity term C is 0 for a voxel whose
capacity is >= the task payload and infinite otherwise (also for voxels without a
reachable point):  f = g + h + C. A voxel with infinite C is never expanded.

Waypoints: the true start, the centres of the voxels visited (start and goal voxels
included), the true goal; consecutive duplicates (e.g. a goal at a voxel centre) merged.

Errors name the inputs by role (``start``, ``goal``, ``payload``; see :mod:`capmap.errors`).
:class:`VoxelSearch` is :func:`plan` on a fixed map, under the contract of :mod:`capmap.capacity.search`.
"""

from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

import numpy as np

from capmap.capacity.directions import axis_of
from capmap.capacity.voxels import Grid
from capmap.errors import CapmapError, NoPath

__all__ = ["NEIGHBOURS", "AXIS_OF_NEIGHBOUR", "capacity_penalty", "SearchResult", "astar", "Plan", "locate", "plan",
           "VoxelSearch", "ROLES"]

ROLES = {"start": "start", "goal": "goal", "payload": "payload"}  # own-terms names of plan()'s inputs

NEIGHBOURS = np.array([d for d in itertools.product((-1, 0, 1), repeat=3) if d != (0, 0, 0)])  # (26, 3)
AXIS_OF_NEIGHBOUR = axis_of(NEIGHBOURS)  # (26,) index into GRID_AXES


def capacity_penalty(capacity_kg: np.ndarray, payload_kg: float) -> np.ndarray:
    """C per voxel (same shape as capacity_kg): 0 if capacity >= payload, inf otherwise (NaN = unreachable)."""
    cap = np.asarray(capacity_kg, dtype=float)
    return np.where(np.nan_to_num(cap, nan=-np.inf) >= payload_kg, 0.0, np.inf)


@dataclass(frozen=True)
class SearchResult:
    """path (P, 3) voxel indices start..goal (empty if none); cost_m: sum of centre distances
    (inf if none); expanded: voxels popped; reached: (shape) bool, voxels the search touched."""

    path: np.ndarray
    cost_m: float
    expanded: int
    reached: np.ndarray


def astar(penalty: np.ndarray, start: tuple[int, int, int], goal: tuple[int, int, int], edge_m: float,
          axis_ok: np.ndarray | None = None) -> SearchResult:
    """A* with f = g + h + C over a 3-D grid; ``penalty`` (nx, ny, nz) is C (0 or inf).
    ``axis_ok`` (nx, ny, nz, 13) bool, optional: a move along grid axis a (:data:`GRID_AXES`, either
    sense) is allowed only when both its voxels allow that axis.

    Ties in f go to the larger g (deeper node), then to insertion order.
    """
    shape = penalty.shape
    start, goal = tuple(int(v) for v in start), tuple(int(v) for v in goal)
    steps = edge_m * np.linalg.norm(NEIGHBOURS, axis=1)
    goal_v = np.array(goal, dtype=float)
    g = np.full(shape, np.inf)
    parent = np.full(shape + (3,), -1, dtype=int)
    closed = np.zeros(shape, dtype=bool)
    g[start] = 0.0
    h0 = edge_m * float(np.linalg.norm(np.array(start) - goal_v))
    heap = [(h0 + penalty[start], 0.0, 0, start)]
    counter = 1
    expanded = 0
    lim = np.array(shape)
    while heap:
        _, neg_g, _, node = heapq.heappop(heap)
        if closed[node]:
            continue
        closed[node] = True
        expanded += 1
        if node == goal:
            break
        gn = -neg_g
        nb = np.array(node) + NEIGHBOURS
        ok = np.all((nb >= 0) & (nb < lim), axis=1)
        for d in np.flatnonzero(ok):
            m = tuple(int(v) for v in nb[d])
            c = penalty[m]
            if closed[m] or np.isinf(c):
                continue
            if axis_ok is not None and not (axis_ok[node + (AXIS_OF_NEIGHBOUR[d],)] and axis_ok[m + (AXIS_OF_NEIGHBOUR[d],)]):
                continue
            gm = gn + steps[d]
            if gm < g[m] - 1e-12:
                g[m] = gm
                parent[m] = node
                f = gm + edge_m * float(np.linalg.norm(nb[d] - goal_v)) + c
                heapq.heappush(heap, (f, -gm, counter, m))
                counter += 1
    if not closed[goal]:
        return SearchResult(np.zeros((0, 3), dtype=int), np.inf, expanded, np.isfinite(g))
    path = [goal]
    while path[-1] != start:
        path.append(tuple(int(v) for v in parent[path[-1]]))
    return SearchResult(np.array(path[::-1]), float(g[goal]), expanded, np.isfinite(g))


@dataclass(frozen=True)
class Plan:
    """A planned path. voxel_path (P, 3) indices; waypoints (W, 3) m (true start, voxel centres,
    true goal); waypoint_kind (W,) 'start' | 'voxel' | 'goal'; waypoint_voxel (W, 3);
    cost_m: A* cost (sum of centre distances); expanded: A* pops; length_m: polyline length."""

    voxel_path: np.ndarray
    waypoints: np.ndarray
    waypoint_kind: tuple[str, ...]
    waypoint_voxel: np.ndarray
    cost_m: float
    expanded: int

    @property
    def length_m(self) -> float:
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())


def _where(role: str, point: np.ndarray) -> str:
    return f"{{{role}}} = [{', '.join(f'{v:g}' for v in point)}]"


def locate(grid: Grid, reachable: np.ndarray, point: np.ndarray, role: str) -> tuple[int, int, int]:
    """The voxel index of a start or goal ``point`` (3,) m; a one-line CapmapError naming its
    ``role`` (:data:`ROLES`) when it is outside the grid or in a voxel without a reachable point
    (``reachable`` (V,) bool, C-ordered over the grid)."""
    idx = grid.index(point[None])[0]
    where = _where(role, point)
    if idx[0] < 0:
        hi = grid.lower + np.array(grid.shape) * grid.edge_m
        raise CapmapError(f"{where} is outside the workspace grid "
                          f"[{', '.join(f'{a:g}..{b:g}' for a, b in zip(grid.lower, hi))}] m", **ROLES)
    idx = tuple(int(v) for v in idx)
    if not reachable[grid.flat(np.array(idx))]:
        raise CapmapError(f"{where} lies in voxel {idx}, which has no point reachable at the task orientation",
                          **ROLES)
    return idx


def _endpoint_voxel(grid: Grid, penalty3: np.ndarray, cap3: np.ndarray, point: np.ndarray, role: str,
                    payload_kg: float) -> tuple[int, int, int]:
    idx = locate(grid, ~np.isnan(cap3.reshape(-1)), point, role)
    if np.isinf(penalty3[idx]):
        raise NoPath(f"{_where(role, point)} lies in voxel {idx} whose capacity {cap3[idx]:.1f} kg is below "
                     f"{{payload}} = {payload_kg:g}", **ROLES)
    return idx


def plan(grid: Grid, capacity_kg: np.ndarray, start_m: np.ndarray, goal_m: np.ndarray, payload_kg: float,
         axis_capacity_kg: np.ndarray | None = None) -> Plan:
    """Plan from start_m to goal_m (3,) m through voxels whose capacity (V,) kg, C-ordered over
    ``grid`` and NaN for unreachable voxels, is >= payload_kg. Raises a one-line CapmapError
    naming the problem when the start or goal is outside the grid or in an unreachable voxel;
    :class:`~capmap.errors.NoPath` when the start or goal voxel is too weak or no path exists.
    Both name the inputs by the roles in :data:`ROLES`.

    Direction-aware moves: with ``axis_capacity_kg`` (V, 13) kg (the capacity of each voxel for
    motion along each grid axis, :data:`~capmap.capacity.directions.GRID_AXES`), a move between
    neighbours is allowed when both voxels carry the payload along its axis; the start and goal
    voxels must still carry it in every direction (the first and last segments, from the true
    start and to the true goal, have any direction)."""
    cap3 = np.asarray(capacity_kg, dtype=float).reshape(grid.shape)
    pen = capacity_penalty(cap3, payload_kg)
    start_m, goal_m = np.asarray(start_m, dtype=float), np.asarray(goal_m, dtype=float)
    s = _endpoint_voxel(grid, pen, cap3, start_m, "start", payload_kg)
    g = _endpoint_voxel(grid, pen, cap3, goal_m, "goal", payload_kg)
    axis_ok = None
    if axis_capacity_kg is not None:
        axis_ok = (np.nan_to_num(np.asarray(axis_capacity_kg, dtype=float), nan=-np.inf) >= payload_kg).reshape(
            grid.shape + (-1,))
        pen = np.where(axis_ok.any(axis=-1), 0.0, np.inf)  # a voxel is entered along an axis it allows
    res = astar(pen, s, g, grid.edge_m, axis_ok)
    if not len(res.path):
        raise NoPath(f"no path from the start voxel {s} to the goal voxel {g} through voxels with capacity >= "
                     f"{{payload}} = {payload_kg:g} ({int(res.reached.sum())} voxels connected to the start, "
                     f"{int(np.isfinite(pen).sum())} voxels strong enough in all)", **ROLES)
    centres = grid.centres(res.path)
    pts = [start_m, *centres, goal_m]
    kinds = ["start", *["voxel"] * len(centres), "goal"]
    vox = [res.path[0], *res.path, res.path[-1]]
    keep = [0]
    for i in range(1, len(pts)):
        if np.linalg.norm(pts[i] - pts[keep[-1]]) > 1e-9:
            keep.append(i)
        elif kinds[i] == "goal":  # a goal at its voxel's centre: keep the 'goal' label
            keep[-1] = i
    return Plan(voxel_path=res.path, waypoints=np.array([pts[i] for i in keep]),
                waypoint_kind=tuple(kinds[i] for i in keep), waypoint_voxel=np.array([vox[i] for i in keep]),
                cost_m=res.cost_m, expanded=res.expanded)


@dataclass(frozen=True)
class VoxelSearch:
    """:func:`plan` on a fixed map, a :class:`~capmap.capacity.search.Search`: capacity_kg (V,) kg over
    ``grid`` (C-ordered, NaN unreachable) and, for direction-aware moves, axis_capacity_kg (V, 13) kg."""

    grid: Grid
    capacity_kg: np.ndarray
    axis_capacity_kg: np.ndarray | None = None

    def plan(self, start_m: np.ndarray, goal_m: np.ndarray, payload_kg: float) -> Plan:
        """The shortest :class:`Plan` from start_m to goal_m (3,) m carrying payload_kg; NoPath when none."""
        return plan(self.grid, self.capacity_kg, start_m, goal_m, payload_kg, self.axis_capacity_kg)
