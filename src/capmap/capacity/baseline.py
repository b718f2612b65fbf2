"""The healthy arm: what it could carry at a point, so that a failure's cost can be stated.

Without a failure a 7-DOF arm chooses its self-motion. Following the spec ("Beyond the paper"),
its capacity at a point X is the largest, over the failed joint's angle t in its range and over
the IK solutions of the arm with that joint held at t, of that solution's capacity (its minimum
over the motion set):

    healthy(X) = max_t max_s min_u capacity(X, t, s, u).

Every posture of the healthy arm at the pose is a solution of the arm held at its own value of
that joint, so the sweep over t covers the whole self-motion; the joint stays where it was chosen
while the end effector moves (its brake holds it, as the failed one's does), which is what the
arm with the joint locked at t does too. So healthy(X) >= the locked arm's value at X for every
lock angle on the sweep and every configuration, exactly: the failed arm's own angle is on the
sweep (:func:`self_motion_angles`). An arm that also moved that joint while carrying could do
better: the healthy value is a lower bound of the healthy arm's, and the loss it gives a lower
bound of what the failure cost.

The angles are searched in two steps. A grid (one turn through the failed angle when the joint turns
360 deg or more) gives each point's best posture over the grid exactly (no candidate dropped): on the
whole sphere every (angle, solution) is evaluated; on a finite set every candidate is first screened on
a subset of the directions (a minimum over fewer directions is an upper bound), and the candidates are
then evaluated on the full set in decreasing order of their bound until no remaining bound exceeds the
best value found (branch and bound). Between grid angles the maximum can only be higher, and it can sit
in a narrow peak a coarse grid steps over, mostly where a branch ends (an IK posture appears or goes, or
reaches 0 kg); so the grid intervals at such an edge near the point's best are searched again on a finer
grid, and the best posture and each such interval's best are followed along their IK branches
(:mod:`capmap.capacity.angle_search`): the angles half a step either side, the better kept, the step halved
each level, each angle's solution the one nearest the current posture. Every value is a posture's, a
lower bound of the healthy arm's; how far the result stays below a fine sweep is measured, not assumed
(the baseline stage evaluates voxels' worst points again on a 1 deg grid).
"""


from __future__ import annotations

import numpy as np

from capmap.capacity.angle_search import between_grid_angles, edge_intervals, polish
from capmap.capacity.engine import argmin_per_group
from capmap.capacity.self_motion import (
    SEARCH_FIELDS,
    HealthyCapacity,
    HealthyProblem,
    Hint,
    SelfMotion,
    postures_capacity,
    postures_minimum,
)

__all__ = ["healthy_capacity", "WITNESS_LEVELS", "WITNESS_OFFSETS"]

WITNESS_LEVELS = 3  # the hint angle's best posture followed this many levels before the farther angles
WITNESS_OFFSETS = ((0,), (-1, 1), (-2, 2))  # grid angles from a hint's, tried batch by batch before a full search


def healthy_capacity(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray | None = None,
                     groups: np.ndarray | None = None, hint: Hint | None = None) -> HealthyCapacity:
    """The healthy value of N points (N, 3) m at the problem's end-effector rotation (3, 3): the best
    over ``hp.sm``'s grid of angles and each angle's IK solutions of the solution's minimum over the
    problem's directions (``hp.screen`` a subset of them bounding each candidate first), then followed
    ``hp.polish_levels`` levels between grid angles (the module's docstring).

    For a voxel's minimum only its lowest point needs its exact value. ``ceiling`` (N,) kg: a point
    whose value reaches its ceiling stops there; ``groups`` (N,) int (the points' voxels): a point also
    stops once its value reaches the least upper bound over its group (each point's value is at most
    its best so far or its next candidate's bound, whichever is larger); ``hint``: a point with a hint
    and a finite ceiling first looks for a posture reaching its ceiling on the hint's configuration,
    at the hint's grid angle, then at grid angles ever farther from it (:func:`_witness`). A stopped
    point has ``exact`` False and capacity_kg a value at or above that ceiling (a posture's, so at most
    its healthy value); the least value of each group below its ceiling is exact. The postures are not
    labelled with their configurations (``SelfMotion.grid_configuration`` where one is needed)."""
    sm = hp.sm
    N = len(points)
    ceiling = np.full(N, np.inf) if ceiling is None else np.asarray(ceiling, dtype=float)
    out = _blank(N, sm.arms[0].n_active)
    rest = np.ones(N, dtype=bool)
    if hint is not None:
        rest &= ~_witness(hp, points, ceiling, hint, out)
    if rest.any():
        g = None if groups is None else np.asarray(groups)[rest]
        sub = _exact(hp, points[rest], ceiling[rest], g) if g is None else _leaders_first(
            hp, points[rest], ceiling[rest], g, out.capacity_kg[rest])
        _put(out, np.flatnonzero(rest), sub)
    return out


def _blank(N: int, n_active: int) -> HealthyCapacity:
    """N points not searched yet."""
    return HealthyCapacity(np.full(N, np.nan), np.full(N, np.nan), np.full((N, n_active), np.nan), np.full(N, -1),
                           np.zeros(N, dtype=int), np.zeros(N, dtype=int), np.zeros(N, dtype=bool))


def _put(out: HealthyCapacity, rows: np.ndarray, sub: HealthyCapacity) -> None:
    """out[rows] = sub, every field."""
    for f in SEARCH_FIELDS:
        getattr(out, f)[rows] = getattr(sub, f)


def _leaders_first(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray, groups: np.ndarray,
                   lower: np.ndarray) -> HealthyCapacity:
    """:func:`_exact` of grouped points, one point per group first: the one whose value is likeliest the
    group's least (the lowest ``lower`` (N,) kg, a posture's value found before; NaN: none, first), its
    value exact below its ceiling. The others' ceilings drop to that value, and each looks first for a
    posture reaching it on the leader's configuration near its angle (:func:`_witness`); only those
    that find none are searched in full (:func:`_exact`, still grouped). Each group's least value below
    its ceiling stays exact: it is the leader's, or an exact one of the rest below it."""
    sm = hp.sm
    lead = argmin_per_group(np.where(np.isnan(lower), -np.inf, lower), groups)
    out = _blank(len(points), sm.arms[0].n_active)
    _put(out, lead, _exact(hp, points[lead], ceiling[lead], None))
    rest = np.ones(len(points), dtype=bool)
    rest[lead] = False
    rest = np.flatnonzero(rest)
    if not len(rest):
        return out
    of = np.full(groups.max() + 1, -1)
    of[groups[lead]] = lead
    led = of[groups[rest]]  # each other point's leader
    v = out.capacity_kg[led]
    ceil = np.where(np.isfinite(v), np.minimum(ceiling[rest], v), ceiling[rest])
    reach = np.isfinite(out.angle_deg[led])
    hint = Hint(np.where(reach, sm.grid_index(np.nan_to_num(out.angle_deg[led])), -1), np.full(len(rest), -1))
    if reach.any():
        hint.configuration[reach] = sm.grid_configuration(out.angle_deg[led][reach], out.q_rad[led][reach])
    sub = _blank(len(rest), sm.arms[0].n_active)
    stop = _witness(hp, points[rest], ceil, hint, sub)
    _put(out, rest[stop], HealthyCapacity(*(getattr(sub, f)[stop] for f in SEARCH_FIELDS)))
    more = rest[~stop]
    if len(more):
        _put(out, more, _exact(hp, points[more], ceil[~stop], groups[more]))
    return out


def _postures(sm: SelfMotion, rotation: np.ndarray, points: np.ndarray, rows: np.ndarray, t: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every IK solution of points[rows] with the joint held at grid angle t (per row, index into the
    angles): (rows of them (M,), their angle indices (M,), the active joints (M, n_active) rad)."""
    k, q = sm.solve(points[rows], sm.angles_deg[t], rotation)
    return rows[k], t[k], q


def _witness(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray, hint: Hint, out: HealthyCapacity
             ) -> np.ndarray:
    """Points with a hint and a finite ceiling: their postures on the hint's configuration at the grid
    angles :data:`WITNESS_OFFSETS` from the hint's (a full turn's grid taken round), batch by batch, each
    point stopping at the first batch holding a posture that reaches its ceiling (that posture's value
    written into ``out``); the first batch's best posture is followed :data:`WITNESS_LEVELS` levels
    (:func:`~capmap.capacity.angle_search.polish`) before the next batch. Within a voxel the best
    configuration mostly stays while the best angle moves little, so most points stop here at one or two
    candidates instead of every (angle, solution) of the grid; the others go on to the full search.
    (N,) bool: the points stopped."""
    sm = hp.sm
    T = len(sm.angles_deg)
    stop = np.zeros(len(points), dtype=bool)
    seen = np.zeros(len(points), dtype=int)
    open_ = np.flatnonzero((hint.angle >= 0) & (hint.configuration >= 0) & np.isfinite(ceiling))
    first = True
    for off in WITNESS_OFFSETS:
        if not len(open_):
            break
        off = np.asarray(off)
        rows = np.repeat(open_, len(off))
        t = hint.angle[rows] + np.tile(off, len(open_))
        t = t % T if sm.turns else t
        ok = (t >= 0) & (t < T)
        pr, tr, qr = _postures(sm, hp.problem.rotation, points, rows[ok], t[ok])
        keep = sm.grid_configuration(sm.angles_deg[tr], qr) == hint.configuration[pr]
        pr, tr, qr = pr[keep], tr[keep], qr[keep]
        seen += np.bincount(pr, minlength=len(points))
        if not len(pr):
            continue
        cap, bnd = postures_capacity(sm, sm.held_rad[tr], qr, hp.problem.directions, hp.problem.motion)
        k = argmin_per_group(-cap, pr)  # each point's best posture in this batch
        r = pr[k]
        out.capacity_kg[r], out.angle_deg[r], out.binding[r], out.q_rad[r] = cap[k], sm.angles_deg[tr[k]], bnd[k], qr[k]
        if first:  # the hint's own angle: its best posture followed a few levels (no IK call: cheap)
            polish(hp, points, out, r[out.capacity_kg[r] < ceiling[r]], min(WITNESS_LEVELS, hp.polish_levels))
            first = False
        r = r[out.capacity_kg[r] >= ceiling[r]]
        out.n_candidates[r] = out.n_full[r] = seen[r]
        stop[r] = True
        open_ = open_[~stop[open_]]
    return stop


def _exact(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray, groups: np.ndarray | None
           ) -> HealthyCapacity:
    """:func:`healthy_capacity` without hints: the grid's best by branch and bound, the exact points below
    their ceiling followed between grid angles; then, while a group's least value is a stopped point's
    (a followed point rose above it), that point's own search, so that each group's least is exact."""
    res, suspect = _branch_and_bound(hp, points, ceiling, groups)
    between_grid_angles(hp, points, res, np.flatnonzero(res.exact & np.isfinite(res.capacity_kg) & (res.capacity_kg < ceiling)),
                        suspect)
    while groups is not None:
        c = np.where(np.isfinite(res.capacity_kg), res.capacity_kg, np.inf)
        least = argmin_per_group(c, groups)
        least = least[~res.exact[least] & (c[least] < ceiling[least])]
        if not len(least):
            break
        sub, suspect = _branch_and_bound(hp, points[least], ceiling[least], None)
        below = np.isfinite(sub.capacity_kg) & (sub.capacity_kg < ceiling[least])
        between_grid_angles(hp, points[least], sub, np.flatnonzero(below), suspect)
        for f in SEARCH_FIELDS:
            getattr(res, f)[least] = getattr(sub, f)
    return res


def _branch_and_bound(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray, groups: np.ndarray | None
                      ) -> tuple[HealthyCapacity, np.ndarray]:
    """The grid's best posture of each point: every candidate screened, then evaluated in order of its
    bound (a finite set: the screen a subset of it, or the whole set, whose values are then the
    candidates'; the whole sphere: every candidate's exact value at once). With the grid intervals
    (N, T) int8 where the best may lie between grid angles (:func:`edge_intervals`, from the screen)."""
    sm, rotation, directions, motion = hp.sm, hp.problem.rotation, hp.problem.directions, hp.problem.motion
    N = len(points)
    ceiling = ceiling.copy()
    groups = None if groups is None else np.unique(np.asarray(groups), return_inverse=True)[1].reshape(-1)
    n_act = sm.arms[0].n_active
    pt, tt, qq = _postures(sm, rotation, points, np.repeat(np.arange(N), len(sm.arms)),
                           np.tile(np.arange(len(sm.arms)), N))
    coef = sm.dyn.batch.coefficients(qq, sm.held_rad[tt]) if len(qq) else None  # once: screen and full set
    # the whole sphere: its exact minimum costs about what a 48-direction screen does, so every candidate's value is
    # computed (3.9 against 3.5 us per candidate, measured), without the screen and its rounds of full evaluations
    whole = directions.exact or len(hp.screen) == len(directions)  # every candidate's value known after the screen
    ub, ub_binding = postures_minimum(sm, coef, directions if directions.exact else hp.screen, motion)
    order = np.lexsort((-ub, pt))  # per point, by decreasing bound
    pt, tt, qq, ub, ub_binding = pt[order], tt[order], qq[order], ub[order], ub_binding[order]
    coef = coef.take(order) if coef is not None and not whole else None
    start = np.searchsorted(pt, np.arange(N))
    count = np.bincount(pt, minlength=N)
    best = np.full(N, -np.inf)
    best_row = np.full(N, -1)
    best_binding = np.full(N, -1)
    n_full = np.zeros(N, dtype=int)
    if whole:
        has = count > 0
        best_row[has] = start[has]
        best[has], best_binding[has], n_full[:] = ub[start[has]], ub_binding[start[has]], count
    rank = 0
    while not whole:
        if groups is not None:  # each group's least upper bound of its points' values
            more = rank < count
            upper = np.where(more, np.maximum(best, ub[np.minimum(start + rank, len(ub) - 1)] if len(ub) else best),
                             best)
            upper = np.where(count > 0, upper, np.inf)
            least = np.full(groups.max() + 1 if N else 0, np.inf)
            np.minimum.at(least, groups, upper)
            ceiling = np.minimum(ceiling, least[groups])
        # points whose candidate of this rank may still beat their best
        live = np.flatnonzero((rank < count) & (best < ceiling))
        live = live[ub[start[live] + rank] > best[live]]
        if not len(live):
            break
        rows = start[live] + rank
        val, bnd = postures_minimum(sm, coef.take(rows), directions, motion)
        n_full[live] += 1
        up = val > best[live]
        best[live[up]], best_row[live[up]], best_binding[live[up]] = val[up], rows[up], bnd[up]
        rank += 1
    reach = best_row >= 0
    # exact: every candidate evaluated or the next one's bound not above the best (ranks are evaluated in order)
    nxt = np.minimum(start + n_full, max(len(ub) - 1, 0))
    done = (n_full >= count) | ((ub[nxt] if len(ub) else best) <= best)
    q = np.full((N, n_act), np.nan)
    q[reach] = qq[best_row[reach]]
    angle = np.full(N, np.nan)
    angle[reach] = sm.angles_deg[tt[best_row[reach]]]
    return HealthyCapacity(capacity_kg=np.where(reach, best, np.nan), angle_deg=angle,
                           q_rad=q, binding=best_binding, n_candidates=count, n_full=n_full,
                           exact=~reach | done), edge_intervals(sm, pt, tt, ub, N)
