"""The (voxel, IK branch) state graph built explicitly, the reference for the branch planner.

Every move is tracked by the verification's own tracker (:func:`capmap.core.tracking.track`,
one ``ik.solve`` per move; its branch-following kernel is the planner's too, and is checked on
its own by the verification tests and the turn test of test_branch_planning), its joint range
checked from the tracked angles, and its capacity taken state by state with the per-configuration Pinocchio
path (:func:`capmap.capacity.engine.state_capacity`: J^-1 joint rates and RNEA), moving along
u and along -u. The graph is grown breadth-first from the start over every tracked move
(whatever its capacity), then shortest paths at a payload come from scipy's Dijkstra on the
moves that carry it. No code of the planner is used.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from capmap.capacity.engine import state_capacity
from capmap.core.tracking import track


def _move(dyn, limits, motion, rotation, p0, p1, q0, S):
    """(ok, q at p1, capacity) of the move p0 -> p1 from q0, S samples."""
    arm = dyn.arm
    pos = np.vstack([p0, [p0 + f * (p1 - p0) for f in np.arange(1, S + 1) / S]])
    tr = track(arm, pos, rotation, q0)
    if not tr.ok or not tr.in_range.all():
        return False, None, 0.0
    u = (p1 - p0) / np.linalg.norm(p1 - p0)
    cap = min(state_capacity(dyn, q, sense * motion.v_max_mps * u, sense * motion.a_max_mps2 * u, limits)[0]
              for q in tr.q for sense in (1.0, -1.0))
    return True, tr.q[-1], cap


def build(dyn, limits, motion, rotation, grid, start_m, goal_m, q0, step_m):
    """Nodes (0 = start, 1 = goal, then (voxel, rounded q) states) and moves (i, j, length, capacity)."""
    S_move = max(1, math.ceil(grid.edge_m * math.sqrt(3) / step_m - 1e-9))
    centres = grid.centres(grid.all_indices())
    sv = int(grid.flat(grid.index(start_m[None])[0]))
    gv = int(grid.flat(grid.index(goal_m[None])[0]))
    keys, q_of, vox_of, moves = {}, {0: q0}, {}, []

    def node(v, q):
        key = (v, tuple(np.round(q, 6)))
        if key not in keys:
            keys[key] = len(keys) + 2
            q_of[keys[key]], vox_of[keys[key]] = q, v
            todo.append(keys[key])
        return keys[key]

    def add(i, p0, p1, v_to, to_goal=False):
        S = max(1, math.ceil(np.linalg.norm(p1 - p0) / step_m - 1e-9)) if (to_goal or i == 0) else S_move
        ok, q1, cap = _move(dyn, limits, motion, rotation, p0, p1, q_of[i], S)
        if ok:
            moves.append((i, 1 if to_goal else node(v_to, q1), float(np.linalg.norm(p1 - p0)), cap))

    todo = []
    add(0, start_m, centres[sv], sv)
    while todo:
        i = todo.pop()
        v = vox_of[i]
        if v == gv:
            add(i, centres[gv], goal_m, gv, to_goal=True)
        idx = np.array(np.unravel_index(v, grid.shape))
        for d in itertools.product((-1, 0, 1), repeat=3):
            nb = idx + np.array(d)
            if d != (0, 0, 0) and np.all((nb >= 0) & (nb < np.array(grid.shape))):
                w = int(grid.flat(nb))
                add(i, centres[v], centres[w], w)
    return len(keys) + 2, moves


def shortest(n_nodes, moves, payload_kg) -> float:
    """Length (m) of the shortest start -> goal path through moves carrying payload_kg (inf if none)."""
    best = {}
    for i, j, w, cap in moves:
        if cap >= payload_kg:
            best[(i, j)] = min(w, best.get((i, j), math.inf))
    if not best:
        return math.inf
    (i, j), w = map(np.array, zip(*best)), np.array(list(best.values()))
    graph = coo_matrix((w + 1e-300, (i, j)), shape=(n_nodes, n_nodes)).tocsr()
    return float(dijkstra(graph, indices=0)[1])
