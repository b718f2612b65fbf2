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
from capmap.capacity.folds import ConfigBrackets, FoldBrackets
from capmap.capacity.patterns import COMPASS, CORNERS, around, rows_in
from capmap.capacity.refine_data import Evaluation, RefineSettings, VoxelMinima
from capmap.capacity.voxels import Grid

__all__ = ["RefineSettings", "Evaluation", "VoxelMinima", "refine", "argmin_columns"]


def _near(cap: np.ndarray, s: RefineSettings) -> np.ndarray:
    """(V, G) values -> (V,): some value within near_band of a payload."""
    if not s.payloads_kg:
        return np.zeros(len(cap), dtype=bool)
    p = np.asarray(s.payloads_kg, dtype=float)
    return np.any(np.abs(cap[..., None] - p) <= s.near_band * p, axis=(1, 2))


def _groups(ev: Evaluation, C: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Point results as groups: all branches (group 0), then each configuration: capacity (N, G)
    and binding (N, G) and axis capacities (N, G, A), +inf where a group has no solution."""
    c, a, b = ev.capacity_kg[:, None], ev.axis_capacity_kg[:, None, :], ev.binding[:, None]
    if C:
        c = np.concatenate([c, ev.config_capacity_kg], axis=1)
        a = np.concatenate([a, ev.config_axis_capacity_kg], axis=1)
        b = np.concatenate([b, ev.config_binding], axis=1)
    return np.where(np.isfinite(c), c, np.inf), b, np.where(np.isfinite(a), a, np.inf)


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
    s = settings
    C = 0 if start.config_capacity_kg is None else start.config_capacity_kg.shape[1]
    V, A = start.axis_capacity_kg.shape
    # groups: 0 = all branches, 1.. = configurations; +inf: no point of the group seen yet
    cap = start.capacity_kg.astype(float)[:, None]
    axis = start.axis_capacity_kg.astype(float)[:, None, :]
    worst = start.worst_m.astype(float)[:, None, :]
    binding = start.binding.astype(int)[:, None]
    n_grp = start.n_reachable.astype(int)[:, None]
    if C:
        cap = np.concatenate([cap, start.config_capacity_kg], axis=1)
        axis = np.concatenate([axis, start.config_axis_capacity_kg], axis=1)
        worst = np.concatenate([worst, start.config_worst_m], axis=1)
        binding = np.concatenate([binding, start.config_binding], axis=1)
        n_grp = np.concatenate([n_grp, start.config_n_points], axis=1)
    reach0 = np.isfinite(start.capacity_kg)
    cap = np.where(np.isfinite(cap) | ~reach0[:, None], cap, np.inf)  # unreachable voxels stay NaN
    axis = np.where(np.isfinite(axis) | ~reach0[:, None, None], axis, np.inf)
    n_pts = start.n_points.astype(int).copy()
    n_reach = start.n_reachable.astype(int).copy()
    change = np.zeros(V)

    def flat0() -> np.ndarray:  # (V, G): the group's value and every axis 0, nothing left to fall
        return (cap == 0.0) & np.all(np.nan_to_num(axis, nan=0.0) == 0.0, axis=2)

    def zero() -> np.ndarray:  # nothing can fall further in any group (groups not seen: nothing to fall)
        z = flat0() | ~np.isfinite(cap)
        z[:, 0] &= np.isfinite(cap[:, 0])
        return np.all(z, axis=1)

    # a voxel whose configurations are not known yet is refined at least once
    converged = ~reach0 | (zero() & ~np.any(np.isinf(cap[:, 1:]), axis=1))
    stopped = np.zeros(V, dtype=bool)  # still falling when the compasses reached their finest step
    idx3 = np.stack(np.unravel_index(start.voxel, grid.shape), axis=1)
    fs = FoldBrackets.empty(V, C)  # per voxel: a bracket [a, b] of different branch counts, once one is seen
    fold, fa, fb = fs.fold, fs.fa, fs.fb
    axis_worst = np.repeat(worst[:, :, None, :], A, axis=2)  # (V, G, A, 3): where each axis minimum is
    axis_open = np.ones(axis.shape, dtype=bool)  # axis minima still falling (their compass continues)
    grp_open = np.ones(cap.shape, dtype=bool)  # group minima still falling
    cb = ConfigBrackets.empty(V, C)  # per voxel and configuration: a bracket of different solution counts
    settled = np.zeros(V, dtype=bool)  # every group quiet but an open bracket: only the bisections go on
    seen = np.zeros((0, 4))  # (voxel, point) of every point evaluated: none twice
    rounds, evaluated = 0, 0
    while True:
        z = zero()
        bisect = np.flatnonzero(fold & ~z & (np.linalg.norm(fb - fa, axis=1) > s.fold_tol_m))
        kv, kc, kmid = cb.midpoints(s.fold_tol_m)  # each configuration's boundary, bisected
        keep = ~z[kv] & ~flat0()[kv, 1 + kc]  # (not where nothing can fall further, in the voxel or the group)
        kv, kc, kmid = kv[keep], kc[keep], kmid[keep]
        searching = np.flatnonzero(~converged & ~stopped & ~settled & (n_pts < s.max_points))
        active = np.union1d(np.union1d(searching, bisect), kv)
        if not len(active):
            break
        rounds += 1
        # new points: the voxel's corners in the first round; then a compass around the worst point of the
        # all-branch value, of each configuration and of each axis minimum still falling (one per distinct
        # point); uniform points up to the voxel's least count; the brackets' midpoints
        if rounds == 1:  # with configurations, the start's worst point again: its value on each of them
            local = np.repeat(active, 8)
            local_pts = grid.lower + (idx3[local] + np.tile(CORNERS, (len(active), 1))) * grid.edge_m
            again = active[np.all(np.isfinite(start.worst_m[active]), axis=1)] if C else active[:0]
            local, local_pts = np.concatenate([local, again]), np.concatenate([local_pts, start.worst_m[again]])
        else:
            h = grid.edge_m * 0.5 ** rounds
            has = searching[np.isfinite(cap[searching, 0]) & grp_open[searching, 0]]
            v, g = np.nonzero(grp_open[searching, 1:] & np.isfinite(cap[searching, 1:]))
            v, g = searching[v], g + 1
            cv, centres = [v], [worst[v, g]]
            v, g, a = np.nonzero(axis_open[searching] & np.isfinite(axis[searching]))
            v = searching[v]
            cv.append(v)
            centres.append(axis_worst[v, g, a])
            cv, centres = np.concatenate(cv), np.concatenate(centres)
            # minima at the same point (often a corner, or the all-branch worst) share one compass
            known = np.column_stack([has, worst[has, 0]])
            rows = np.column_stack([cv, centres])
            _, keep = np.unique(rows, axis=0, return_index=True)
            keep = keep[~rows_in(rows[keep], known)]
            v, centre = cv[keep], centres[keep]
            local = np.concatenate([np.repeat(has, len(COMPASS)), np.repeat(v, len(COMPASS))])
            local_pts = np.concatenate([around(worst[has, 0], COMPASS, h, grid, idx3[has]),
                                        around(centre, COMPASS, h, grid, idx3[v])])
        rows = np.column_stack([local, local_pts])  # a point of a voxel evaluated once (compasses clip to corners)
        _, first = np.unique(rows, axis=0, return_index=True)
        first = np.sort(first)
        first = first[~rows_in(rows[first], seen)]
        n_first = len(first)  # then the brackets' midpoints, in this order (the brackets find them by index)
        local = np.concatenate([local[first], bisect, kv])
        local_pts = np.concatenate([local_pts[first], 0.5 * (fa[bisect] + fb[bisect]), kmid])
        n_local = np.bincount(local, minlength=V)[active]
        need = np.where(_near(cap[active], s), s.near_min_points, s.min_points)
        # (from the second round: the corners and the first compass count before any uniform point)
        new = np.where(np.isin(active, searching) & (rounds > 1), np.clip(need - n_pts[active] - n_local, 0, None), 0)
        uniform = np.repeat(active, new)
        owner = np.concatenate([local, uniform])
        pts = np.concatenate([local_pts,
                              grid.lower + (idx3[uniform] + rng.uniform(0.0, 1.0, (len(uniform), 3))) * grid.edge_m])
        new = new + n_local
        ev, n_unique = _evaluate_once(evaluator, pts, cap[owner, 0], owner)
        if progress:
            progress(rounds, len(active), n_unique)
        evaluated += n_unique
        seen = np.concatenate([seen, np.column_stack([owner, pts])])
        c, b, ac = _groups(ev, C)
        old = cap[active].copy()
        axis_old = axis[active].copy()
        # per group and per (group, axis): the new minimum of each voxel and where it is (one sort for all)
        G = 1 + C
        vs, rows_min = argmin_columns(np.concatenate([c, ac.reshape(len(pts), G * A)], axis=1), owner)
        best_i, best_a = rows_min[:, :G], rows_min[:, G:].reshape(len(vs), G, A)
        gi = np.arange(G)
        val = c[best_i, gi]
        lower = val < cap[vs]
        vv, gg = np.nonzero(lower)
        cap[vs[vv], gg] = val[vv, gg]
        worst[vs[vv], gg] = pts[best_i[vv, gg]]
        binding[vs[vv], gg] = b[best_i[vv, gg], gg]
        np.add.at(n_grp, owner, np.isfinite(c).astype(int))
        aval = ac[best_a, gi[None, :, None], np.arange(A)[None, None, :]]
        vv, gg, aa = np.nonzero(aval < axis[vs])
        axis[vs[vv], gg, aa] = aval[vv, gg, aa]
        axis_worst[vs[vv], gg, aa] = pts[best_a[vv, gg, aa]]
        drop = _rel_drop(old, cap[active])  # (active, G)
        axis_drop = _rel_drop(axis_old, axis[active])  # (active, G, A)
        cnt = ev.config_branches if C else np.zeros((len(pts), 0), dtype=int)
        fs.track(owner, pts, ev.n_branches, cnt, n_first, bisect)
        mid = n_first + len(bisect) + np.arange(len(kv))
        cb.track(kv, kc, pts[mid], cnt[mid, kc], owner, pts, cnt, fs.ref_pt, fs.ref_c)
        n_pts[active] += new
        np.add.at(n_reach, owner, np.isfinite(ev.capacity_kg).astype(int))
        open_fold = fold[active] & (np.linalg.norm(fb[active] - fa[active], axis=1) > s.fold_tol_m)
        # a closed bracket with capacity 0 is a singular fold: across it every axis falls to 0 as well; the
        # configurations whose solutions it ends (different counts at its two ends, within fold_tol_m of it)
        # fall to 0 there, their worst point the bracket's end on their side
        singular = active[fold[active] & ~open_fold & (cap[active, 0] == 0.0)]
        ends = np.zeros((len(singular), 1 + C), dtype=bool)
        ends[:, 1:] = fs.ca[singular] != fs.cb[singular]
        on_b = fs.cb[singular] > fs.ca[singular]
        for g in range(1, 1 + C):
            e = ends[:, g]
            worst[singular[e], g] = np.where(on_b[e, g - 1][:, None], fb[singular[e]], fa[singular[e]])
            binding[singular[e], g] = binding[singular[e], 0]
        cap[singular] = np.where(ends, 0.0, cap[singular])
        axis[singular] = np.where((cap[singular] == 0.0)[:, :, None], 0.0, axis[singular])
        # the configurations an open fold ends (different solution counts at its two ends) wait for the
        # bisection: their minimum lies at the fold, where the bracket closes; no compass for them
        pending = np.zeros((len(active), 1 + C), dtype=bool)
        pending[:, 1:] = open_fold[:, None] & (fs.ca[active] != fs.cb[active])
        # a group whose value and axes are all 0 has nothing left to fall
        done = flat0()[active]
        # every group and every axis has converged too
        quiet = pending | done
        grp_drop = np.where(quiet, 0.0, np.maximum(drop, np.nan_to_num(axis_drop.max(axis=2, initial=0.0))))
        change[active] = grp_drop.max(axis=1)
        grp_open[active] = grp_drop >= s.rel_tol
        axis_open[active] = (axis_drop >= s.rel_tol) & ~quiet[:, :, None] & (0.5 ** (rounds + 1) >= s.finest_step)
        enough = (n_pts[active] >= s.min_points) & (~_near(cap[active], s) | (n_pts[active] >= s.near_min_points))
        open_cfg = np.any(cb.open(s.fold_tol_m)[active] & ~flat0()[active, 1:], axis=1)
        converged[active] = ((change[active] < s.rel_tol) & enough & ~open_fold & ~open_cfg) | zero()[active]
        settled[active] = (change[active] < s.rel_tol) & enough & (open_fold | open_cfg)
        if 0.5 ** (rounds + 1) < s.finest_step:  # the compasses have reached their finest step: stop
            stopped[active] = True
    unseen = np.isinf(cap)  # groups no point held: NaN
    cap[unseen] = np.nan
    axis[np.isinf(axis)] = np.nan
    worst[unseen] = np.nan
    binding[unseen] = -1
    per_config = {}
    if C:
        per_config = dict(config_capacity_kg=cap[:, 1:], config_axis_capacity_kg=axis[:, 1:], config_worst_m=worst[:, 1:],
                          config_binding=binding[:, 1:], config_n_points=n_grp[:, 1:])
    return VoxelMinima(voxel=start.voxel, capacity_kg=cap[:, 0], axis_capacity_kg=axis[:, 0], n_points=n_pts,
                       n_reachable=n_reach, last_change=change, converged=converged, worst_m=worst[:, 0],
                       binding=binding[:, 0], rounds=rounds, n_evaluated=evaluated, **per_config)


def argmin_columns(values: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The groups present in groups (N,) int, ascending (G,), and per group and column of values (N, K)
    the row of the smallest value (G, K); ties go to the first row (as
    :func:`capmap.capacity.engine.argmin_per_group` on each column, with one sort for all columns)."""
    order = np.argsort(groups, kind="stable")
    g = groups[order]
    starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]]) if len(g) else np.zeros(0, dtype=int)
    v = values[order]
    mins = np.minimum.reduceat(v, starts, axis=0)
    seg = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, len(order)]))
    pos = np.where(v == mins[seg], np.arange(len(order))[:, None], len(order))
    return g[starts], order[np.minimum.reduceat(pos, starts, axis=0)]


def _evaluate_once(evaluator: Evaluator, pts: np.ndarray, ceiling: np.ndarray, owner: np.ndarray
                   ) -> tuple[Evaluation, int]:
    """``evaluator`` on the distinct points of a round only (a bracket's midpoint shared by a voxel's
    configurations; for a pointwise evaluator, also a corner or face point shared by neighbouring voxels): results
    per row of pts, and the number of points evaluated. A point shared by voxels is evaluated
    once, owned by one of them, with the highest of their ceilings."""
    key = pts if evaluator.pointwise else np.column_stack([owner, pts])
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    if len(first) == len(pts):
        return evaluator.evaluate(pts, ceiling, owner), len(pts)
    ceil = np.full(len(first), -np.inf)
    np.maximum.at(ceil, inv, ceiling)
    ev = evaluator.evaluate(pts[first], ceil, owner[first])
    return Evaluation(*(None if (x := getattr(ev, f)) is None else x[inv] for f in Evaluation.__dataclass_fields__)), \
        len(first)


def _rel_drop(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """(old - new) / old elementwise, 0 where old is not positive or new is 0 (nothing left to fall);
    from +inf (not seen before) 1 where new is finite and positive, else 0."""
    fin = np.isfinite(old)
    with np.errstate(invalid="ignore"):  # inf - inf where old is not finite: replaced below
        d = np.where(fin & (old > 0), (old - new) / np.where(fin & (old > 0), old, 1.0), 0.0)
    d = np.where(np.isinf(old), np.where(np.isinf(new), 0.0, 1.0), d)
    return np.where(new == 0.0, 0.0, d)
