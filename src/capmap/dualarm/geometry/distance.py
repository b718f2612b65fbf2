"""Closest points between segments and triangles, batched over the leading axis (compiled loops).

A swept-sphere volume is a core (a segment or a triangle) dilated by a radius; the safety
distance of two volumes is the distance of their cores minus both radii. The public
functions take arrays of N pairs: points (N, 3) m. The kernels are compiled with numba and
read their points straight from the tables by row, so the optimiser can evaluate a few
dozen pairs per node at C speed (numpy's per-call overhead would dominate such batches).

- segment-segment: the bounded least-squares problem min |P(s) - Q(t)| over (s, t) in
  [0, 1]^2, solved in closed form case by case (Ericson, Real-Time Collision Detection,
  5.1.9): the unconstrained stationary point clamped to [0, 1] in s, then t recomputed and
  clamped, then s again; point-like and parallel segments handled.
- point-triangle: the closest point of a triangle by its Voronoi regions (ibid., 5.1.5).
- segment-triangle: the minimum over the segment's end points against the triangle and the
  segment against the triangle's three edges, and zero where the segment crosses the
  triangle (the closest points of two convex sets involve a vertex or an edge of one of
  them unless they intersect).

Gradients: with closest points P on the first core and Q on the second, d = |P - Q| and
dd = n . (dP - dQ), n = (P - Q) / d, where dP, dQ are the velocities of the material
points at P and Q (the closest points' own motion along the cores does not change d to
first order).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["Closest", "segment_segment", "point_triangle", "segment_triangle", "segseg", "segtri", "segpoint", "EPS"]

EPS = 1e-14  # a segment shorter than sqrt(EPS) m is a point
_jit = numba.njit(cache=True)
# the batch kernels' loops over pairs inline the helpers in numba's IR (~2.5x the pairs per second of plain calls);
# the node kernel and the pair filters call segseg and segtri, plain calls typing that inlined code once (numba's IR
# inlining re-types it at every call site: those callers compiled several times slower)
_inline = numba.njit(cache=True, inline="always")


@dataclass(frozen=True)
class Closest:
    """Per pair: distance (N,) m between the cores, closest points p (N, 3) on the first and
    q (N, 3) on the second core."""

    distance: np.ndarray
    p: np.ndarray
    q: np.ndarray

    @property
    def normal(self) -> np.ndarray:
        """(p - q) / distance (N, 3); zero where the cores touch."""
        d = self.distance[:, None]
        return np.where(d > 0, (self.p - self.q) / np.where(d > 0, d, 1.0), 0.0)


@_inline
def _clamp01(x):
    return 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)


@_inline
def _segseg_st(A, a, B, b, C, c, D, d):
    """(s, t) of the closest points of segments A[a] -> B[b] and C[c] -> D[d] (rows of (n, 3) tables)."""
    aa = ee = f = cc = bb = 0.0
    for i in range(3):
        d1, d2, r = B[b, i] - A[a, i], D[d, i] - C[c, i], A[a, i] - C[c, i]
        aa += d1 * d1
        ee += d2 * d2
        f += d2 * r
        cc += d1 * r
        bb += d1 * d2
    if aa <= EPS and ee <= EPS:
        return 0.0, 0.0
    if aa <= EPS:
        return 0.0, _clamp01(f / ee)
    if ee <= EPS:
        return _clamp01(-cc / aa), 0.0
    denom = aa * ee - bb * bb
    s = _clamp01((bb * f - cc * ee) / denom) if denom > EPS * aa * ee else 0.0  # parallel: any s
    t = (bb * s + f) / ee
    if t < 0.0:
        return _clamp01(-cc / aa), 0.0
    if t > 1.0:
        return _clamp01((bb - cc) / aa), 1.0
    return s, t


@_inline
def _pointtri_uv(X, x, V, v, s, Y, y):
    """Barycentric (u, w) of the point of triangle V[v] (3, 3) nearest the point X[x] + s (Y[y] - X[x])."""
    d1 = d2 = d3 = d4 = d5 = d6 = 0.0
    for i in range(3):
        p = X[x, i] + s * (Y[y, i] - X[x, i])
        ab, ac = V[v, 1, i] - V[v, 0, i], V[v, 2, i] - V[v, 0, i]
        d1 += ab * (p - V[v, 0, i])
        d2 += ac * (p - V[v, 0, i])
        d3 += ab * (p - V[v, 1, i])
        d4 += ac * (p - V[v, 1, i])
        d5 += ab * (p - V[v, 2, i])
        d6 += ac * (p - V[v, 2, i])
    if d1 <= 0.0 and d2 <= 0.0:
        return 0.0, 0.0
    if d3 >= 0.0 and d4 <= d3:
        return 1.0, 0.0
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 1.0
    vc, vb, va = d1 * d4 - d3 * d2, d5 * d2 - d1 * d6, d3 * d6 - d5 * d4
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        return d1 / (d1 - d3), 0.0
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        return 0.0, d2 / (d2 - d6)
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 1.0 - w, w
    denom = va + vb + vc
    return vb / denom, vc / denom


@_inline
def _gap2(A, a, B, b, s, V, v, u, w):
    """|A[a] + s (B[b] - A[a]) - V[v] point (u, w)|^2."""
    dd = 0.0
    for i in range(3):
        p = A[a, i] + s * (B[b, i] - A[a, i])
        q = V[v, 0, i] + u * (V[v, 1, i] - V[v, 0, i]) + w * (V[v, 2, i] - V[v, 0, i])
        dd += (p - q) ** 2
    return dd


@_inline
def _segtri_suw(A, a, B, b, V, v):
    """(s, u, w, distance^2) of the closest points of segment A[a] -> B[b] and triangle V[v]."""
    best, bs, bu, bw = np.inf, 0.0, 0.0, 0.0
    for k in range(3):  # the segment against each edge (an edge is the triangle's V[v, k] -> V[v, k+1])
        m = (k + 1) % 3
        s, t = _segseg_st(A, a, B, b, V[v], k, V[v], m)
        u = (t if k == 0 else (1.0 - t if k == 1 else 0.0))
        w = (0.0 if k == 0 else (t if k == 1 else 1.0 - t))
        dd = _gap2(A, a, B, b, s, V, v, u, w)
        if dd < best:
            best, bs, bu, bw = dd, s, u, w
    for s in (0.0, 1.0):  # each end point against the triangle
        u, w = _pointtri_uv(A, a, V, v, s, B, b)
        dd = _gap2(A, a, B, b, s, V, v, u, w)
        if dd < best:
            best, bs, bu, bw = dd, s, u, w
    # does the segment cross the triangle? (Moller-Trumbore)
    dx, dy, dz = B[b, 0] - A[a, 0], B[b, 1] - A[a, 1], B[b, 2] - A[a, 2]
    ax, ay, az = V[v, 1, 0] - V[v, 0, 0], V[v, 1, 1] - V[v, 0, 1], V[v, 1, 2] - V[v, 0, 2]
    bx, by, bz = V[v, 2, 0] - V[v, 0, 0], V[v, 2, 1] - V[v, 0, 1], V[v, 2, 2] - V[v, 0, 2]
    hx, hy, hz = dy * bz - dz * by, dz * bx - dx * bz, dx * by - dy * bx
    det = ax * hx + ay * hy + az * hz
    scale = (ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz) * (dx * dx + dy * dy + dz * dz)
    if abs(det) > EPS * np.sqrt(scale + EPS):
        sx, sy, sz = A[a, 0] - V[v, 0, 0], A[a, 1] - V[v, 0, 1], A[a, 2] - V[v, 0, 2]
        u = (sx * hx + sy * hy + sz * hz) / det
        qx, qy, qz = sy * az - sz * ay, sz * ax - sx * az, sx * ay - sy * ax
        w = (dx * qx + dy * qy + dz * qz) / det
        t = (bx * qx + by * qy + bz * qz) / det
        if u >= 0.0 and w >= 0.0 and u + w <= 1.0 and 0.0 <= t <= 1.0:
            return t, u, w, 0.0
    return bs, bu, bw, best


@_inline
def _segseg(A, a, B, b, C, c, D, d, P, Q, n):
    """Closest points of A[a] -> B[b] and C[c] -> D[d] into rows P[n], Q[n]; the distance."""
    s, t = _segseg_st(A, a, B, b, C, c, D, d)
    dd = 0.0
    for i in range(3):
        P[n, i] = A[a, i] + s * (B[b, i] - A[a, i])
        Q[n, i] = C[c, i] + t * (D[d, i] - C[c, i])
        dd += (P[n, i] - Q[n, i]) ** 2
    return np.sqrt(dd)


@_inline
def _segtri(A, a, B, b, V, v, P, Q, n):
    """Closest points of segment A[a] -> B[b] and triangle V[v] into rows P[n], Q[n]; the distance."""
    s, u, w, dd = _segtri_suw(A, a, B, b, V, v)
    for i in range(3):
        P[n, i] = A[a, i] + s * (B[b, i] - A[a, i])
        Q[n, i] = V[v, 0, i] + u * (V[v, 1, i] - V[v, 0, i]) + w * (V[v, 2, i] - V[v, 0, i])
    return np.sqrt(dd)


@_jit
def segseg(A, a, B, b, C, c, D, d, P, Q, n):
    """Closest points of A[a] -> B[b] and C[c] -> D[d] into rows P[n], Q[n]; the distance."""
    return _segseg(A, a, B, b, C, c, D, d, P, Q, n)


@_jit
def segtri(A, a, B, b, V, v, P, Q, n):
    """Closest points of segment A[a] -> B[b] and triangle V[v] into rows P[n], Q[n]; the distance."""
    return _segtri(A, a, B, b, V, v, P, Q, n)


@_jit
def segpoint(A, B, s, x, y, z):
    """Distance (m) from the point (x, y, z) to segment A[s] -> B[s]."""
    dx, dy, dz = B[s, 0] - A[s, 0], B[s, 1] - A[s, 1], B[s, 2] - A[s, 2]
    ex, ey, ez = x - A[s, 0], y - A[s, 1], z - A[s, 2]
    L2 = dx * dx + dy * dy + dz * dz
    t = 0.0 if L2 == 0.0 else min(max((ex * dx + ey * dy + ez * dz) / L2, 0.0), 1.0)
    ex, ey, ez = ex - t * dx, ey - t * dy, ez - t * dz
    return np.sqrt(ex * ex + ey * ey + ez * ez)


@_jit
def _segseg_batch(p0, p1, q0, q1, d, P, Q):
    for n in range(len(d)):
        d[n] = _segseg(p0, n, p1, n, q0, n, q1, n, P, Q, n)


@_jit
def _segtri_batch(p0, p1, V, d, P, Q):
    for n in range(len(d)):
        d[n] = _segtri(p0, n, p1, n, V, n, P, Q, n)


@_jit
def _pointtri_batch(x, V, out):
    for n in range(len(x)):
        u, w = _pointtri_uv(x, n, V, n, 0.0, x, n)
        for i in range(3):
            out[n, i] = V[n, 0, i] + u * (V[n, 1, i] - V[n, 0, i]) + w * (V[n, 2, i] - V[n, 0, i])


def _rows(first, *xs):
    """Writable C-contiguous float copies broadcast to first's shape (one argument type for the kernels,
    whatever the caller passes: read-only broadcasts would compile a second signature)."""
    shape = np.shape(first)
    return tuple(np.array(np.broadcast_to(x, shape), dtype=float, order="C") for x in (first, *xs))


def segment_segment(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> Closest:
    """Closest points of segments p0 -> p1 and q0 -> q1 (each (N, 3))."""
    p0, p1, q0, q1 = _rows(p0, p1, q0, q1)
    d, P, Q = np.empty(len(p0)), np.empty_like(p0), np.empty_like(p0)
    _segseg_batch(p0, p1, q0, q1, d, P, Q)
    return Closest(d, P, Q)


def point_triangle(x: np.ndarray, v0: np.ndarray, v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    """Closest points (N, 3) of triangles (v0, v1, v2) to points x (each (N, 3))."""
    x, v0, v1, v2 = _rows(x, v0, v1, v2)
    out = np.empty_like(x)
    _pointtri_batch(x, np.stack([v0, v1, v2], axis=1), out)
    return out


def segment_triangle(p0: np.ndarray, p1: np.ndarray, v0: np.ndarray, v1: np.ndarray, v2: np.ndarray) -> Closest:
    """Closest points of segments p0 -> p1 and triangles (v0, v1, v2) (each (N, 3))."""
    p0, p1, v0, v1, v2 = _rows(p0, p1, v0, v1, v2)
    d, P, Q = np.empty(len(p0)), np.empty_like(p0), np.empty_like(p0)
    _segtri_batch(p0, p1, np.stack([v0, v1, v2], axis=1), d, P, Q)
    return Closest(d, P, Q)
