"""Planning on the branch that is executed: A* over (voxel, IK branch) states.

The voxel map (:mod:`capmap.capacity.planning`) is the minimum over every IK branch, so it is
safe for any branch but says nothing about the branch the arm is on: a plan through voxels
that carry the payload may still need a joint to pass its stop, or run into a singular
surface of that branch. Here a state is a voxel centre together with one exact IK solution
there (each joint angle continuous, so +-270 deg joints keep their turn), and a move is kept
only when it is executable on that branch:

- the branch is tracked from the state's configuration along the straight move at samples at
  most ``step_m`` apart (at each sample the IK solution nearest the previous one, whole turns
  allowed, as :func:`capmap.core.tracking.track` does), no joint changing by more than
  ``max_step_rad`` between samples and every joint within its range;
- the tracked configurations (the start's and every sample's) carry the payload for motion
  along the move's line (either sense, v_max and a_max at once:
  :func:`capmap.capacity.engine.line_capacity`).

The path runs from the true start (its configuration: the exact branch nearest ``q_start``)
to the centre of its voxel, through neighbouring voxel centres (26 moves), and from the goal
voxel's centre to the true goal, arriving on whichever branch the moves lead to. Costs are
segment lengths and the heuristic is the straight distance to the goal, so the first path
to pop the goal is the shortest executable one among these states. The samples are a
screen, not a proof: :func:`capmap.capacity.verification.verify_path` samples the timed
motion densely and is what says a plan carries the payload.

Errors name the inputs by role (``start``, ``goal``, ``payload``; ``q_ini``: the start configuration).
:class:`BranchSearch` is :func:`plan_on_branch` from a fixed start configuration, under the contract of
:mod:`capmap.capacity.search`.
"""

from __future__ import annotations

import heapq
import logging
from dataclasses import dataclass

import numpy as np

from capmap.capacity.branch_moves import BranchProblem, MoveCache, fractions, move_capacity, solve_at, track_moves
from capmap.capacity.planning import ROLES, locate
from capmap.core import ik
from capmap.core.tracking import nearest_branch, start_branch
from capmap.errors import NoPath

__all__ = ["BranchProblem", "BranchPlan", "plan_on_branch", "BranchSearch"]

PROGRESS_EVERY = 2000  # states expanded between progress lines

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class BranchPlan:
    """A plan on one branch. W waypoints: ``waypoints`` (W, 3) m, ``waypoint_kind`` ('start' |
    'voxel' | 'goal'), ``waypoint_voxel`` (W, 3) indices, ``q`` (W, n_active) rad (continuous
    along the path), ``move_capacity_kg`` (W,) the smallest capacity of the tracked samples of
    the move arriving at each waypoint (NaN at the start); ``expanded`` states popped,
    ``states`` states reached, ``voxels_solved`` voxels whose moves were tracked."""

    waypoints: np.ndarray
    waypoint_kind: tuple[str, ...]
    waypoint_voxel: np.ndarray
    q: np.ndarray
    move_capacity_kg: np.ndarray
    expanded: int
    states: int
    voxels_solved: int

    @property
    def length_m(self) -> float:
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())


def _search(s: MoveCache, start_m: np.ndarray, goal_m: np.ndarray, q0: np.ndarray, payload_kg: float):
    """A* from the true start on configuration q0; the node list and the goal node's index (or None)."""
    pb, grid = s.problem, s.problem.grid
    sv = int(grid.flat(np.array(locate(grid, pb.usable, start_m, "start"))))
    gv = int(grid.flat(np.array(locate(grid, pb.usable, goal_m, "goal"))))
    centre = np.array([s.centre_of(sv), s.centre_of(gv)])
    # nodes: (position (3,), q (n,), voxel, kind, parent, move capacity)
    nodes = [(start_m, q0, sv, "start", -1, np.nan)]
    g_of, key_of = {0: 0.0}, {"start": 0}
    heap = [(float(np.linalg.norm(goal_m - start_m)), 0.0, 0)]
    closed, expanded = set(), 0

    def push(key, pos, q, v, kind, parent, cap, g_new):
        i = key_of.get(key)
        if i is not None and (i in closed or g_new >= g_of[i] - 1e-12):
            return
        if i is None:
            i = key_of[key] = len(nodes)
            nodes.append(None)
        nodes[i] = (pos, q, v, kind, parent, cap)
        g_of[i] = g_new
        heapq.heappush(heap, (g_new + float(np.linalg.norm(goal_m - pos)), -g_new, i))

    def improves(key, g_new):  # a state not reached yet, or reached more dearly and not closed
        j = key_of.get(key)
        return j is None or (j not in closed and g_new < g_of[j] - 1e-12)

    def arrive(v, q, parent, cap, g_new):
        key, q_c = s.state_at(v, q)
        push(key, s.centre_of(v), q_c, v, "voxel", parent, cap, g_new)

    def single(i, p1):  # one move from node i to p1 (start -> its centre, goal centre -> goal)
        pos, q = nodes[i][:2]
        sets, counts = solve_at(pb, pos + fractions(float(np.linalg.norm(p1 - pos)), pb.step_m)[:, None] * (p1 - pos))
        ok, path = track_moves(pb, q[None], sets[None], counts[None])
        if not ok[0]:
            return None, 0.0
        cap = move_capacity(pb, q[None], path, ((p1 - pos) / np.linalg.norm(p1 - pos))[None])[0]
        return (path[0, -1], cap) if cap >= payload_kg else (None, cap)

    while heap:
        _, neg_g, i = heapq.heappop(heap)
        if i in closed:
            continue
        closed.add(i)
        expanded += 1
        if expanded % PROGRESS_EVERY == 0:
            log.info(f"branch search: {expanded} states expanded, {len(nodes)} reached, {len(s.solved)} voxels' moves "
                     f"tracked, best distance left {np.linalg.norm(goal_m - nodes[i][0]):.2f} m")
        pos, q, v, kind = nodes[i][:4]
        g = -neg_g
        if kind == "goal":
            return nodes, i, expanded
        if kind == "start":
            if np.linalg.norm(centre[0] - start_m) <= 1e-9:
                arrive(sv, q, i, np.nan, g)
            else:
                q1, cap = single(i, centre[0])
                if q1 is not None:
                    arrive(sv, q1, i, cap, g + float(np.linalg.norm(centre[0] - start_m)))
            continue
        if v == gv:
            if np.linalg.norm(goal_m - centre[1]) <= 1e-9:
                push("goal", goal_m, q, v, "goal", i, nodes[i][5], g)  # the move that arrived here
            else:
                q1, cap = single(i, goal_m)
                if q1 is not None:
                    push("goal", goal_m, q1, v, "goal", i, cap, g + float(np.linalg.norm(goal_m - centre[1])))
        for key, p1, q_c, w, c, g_new in _moves_out(s, pos, q, v, g, improves):
            if c >= payload_kg:
                push(key, p1, q_c, w, "voxel", i, c, g_new)
    return nodes, None, expanded


def _moves_out(s: MoveCache, pos: np.ndarray, q: np.ndarray, v: int, g: float, improves) -> list[tuple]:
    """The moves from state (pos, q) in voxel v, reached at cost g, to its neighbours that track on the
    branch and would improve a state (``improves(key, g_new)``): (state key, arrival point (3,), q there,
    voxel, the move's capacity kg, cost there); only these moves are loaded."""
    pb = s.problem
    w, p1, sets, counts = s.voxel_moves(v)
    if not len(w):
        return []
    ok, path = track_moves(pb, np.repeat(q[None], len(w), axis=0), sets, counts)
    step = np.linalg.norm(p1 - pos, axis=1)
    arrivals = []  # tracked moves that would improve a state not yet closed: only these are loaded
    for e in np.flatnonzero(ok):
        key, q_c = s.state_at(int(w[e]), path[e, -1])
        if improves(key, g + step[e]):
            arrivals.append((e, key, q_c))
    if not arrivals:
        return []
    e_ok = np.array([a[0] for a in arrivals])
    cap = move_capacity(pb, np.repeat(q[None], len(e_ok), axis=0), path[e_ok], (p1[e_ok] - pos) / step[e_ok, None])
    return [(key, p1[e], q_c, int(w[e]), c, g + float(step[e])) for (e, key, q_c), c in zip(arrivals, cap)]


def _result(s: MoveCache, nodes: list, goal: int, expanded: int) -> BranchPlan:
    chain = [goal]
    while nodes[chain[-1]][4] >= 0:
        chain.append(nodes[chain[-1]][4])
    chain = chain[::-1]
    grid = s.problem.grid
    keep = [0]  # consecutive duplicates merged (a start or goal at its voxel's centre), keeping the labels
    for j in range(1, len(chain)):
        if np.linalg.norm(nodes[chain[j]][0] - nodes[chain[keep[-1]]][0]) > 1e-9:
            keep.append(j)
        elif nodes[chain[j]][3] == "goal":
            keep[-1] = j
    chain = [chain[j] for j in keep]
    pos = np.array([nodes[i][0] for i in chain])
    kinds = [nodes[i][3] for i in chain]
    vox = np.array([np.unravel_index(nodes[i][2], grid.shape) for i in chain])
    return BranchPlan(waypoints=pos, waypoint_kind=tuple(kinds), waypoint_voxel=vox,
                      q=np.array([nodes[i][1] for i in chain]), move_capacity_kg=np.array([nodes[i][5] for i in chain]),
                      expanded=expanded, states=len(nodes), voxels_solved=len(s.solved))


def plan_on_branch(problem: BranchProblem, start_m: np.ndarray, goal_m: np.ndarray, q_start: np.ndarray,
                   payload_kg: float) -> BranchPlan:
    """The shortest plan from start_m to goal_m (3,) m executable on the IK branch nearest
    q_start (n_active,) rad carrying payload_kg (see the module docstring).

    Raises a one-line CapmapError (roles :data:`capmap.capacity.planning.ROLES`; ``q_ini``: the
    start configuration) when the start or goal lies outside the
    grid or in a voxel without a reachable point, or q_start is not a configuration at the start;
    :class:`~capmap.errors.NoPath` when no executable path exists on that branch, saying whether
    the goal is reachable from another IK branch at the start (the arm would have to change branch).
    """
    start_m, goal_m = np.asarray(start_m, dtype=float), np.asarray(goal_m, dtype=float)
    q0, _ = start_branch(problem.dyn.arm, start_m, problem.rotation, q_start)
    s = MoveCache(problem)
    nodes, goal, expanded = _search(s, start_m, goal_m, q0, payload_kg)
    if goal is not None:
        return _result(s, nodes, goal, expanded)
    reached = len({n[2] for n in nodes})
    sol = ik.solve(problem.dyn.arm, start_m[None], problem.rotation)
    n = int(sol.n_solutions[0])
    k0, _, _ = nearest_branch(sol.q[0, :n], q0)
    others = []
    for k in (k for k in range(n) if k != k0):
        log.info(f"no path on the start's branch {k0 + 1} of {n}; trying branch {k + 1} at the start")
        if _search(s, start_m, goal_m, sol.q[0, k], payload_kg)[1] is not None:
            others.append(k + 1)
    where = (f"the goal is reachable from IK branch{'es' if len(others) > 1 else ''} {', '.join(map(str, others))} of {n} "
             "at the start: the arm would have to change branch" if others
             else f"nor from any of the other {n - 1} IK branches at the start")
    raise NoPath(f"no path executable on the start's IK branch ({k0 + 1} of {n}) carrying {{payload}} = {payload_kg:g} "
                 f"({len(nodes)} states in {reached} voxels reached; {expanded} expanded); {where}", **ROLES)


@dataclass(frozen=True)
class BranchSearch:
    """:func:`plan_on_branch` on a fixed problem from the IK branch nearest q_start (n_active,) rad, a
    :class:`~capmap.capacity.search.Search`."""

    problem: BranchProblem
    q_start: np.ndarray

    def plan(self, start_m: np.ndarray, goal_m: np.ndarray, payload_kg: float) -> BranchPlan:
        """The shortest :class:`BranchPlan` from start_m to goal_m (3,) m carrying payload_kg; NoPath when none."""
        return plan_on_branch(self.problem, start_m, goal_m, self.q_start, payload_kg)
