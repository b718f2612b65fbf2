"""Voxel values that do not overstate: refine each voxel's minimum until it has converged.

A voxel's capacity is the minimum over the points inside it (the spec's step 7), estimated from the
points evaluated there. A handful of points overstates it where the capacity falls steeply inside the
voxel (a singular configuration, a branch that appears at a workspace boundary), so every voxel that
has a reachable point is refined in rounds: the first evaluates the voxel's corners; then, each round,
a compass of points around the worst point of the all-branch value, of each configuration and of each
per-axis minimum while it still falls, the step halving every round (a local minimiser from the worst
points), and from the second round uniform points until the voxel holds ``min_points``
(``near_min_points`` when its value lies within ``near_band`` of a task payload); no point of a voxel is
evaluated twice, and a point several voxels ask for in a round (a shared corner or face point) is
evaluated once. The voxel has converged when the round lowered its minimum, and each per-axis minimum,
by less than ``rel_tol``; the compass' step reaching ``finest_step`` of the edge (every voxel's, an open
bracket's bisection goes on), or the voxel holding ``max_points``, ends its search (it is then reported
as not converged if its minima were still falling).

Where two points of a voxel have different numbers of IK branches, a fold of the IK map (a singular
surface, or the workspace boundary) crosses the voxel; there two branches merge at a singular
configuration and the capacity falls towards 0 in a thin shell that uniform points rarely hit. Such a
voxel bisects the segment between two points of different branch counts, one point per round, until
the bracket is shorter than ``fold_tol_m``, and stays unconverged until then (once its minima settled,
only the bisection goes on). Likewise per configuration: where two points of a voxel hold different
numbers of a configuration's solutions, its boundary (a singular surface where it meets another, or a
fold) crosses the voxel and that segment is bisected too; near a singular boundary the configuration's
capacity falls to 0, which the bisection's last points find (a configuration whose value and every
per-axis value are 0 already has nothing left to find: its bracket stops). When the closed fold bracket holds a point
of capacity 0, the fold is a singular surface: moving along any grid axis that crosses it needs
unbounded joint rates, so every per-axis value of the voxel is set to 0 too (a grid axis tangent to the
fold everywhere in the voxel is the exception this rounds down). With configuration maps
(:meth:`VoxelMinima.with_configurations`) every configuration is refined beside the all-branch value from
the same points; the configurations a fold ends (the two whose solutions merge on it) fall to 0 with it,
the others keep their own values.

A voxel whose minimum and per-axis minima are all 0 cannot fall further and has converged. The per-axis
capacities (moves along the 13 grid axes) are minimised over the same points. The evaluation of points
is an :class:`~capmap.capacity.evaluator.Evaluator` passed in (this module holds the rounds); randomness
comes from the Generator given.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from capmap.capacity.evaluator import Evaluator
from capmap.capacity.patterns import unique_rows
from capmap.capacity.refine_data import Evaluation, RefineSettings, VoxelMinima
from capmap.capacity.refine_rounds import Rounds, argmin_columns
from capmap.capacity.voxels import Grid

__all__ = ["RefineSettings", "Evaluation", "VoxelMinima", "refine", "argmin_columns"]


def refine(grid: Grid, start: VoxelMinima, evaluator: Evaluator, settings: RefineSettings,
           rng: np.random.Generator, progress: Callable[[int, int, int], None] | None = None) -> VoxelMinima:
    """Refine the voxels of ``start`` (their minima from the points already evaluated; a voxel
    without a reachable point keeps NaN and is not refined). ``evaluator`` gives the point results
    (:mod:`capmap.capacity.evaluator`'s contract), each point's ceiling its voxel's all-branch minimum so
    far and its owner that voxel; ``progress(round, active voxels, points)`` is called per round. A
    point several brackets of a voxel ask for in one round is evaluated once; for a ``pointwise``
    evaluator also a point several voxels ask for (neighbours share their corners), owned by one of
    them with the highest of their ceilings.

    With configuration fields in ``start`` (:meth:`VoxelMinima.with_configurations`; the evaluator
    then gives them too), every configuration's minimum and per-axis minima are refined as the
    all-branch ones are (groups: all branches, then each configuration), from the same points: a
    voxel has converged when every group has; a compass around each group's worst point still
    falling. A fold ends some configurations (their solution counts differ at the bracket's two ends:
    the two that merge on the singular surface): while the bracket is open they wait (no compass, not
    counted against convergence), and when it closes on a singular fold (all-branch capacity 0) their
    minimum and per-axis values are 0 (the infimum at the surface), their worst point the bracket's end
    on their side, within ``fold_tol_m`` of it. A group whose value and axes are all 0 has converged.
    The start's worst point is evaluated again in the first round, so that the configurations' minima
    hold the point of the all-branch one (the lowest of them is then at most the all-branch value).
    A configuration that no point of a voxel holds stays NaN there."""
    st = Rounds.begin(grid, start)
    while (plan := st.plan(settings)) is not None:
        st.rounds += 1
        owner, pts, new, n_first = st.points(start, plan, settings, rng)
        ev, n_unique = _evaluate_once(evaluator, pts, st.cap[owner, 0], owner)
        if progress:
            progress(st.rounds, len(plan.active), n_unique)
        st.evaluated += n_unique
        st.seen = np.concatenate([st.seen, np.column_stack([owner, pts])])
        drop, axis_drop = st.absorb(ev, owner, pts, plan)
        st.track(ev, owner, pts, plan, n_first)
        st.settle(plan, new, drop, axis_drop, settings)
    return st.result()


def _evaluate_once(evaluator: Evaluator, pts: np.ndarray, ceiling: np.ndarray, owner: np.ndarray
                   ) -> tuple[Evaluation, int]:
    """``evaluator`` on the distinct points of a round only (a bracket's midpoint shared by a voxel's
    configurations; for a pointwise evaluator, also a corner or face point shared by neighbouring voxels): results
    per row of pts, and the number of points evaluated. A point shared by voxels is evaluated
    once, owned by one of them, with the highest of their ceilings."""
    key = pts if evaluator.pointwise else np.column_stack([owner, pts])
    first, inv = unique_rows(key)
    if len(first) == len(pts):
        return evaluator.evaluate(pts, ceiling, owner), len(pts)
    ceil = np.full(len(first), -np.inf)
    np.maximum.at(ceil, inv, ceiling)
    ev = evaluator.evaluate(pts[first], ceil, owner[first])
    return Evaluation(*(None if (x := getattr(ev, f)) is None else x[inv] for f in Evaluation.__dataclass_fields__)), \
        len(first)
