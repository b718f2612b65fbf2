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

The angles are a grid (one turn through the failed angle when the joint turns 360 deg or more);
between grid angles the maximum can only be higher: every value is a posture's, a lower bound of the
healthy arm's. How much a finer grid adds is measured, not assumed (the baseline stage evaluates
voxels' worst points again at half and a quarter of the step): the maximum can sit in a narrow peak,
e.g. a few degrees wide just inside the angles where the pose becomes reachable, which a coarse
grid steps over and a search along the grid's best posture does not reach.

The maximum over the grid is exact (no candidate dropped): every (angle, solution) is first screened
on a subset of the directions (a minimum over fewer directions is an upper bound), and the candidates
are then evaluated on the full set in decreasing order of their bound until no remaining bound
exceeds the best value found (branch and bound).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.capacity.directions import Directions
from capmap.capacity.engine import Motion, argmin_per_group, direction_minimum
from capmap.capacity.problem import CapacityProblem
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm
from capmap.errors import CapmapError

__all__ = ["self_motion_angles", "SelfMotion", "HealthyProblem", "HealthyCapacity", "healthy_capacity",
           "screening_subset"]


def self_motion_angles(lower_deg: float, upper_deg: float, through_deg: float, step_deg: float) -> np.ndarray:
    """Angles (T,) deg of the failed joint swept: ``through_deg`` (the failed arm's angle) plus
    multiples of ``step_deg``; one turn (every angle mod 360 once, shifted into the range) when the
    range spans 360 deg or more, else every grid angle inside [lower, upper] and both ends. Sorted."""
    if not step_deg > 0 or not np.isfinite(step_deg):
        raise CapmapError(f"{{step}} = {step_deg!r} must be a positive number of degrees", step="the angle step")
    if not lower_deg - 1e-9 <= through_deg <= upper_deg + 1e-9:
        raise CapmapError(f"{{step}}: the failed angle {through_deg:g} is outside [{lower_deg:g}, {upper_deg:g}] deg",
                          step="the angle step")
    if upper_deg - lower_deg >= 360.0 - 1e-9:
        n = int(np.ceil(360.0 / step_deg - 1e-9))
        a = through_deg + step_deg * (np.arange(n) - n // 2)  # half a turn each side: the failed angle as it is
        a = np.where(a > upper_deg + 1e-9, a - 360.0, a)  # the others' representatives inside the range
        a = np.where(a < lower_deg - 1e-9, a + 360.0, a)
    else:
        m = np.arange(np.ceil((lower_deg - through_deg) / step_deg - 1e-9),
                      np.floor((upper_deg - through_deg) / step_deg + 1e-9) + 1)
        a = np.concatenate([through_deg + step_deg * m, [lower_deg, upper_deg]])
    a = np.clip(np.sort(a), lower_deg, upper_deg)
    return a[np.concatenate([[True], np.diff(a) > 1e-9])]


def screening_subset(directions: Directions, n: int) -> Directions:
    """At most n of the directions, spread over the set (farthest-point order from the first): the
    screening set, a subset so that its minimum bounds the full set's from above."""
    u = directions.u
    n = min(int(n), len(u))
    pick = [0]
    dist = np.linalg.norm(u - u[0], axis=1)
    for _ in range(n - 1):
        k = int(np.argmax(dist))
        pick.append(k)
        dist = np.minimum(dist, np.linalg.norm(u - u[k], axis=1))
    k = np.array(sorted(pick))
    return Directions(u[k], directions.alpha_deg[k], directions.beta_deg[k], f"{directions.kind}[{len(k)}]")


@dataclass(frozen=True)
class SelfMotion:
    """The healthy arm as its failed joint's angles: ``arms[t]`` the arm with that joint held at
    ``angles_deg[t]`` (its IK); ``dyn`` the dynamics of the first (the joint's angle set per
    configuration: one batch over every angle) and ``limits`` the load limits on its outputs (the same
    outputs at every angle: the same joint is held)."""

    angles_deg: np.ndarray
    arms: tuple[LockedArm, ...]
    dyn: ArmDynamics
    limits: AffineLimits

    @classmethod
    def build(cls, angles_deg: np.ndarray, lock, limits_for) -> "SelfMotion":
        """``lock(angle_deg) -> LockedArm`` per angle and ``limits_for(arm) -> AffineLimits``."""
        arms = tuple(lock(float(a)) for a in angles_deg)
        return cls(np.asarray(angles_deg, dtype=float), arms, ArmDynamics(arms[0]), limits_for(arms[0]))

    @property
    def held_rad(self) -> np.ndarray:
        """The angles (T,) rad."""
        return np.deg2rad(self.angles_deg)


@dataclass(frozen=True)
class HealthyCapacity:
    """Per point (N,): capacity_kg the healthy value (NaN: no angle reaches the pose), angle_deg the
    failed joint's angle attaining it, q_rad (N, n_active) the active joints there, binding the binding
    output's index into the limits' names (+ singular), n_candidates the (angle, solution) pairs seen,
    n_full those evaluated on the full direction set, exact: the value is the maximum (not stopped at
    a ceiling)."""

    capacity_kg: np.ndarray
    angle_deg: np.ndarray
    q_rad: np.ndarray
    binding: np.ndarray
    n_candidates: np.ndarray
    n_full: np.ndarray
    exact: np.ndarray


def _capacity(sm: SelfMotion, held_rad: np.ndarray, q: np.ndarray, dirs: Directions, motion: Motion
              ) -> tuple[np.ndarray, np.ndarray]:
    """Each posture's minimum over ``dirs`` (M,) kg and its binding output (M,): active joints q (M, n_active)
    rad with the failed joint at held_rad (M,)."""
    if not len(q):
        return np.zeros(0), np.zeros(0, dtype=int)
    coef = sm.dyn.batch.coefficients(q, held_rad)
    cap, _, _, binding = direction_minimum(coef, dirs, motion, sm.dyn.gravity, sm.limits)
    return cap, binding


@dataclass(frozen=True)
class HealthyProblem:
    """The healthy arm's question: the failed arm's ``problem`` (its end-effector rotation, motion and
    direction set), the self-motion ``sm`` over the failed joint's angles and the ``screen`` subset of
    the directions (:func:`screening_subset`) that bounds each candidate first."""

    problem: CapacityProblem
    sm: SelfMotion
    screen: Directions


def healthy_capacity(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray | None = None,
                     groups: np.ndarray | None = None, hint: np.ndarray | None = None) -> HealthyCapacity:
    """The healthy value of N points (N, 3) m at the problem's end-effector rotation (3, 3): the maximum
    over ``hp.sm``'s angles and each angle's IK solutions of the solution's minimum over the problem's
    directions; ``hp.screen`` a subset of them bounding each candidate first.

    For a voxel's minimum only its lowest point needs its exact value. ``ceiling`` (N,) kg: a point
    whose value reaches its ceiling stops there; ``groups`` (N,) int (the points' voxels): a point also
    stops once its value reaches the least upper bound over its group (each point's value is at most
    its best so far or its next candidate's bound, whichever is larger); ``hint`` (N,) int: an angle
    (index into ``sm.angles_deg``, -1 none) whose solutions are evaluated first, a point stopping there
    when one reaches its ceiling (a neighbour's best angle: most points of a voxel do not lower its
    minimum). A stopped point has ``exact`` False and capacity_kg a value at or above that ceiling (a
    posture's, so at most its maximum); the least value of each group (with its ceiling) is exact."""
    sm, rotation, directions, motion = hp.sm, hp.problem.rotation, hp.problem.directions, hp.problem.motion
    N = len(points)
    ceiling = np.full(N, np.inf) if ceiling is None else np.asarray(ceiling, dtype=float)
    out = HealthyCapacity(np.full(N, np.nan), np.full(N, np.nan), np.full((N, sm.arms[0].n_active), np.nan),
                          np.full(N, -1), np.zeros(N, dtype=int), np.zeros(N, dtype=int), np.zeros(N, dtype=bool))
    rest = np.ones(N, dtype=bool)
    if hint is not None:
        rows = np.flatnonzero((hint >= 0) & np.isfinite(ceiling))
        pr, tr, qr = [], [], []
        for t in np.unique(hint[rows]):
            mine = rows[hint[rows] == t]
            sol = ik.solve(sm.arms[t], points[mine], rotation)
            pts, brs = np.nonzero(np.arange(sol.q.shape[1])[None, :] < sol.n_solutions[:, None])
            pr.append(mine[pts])
            tr.append(np.full(len(pts), t))
            qr.append(sol.q[pts, brs])
        if pr:
            pr, tr, qr = np.concatenate(pr), np.concatenate(tr), np.concatenate(qr)
            cap, bnd = _capacity(sm, sm.held_rad[tr], qr, directions, motion)
            sel = argmin_per_group(-cap, pr)  # each point's best posture
            k = np.full(N, -1)
            k[pr[sel]] = sel
            has = k >= 0
            stop = np.zeros(N, dtype=bool)
            stop[has] = cap[k[has]] >= ceiling[has]
            ks = k[stop]
            out.capacity_kg[stop], out.angle_deg[stop], out.binding[stop] = cap[ks], sm.angles_deg[tr[ks]], bnd[ks]
            out.q_rad[stop] = qr[ks]
            out.n_candidates[stop] = out.n_full[stop] = np.bincount(pr, minlength=N)[stop]
            rest &= ~stop
    if rest.any():
        sub = _branch_and_bound(hp, points[rest], ceiling[rest],
                                None if groups is None else np.asarray(groups)[rest])
        for f in HealthyCapacity.__dataclass_fields__:
            getattr(out, f)[rest] = getattr(sub, f)
    return out


def _branch_and_bound(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray, groups: np.ndarray | None
                      ) -> HealthyCapacity:
    """:func:`healthy_capacity` without hints: every candidate screened, then evaluated in order."""
    sm, rotation, directions, motion = hp.sm, hp.problem.rotation, hp.problem.directions, hp.problem.motion
    N = len(points)
    ceiling = ceiling.copy()
    groups = None if groups is None else np.unique(np.asarray(groups), return_inverse=True)[1].reshape(-1)
    n_act = sm.arms[0].n_active
    cand_pt, cand_t, cand_q = [], [], []
    for t, arm in enumerate(sm.arms):
        sol = ik.solve(arm, points, rotation)
        pts, brs = np.nonzero(np.arange(sol.q.shape[1])[None, :] < sol.n_solutions[:, None])
        q = sol.q[pts, brs]
        cand_pt.append(pts)
        cand_t.append(np.full(len(pts), t))
        cand_q.append(q)
    pt = np.concatenate(cand_pt) if cand_pt else np.zeros(0, dtype=int)
    tt = np.concatenate(cand_t) if cand_t else np.zeros(0, dtype=int)
    qq = np.concatenate(cand_q) if cand_q else np.zeros((0, n_act))
    ub = _capacity(sm, sm.held_rad[tt], qq, hp.screen, motion)[0]
    order = np.lexsort((-ub, pt))  # per point, by decreasing bound
    pt, tt, qq, ub = pt[order], tt[order], qq[order], ub[order]
    start = np.searchsorted(pt, np.arange(N))
    count = np.bincount(pt, minlength=N)
    best = np.full(N, -np.inf)
    best_row = np.full(N, -1)
    best_binding = np.full(N, -1)
    n_full = np.zeros(N, dtype=int)
    rank = 0
    while True:
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
        val, bnd = _capacity(sm, sm.held_rad[tt[rows]], qq[rows], directions, motion)
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
                           exact=~reach | done)
