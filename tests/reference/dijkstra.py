"""Shortest paths on the masked 26-neighbour voxel graph by scipy's Dijkstra (an independent
graph build: no capmap code), the reference for the A* planner."""

from __future__ import annotations

import itertools

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra


def dijkstra_cost(ok: np.ndarray, start, goal, edge: float, edge_ok=None) -> float:
    """Shortest centre-to-centre distance through voxels with ok == True (inf if none).
    ``edge_ok(voxel, neighbour, offset)``: an extra test per move (direction-aware maps)."""
    shape = ok.shape
    rows, cols, w = [], [], []
    for idx in itertools.product(*(range(n) for n in shape)):
        if not ok[idx]:
            continue
        for d in itertools.product((-1, 0, 1), repeat=3):
            if d == (0, 0, 0):
                continue
            nb = tuple(i + di for i, di in zip(idx, d))
            if all(0 <= nb[a] < shape[a] for a in range(3)) and ok[nb] and (edge_ok is None or edge_ok(idx, nb, d)):
                rows.append(np.ravel_multi_index(idx, shape))
                cols.append(np.ravel_multi_index(nb, shape))
                w.append(edge * np.sqrt(sum(di * di for di in d)))
    n = ok.size
    graph = coo_matrix((w, (rows, cols)), shape=(n, n)).tocsr()
    dist = dijkstra(graph, indices=np.ravel_multi_index(start, shape))
    return float(dist[np.ravel_multi_index(goal, shape)])
