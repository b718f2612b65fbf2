"""Pair groups: many pairs dropped by one test (the node kernel's and the pair filter's broad phase).

A group is the pairs of one moving primitive (a robot or panel segment, or a panel triangle) with the
static primitives of one named body (an environment face or capsule, an unknown-space box), when
there are at least :data:`MIN_GROUP` of them. The body's static primitives lie in a ball, centre c and
reach rho (the farthest core point plus that primitive's radius, fixed at :func:`static_balls`), so
every pair's safety distance is at least ``|c - moving core| - rho - r_moving`` (:func:`group_bound`):
when that clears a threshold, every pair of the group does, and none needs its own bound or distance.
Tested against every pair's exact distance in tests/dualarm/test_fddp.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from capmap.dualarm.geometry.distance import _pointtri_uv, segpoint

__all__ = ["MIN_GROUP", "SegmentPrims", "TrianglePrims", "BodyBalls", "static_balls", "pair_groups", "group_bound"]

MIN_GROUP = 2  # a single pair is tested on its own (a group's test would only add one)


@dataclass(frozen=True, eq=False)
class SegmentPrims:
    """S segments (capsule cores): f (S, 6) the ends a, b m (in their joint's frame; the world for joint 0),
    j (S,) int their joint (0: static), r (S,) their radii m, body (S,) the named body each belongs to."""

    f: np.ndarray
    j: np.ndarray
    r: np.ndarray
    body: np.ndarray


@dataclass(frozen=True, eq=False)
class TrianglePrims:
    """T swept triangles: f (T, 9) the vertices m (in their joint's frame; the world for joint 0), j (T,) int
    their joint (0: static), r (T,) their radii m, body (T,) the named body each belongs to."""

    f: np.ndarray
    j: np.ndarray
    r: np.ndarray
    body: np.ndarray


@dataclass(frozen=True, eq=False)
class BodyBalls:
    """The static bodies' balls: seg_g (S,), tri_g (T,) int: each static primitive's body ball, -1 for a moving
    one; balls (G, 4): centre m and reach m of each body."""

    seg_g: np.ndarray
    tri_g: np.ndarray
    balls: np.ndarray


def static_balls(seg: SegmentPrims, tri: TrianglePrims) -> BodyBalls:
    """Each static body's ball (centre m and reach m) over its static segments (S, 6 ends), triangles (T, 9
    vertices) and their radii, and which ball each static primitive belongs to."""
    seg_f, seg_j, seg_r, seg_body = seg.f, seg.j, seg.r, seg.body
    tri_f, tri_j, tri_r, tri_body = tri.f, tri.j, tri.r, tri.body
    seg_g, tri_g = np.full(len(seg_f), -1, np.int64), np.full(len(tri_f), -1, np.int64)
    names = sorted({str(b) for b in seg_body[seg_j == 0]} | {str(b) for b in tri_body[tri_j == 0]})
    balls = np.zeros((len(names), 4))
    for g, name in enumerate(names):
        s = (seg_j == 0) & (np.asarray(seg_body, dtype=str) == name)
        t = (tri_j == 0) & (np.asarray(tri_body, dtype=str) == name)
        seg_g[s], tri_g[t] = g, g
        pts = np.vstack([seg_f[s].reshape(-1, 3), tri_f[t].reshape(-1, 3)])
        c = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        far_s = np.linalg.norm(seg_f[s].reshape(-1, 2, 3) - c, axis=2).max(axis=1) + seg_r[s]
        far_t = np.linalg.norm(tri_f[t].reshape(-1, 3, 3) - c, axis=2).max(axis=1) + tri_r[t]
        balls[g, :3], balls[g, 3] = c, np.concatenate([far_s, far_t]).max()
    return BodyBalls(seg_g, tri_g, balls)


def pair_groups(rows: np.ndarray, seg_j: np.ndarray, seg_r: np.ndarray, tri_j: np.ndarray, tri_r: np.ndarray,
                bodies: BodyBalls) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(order (P,): the pair rows (kind, first, second) grouped; groups (G, 4) int: start and end in
    ``order``, the column of ``rows`` naming the moving primitive (0: test each pair on its own) and 1
    when that primitive is a triangle; spheres (G, 4): the body's centre m and its reach plus the moving
    primitive's radius m). seg_j (S,), tri_j (T,): the primitives' joints (0: static); seg_r (S,), tri_r (T,):
    their radii m; ``bodies``: :func:`static_balls`'."""
    return _pair_groups(np.ascontiguousarray(rows, dtype=np.int64), seg_j, seg_r, tri_j, tri_r, bodies.seg_g,
                        bodies.tri_g, bodies.balls, MIN_GROUP)


@numba.njit(cache=True)
def _pair_groups(rows, seg_j, seg_r, tri_j, tri_r, seg_g, tri_g, balls, min_group):
    P = rows.shape[0]
    key = np.empty(P, np.int64)
    col, body, rmov = np.zeros(P, np.int64), np.full(P, -1, np.int64), np.zeros(P)
    for n in range(P):
        kind, a, b = rows[n, 0], rows[n, 1], rows[n, 2]
        b_static = (seg_j[b] if kind == 0 else tri_j[b]) == 0
        a_static = seg_j[a] == 0
        if not a_static and b_static:
            col[n], body[n], rmov[n] = 1, seg_g[b] if kind == 0 else tri_g[b], seg_r[a]
            key[n] = (1 << 60) + (kind << 58) + (a << 30) + body[n]
        elif a_static and not b_static:
            col[n], body[n], rmov[n] = 2, seg_g[a], seg_r[b] if kind == 0 else tri_r[b]
            key[n] = (2 << 60) + (kind << 58) + (b << 30) + body[n]  # kind: b a segment or a triangle
        else:
            key[n] = -1
    order = np.argsort(key, kind="mergesort")  # stable: pairs keep their order within a group
    groups, spheres = np.zeros((P, 4), np.int64), np.zeros((P, 4))
    G, s = 0, 0
    while s < P:
        e = s + 1
        while e < P and key[order[e]] == key[order[s]]:
            e += 1
        n = order[s]
        if col[n] > 0 and e - s >= min_group:
            groups[G, 0], groups[G, 1], groups[G, 2] = s, e, col[n]
            groups[G, 3] = 1 if rows[n, 0] == 1 and col[n] == 2 else 0
            for i in range(3):
                spheres[G, i] = balls[body[n], i]
            spheres[G, 3] = balls[body[n], 3] + rmov[n]
            G += 1
        else:  # one group per pair, tested on its own (column 0)
            for t in range(s, e):
                groups[G, 0], groups[G, 1] = t, t + 1
                G += 1
        s = e
    return order.astype(np.int64), groups[:G].copy(), spheres[:G].copy()


@numba.njit(cache=True)
def group_bound(A, B, V, rows, order, groups, spheres, gi):
    """A lower bound (m) of the safety distance of every pair of group ``gi`` (:func:`pair_groups`) at the
    world segments A, B (S, 3) and triangles V (T, 3, 3): the distance from the body's centre to the
    moving core, less the reach."""
    mi = rows[order[groups[gi, 0]], groups[gi, 2]]
    if groups[gi, 3] == 1:
        u, w = _pointtri_uv(spheres, gi, V, mi, 0.0, spheres, gi)
        d2 = 0.0
        for i in range(3):
            q = V[mi, 0, i] + u * (V[mi, 1, i] - V[mi, 0, i]) + w * (V[mi, 2, i] - V[mi, 0, i])
            d2 += (spheres[gi, i] - q) ** 2
        return np.sqrt(d2) - spheres[gi, 3]
    return segpoint(A, B, mi, spheres[gi, 0], spheres[gi, 1], spheres[gi, 2]) - spheres[gi, 3]
