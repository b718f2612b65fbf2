"""The capacity problem: what a load-carrying capacity is asked of on one locked arm.

A :class:`CapacityProblem` is frozen data (the locked arm, the task's end-effector rotation, the
motion, the load limits on the arm's outputs, the motion directions, the grid axes whose per-axis
values are wanted and the configuration labels) with the arm's dynamics built once beside it (one
Pinocchio ``Model``, one ``Data``). Every question about capacity on a locked arm goes through it:
:meth:`CapacityProblem.solve` (every IK branch of each point, then each point's minimum over
branches x directions: :func:`capmap.capacity.engine.point_capacity`) and
:meth:`CapacityProblem.per_branch` (each given configuration on its own). The map's tables, the
refinement, the point query, the atlas and the kernels' warm-up all call these two; the evaluators
of :mod:`capmap.capacity.evaluator` wrap them for the refinement.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from capmap.capacity.directions import Directions
from capmap.capacity.engine import Motion, PointCapacity, point_capacity
from capmap.core import ik
from capmap.core.configuration import Configurations
from capmap.core.dynamics import ArmDynamics
from capmap.core.ik.finish import IKSolutions
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm

__all__ = ["CapacityProblem"]


@dataclass(frozen=True)
class CapacityProblem:
    """The capacity problem of ``arm`` (a :class:`LockedArm`) at end-effector ``rotation`` (3, 3) in the
    base frame, moving at ``motion``, under ``limits`` (on :func:`capmap.core.dynamics.output_names` of
    the arm), minimised over ``directions``. ``axes`` (antipodal pairs, e.g.
    :func:`capmap.capacity.directions.grid_axes`; None: no per-axis values) and ``labels`` (the chain's
    configuration labels; None: no per-configuration values) say which extra minima :meth:`solve` gives.
    ``dyn`` is built from the arm once per problem."""

    arm: LockedArm
    rotation: np.ndarray
    motion: Motion
    limits: AffineLimits
    directions: Directions
    axes: Directions | None = None
    labels: Configurations | None = None
    dyn: ArmDynamics = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "dyn", ArmDynamics(self.arm))

    def branches(self, points_m: np.ndarray) -> IKSolutions:
        """Every IK branch of the arm at points (N, 3) m and the problem's rotation."""
        return ik.solve(self.arm, np.asarray(points_m, dtype=float).reshape(-1, 3), self.rotation)

    def capacity(self, sol: IKSolutions) -> PointCapacity:
        """Each point's capacity (kg, min over its branches in ``sol`` x the directions), with the per-axis
        and per-configuration minima the problem asks for."""
        return point_capacity(self.dyn, sol.q, sol.n_solutions, self.directions, self.motion, self.limits,
                              self.axes, self.labels)

    def solve(self, points_m: np.ndarray, chunk: int = 2000) -> tuple[IKSolutions, PointCapacity]:
        """IK and capacity of N points (N, 3) m, ``chunk`` points at a time (memory: chunk x branches x
        directions states): the IK solutions and :class:`PointCapacity`, both for all N points."""
        pts = np.asarray(points_m, dtype=float).reshape(-1, 3)
        if len(pts) <= chunk:
            sol = self.branches(pts)
            return sol, self.capacity(sol)
        parts = [self.solve(pts[r:r + chunk], chunk) for r in range(0, len(pts), chunk)]
        K = max(s.q.shape[1] for s, _ in parts)
        q = np.concatenate([np.pad(s.q, ((0, 0), (0, K - s.q.shape[1]), (0, 0)), constant_values=np.nan)
                            for s, _ in parts])
        sol = IKSolutions(q, np.concatenate([s.n_solutions for s, _ in parts]), parts[0][0].method)
        return sol, _concat([pc for _, pc in parts])

    def per_branch(self, q_rad: np.ndarray) -> PointCapacity:
        """The capacity of each configuration q_rad (K, n_active) rad on its own (K rows: the branch's
        minimum over the directions, its worst direction and binding limit)."""
        q = np.asarray(q_rad, dtype=float).reshape(-1, self.arm.n_active)
        return point_capacity(self.dyn, q[:, None, :], np.ones(len(q), dtype=int), self.directions, self.motion,
                              self.limits)


def _concat(parts: list[PointCapacity]) -> PointCapacity:
    """Point results of consecutive chunks as one."""
    fields = {}
    for f in PointCapacity.__dataclass_fields__:
        vals = [getattr(p, f) for p in parts]
        fields[f] = vals[0] if f == "names" or vals[0] is None else np.concatenate(vals)
    return PointCapacity(**fields)
