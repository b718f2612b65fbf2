"""Swept-sphere volumes: capsules (segment + radius) and swept triangles (triangle + radius),
and the minimum-volume capsule that covers a set of balls.

A capsule covers a ball (centre c, radius rho) when dist(c, segment) + rho <= R. For a fixed
axis line (direction u through o) and radius R, the shortest covering segment is exact:
with t_i = (c_i - o) . u and rho_i the ball's distance from the line, each ball needs the
segment to reach within h_i = sqrt((R - r_i)^2 - rho_i^2) of t_i, so [t0, t1] =
[min(t_i + h_i), max(t_i - h_i)]. The volume pi R^2 L + 4/3 pi R^3 is then minimised over R
(bounded scalar search) and the line over (u, o) (Nelder-Mead from the principal axis).
A mesh or polytope is covered when its vertices are (the capsule is convex); a cylinder's
rims are sampled on a circumscribed polygon so that their hull contains the circles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize
from scipy.spatial import ConvexHull, QhullError

from capmap.errors import CapmapError

__all__ = ["Capsule", "SweptTriangle", "capsule_volume", "fit_capsule", "covers", "cylinder_points", "box_points"]


@dataclass(frozen=True)
class Capsule:
    """Segment a -> b (3,) m dilated by radius r m."""

    a: np.ndarray
    b: np.ndarray
    r: float

    @property
    def volume(self) -> float:
        return capsule_volume(float(np.linalg.norm(self.b - self.a)), self.r)


@dataclass(frozen=True)
class SweptTriangle:
    """Triangle v (3, 3) m (rows are vertices) dilated by radius r m."""

    v: np.ndarray
    r: float


def capsule_volume(length: float, r: float) -> float:
    return float(np.pi * r * r * length + 4.0 / 3.0 * np.pi * r**3)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _frame(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing u to an orthonormal basis."""
    h = np.array([1.0, 0, 0]) if abs(u[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = _cross(u, h)
    e1 /= np.sqrt(e1 @ e1)
    return e1, _cross(u, e1)


def _best_for_line(c: np.ndarray, r: np.ndarray, o: np.ndarray, u: np.ndarray) -> tuple[float, float, float, float]:
    """(volume, R, t0, t1) of the smallest capsule on the line o + t u covering balls (c, r); R by two
    rounds of a 48-point grid (the second within the best cell of the first)."""
    rel = c - o
    t = rel @ u
    rho = np.linalg.norm(rel - np.outer(t, u), axis=1)
    r_min = float((rho + r).max())

    def geometry(R):  # R (k,) -> volume, t0, t1 (each (k,))
        h = np.sqrt(np.maximum((R[:, None] - r) ** 2 - rho**2, 0.0))
        t0, t1 = (t + h).min(axis=1), (t - h).max(axis=1)
        return np.pi * R**2 * np.maximum(t1 - t0, 0.0) + 4.0 / 3.0 * np.pi * R**3, t0, t1

    lo, hi = r_min, r_min + float(t.max() - t.min()) + 1e-9
    for _ in range(2):
        R = np.linspace(lo, hi, 48)
        vol = geometry(R)[0]
        k = int(np.argmin(vol))
        lo, hi = R[max(k - 1, 0)], R[min(k + 1, 47)]
    vol, t0, t1 = (x[0] for x in geometry(R[[k]]))
    if t1 < t0:  # a sphere suffices: centre the (degenerate) segment
        t0 = t1 = 0.5 * (t0 + t1)
    return float(vol), float(R[k]), float(t0), float(t1)


def _directions(n: int) -> np.ndarray:
    """n near-uniform unit vectors on a hemisphere (an axis and its opposite are one line)."""
    i = np.arange(n) + 0.5
    z = 1 - i / n
    phi = np.pi * (1 + 5**0.5) * i
    s = np.sqrt(1 - z * z)
    return np.column_stack([s * np.cos(phi), s * np.sin(phi), z])


_FIT_POINTS = 256  # the most balls the line search scores (a mesh's hull has thousands of vertices)


def _farthest(c: np.ndarray, k: int) -> np.ndarray:
    """Indices of k points of c (n, 3) spread by farthest-point sampling (from the first point)."""
    keep = np.zeros(k, dtype=int)
    d = np.linalg.norm(c - c[0], axis=1)
    for i in range(1, k):
        keep[i] = int(np.argmax(d))
        d = np.minimum(d, np.linalg.norm(c - c[keep[i]], axis=1))
    return keep


def fit_capsule(centres: np.ndarray, radii: np.ndarray | None = None, restarts: int = 2) -> Capsule:
    """The minimum-volume capsule covering balls (centres (n, 3) m, radii (n,) m; points: radius 0):
    the principal axes and 150 directions through the centroid are scored, the best ``restarts``
    lines refined by Nelder-Mead over direction and offset. Of points only the convex hull's vertices
    count; beyond 256 balls the lines are scored on a farthest-point subset and the capsule on each
    refined line is then the smallest covering every ball (coverage exact, volume near minimal)."""
    c = np.asarray(centres, dtype=float)
    if c.ndim != 2 or c.shape[1] != 3 or len(c) == 0:
        raise CapmapError(f"a capsule needs points of shape (n, 3), got {c.shape}")
    r = np.zeros(len(c)) if radii is None else np.asarray(radii, dtype=float)
    point = r == 0
    if point.sum() > 8:  # of the points (balls of radius 0) only the convex hull's vertices matter
        try:
            hull = c[point][ConvexHull(c[point]).vertices]
            c, r = np.concatenate([hull, c[~point]]), np.concatenate([np.zeros(len(hull)), r[~point]])
        except QhullError:  # flat or degenerate sets keep every point
            pass
    c_all, r_all = c, r
    if len(c) > _FIT_POINTS:  # the line is searched on a spread subset; the capsule on it covers them all
        keep = _farthest(c, _FIT_POINTS)
        c, r = c[keep], r[keep]
    mean = c.mean(axis=0)
    axes = np.linalg.svd(c - mean, full_matrices=False)[2] if len(c) > 1 else np.eye(3)

    def unpack(x, u0):
        e1, e2 = _frame(u0)
        u = u0 + x[0] * e1 + x[1] * e2
        u /= np.linalg.norm(u)
        f1, f2 = _frame(u)
        return mean + x[2] * f1 + x[3] * f2, u

    candidates = np.concatenate([axes[:min(3, len(axes))], _directions(150)])
    scores = [_best_for_line(c, r, mean, u)[0] for u in candidates]
    best = None
    for u0 in candidates[np.argsort(scores)[:restarts]]:
        res = minimize(lambda x, u0=u0: _best_for_line(c, r, *unpack(x, u0))[0], np.zeros(4), method="Nelder-Mead",
                       options={"xatol": 1e-5, "fatol": 1e-10, "maxiter": 600})
        o, u = unpack(res.x, u0)
        vol, R, t0, t1 = _best_for_line(c_all, r_all, o, u)
        if best is None or vol < best[0]:
            best = (vol, Capsule(o + t0 * u, o + t1 * u, R))
    return best[1]


def covers(capsule: Capsule, points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Which points (n, 3) lie inside the capsule (within tol)."""
    a, b = capsule.a, capsule.b
    d = b - a
    L2 = float(d @ d)
    t = np.clip((points - a) @ d / L2, 0.0, 1.0) if L2 > 0 else np.zeros(len(points))
    return np.linalg.norm(points - (a + np.outer(t, d)), axis=1) <= capsule.r + tol


def cylinder_points(radius: float, half_length: float, n: int = 24) -> np.ndarray:
    """Points (2n, 3) on two circumscribed n-gons of a z-axis cylinder's rims (their hull contains it)."""
    phi = 2 * np.pi * np.arange(n) / n
    R = radius / np.cos(np.pi / n)
    ring = np.column_stack([R * np.cos(phi), R * np.sin(phi), np.zeros(n)])
    return np.concatenate([ring + [0, 0, -half_length], ring + [0, 0, half_length]])


def box_points(half_sides: np.ndarray) -> np.ndarray:
    """The 8 corners (8, 3) of a centred box."""
    s = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    return s * np.asarray(half_sides, dtype=float)
