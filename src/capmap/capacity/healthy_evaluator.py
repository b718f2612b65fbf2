"""The healthy arm's implementation of the refinement's :class:`~capmap.capacity.evaluator.Evaluator`
contract (:mod:`capmap.capacity.evaluator`; checked by ``tests/capacity/test_contracts_evaluator.py``):
:class:`HealthyEvaluator`, whose state is its swept joint's angles and, per voxel, the angle of the
voxel's least value so far (a hint tried first)."""

from __future__ import annotations

import numpy as np

from capmap.capacity.baseline import healthy_capacity
from capmap.capacity.engine import argmin_per_group
from capmap.capacity.refine_data import Evaluation
from capmap.capacity.self_motion import HealthyProblem, Hint

__all__ = ["HealthyEvaluator"]


class HealthyEvaluator:
    """The healthy arm's points (:func:`capmap.capacity.baseline.healthy_capacity`) of ``hp`` (the arm over
    its swept joint's angles, the task's rotation, motion and directions, the screening set); ``n_voxels``
    the owners' range (the refinement's voxels: owner = a voxel's row). A voxel's points are evaluated
    together, ``chunk`` at a time; each voxel's least value exact, the others may stop at it, tried first
    on the configuration of the voxel's least value's posture, at and near its angle. No per-axis or
    per-configuration values. Per voxel it keeps its least value's point and posture (``least_m``,
    ``angle_of``: where the search of its next points starts, :meth:`hint`)."""

    pointwise = False

    def __init__(self, hp: HealthyProblem, n_voxels: int, chunk: int = 1000):
        self.hp, self.chunk, self.n_evaluated = hp, int(chunk), 0
        self.hint_of = np.full(int(n_voxels), -1)  # per voxel: the grid angle (index) of its least value's posture
        self.configuration_of = np.full(int(n_voxels), -1)  # and that posture's configuration label
        self.least_m = np.full((int(n_voxels), 3), np.nan)  # the point of that least value
        self.angle_of = np.full(int(n_voxels), np.nan)  # and its posture's angle (deg)

    def evaluate(self, points: np.ndarray, ceiling: np.ndarray | None = None,
                 owner: np.ndarray | None = None) -> Evaluation:
        N = len(points)
        order = np.argsort(owner, kind="stable") if owner is not None else np.arange(N)
        cap, binding, angle = np.full(N, np.nan), np.full(N, -1), np.full(N, np.nan)
        q = np.full((N, self.hp.sm.arms[0].n_active), np.nan)
        for r in range(0, N, self.chunk):
            rows = order[r:r + self.chunk]
            hc = healthy_capacity(self.hp, points[rows], None if ceiling is None else ceiling[rows],
                                  None if owner is None else owner[rows], None if owner is None else self.hint(owner[rows]))
            cap[rows], binding[rows], angle[rows], q[rows] = hc.capacity_kg, hc.binding, hc.angle_deg, hc.q_rad
        self.n_evaluated += N
        if owner is not None and N:  # a voxel's new least value: its posture (labelled) is the voxel's next hint
            c = np.where(np.isfinite(cap), cap, np.inf)
            i = argmin_per_group(c, owner)
            i = i[np.isfinite(c[i]) & (c[i] < (np.inf if ceiling is None else ceiling[i]))]
            self.hint_of[owner[i]] = self.hp.sm.grid_index(angle[i])
            self.configuration_of[owner[i]] = self.hp.sm.grid_configuration(angle[i], q[i])
            self.least_m[owner[i]], self.angle_of[owner[i]] = points[i], angle[i]
        return Evaluation(cap, np.zeros((N, 0)), binding, np.isfinite(cap).astype(int))

    def hint(self, owner: np.ndarray) -> Hint:
        """Where the search of points of these owners (N,) starts: their voxels' least value's posture
        (its grid angle and configuration; -1 before the voxel has one)."""
        return Hint(self.hint_of[owner], self.configuration_of[owner])
