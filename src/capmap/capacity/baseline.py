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
360 deg or more) gives each point's best posture over the grid exactly (no candidate dropped): every
(angle, solution) is first screened on a subset of the directions (a minimum over fewer directions is
an upper bound), and the candidates are then evaluated on the full set in decreasing order of their
bound until no remaining bound exceeds the best value found (branch and bound; with the whole set as
its screen, the screening is the evaluation). Between grid angles the maximum can only be higher, and
it can sit in a narrow peak a coarse grid steps over; so the best posture is then followed along its
IK branch (``HealthyProblem.polish_levels``): the angles half a grid step either side of it, the better
kept, the step halved each level, each angle's solution the one nearest the current posture. Every
value is a posture's, a lower bound of the healthy arm's; how far the result stays below a fine sweep
is measured, not assumed (the baseline stage evaluates voxels' worst points again on a 1 deg grid).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from capmap.capacity.directions import Directions, sphere
from capmap.capacity.engine import Motion, argmin_per_group, direction_minimum
from capmap.capacity.problem import CapacityProblem
from capmap.core import ik
from capmap.core.coefficients import Coefficients
from capmap.core.configuration import Configurations, arm_configurations
from capmap.core.dynamics import ArmDynamics
from capmap.core.ik.finish import RESIDUAL_TOL, wrap_to_range
from capmap.core.kinematics import pose_error
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm, free
from capmap.errors import CapmapError

__all__ = ["self_motion_angles", "SelfMotion", "HealthyProblem", "HealthyCapacity", "Hint", "healthy_capacity",
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
    screening set, a subset so that its minimum bounds the full set's from above. Of the whole sphere
    (an exact set) n near-uniform directions on it (:func:`~capmap.capacity.directions.sphere`): every
    direction is in that motion set, and its 16 start directions alone bound it loosely (~6 % median
    above the exact minimum, against ~1 % for 48)."""
    if directions.exact:
        return sphere(int(n))
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
    outputs at every angle: the same joint is held). ``lower_deg``, ``upper_deg``: the joint's range
    (an angle between grid angles is taken modulo 360 into it when it spans a turn); ``lock`` builds the
    arm held at any angle (:meth:`arm_at`)."""

    angles_deg: np.ndarray
    arms: tuple[LockedArm, ...]
    dyn: ArmDynamics
    limits: AffineLimits
    lower_deg: float
    upper_deg: float
    lock: Callable[[float], LockedArm]
    _more: dict = field(default_factory=dict, compare=False, repr=False)  # arms held between grid angles
    _labels: dict = field(default_factory=dict, compare=False, repr=False)  # each arm's configuration labels

    @classmethod
    def build(cls, angles_deg: np.ndarray, lock, limits_for, lower_deg: float | None = None,
              upper_deg: float | None = None) -> "SelfMotion":
        """``lock(angle_deg) -> LockedArm`` per angle and ``limits_for(arm) -> AffineLimits``; the joint's
        range (default: that of the angles)."""
        a = np.asarray(angles_deg, dtype=float)
        arms = tuple(lock(float(x)) for x in a)
        return cls(a, arms, ArmDynamics(arms[0]), limits_for(arms[0]),
                   float(a.min() if lower_deg is None else lower_deg), float(a.max() if upper_deg is None else upper_deg),
                   lock)

    @property
    def held_rad(self) -> np.ndarray:
        """The angles (T,) rad."""
        return np.deg2rad(self.angles_deg)

    @property
    def step_deg(self) -> float:
        """The grid's step (deg): the spacing of most of its angles."""
        return float(np.median(np.diff(self.angles_deg))) if len(self.angles_deg) > 1 else 360.0

    @property
    def turns(self) -> bool:
        """Whether the joint's range spans a turn (its angles are then taken modulo 360 into it)."""
        return self.upper_deg - self.lower_deg >= 360.0 - 1e-9

    def into_range(self, angle_deg: np.ndarray) -> np.ndarray:
        """Angles (N,) deg as the joint holds them: shifted by a turn into its range when it spans one,
        NaN where outside it otherwise."""
        a = np.asarray(angle_deg, dtype=float)
        if self.turns:
            a = np.where(a > self.upper_deg + 1e-9, a - 360.0, a)
            return np.where(a < self.lower_deg - 1e-9, a + 360.0, a)
        return np.where((a >= self.lower_deg - 1e-9) & (a <= self.upper_deg + 1e-9), a, np.nan)

    def grid_index(self, angle_deg: np.ndarray) -> np.ndarray:
        """The nearest grid angle's index (N,) of angles (N,) deg (round a turn when the range spans one)."""
        d = np.asarray(angle_deg, dtype=float)[:, None] - self.angles_deg[None, :]
        if self.turns:
            d = (d + 180.0) % 360.0 - 180.0
        return np.argmin(np.abs(d), axis=1)

    def arm_at(self, angle_deg: float) -> LockedArm:
        """The arm held at ``angle_deg`` (a grid angle's own arm, or built once and kept)."""
        k = int(np.searchsorted(self.angles_deg, angle_deg))
        for j in (k - 1, k):
            if 0 <= j < len(self.angles_deg) and abs(self.angles_deg[j] - angle_deg) < 1e-9:
                return self.arms[j]
        key = round(float(angle_deg), 9)
        if key not in self._more:
            self._more[key] = self.lock(key)
        return self._more[key]

    @cached_property
    def free_chain(self):
        """The arm's chain with every joint moving (the held one among them), for following a branch."""
        return free(self.arms[0].robot).chain

    def configurations(self, arm: LockedArm) -> Configurations:
        """The configuration labels of one of its arms (built once per arm)."""
        if id(arm) not in self._labels:
            self._labels[id(arm)] = (arm, arm_configurations(arm))  # the arm kept: its id stays its own
        return self._labels[id(arm)][1]

    def configuration(self, angle_deg: np.ndarray, q: np.ndarray) -> np.ndarray:
        """The configuration label (N,) of postures: the joint held at angle_deg (N,) deg (NaN: none, -1),
        the active joints q (N, n_active) rad."""
        out = np.full(len(angle_deg), -1)
        have = np.flatnonzero(np.isfinite(angle_deg))
        key = np.round(angle_deg[have], 9)
        for a in np.unique(key):
            rows = have[key == a]
            out[rows] = self.configurations(self.arm_at(float(a))).labels(q[rows])
        return out


@dataclass(frozen=True)
class HealthyCapacity:
    """Per point (N,): capacity_kg the healthy value (NaN: no angle reaches the pose), angle_deg the
    failed joint's angle attaining it, q_rad (N, n_active) the active joints there, binding the binding
    output's index into the limits' names (+ singular), n_candidates the (angle, solution) pairs seen,
    n_full those evaluated on the full direction set, exact: the value is the search's (not stopped at
    a ceiling); configuration the posture's configuration label (-1: none)."""

    capacity_kg: np.ndarray
    angle_deg: np.ndarray
    q_rad: np.ndarray
    binding: np.ndarray
    n_candidates: np.ndarray
    n_full: np.ndarray
    exact: np.ndarray
    configuration: np.ndarray | None = None


FINER = 8  # a 0 kg plateau on the grid: its points searched again on a grid this many times finer
WITNESS_LEVELS = 3  # the hint angle's best posture followed this many levels before the farther angles
WITNESS_OFFSETS = ((0,), (-1, 1), (-2, 2))  # grid angles from a hint's, tried batch by batch before a full search
_NEWTON_STEPS = 8  # following a branch over at most half a grid step: converged to 1e-12 well within this
_SEARCH_FIELDS = ("capacity_kg", "angle_deg", "q_rad", "binding", "n_candidates", "n_full", "exact")


@dataclass(frozen=True)
class Hint:
    """Where a point's search starts (a neighbour's best posture: most points of a voxel do not lower its
    minimum): per point (N,) a grid angle (index into ``SelfMotion.angles_deg``, -1 none) and a
    configuration label (-1 none)."""

    angle: np.ndarray
    configuration: np.ndarray


def _capacity(sm: SelfMotion, held_rad: np.ndarray, q: np.ndarray, dirs: Directions, motion: Motion
              ) -> tuple[np.ndarray, np.ndarray]:
    """Each posture's minimum over ``dirs`` (M,) kg and its binding output (M,): active joints q (M, n_active)
    rad with the failed joint at held_rad (M,)."""
    if not len(q):
        return np.zeros(0), np.zeros(0, dtype=int)
    return _minimum(sm, sm.dyn.batch.coefficients(q, held_rad), dirs, motion)


def _minimum(sm: SelfMotion, coef: Coefficients | None, dirs: Directions, motion: Motion
             ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_capacity` of postures whose coefficients are known (None: no posture)."""
    if coef is None:
        return np.zeros(0), np.zeros(0, dtype=int)
    cap, _, _, binding = direction_minimum(coef, dirs, motion, sm.dyn.gravity, sm.limits)
    return cap, binding


@dataclass(frozen=True)
class HealthyProblem:
    """The healthy arm's question: the failed arm's ``problem`` (its end-effector rotation, motion and
    direction set), the self-motion ``sm`` over the failed joint's angles, the ``screen`` subset of
    the directions (:func:`screening_subset`) that bounds each candidate first, and ``polish_levels``:
    how many times a point's best posture on the grid is followed to the better of the angles a step
    either side, from half the grid's step, halving it each level (0: the grid's best)."""

    problem: CapacityProblem
    sm: SelfMotion
    screen: Directions
    polish_levels: int = 0


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
    its healthy value); the least value of each group below its ceiling is exact."""
    sm = hp.sm
    N = len(points)
    ceiling = np.full(N, np.inf) if ceiling is None else np.asarray(ceiling, dtype=float)
    out = HealthyCapacity(np.full(N, np.nan), np.full(N, np.nan), np.full((N, sm.arms[0].n_active), np.nan),
                          np.full(N, -1), np.zeros(N, dtype=int), np.zeros(N, dtype=int), np.zeros(N, dtype=bool))
    rest = np.ones(N, dtype=bool)
    if hint is not None:
        rest &= ~_witness(hp, points, ceiling, hint, out)
    if rest.any():
        sub = _exact(hp, points[rest], ceiling[rest], None if groups is None else np.asarray(groups)[rest])
        for f in _SEARCH_FIELDS:
            getattr(out, f)[rest] = getattr(sub, f)
    return replace(out, configuration=sm.configuration(out.angle_deg, out.q_rad))


def _postures(sm: SelfMotion, rotation: np.ndarray, points: np.ndarray, rows: np.ndarray, t: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every IK solution of points[rows] with the joint held at grid angle t (per row, index into the
    angles): (rows of them (M,), their angle indices (M,), the active joints (M, n_active) rad)."""
    pr, tr, qr = [np.zeros(0, dtype=int)], [np.zeros(0, dtype=int)], [np.zeros((0, sm.arms[0].n_active))]
    for a in np.unique(t):
        mine = rows[t == a]
        sol = ik.solve(sm.arms[a], points[mine], rotation)
        pts, brs = np.nonzero(np.arange(sol.q.shape[1])[None, :] < sol.n_solutions[:, None])
        pr.append(mine[pts])
        tr.append(np.full(len(pts), a))
        qr.append(sol.q[pts, brs])
    return np.concatenate(pr), np.concatenate(tr), np.concatenate(qr)


def _witness(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray, hint: Hint, out: HealthyCapacity
             ) -> np.ndarray:
    """Points with a hint and a finite ceiling: their postures on the hint's configuration at the grid
    angles :data:`WITNESS_OFFSETS` from the hint's (a full turn's grid taken round), batch by batch, each
    point stopping at the first batch holding a posture that reaches its ceiling (that posture's value
    written into ``out``); the first batch's best posture is followed :data:`WITNESS_LEVELS` levels
    (:func:`_polish`) before the next batch. Within a voxel the best configuration mostly stays while the best angle moves
    little, so most points stop here at one or two candidates instead of every (angle, solution) of the
    grid; the others go on to the full search. (N,) bool: the points stopped."""
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
        keep = sm.configuration(sm.angles_deg[tr], qr) == hint.configuration[pr]
        pr, tr, qr = pr[keep], tr[keep], qr[keep]
        seen += np.bincount(pr, minlength=len(points))
        if not len(pr):
            continue
        cap, bnd = _capacity(sm, sm.held_rad[tr], qr, hp.problem.directions, hp.problem.motion)
        k = argmin_per_group(-cap, pr)  # each point's best posture in this batch
        r = pr[k]
        out.capacity_kg[r], out.angle_deg[r], out.binding[r], out.q_rad[r] = cap[k], sm.angles_deg[tr[k]], bnd[k], qr[k]
        if first:  # the hint's own angle: its best posture followed a few levels (no IK call: cheap)
            _polish(hp, points, out, r[out.capacity_kg[r] < ceiling[r]], min(WITNESS_LEVELS, hp.polish_levels))
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
    res = _branch_and_bound(hp, points, ceiling, groups)
    _search(hp, points, res, np.flatnonzero(res.exact & np.isfinite(res.capacity_kg) & (res.capacity_kg < ceiling)))
    while groups is not None:
        c = np.where(np.isfinite(res.capacity_kg), res.capacity_kg, np.inf)
        least = argmin_per_group(c, groups)
        least = least[~res.exact[least] & (c[least] < ceiling[least])]
        if not len(least):
            break
        sub = _branch_and_bound(hp, points[least], ceiling[least], None)
        _search(hp, points[least], sub, np.flatnonzero(np.isfinite(sub.capacity_kg) & (sub.capacity_kg < ceiling[least])))
        for f in _SEARCH_FIELDS:
            getattr(res, f)[least] = getattr(sub, f)
    return res


def _search(hp: HealthyProblem, points: np.ndarray, res: HealthyCapacity, rows: np.ndarray) -> None:
    """Between grid angles, in place, for points[rows] whose grid best is ``res``'s: where that best is 0
    kg (every grid posture at a limit or singular: a plateau that shows no way up) the angles
    1/:data:`FINER` of a step apart first (:func:`_finer`; a peak a few degrees wide, e.g. where a pair of IK branches
    is born, lies between grid angles), then the best posture followed (:func:`_polish`)."""
    if hp.polish_levels and len(rows):
        _finer(hp, points, res, rows[res.capacity_kg[rows] <= 0])
    _polish(hp, points, res, rows)


def _finer(hp: HealthyProblem, points: np.ndarray, res: HealthyCapacity, rows: np.ndarray) -> None:
    """Every IK solution of points[rows] at the angles 1/:data:`FINER` of a step apart between the grid
    angles, the best posture kept where it beats ``res``'s (in place)."""
    sm = hp.sm
    if not len(rows):
        return
    off = sm.step_deg * np.arange(1, FINER) / FINER
    angles = sm.into_range((sm.angles_deg[:, None] + off[None, :]).ravel())
    angles = np.unique(np.round(angles[np.isfinite(angles)], 9))
    pr, ar, qr = [np.zeros(0, dtype=int)], [np.zeros(0)], [np.zeros((0, sm.arms[0].n_active))]
    for a in angles:
        sol = ik.solve(sm.arm_at(float(a)), points[rows], hp.problem.rotation)
        p_, b_ = np.nonzero(np.arange(sol.q.shape[1])[None, :] < sol.n_solutions[:, None])
        pr.append(rows[p_])
        ar.append(np.full(len(p_), a))
        qr.append(sol.q[p_, b_])
    pr, ar, qr = np.concatenate(pr), np.concatenate(ar), np.concatenate(qr)
    if not len(pr):
        return
    cap, bnd = _capacity(sm, np.deg2rad(ar), qr, hp.problem.directions, hp.problem.motion)
    k = argmin_per_group(-cap, pr)
    k = k[cap[k] > res.capacity_kg[pr[k]]]
    r = pr[k]
    res.capacity_kg[r], res.angle_deg[r], res.q_rad[r], res.binding[r] = cap[k], ar[k], qr[k], bnd[k]
    res.n_candidates[r] += np.bincount(pr, minlength=len(points))[r]
    res.n_full[r] += np.bincount(pr, minlength=len(points))[r]


def _polish(hp: HealthyProblem, points: np.ndarray, res: HealthyCapacity, rows: np.ndarray,
            levels: int | None = None) -> None:
    """Follow the best posture of points[rows] (``res``: its angle and joints) between grid angles, in
    place: ``levels`` (default ``hp.polish_levels``) levels, from half the grid's step, halving it; at each level the angles a
    step either side, each reached from the current posture along its IK branch (:func:`_follow`), the
    best of the three kept. Values only rise; each is the posture's it records."""
    sm, directions, motion = hp.sm, hp.problem.directions, hp.problem.motion
    h = sm.step_deg / 2
    for _ in range((hp.polish_levels if levels is None else levels) if len(rows) else 0):
        best, angle, q, bnd = (res.capacity_kg[rows].copy(), res.angle_deg[rows].copy(), res.q_rad[rows].copy(),
                               res.binding[rows].copy())
        for sign in (-1.0, 1.0):
            a = sm.into_range(res.angle_deg[rows] + sign * h)
            r, qs = _follow(sm, hp.problem.rotation, points[rows], a, res.q_rad[rows])
            if not len(r):
                continue
            val, b = _capacity(sm, np.deg2rad(a[r]), qs, directions, motion)
            up = val > best[r]
            best[r[up]], angle[r[up]], q[r[up]], bnd[r[up]] = val[up], a[r[up]], qs[up], b[up]
        res.capacity_kg[rows], res.angle_deg[rows], res.q_rad[rows], res.binding[rows] = best, angle, q, bnd
        h /= 2


def _follow(sm: SelfMotion, rotation: np.ndarray, points: np.ndarray, angle_deg: np.ndarray, q: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """Per point (N, 3) with the joint moved to angle_deg (N,) (NaN: none) from the posture q (N, n_active)
    rad (at the rotation (3, 3)), the posture of the same IK branch there: Newton's method on the active
    joints from q (damped least squares on the arm's Jacobian without the held joint's column), accepted
    where the pose is met to the IK's tolerance and every active joint lies in its range. (The points that
    reach one (M,), their active joints (M, n_active).)"""
    arm = sm.arms[0]
    chain, act, j = sm.free_chain, arm.active, arm.locked_joint - 1
    rows = np.flatnonzero(np.isfinite(angle_deg) & np.all(np.isfinite(q), axis=1))
    target = np.broadcast_to(np.eye(4), (len(rows), 4, 4)).copy()
    target[:, :3, :3], target[:, :3, 3] = rotation, points[rows]
    full = np.zeros((len(rows), arm.robot.n_joints))
    full[:, act], full[:, j] = q[rows], np.deg2rad(angle_deg[rows])
    for _ in range(_NEWTON_STEPS):
        T, J = chain.jacobian(full)
        e = pose_error(T, target)
        Ja = J[:, :, act]
        JtJ = np.swapaxes(Ja, 1, 2) @ Ja + 1e-12 * np.eye(len(act))
        full[:, act] += np.linalg.solve(JtJ, (np.swapaxes(Ja, 1, 2) @ e[..., None]))[..., 0]
    err = np.linalg.norm(pose_error(chain.fk(full), target), axis=1)
    qa, inside = wrap_to_range(full[:, act], arm.q_lower, arm.q_upper)
    ok = (err <= RESIDUAL_TOL) & inside.all(axis=1)
    return rows[ok], qa[ok]


def _branch_and_bound(hp: HealthyProblem, points: np.ndarray, ceiling: np.ndarray, groups: np.ndarray | None
                      ) -> HealthyCapacity:
    """The grid's best posture of each point: every candidate screened, then evaluated in order of its
    bound (when the screen is the whole set of a finite set, the screen's values are the candidates'; a
    subset of an exact set, the whole sphere, only bounds them)."""
    sm, rotation, directions, motion = hp.sm, hp.problem.rotation, hp.problem.directions, hp.problem.motion
    N = len(points)
    ceiling = ceiling.copy()
    groups = None if groups is None else np.unique(np.asarray(groups), return_inverse=True)[1].reshape(-1)
    n_act = sm.arms[0].n_active
    pt, tt, qq = _postures(sm, rotation, points, np.repeat(np.arange(N), len(sm.arms)),
                           np.tile(np.arange(len(sm.arms)), N))
    coef = sm.dyn.batch.coefficients(qq, sm.held_rad[tt]) if len(qq) else None  # once: screen and full set
    ub, ub_binding = _minimum(sm, coef, hp.screen, motion)
    order = np.lexsort((-ub, pt))  # per point, by decreasing bound
    pt, tt, qq, ub, ub_binding = pt[order], tt[order], qq[order], ub[order], ub_binding[order]
    coef = coef.take(order) if coef is not None else None
    start = np.searchsorted(pt, np.arange(N))
    count = np.bincount(pt, minlength=N)
    best = np.full(N, -np.inf)
    best_row = np.full(N, -1)
    best_binding = np.full(N, -1)
    n_full = np.zeros(N, dtype=int)
    whole = not directions.exact and len(hp.screen) == len(directions)  # the screen is the set: values known
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
        val, bnd = _minimum(sm, coef.take(rows), directions, motion)
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
