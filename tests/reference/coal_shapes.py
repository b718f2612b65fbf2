"""coal (the collision library Pinocchio uses) as the reference for swept-sphere distances:
capsules and one-triangle meshes placed in the world frame."""

from __future__ import annotations

import coal
import numpy as np

__all__ = ["capsule", "triangle", "distance"]


def capsule(a: np.ndarray, b: np.ndarray, r: float) -> tuple[coal.Capsule, coal.Transform3s]:
    """A coal capsule spanning a -> b (3,) m with radius r (its axis is z, centred); a sphere when a = b."""
    d = b - a
    L = np.linalg.norm(d)
    if L == 0:
        return coal.Sphere(r), coal.Transform3s(np.eye(3), a)
    z = d / L
    x = np.cross(z, [1.0, 0, 0] if abs(z[0]) < 0.9 else [0, 1.0, 0])
    x /= np.linalg.norm(x)
    return coal.Capsule(r, L), coal.Transform3s(np.column_stack([x, np.cross(z, x), z]), (a + b) / 2)


def triangle(v0: np.ndarray, v1: np.ndarray, v2: np.ndarray) -> tuple[coal.BVHModelOBBRSS, coal.Transform3s]:
    """A one-triangle mesh with world-frame vertices."""
    bvh = coal.BVHModelOBBRSS()
    bvh.beginModel(1, 3)
    bvh.addTriangle(v0, v1, v2)
    bvh.endModel()
    return bvh, coal.Transform3s()


def distance(g1, T1, g2, T2) -> float:
    """coal's distance of two placed shapes (m; its own convention when they overlap)."""
    return coal.distance(g1, T1, g2, T2, coal.DistanceRequest(), coal.DistanceResult())
