"""The state of the voxel refinement between its rounds (:func:`capmap.capacity.refine.refine` holds the
loop and its contract): per voxel and group (all branches, then each configuration) the minimum so far,
where it is and what binds it, the per-axis minima, the fold and configuration brackets and what has
converged; and the steps of a round: which voxels are active, the points they ask for, the evaluation
folded in, convergence. Numerics only, no I/O."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.capacity.folds import ConfigBrackets, ConfigMidpoints, FoldBrackets, RoundPoints
from capmap.capacity.patterns import COMPASS, CORNERS, around, rows_in, sorted_unique_rows, unique_rows
from capmap.capacity.refine_data import Evaluation, RefineSettings, VoxelMinima
from capmap.capacity.voxels import Grid

__all__ = ["Rounds", "RoundPlan", "argmin_columns"]


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


def _rel_drop(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """(old - new) / old elementwise, 0 where old is not positive or new is 0 (nothing left to fall);
    from +inf (not seen before) 1 where new is finite and positive, else 0."""
    fin = np.isfinite(old)
    with np.errstate(invalid="ignore"):  # inf - inf where old is not finite: replaced below
        d = np.where(fin & (old > 0), (old - new) / np.where(fin & (old > 0), old, 1.0), 0.0)
    d = np.where(np.isinf(old), np.where(np.isinf(new), 0.0, 1.0), d)
    return np.where(new == 0.0, 0.0, d)


@dataclass(frozen=True)
class RoundPlan:
    """Who works in a round: voxels whose fold bracket is bisected (``bisect``), configuration brackets
    bisected (voxel ``kv``, configuration ``kc``, midpoint ``kmid`` (K, 3) m), voxels still searching,
    and all of them (``active``, sorted)."""

    bisect: np.ndarray
    kv: np.ndarray
    kc: np.ndarray
    kmid: np.ndarray
    searching: np.ndarray
    active: np.ndarray


@dataclass
class Rounds:
    """The refinement's state (V voxels, G = 1 + C groups, A axes): ``cap`` (V, G) kg and ``axis``
    (V, G, A) kg the minima so far (+inf: no point of the group seen; NaN: unreachable voxel), ``worst``
    (V, G, 3) and ``axis_worst`` (V, G, A, 3) m where they are, ``binding`` (V, G), point counts, the
    brackets and the per-voxel flags of convergence."""

    grid: Grid
    voxel: np.ndarray
    idx3: np.ndarray
    cap: np.ndarray
    axis: np.ndarray
    worst: np.ndarray
    binding: np.ndarray
    n_grp: np.ndarray
    n_pts: np.ndarray
    n_reach: np.ndarray
    fs: FoldBrackets
    cb: ConfigBrackets
    change: np.ndarray
    converged: np.ndarray
    stopped: np.ndarray  # still falling when the compasses reached their finest step
    settled: np.ndarray  # every group quiet but an open bracket: only the bisections go on
    axis_worst: np.ndarray
    axis_open: np.ndarray  # axis minima still falling (their compass continues)
    grp_open: np.ndarray  # group minima still falling
    seen: np.ndarray  # (voxel, point) of every point evaluated: none twice
    rounds: int = 0
    evaluated: int = 0

    @classmethod
    def begin(cls, grid: Grid, start: VoxelMinima) -> "Rounds":
        C = 0 if start.config_capacity_kg is None else start.config_capacity_kg.shape[1]
        V, A = start.axis_capacity_kg.shape
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
        st = cls(grid, start.voxel, np.stack(np.unravel_index(start.voxel, grid.shape), axis=1), cap, axis, worst,
                 binding, n_grp, start.n_points.astype(int).copy(), start.n_reachable.astype(int).copy(),
                 FoldBrackets.empty(V, C), ConfigBrackets.empty(V, C), np.zeros(V), np.zeros(V, dtype=bool),
                 np.zeros(V, dtype=bool), np.zeros(V, dtype=bool), np.repeat(worst[:, :, None, :], A, axis=2),
                 np.ones(axis.shape, dtype=bool), np.ones(cap.shape, dtype=bool), np.zeros((0, 4)))
        # a voxel whose configurations are not known yet is refined at least once
        st.converged = ~reach0 | (st.zero() & ~np.any(np.isinf(cap[:, 1:]), axis=1))
        return st

    @property
    def C(self) -> int:
        return self.cap.shape[1] - 1

    def flat0(self) -> np.ndarray:
        """(V, G): the group's value and every axis 0, nothing left to fall."""
        return (self.cap == 0.0) & np.all(np.nan_to_num(self.axis, nan=0.0) == 0.0, axis=2)

    def zero(self) -> np.ndarray:
        """(V,): nothing can fall further in any group (groups not seen: nothing to fall)."""
        z = self.flat0() | ~np.isfinite(self.cap)
        z[:, 0] &= np.isfinite(self.cap[:, 0])
        return np.all(z, axis=1)

    def plan(self, s: RefineSettings) -> RoundPlan | None:
        """Who works in the next round (None: nobody, the refinement is done)."""
        fs, z = self.fs, self.zero()
        bisect = np.flatnonzero(fs.fold & ~z & (np.linalg.norm(fs.fb - fs.fa, axis=1) > s.fold_tol_m))
        kv, kc, kmid = self.cb.midpoints(s.fold_tol_m)  # each configuration's boundary, bisected
        keep = ~z[kv] & ~self.flat0()[kv, 1 + kc]  # (not where nothing can fall further, in the voxel or the group)
        kv, kc, kmid = kv[keep], kc[keep], kmid[keep]
        searching = np.flatnonzero(~self.converged & ~self.stopped & ~self.settled & (self.n_pts < s.max_points))
        active = np.union1d(np.union1d(searching, bisect), kv)
        return RoundPlan(bisect, kv, kc, kmid, searching, active) if len(active) else None

    def _local(self, start: VoxelMinima, p: RoundPlan) -> tuple[np.ndarray, np.ndarray]:
        """The voxels' own new points (owner (N,), point (N, 3) m): the corners in the first round; then a
        compass around the worst point of the all-branch value, of each configuration and of each axis
        minimum still falling (one per distinct point)."""
        grid, idx3, worst, active, searching = self.grid, self.idx3, self.worst, p.active, p.searching
        if self.rounds == 1:  # with configurations, the start's worst point again: its value on each of them
            local = np.repeat(active, 8)
            local_pts = grid.lower + (idx3[local] + np.tile(CORNERS, (len(active), 1))) * grid.edge_m
            again = active[np.all(np.isfinite(start.worst_m[active]), axis=1)] if self.C else active[:0]
            return np.concatenate([local, again]), np.concatenate([local_pts, start.worst_m[again]])
        h = grid.edge_m * 0.5 ** self.rounds
        has = searching[np.isfinite(self.cap[searching, 0]) & self.grp_open[searching, 0]]
        v, g = np.nonzero(self.grp_open[searching, 1:] & np.isfinite(self.cap[searching, 1:]))
        v, g = searching[v], g + 1
        cv, centres = [v], [worst[v, g]]
        v, g, a = np.nonzero(self.axis_open[searching] & np.isfinite(self.axis[searching]))
        v = searching[v]
        cv.append(v)
        centres.append(self.axis_worst[v, g, a])
        cv, centres = np.concatenate(cv), np.concatenate(centres)
        # minima at the same point (often a corner, or the all-branch worst) share one compass
        known = np.column_stack([has, worst[has, 0]])
        rows = np.column_stack([cv, centres])
        keep = sorted_unique_rows(rows)
        keep = keep[~rows_in(rows[keep], known)]
        v, centre = cv[keep], centres[keep]
        return (np.concatenate([np.repeat(has, len(COMPASS)), np.repeat(v, len(COMPASS))]),
                np.concatenate([around(worst[has, 0], COMPASS, h, grid, idx3[has]),
                                around(centre, COMPASS, h, grid, idx3[v])]))

    def points(self, start: VoxelMinima, p: RoundPlan, s: RefineSettings, rng: np.random.Generator
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """A round's points: owner (N,), points (N, 3) m, each active voxel's count of new points, and
        where the brackets' midpoints start (their rows follow the voxels' own points, bisections first);
        uniform points up to the voxel's least count from the second round."""
        local, local_pts = self._local(start, p)
        rows = np.column_stack([local, local_pts])  # a point of a voxel evaluated once (compasses clip to corners)
        first, _ = unique_rows(rows)
        first = first[~rows_in(rows[first], self.seen)]
        n_first = len(first)  # then the brackets' midpoints, in this order (the brackets find them by index)
        fs, active = self.fs, p.active
        local = np.concatenate([local[first], p.bisect, p.kv])
        local_pts = np.concatenate([local_pts[first], 0.5 * (fs.fa[p.bisect] + fs.fb[p.bisect]), p.kmid])
        n_local = np.bincount(local, minlength=len(self.cap))[active]
        need = np.where(_near(self.cap[active], s), s.near_min_points, s.min_points)
        # (from the second round: the corners and the first compass count before any uniform point)
        new = np.where(np.isin(active, p.searching) & (self.rounds > 1),
                       np.clip(need - self.n_pts[active] - n_local, 0, None), 0)
        uniform = np.repeat(active, new)
        g = self.grid
        pts = np.concatenate([local_pts, g.lower + (self.idx3[uniform] + rng.uniform(0.0, 1.0, (len(uniform), 3))) * g.edge_m])
        return np.concatenate([local, uniform]), pts, new + n_local, n_first

    def absorb(self, ev: Evaluation, owner: np.ndarray, pts: np.ndarray, p: RoundPlan
               ) -> tuple[np.ndarray, np.ndarray]:
        """Fold a round's point results into the minima; the relative drops of the active voxels' group
        minima (active, G) and axis minima (active, G, A)."""
        C, A = self.C, self.axis.shape[2]
        c, b, ac = _groups(ev, C)
        cap, axis, active = self.cap, self.axis, p.active
        old, axis_old = cap[active].copy(), axis[active].copy()
        # per group and per (group, axis): the new minimum of each voxel and where it is (one sort for all)
        G = 1 + C
        vs, rows_min = argmin_columns(np.concatenate([c, ac.reshape(len(pts), G * A)], axis=1), owner)
        best_i, best_a = rows_min[:, :G], rows_min[:, G:].reshape(len(vs), G, A)
        gi = np.arange(G)
        val = c[best_i, gi]
        vv, gg = np.nonzero(val < cap[vs])
        cap[vs[vv], gg] = val[vv, gg]
        self.worst[vs[vv], gg] = pts[best_i[vv, gg]]
        self.binding[vs[vv], gg] = b[best_i[vv, gg], gg]
        np.add.at(self.n_grp, owner, np.isfinite(c).astype(int))
        aval = ac[best_a, gi[None, :, None], np.arange(A)[None, None, :]]
        vv, gg, aa = np.nonzero(aval < axis[vs])
        axis[vs[vv], gg, aa] = aval[vv, gg, aa]
        self.axis_worst[vs[vv], gg, aa] = pts[best_a[vv, gg, aa]]
        np.add.at(self.n_reach, owner, np.isfinite(ev.capacity_kg).astype(int))
        return _rel_drop(old, cap[active]), _rel_drop(axis_old, axis[active])

    def track(self, ev: Evaluation, owner: np.ndarray, pts: np.ndarray, p: RoundPlan, n_first: int) -> None:
        """The brackets follow the round's branch and solution counts."""
        cnt = ev.config_branches if self.C else np.zeros((len(pts), 0), dtype=int)
        points = RoundPoints(owner, pts, ev.n_branches, cnt)
        self.fs.track(points, n_first, p.bisect)
        mid = n_first + len(p.bisect) + np.arange(len(p.kv))
        self.cb.track(ConfigMidpoints(p.kv, p.kc, pts[mid], cnt[mid, p.kc]), points, self.fs.ref_pt, self.fs.ref_c)

    def settle(self, p: RoundPlan, new: np.ndarray, drop: np.ndarray, axis_drop: np.ndarray,
               s: RefineSettings) -> None:
        """After a round: the active voxels' point counts (``new`` each), singular folds closed, and which
        voxels converged, settled (only bisections left) or stopped (finest compass step)."""
        fs, cb, cap, axis, worst, binding, active = self.fs, self.cb, self.cap, self.axis, self.worst, self.binding, p.active
        C = self.C
        self.n_pts[active] += new
        open_fold = fs.fold[active] & (np.linalg.norm(fs.fb[active] - fs.fa[active], axis=1) > s.fold_tol_m)
        # a closed bracket with capacity 0 is a singular fold: across it every axis falls to 0 as well; the
        # configurations whose solutions it ends (different counts at its two ends, within fold_tol_m of it)
        # fall to 0 there, their worst point the bracket's end on their side
        singular = active[fs.fold[active] & ~open_fold & (cap[active, 0] == 0.0)]
        ends = np.zeros((len(singular), 1 + C), dtype=bool)
        ends[:, 1:] = fs.ca[singular] != fs.cb[singular]
        on_b = fs.cb[singular] > fs.ca[singular]
        for g in range(1, 1 + C):
            e = ends[:, g]
            worst[singular[e], g] = np.where(on_b[e, g - 1][:, None], fs.fb[singular[e]], fs.fa[singular[e]])
            binding[singular[e], g] = binding[singular[e], 0]
        cap[singular] = np.where(ends, 0.0, cap[singular])
        axis[singular] = np.where((cap[singular] == 0.0)[:, :, None], 0.0, axis[singular])
        # the configurations an open fold ends (different solution counts at its two ends) wait for the
        # bisection: their minimum lies at the fold, where the bracket closes; no compass for them
        pending = np.zeros((len(active), 1 + C), dtype=bool)
        pending[:, 1:] = open_fold[:, None] & (fs.ca[active] != fs.cb[active])
        # a group whose value and axes are all 0 has nothing left to fall; every group and every axis has
        # converged too
        quiet = pending | self.flat0()[active]
        grp_drop = np.where(quiet, 0.0, np.maximum(drop, np.nan_to_num(axis_drop.max(axis=2, initial=0.0))))
        self.change[active] = grp_drop.max(axis=1)
        self.grp_open[active] = grp_drop >= s.rel_tol
        finer = 0.5 ** (self.rounds + 1) >= s.finest_step
        self.axis_open[active] = (axis_drop >= s.rel_tol) & ~quiet[:, :, None] & finer
        n = self.n_pts[active]
        enough = (n >= s.min_points) & (~_near(cap[active], s) | (n >= s.near_min_points))
        open_cfg = np.any(cb.open(s.fold_tol_m)[active] & ~self.flat0()[active, 1:], axis=1)
        calm = self.change[active] < s.rel_tol
        self.converged[active] = (calm & enough & ~open_fold & ~open_cfg) | self.zero()[active]
        self.settled[active] = calm & enough & (open_fold | open_cfg)
        if not finer:  # the compasses have reached their finest step: stop
            self.stopped[active] = True

    def result(self) -> VoxelMinima:
        """The refined minima (groups no point held: NaN)."""
        cap, axis, worst, binding = self.cap, self.axis, self.worst, self.binding
        unseen = np.isinf(cap)
        cap[unseen] = np.nan
        axis[np.isinf(axis)] = np.nan
        worst[unseen] = np.nan
        binding[unseen] = -1
        per_config = {}
        if self.C:
            per_config = dict(config_capacity_kg=cap[:, 1:], config_axis_capacity_kg=axis[:, 1:],
                              config_worst_m=worst[:, 1:], config_binding=binding[:, 1:], config_n_points=self.n_grp[:, 1:])
        return VoxelMinima(voxel=self.voxel, capacity_kg=cap[:, 0], axis_capacity_kg=axis[:, 0], n_points=self.n_pts,
                           n_reachable=self.n_reach, last_change=self.change, converged=self.converged,
                           worst_m=worst[:, 0], binding=binding[:, 0], rounds=self.rounds, n_evaluated=self.evaluated,
                           **per_config)
