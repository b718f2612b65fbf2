"""One contract for evaluating points for a voxel map: :class:`Evaluator`, and its two implementations.

The refinement (:func:`capmap.capacity.refine.refine`) holds the rounds; an evaluator turns points
into point results (:class:`Evaluation`). The contract, checked against every implementation by
``tests/capacity/test_contracts_evaluator.py``:

- ``evaluate(points (N, 3) m)`` alone: every value exact (its independent reference: Pinocchio's
  dynamics, an LP per direction).
- with ``ceiling`` (N,) kg and ``owner`` (N,) int (each point's voxel and that voxel's least value so
  far): the least ``capacity_kg`` of each owner's points is exact wherever it lies below the owner's
  ceiling; any other point may carry a value at or above that least one (never below the exact
  least). Per-axis and per-configuration values are always exact.
- ``pointwise`` True: a point's value depends on that point and its own ceiling only, so a point that
  several voxels share may be evaluated once with the highest of their ceilings; False: a point may be
  pruned by the other points of its owner (the refinement then evaluates shared points per voxel).

:class:`LockedEvaluator` is the failed arm's (every value exact: the ceiling is not used);
:class:`capmap.capacity.healthy_evaluator.HealthyEvaluator` the healthy arm's, in its own module so that
the map's stages do not depend on the healthy arm's search (their code fingerprints follow imports).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from capmap.capacity.problem import CapacityProblem
from capmap.capacity.refine_data import Evaluation

__all__ = ["Evaluator", "LockedEvaluator"]


@runtime_checkable
class Evaluator(Protocol):
    """Point results for the refinement (the module's contract). ``n_evaluated``: points evaluated so far."""

    pointwise: bool
    n_evaluated: int

    def evaluate(self, points: np.ndarray, ceiling: np.ndarray | None = None,
                 owner: np.ndarray | None = None) -> Evaluation: ...


class LockedEvaluator:
    """The locked arm's points: every IK branch x every direction of ``problem``, each value exact,
    ``chunk`` points per call of the problem (memory)."""

    pointwise = True

    def __init__(self, problem: CapacityProblem, chunk: int = 2000):
        self.problem, self.chunk, self.n_evaluated = problem, int(chunk), 0

    def evaluate(self, points: np.ndarray, ceiling: np.ndarray | None = None,
                 owner: np.ndarray | None = None) -> Evaluation:
        sol, pc = self.problem.solve(points, self.chunk)
        self.n_evaluated += len(sol.n_solutions)
        return Evaluation(pc.capacity_kg, pc.axis_capacity_kg, pc.binding, sol.n_solutions, pc.config_capacity_kg,
                          pc.config_axis_capacity_kg, pc.config_binding, pc.config_branches)
