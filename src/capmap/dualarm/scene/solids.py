"""The assembly scene: solid boxes and cylinders (cabin, satellite, pins), the panel and its
poses, and a synthetic scan of the scene's surfaces as a depth camera would see them.

The scan samples every surface on a grid of ``spacing_m``, keeps the points that some
viewpoint sees (the surface faces it and no solid lies between), and adds Gaussian noise
of ``noise_m`` along each coordinate. Everything here is SI, in the robot's base frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["Box", "Cylinder", "PanelSpec", "Scene", "ScanSettings", "scan", "surface_points", "pose", "nearest_solid"]


def pose(xyz, rpy_deg) -> np.ndarray:
    """Homogeneous transform (4, 4) from a position and roll-pitch-yaw (deg, R = Rz Ry Rx)."""
    r, p, y = np.deg2rad(np.asarray(rpy_deg, dtype=float))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    T = np.eye(4)
    T[:3, :3] = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                 [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                 [-sp, cp * sr, cp * cr]]
    T[:3, 3] = xyz
    return T


@dataclass(frozen=True)
class Box:
    """An axis-aligned solid box: name, lower (3,) and upper (3,) corners m."""

    name: str
    lower: np.ndarray
    upper: np.ndarray


@dataclass(frozen=True)
class Cylinder:
    """A solid cylinder: name, axis end points p0, p1 (3,) m, radius m."""

    name: str
    p0: np.ndarray
    p1: np.ndarray
    radius: float


@dataclass(frozen=True)
class PanelSpec:
    """The held panel: size (3,) m along its x (thickness), y, z; hole positions (h, 2) panel-local
    (y, z) m and radius; grasp points (2, 3) panel-local m of the left and right grippers; mass kg and
    principal moments of inertia (3,) kg m^2 about its centre along its axes."""

    size: np.ndarray
    holes: np.ndarray
    hole_radius: float
    grasp: np.ndarray
    mass: float = 0.0
    inertia: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def corners(self) -> np.ndarray:
        """The face's four corners (4, 3) in the panel frame (its mid-plane x = 0), in order."""
        _, w, h = self.size / 2
        return np.array([[0, -w, -h], [0, w, -h], [0, w, h], [0, -w, h]], dtype=float)


@dataclass(frozen=True)
class Scene:
    """Solids (boxes, cylinders), the panel, its poses start, pre_insertion, final (4, 4), the
    insertion axis (point (3,), unit direction (3,)), pin_zone (2, 3) m: a box holding the pins
    that the panel's holes slide over (not checked against the panel), and the start
    configuration q_start (14,) rad of the two arms (left s0..w2, right s0..w2)."""

    name: str
    boxes: tuple[Box, ...]
    cylinders: tuple[Cylinder, ...]
    panel: PanelSpec
    start: np.ndarray
    pre_insertion: np.ndarray
    final: np.ndarray
    axis_point: np.ndarray
    axis_direction: np.ndarray
    pin_zone: np.ndarray
    q_start: np.ndarray


@dataclass(frozen=True)
class ScanSettings:
    """viewpoints (v, 3) m; spacing_m of the surface grid; noise_m (Gaussian sigma per coordinate);
    max_range_m of the cameras."""

    viewpoints: np.ndarray
    spacing_m: float
    noise_m: float
    max_range_m: float = 4.0


def _grid(n0: int, n1: int) -> tuple[np.ndarray, np.ndarray]:
    a, b = np.meshgrid((np.arange(n0) + 0.5) / n0, (np.arange(n1) + 0.5) / n1, indexing="ij")
    return a.ravel(), b.ravel()


def surface_points(scene: Scene, spacing: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points (P, 3) on every solid's surface about ``spacing`` apart, their outward normals
    (P, 3) and the index (P,) of their solid (boxes first, then cylinders)."""
    pts, nrm, owner = [], [], []
    for k, box in enumerate(scene.boxes):
        lo, hi = box.lower, box.upper
        for axis in range(3):
            u, v = [a for a in range(3) if a != axis]
            nu = max(1, int(np.ceil((hi[u] - lo[u]) / spacing)))
            nv = max(1, int(np.ceil((hi[v] - lo[v]) / spacing)))
            a, b = _grid(nu, nv)
            for side, value in ((-1.0, lo[axis]), (1.0, hi[axis])):
                p = np.zeros((len(a), 3))
                p[:, u], p[:, v], p[:, axis] = lo[u] + a * (hi[u] - lo[u]), lo[v] + b * (hi[v] - lo[v]), value
                n = np.zeros_like(p)
                n[:, axis] = side
                pts.append(p)
                nrm.append(n)
                owner.append(np.full(len(p), k))
    for k, cyl in enumerate(scene.cylinders, start=len(scene.boxes)):
        d = cyl.p1 - cyl.p0
        L = np.linalg.norm(d)
        z = d / L
        x = np.cross(z, [1.0, 0, 0] if abs(z[0]) < 0.9 else [0, 1.0, 0])
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        na = max(6, int(np.ceil(2 * np.pi * cyl.radius / spacing)))
        a, b = _grid(na, max(1, int(np.ceil(L / spacing))))
        radial = np.outer(np.cos(2 * np.pi * a), x) + np.outer(np.sin(2 * np.pi * a), y)
        pts.append(cyl.p0 + np.outer(b * L, z) + cyl.radius * radial)
        nrm.append(radial)
        owner.append(np.full(len(a), k))
        a, b = _grid(na, max(1, int(np.ceil(cyl.radius / spacing))))  # the far end cap (the near one sits on a face)
        disc = np.sqrt(b)[:, None] * cyl.radius * (np.outer(np.cos(2 * np.pi * a), x) + np.outer(np.sin(2 * np.pi * a), y))
        pts.append(cyl.p1 + disc)
        nrm.append(np.broadcast_to(z, disc.shape).copy())
        owner.append(np.full(len(a), k))
    return np.concatenate(pts), np.concatenate(nrm), np.concatenate(owner)


def _blocked_by_boxes(p: np.ndarray, v: np.ndarray, boxes: tuple[Box, ...], owner: np.ndarray) -> np.ndarray:
    """Whether the segment from each point p (P, 3) to the viewpoint v (3,) passes through a box
    other than the point's own (slab test)."""
    d = v - p
    blocked = np.zeros(len(p), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        for k, box in enumerate(boxes):
            t0, t1 = (box.lower - p) * inv, (box.upper - p) * inv
            near = np.nanmax(np.minimum(t0, t1), axis=1)
            far = np.nanmin(np.maximum(t0, t1), axis=1)
            hit = (near < far) & (far > 1e-6) & (near < 1 - 1e-6)
            blocked |= hit & (owner != k)
    return blocked


def scan(scene: Scene, settings: ScanSettings, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A noisy partial scan, each camera's own: points (P, 3) m and the viewpoint that took each (P,) (a
    surface two cameras see is in the cloud twice, once from each, as a multi-camera scan has it)."""
    p, n, owner = surface_points(scene, settings.spacing_m)
    out, seen_by = [], []
    for k, v in enumerate(np.atleast_2d(settings.viewpoints)):
        to_v = v - p
        dist = np.linalg.norm(to_v, axis=1)
        ok = (np.einsum("ij,ij->i", n, to_v) > 0) & (dist <= settings.max_range_m)
        idx = np.flatnonzero(ok)
        ok[idx] &= ~_blocked_by_boxes(p[idx], v, scene.boxes, owner[idx])
        out.append(p[ok] + rng.normal(0.0, settings.noise_m, size=(int(ok.sum()), 3)))
        seen_by.append(np.full(int(ok.sum()), k))
    return np.concatenate(out), np.concatenate(seen_by)


def nearest_solid(scene: Scene, points: np.ndarray, spacing: float = 0.02, within_m: float = 0.1) -> np.ndarray:
    """The name of the solid whose surface is nearest each point (n, 3) ('' beyond within_m):
    labels for volumes fitted to a cloud of this scene."""
    surf, _, owner = surface_points(scene, spacing)
    names = np.array([s.name for s in (*scene.boxes, *scene.cylinders)] + [""], dtype=object)
    dist, idx = cKDTree(surf).query(np.atleast_2d(points))
    return np.where(dist <= within_m, names[owner[idx]], "")
