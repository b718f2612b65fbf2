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
from capmap.capacity.engine import (
    SINGULAR,
    Motion,
    PointCapacity,
    argmin_per_group,
    coefficients,
    direction_minimum,
    motion_features,
)
from capmap.capacity.sweep import min_per_pair
from capmap.core import ik
from capmap.core.configuration import Configurations
from capmap.core.dynamics import ArmDynamics
from capmap.core.ik.finish import IKSolutions
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm

__all__ = ["CapacityProblem", "point_capacity"]


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
        return point_capacity(self, sol.q, sol.n_solutions)

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
        return point_capacity(self, q[:, None, :], np.ones(len(q), dtype=int), extras=False)


def point_capacity(problem: CapacityProblem, q_sets: np.ndarray, n_solutions: np.ndarray,
                   extras: bool = True) -> PointCapacity:
    """Capacity of N points of ``problem`` from their IK configuration sets.

    q_sets: (N, K, n_active) rad, NaN-padded beyond n_solutions (N,) per point; each point's least
    value over its configurations x the problem's directions. With ``extras`` and the problem's
    ``axes`` (directions in antipodal pairs, e.g. :func:`~capmap.capacity.directions.grid_axes`), also
    the capacity along each pair's line (moving along u or -u), min over the configuration set:
    axis_capacity_kg (N, P). With ``extras`` and the problem's ``labels`` (the chain's configuration
    labels, :mod:`capmap.core.configuration`), the same minima per configuration label (C labels):
    config_capacity_kg (N, C), config_binding (N, C) and, with axes, config_axis_capacity_kg (N, C, P);
    the all-branch values are their minima over C.
    """
    dyn, directions, motion, limits = problem.dyn, problem.directions, problem.motion, problem.limits
    axes, configurations = (problem.axes, problem.labels) if extras else (None, None)
    N, K = q_sets.shape[:2]
    names = limits.names + (SINGULAR,)
    cap = np.full(N, np.nan)
    binding = np.full(N, -1)
    branch = np.full(N, -1)
    direction = np.full(N, -1)
    worst_u = np.full((N, 3), np.nan)
    valid = np.arange(K)[None, :] < np.asarray(n_solutions)[:, None]
    pts, brs = np.nonzero(valid)
    axis_cap = None if axes is None else np.full((N, len(axes.pairs)), np.nan)
    if len(pts):
        coef = coefficients(dyn, q_sets[pts, brs])
        c_cfg, worst_dir, u_cfg, b_cfg = direction_minimum(coef, directions, motion, dyn.gravity, limits)
        if axes is not None:
            a = motion.a_max_mps2
            per_axis, _ = min_per_pair(coef.stacked(), coef.S, motion_features(axes.u, motion), a * axes.u, dyn.gravity,
                                       limits.limit, axes.pairs)
            per_axis[coef.singular] = 0.0
            axis_cap[:] = np.inf
            np.minimum.at(axis_cap, pts, per_axis)
            axis_cap[np.asarray(n_solutions) == 0] = np.nan
        sel = argmin_per_group(c_cfg, pts)  # min over each point's configurations
        p = pts[sel]
        cap[p] = c_cfg[sel]
        branch[p] = brs[sel]
        direction[p] = worst_dir[sel]
        worst_u[p] = u_cfg[sel]
        binding[p] = b_cfg[sel]
    per_config = {}
    if configurations is not None:
        C = len(configurations.names)
        lab = configurations.labels(q_sets[pts, brs]) if len(pts) else np.zeros(0, dtype=int)
        cc = np.full((N, C), np.nan)
        cb = np.full((N, C), -1)
        if len(pts):
            group = pts * C + lab  # an aspect can hold several solutions of a point: their minimum
            sel = argmin_per_group(c_cfg, group)
            cc.reshape(-1)[group[sel]] = c_cfg[sel]
            cb.reshape(-1)[group[sel]] = b_cfg[sel]
        nb = np.zeros((N, C), dtype=int)
        np.add.at(nb, (pts, lab), 1)
        per_config = {"config_capacity_kg": cc, "config_binding": cb, "config_branches": nb}
        if axes is not None:
            ca = np.full((N, C, len(axes.pairs)), np.inf)
            if len(pts):
                np.minimum.at(ca, (pts, lab), per_axis)
            ca[~np.isfinite(cc)] = np.nan
            per_config["config_axis_capacity_kg"] = ca
    return PointCapacity(capacity_kg=cap, binding=binding, branch=branch, direction=direction, worst_u=worst_u,
                         n_states=np.asarray(n_solutions) * len(directions), names=names, axis_capacity_kg=axis_cap,
                         **per_config)


def _concat(parts: list[PointCapacity]) -> PointCapacity:
    """Point results of consecutive chunks as one."""
    fields = {}
    for f in PointCapacity.__dataclass_fields__:
        vals = [getattr(p, f) for p in parts]
        fields[f] = vals[0] if f == "names" or vals[0] is None else np.concatenate(vals)
    return PointCapacity(**fields)
