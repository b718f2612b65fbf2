"""The healthy arm's question and answer as data (:mod:`capmap.capacity.baseline` searches it): the
failed joint's grid of angles and the arm held at any angle (:class:`SelfMotion`), the question
(:class:`HealthyProblem`), the answer per point (:class:`HealthyCapacity`), where a point's search
starts (:class:`Hint`), and the capacity of a batch of postures, each held at its own angle."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from capmap.capacity.directions import Directions, sphere
from capmap.capacity.engine import Motion, direction_minimum
from capmap.capacity.problem import CapacityProblem
from capmap.core import ik
from capmap.core.coefficients import Coefficients
from capmap.core.configuration import Configurations, arm_configurations
from capmap.core.dynamics import ArmDynamics
from capmap.core.kinematics import inverse_transform
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm, free
from capmap.errors import CapmapError

__all__ = ["self_motion_angles", "screening_subset", "SelfMotion", "HealthyProblem", "HealthyCapacity", "Hint",
           "SEARCH_FIELDS", "postures_capacity", "postures_minimum"]

SEARCH_FIELDS = ("capacity_kg", "angle_deg", "q_rad", "binding", "n_candidates", "n_full", "exact")  # per point


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
        a = _into_turn(a, lower_deg, upper_deg)  # the others' representatives inside the range
    else:
        m = np.arange(np.ceil((lower_deg - through_deg) / step_deg - 1e-9),
                      np.floor((upper_deg - through_deg) / step_deg + 1e-9) + 1)
        a = np.concatenate([through_deg + step_deg * m, [lower_deg, upper_deg]])
    a = np.clip(np.sort(a), lower_deg, upper_deg)
    return a[np.concatenate([[True], np.diff(a) > 1e-9])]


def _into_turn(a: np.ndarray, lower_deg: float, upper_deg: float) -> np.ndarray:
    """Angles (N,) deg shifted by a turn into [lower, upper] (a range spanning a turn or more)."""
    a = np.where(a > upper_deg + 1e-9, a - 360.0, a)
    return np.where(a < lower_deg - 1e-9, a + 360.0, a)


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
            return _into_turn(a, self.lower_deg, self.upper_deg)
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

    def solve(self, points: np.ndarray, angle_deg: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every IK solution of each point (M, 3) m with the joint held at its own angle_deg (M,) deg, the
        end effector at the rotation (3, 3): (the point of each solution (K,), its active joints
        (K, n_active) rad). A folding joint (:attr:`fold`): every target in one call on the first grid
        angle's arm (:meth:`moved`); otherwise one call per angle, on the arm held there."""
        ref = self.arms[0]
        near = np.flatnonzero(self.within_reach(points, rotation))  # the others have no solution at any angle
        points, angle_deg = points[near], np.asarray(angle_deg, dtype=float)[near]
        if self.fold is not None:
            T, groups, arms = self.moved(points, angle_deg, rotation), [np.arange(len(points))], [ref]
        else:
            T = ik.targets(points, rotation)
            uniq, inv = np.unique(np.round(angle_deg, 9), return_inverse=True)
            groups = [np.flatnonzero(inv.reshape(-1) == u) for u in range(len(uniq))]
            arms = [self.arm_at(float(a)) for a in uniq]
        rows, qs = [np.zeros(0, dtype=int)], [np.zeros((0, ref.n_active))]
        for g, arm in zip(groups, arms):
            if not len(g):
                continue
            sol = ik.solve_chain(arm.chain, T[g], arm.q_lower, arm.q_upper)
            p_, b_ = np.nonzero(np.arange(sol.q.shape[1])[None, :] < sol.n_solutions[:, None])
            rows.append(near[g[p_]])
            qs.append(sol.q[p_, b_])
        return np.concatenate(rows), np.concatenate(qs)

    def within_reach(self, points: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """(M,) bool: False where the arm cannot reach the points (M, 3) m at the rotation (3, 3) or (M, 3, 3)
        with any joint angles (a bound, exact as a test: a False point has no IK solution at any angle).
        With the free chain T = F0 Rz(q1) F1 ... Rz(qn) Fn, the frame before Fn sits at p - R Rn^T tn, within
        |t1| + ... + |t(n-1)| of F0's origin whatever the angles (each Fk's translation tk, rotations keep lengths)."""
        F = self.free_chain.X
        tip = np.asarray(rotation, dtype=float) @ (F[-1][:3, :3].T @ F[-1][:3, 3])
        radius = sum(float(np.linalg.norm(F[k][:3, 3])) for k in range(1, len(F) - 1))
        return np.linalg.norm(np.asarray(points, dtype=float) - tip - F[0][:3, 3], axis=-1) <= radius * (1 + 1e-9) + 1e-9

    @cached_property
    def fold(self) -> int | None:
        """0 when the held joint is the chain's first, so that the arm held at angle a is the free chain
        (F) with its first two fixed transforms and that joint folded into F0 Rz(a) F1; -1 when it is the
        last (F(n-1) Rz(a) Fn); None otherwise. Checked on every grid angle's arm (to rounding)."""
        F, j = self.free_chain.X, self.arms[0].locked_joint
        kind = 0 if j == 1 else -1 if j == self.free_chain.n else None
        if kind is None:
            return None
        k, rest, free_rest = (0, slice(1, None), F[2:]) if kind == 0 else (-1, slice(None, -1), F[:-2])
        held = self._held(self.angles_deg, kind)
        same = all(np.allclose(a.chain.X[k], h, rtol=0.0, atol=1e-12) and np.array_equal(a.chain.X[rest], free_rest)
                   for a, h in zip(self.arms, held))
        return kind if same else None

    def _held(self, angle_deg: np.ndarray, kind: int) -> np.ndarray:
        """The folded fixed transform (M, 4, 4) at angles (M,) deg: F0 Rz(a) F1 (kind 0), F(n-1) Rz(a) Fn (-1)."""
        F = self.free_chain.X
        a = np.deg2rad(np.asarray(angle_deg, dtype=float))
        Rz = np.zeros((len(a), 4, 4))
        Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1] = np.cos(a), -np.sin(a), np.sin(a), np.cos(a)
        Rz[:, 2, 2] = Rz[:, 3, 3] = 1.0
        return F[0] @ Rz @ F[1] if kind == 0 else F[-2] @ Rz @ F[-1]

    def moved(self, points: np.ndarray, angle_deg: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """For a folding joint (:attr:`fold`): the targets (M, 4, 4) of the first grid angle's arm that put
        the arm held at angle_deg (M,) deg at the points (M, 3) m with the rotation (3, 3) (equal to
        rounding): its base moved, T -> X0(ref) X0(a)^-1 T, or its tip, T -> T Xn(a)^-1 Xn(ref)."""
        T = ik.targets(points, rotation)
        if not len(T):
            return T
        ref, held = self.arms[0].chain.X, inverse_transform(self._held(angle_deg, self.fold))
        return ref[0] @ held @ T if self.fold == 0 else T @ held @ ref[-1]

    def grid_configuration(self, angle_deg: np.ndarray, q: np.ndarray) -> np.ndarray:
        """The configuration label (N,) of postures (angle_deg (N,) deg, finite; q (N, n_active) rad) as the
        arm at the nearest grid angle labels them (a search's hint: no arm built between grid angles). A folding
        joint's grid arms differ only in their first (last) fixed transform, which the labels do not see (a
        chain's shoulder, elbow and wrist flags are taken in the frame after its first transform and at the
        wrist before its last; the sign of det J is that of any base or tool frame): one call on the first."""
        if self.fold is not None:
            return self.configurations(self.arms[0]).labels(q) if len(q) else np.full(0, -1)
        t = self.grid_index(angle_deg)
        out = np.full(len(t), -1)
        for a in np.unique(t):
            out[t == a] = self.configurations(self.arms[a]).labels(q[t == a])
        return out

    def configurations(self, arm: LockedArm) -> Configurations:
        """The configuration labels of one of its arms (built once per arm)."""
        if id(arm) not in self._labels:
            self._labels[id(arm)] = (arm, arm_configurations(arm))  # the arm kept: its id stays its own
        return self._labels[id(arm)][1]


@dataclass(frozen=True)
class HealthyCapacity:
    """Per point (N,): capacity_kg the healthy value (NaN: no angle reaches the pose), angle_deg the
    failed joint's angle attaining it, q_rad (N, n_active) the active joints there, binding the binding
    output's index into the limits' names (+ singular), n_candidates the (angle, solution) pairs seen,
    n_full those evaluated on the full direction set, exact: the value is the search's (not stopped at
    a ceiling)."""

    capacity_kg: np.ndarray
    angle_deg: np.ndarray
    q_rad: np.ndarray
    binding: np.ndarray
    n_candidates: np.ndarray
    n_full: np.ndarray
    exact: np.ndarray


@dataclass(frozen=True)
class Hint:
    """Where a point's search starts (a neighbour's best posture: most points of a voxel do not lower its
    minimum): per point (N,) a grid angle (index into ``SelfMotion.angles_deg``, -1 none) and a
    configuration label (-1 none)."""

    angle: np.ndarray
    configuration: np.ndarray


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


def postures_capacity(sm: SelfMotion, held_rad: np.ndarray, q: np.ndarray, dirs: Directions, motion: Motion
              ) -> tuple[np.ndarray, np.ndarray]:
    """Each posture's minimum over ``dirs`` (M,) kg and its binding output (M,): active joints q (M, n_active)
    rad with the failed joint at held_rad (M,)."""
    if not len(q):
        return np.zeros(0), np.zeros(0, dtype=int)
    return postures_minimum(sm, sm.dyn.batch.coefficients(q, held_rad), dirs, motion)


def postures_minimum(sm: SelfMotion, coef: Coefficients | None, dirs: Directions, motion: Motion
             ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`postures_capacity` of postures whose coefficients are known (None: no posture)."""
    if coef is None:
        return np.zeros(0), np.zeros(0, dtype=int)
    cap, _, _, binding = direction_minimum(coef, dirs, motion, sm.dyn.gravity, sm.limits)
    return cap, binding
