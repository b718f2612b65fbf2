"""Monte Carlo workspace of the locked arm.

``joint_samples`` is the paper's method: active joints uniform in their ranges, locked
joint fixed, forward kinematics gives end-effector positions. ``voxel_fill`` adds, for
every voxel of the bounding grid, its centre plus ``jitter`` uniform points inside it, so
no voxel goes unevaluated for lack of samples. Randomness comes only from the Generator
passed in.
"""

from __future__ import annotations

import numpy as np

from capmap.capacity.voxels import Grid
from capmap.core.reduction import LockedArm

__all__ = ["joint_samples", "voxel_fill"]


def joint_samples(arm: LockedArm, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """n uniform joint vectors (n, n_active) rad and their end-effector positions (n, 3) m."""
    q = rng.uniform(arm.q_lower, arm.q_upper, size=(n, arm.n_active))
    return q, arm.fk(q)[:, :3, 3]


def voxel_fill(grid: Grid, jitter: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Every voxel's centre plus ``jitter`` uniform points inside it.

    Returns positions (M, 3) m and kind (M,) int: 0 = centre, 1 = jitter.
    M = n_voxels * (1 + jitter), voxel-major order.
    """
    centres = grid.centres()  # (V, 3)
    V = len(centres)
    offsets = rng.uniform(-0.5, 0.5, size=(V, jitter, 3)) * grid.edge_m
    pts = np.concatenate([centres[:, None, :], centres[:, None, :] + offsets], axis=1).reshape(-1, 3)
    kind = np.tile(np.r_[0, np.ones(jitter, dtype=int)], V)
    return pts, kind
