"""The contract of the path searches: start, goal and payload in, a plan of waypoints out, or a
reason why there is none.

Two A* searches meet it:

- :class:`capmap.capacity.planning.VoxelSearch`: through the voxel capacity map, isotropic or
  with direction-aware moves (:func:`capmap.capacity.planning.plan`);
- :class:`capmap.capacity.branch_planning.BranchSearch`: over (voxel, IK branch) states, on the
  branch that is executed (:func:`capmap.capacity.branch_planning.plan_on_branch`).

Both search a graph whose nodes are the true start, voxel centres (or voxel-centre states) and
the true goal, with edges between 26-neighbour voxels weighted by the distance of their centres
(m), and both return the shortest path of that graph (the heuristic, the straight distance to the
goal, is admissible and consistent): ``length_m`` equals the graph's Dijkstra distance from start
to goal, which is what the contract tests (tests/capacity/test_contracts_search.py) check.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from capmap.errors import NoPath

__all__ = ["PathPlan", "Search", "Outcome", "attempt"]


@runtime_checkable
class PathPlan(Protocol):
    """What every plan carries. W waypoints: ``waypoints`` (W, 3) m, the true start first and the true
    goal last, voxel centres between (consecutive duplicates merged); ``waypoint_kind`` (W,) 'start' |
    'voxel' | 'goal'; ``waypoint_voxel`` (W, 3) grid indices; ``expanded``: nodes the search popped;
    ``length_m``: the polyline length of the waypoints (m), the path's cost."""

    waypoints: np.ndarray
    waypoint_kind: tuple[str, ...]
    waypoint_voxel: np.ndarray
    expanded: int

    @property
    def length_m(self) -> float: ...


@runtime_checkable
class Search(Protocol):
    """A path search with its map fixed: ``plan(start_m (3,) m, goal_m (3,) m, payload_kg)`` returns the
    shortest :class:`PathPlan` carrying payload_kg. When there is none it raises
    :class:`~capmap.errors.NoPath`, whose one-line message is the reason (naming the inputs by the roles
    ``start``, ``goal``, ``payload``); a start or goal outside the grid or in a voxel without a reachable
    point is a :class:`~capmap.errors.CapmapError`."""

    def plan(self, start_m: np.ndarray, goal_m: np.ndarray, payload_kg: float) -> PathPlan: ...


@dataclass(frozen=True)
class Outcome:
    """A search's answer as a value: ``plan`` (None when there is no path) and ``reason`` ('' when there
    is a plan, else the NoPath message in its own terms)."""

    plan: PathPlan | None
    reason: str

    @property
    def length_m(self) -> float:
        """The plan's length (m), inf when there is no path."""
        return self.plan.length_m if self.plan is not None else float("inf")


def attempt(search: Search, start_m: np.ndarray, goal_m: np.ndarray, payload_kg: float) -> Outcome:
    """Run ``search.plan`` and return its :class:`Outcome` (NoPath caught; other errors raised)."""
    try:
        return Outcome(search.plan(start_m, goal_m, payload_kg), "")
    except NoPath as err:
        return Outcome(None, str(err))
