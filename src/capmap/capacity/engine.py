"""Exact dynamic load-carrying capacity.

With the motion fixed, every constrained output is affine in the payload mass m:
y(m) = y0 + m s, with limits |y_k| <= L_k. The largest admissible m is therefore

    m* = min_k  { (L_k - y0_k) / s_k  if s_k > 0;  (L_k + y0_k) / -s_k  if s_k < 0 },

and m* = 0 when some |y0_k| > L_k already (the state violates a limit with no payload).
Over a set of directions, y0 and s are evaluated from the exact polynomial coefficients
(:class:`capmap.core.coefficients.Coefficients`, batched; re-exported here) with one matrix product.
A point's capacity over its IK branches: :func:`capmap.capacity.problem.point_capacity`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.capacity.directions import Directions
from capmap.capacity.sphere import min_over_sphere
from capmap.capacity.sweep import min_over_directions
from capmap.core.coefficients import Coefficients
from capmap.core.dynamics import ArmDynamics, output_names
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm
from capmap.errors import CapmapError

__all__ = ["LoadLimits", "Motion", "Coefficients", "coefficients", "coefficients_pinocchio", "state_affine", "joint_state_affine",
           "state_capacity", "direction_features", "affine_over_directions", "capacity_over_directions",
           "PointCapacity", "direction_minimum", "argmin_per_group", "motion_features", "margin_pct",
           "SINGULAR"]

SINGULAR = "singular"


@dataclass(frozen=True)
class LoadLimits:
    """Load limits of an arm: per-joint torque (n_joints,) N m (the locked joint's is ignored); base
    force (3,) N and moment (3,) N m, per axis of the base frame."""

    joint_torque_nm: np.ndarray
    base_force_n: np.ndarray
    base_moment_nm: np.ndarray

    @classmethod
    def uniform(cls, n_joints: int, torque_nm: float, force_n: float, moment_nm: float) -> "LoadLimits":
        return cls(np.full(n_joints, float(torque_nm)), np.full(3, float(force_n)), np.full(3, float(moment_nm)))

    def for_arm(self, arm: LockedArm) -> AffineLimits:
        """The limits of ``arm``'s constrained outputs, in the order of :func:`output_names`."""
        if len(self.joint_torque_nm) != arm.robot.n_joints:
            raise CapmapError(f"{{torque}} has {len(self.joint_torque_nm)} entries but {arm.robot.name} has "
                              f"{arm.robot.n_joints} joints", torque="the joint-torque limit")
        vec = np.concatenate([self.joint_torque_nm[arm.active], self.base_force_n, self.base_moment_nm]).astype(float)
        return AffineLimits(vec, output_names(arm))


def margin_pct(capacity_kg, payload_kg: float):
    """Capacity over the payload, in % of the payload (NaN for a zero payload)."""
    return 100 * (capacity_kg - payload_kg) / payload_kg if payload_kg > 0 else np.nan


@dataclass(frozen=True)
class Motion:
    """End-effector straight-line motion: speed v_max (m/s), acceleration a_max (m/s^2)."""

    v_max_mps: float
    a_max_mps2: float


def state_affine(dyn: ArmDynamics, q_active: np.ndarray, v_lin: np.ndarray, a_lin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(y0, s) of one motion state computed directly: joint motion by J^-1, one RNEA each."""
    q, qd, qdd = dyn.motion(q_active, v_lin, a_lin)
    return joint_state_affine(dyn, q, qd, qdd, a_lin)


def joint_state_affine(dyn: ArmDynamics, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                       a_lin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(y0, s), each (n_out,), of a joint motion state: full q, qd, qdd (nv,), with the
    end-effector linear acceleration a_lin (3,) m/s^2 that the payload shares. y(m) = y0 + m s."""
    y0 = dyn.outputs(q, qd, qdd)
    s = dyn.outputs(q, np.zeros_like(qd), np.zeros_like(qdd), payload_force=np.asarray(a_lin) - dyn.gravity,
                    gravity=False)
    return y0, s


def state_capacity(dyn: ArmDynamics, q_active: np.ndarray, v_lin: np.ndarray, a_lin: np.ndarray,
                   limits: AffineLimits) -> tuple[float, str]:
    """Capacity (kg) of one motion state and the name of its binding limit."""
    y0, s = state_affine(dyn, q_active, v_lin, a_lin)
    cap, k = limits.largest(y0, s)
    return float(cap), limits.names[int(k)]


def coefficients(dyn: ArmDynamics, q_active: np.ndarray) -> Coefficients:
    """Coefficients for configurations q_active (B, n_active) rad, the whole batch at once
    (:class:`capmap.core.batch_dynamics.BatchDynamics`; equal to the per-configuration Pinocchio
    computation :func:`coefficients_pinocchio` to ~1e-12)."""
    q_active = np.atleast_2d(q_active)
    if not len(q_active):
        return Coefficients.empty(dyn.n_out)
    return dyn.batch.coefficients(q_active)


def coefficients_pinocchio(dyn: ArmDynamics, q_active: np.ndarray) -> Coefficients:
    """The reference path: :meth:`ArmDynamics.coefficients` (16 RNEA + 6 drift calls of Pinocchio)
    configuration by configuration."""
    rows = [dyn.coefficients(q) for q in np.atleast_2d(q_active)]
    if not rows:
        return Coefficients.empty(dyn.n_out)
    return Coefficients.stack(rows)


def direction_features(u: np.ndarray) -> np.ndarray:
    """Quadratic features phi(u) (D, 6) = [u0^2, u1^2, u2^2, u0 u1, u0 u2, u1 u2]."""
    return np.stack([u[:, 0] ** 2, u[:, 1] ** 2, u[:, 2] ** 2, u[:, 0] * u[:, 1], u[:, 0] * u[:, 2],
                     u[:, 1] * u[:, 2]], axis=1)


def affine_over_directions(coef: Coefficients, u: np.ndarray, motion: Motion,
                           gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(y0, s), each (B, n_out, D), for every configuration x direction u (D, 3)."""
    y0 = coef.stacked() @ motion_features(u, motion).T
    s = coef.S @ (motion.a_max_mps2 * u - gravity).T
    return y0, s


def capacity_over_directions(coef: Coefficients, directions: Directions, motion: Motion, gravity: np.ndarray,
                             limits: AffineLimits) -> tuple[np.ndarray, np.ndarray]:
    """Capacity (B, D) kg and binding output index (B, D) (n_out = singular configuration)."""
    y0, s = affine_over_directions(coef, directions.u, motion, gravity)
    cap, binding = limits.largest(y0, s, axis=1)
    cap[coef.singular] = 0.0
    binding[coef.singular] = len(limits)
    return cap, binding


def direction_minimum(coef: Coefficients, directions: Directions, motion: Motion, gravity: np.ndarray,
                      limits: AffineLimits) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each configuration's minimum over the motion set: capacity (M,) kg, the worst direction's index
    into ``directions`` (M,) (-1 where it lies off the set: ``directions.exact``, the whole sphere) and
    the worst direction (M, 3), binding output (M,) (n_out: singular configuration, capacity 0)."""
    C, a = coef.stacked(), motion.a_max_mps2
    if directions.exact:
        cap, worst_u, binding, _ = min_over_sphere(C, coef.S, a, motion.v_max_mps, gravity, limits.limit,
                                                   directions.u)
        worst = np.full(len(cap), -1)
    else:
        cap, worst, binding = min_over_directions(C, coef.S, motion_features(directions.u, motion), a * directions.u,
                                                  gravity, limits.limit, directions.pairs)
        worst_u = directions.u[worst] if len(worst) else np.zeros((0, 3))
    cap[coef.singular] = 0.0
    binding[coef.singular] = len(limits)
    return cap, worst, worst_u, binding


@dataclass(frozen=True)
class PointCapacity:
    """Per-point results for N points (arrays of length N).

    capacity_kg: min over configuration set x motion set (NaN if unreachable);
    binding: index into ``names`` (-1 if unreachable); branch, direction: the worst pair
    (-1 if unreachable; direction -1 also where the minimum lies off the set: an exact set); worst_u
    (N, 3) the worst direction (NaN if unreachable); n_states: configurations x directions of the set
    (of an exact set: its start directions)."""

    capacity_kg: np.ndarray
    binding: np.ndarray
    branch: np.ndarray
    direction: np.ndarray
    worst_u: np.ndarray
    n_states: np.ndarray
    names: tuple[str, ...]
    axis_capacity_kg: np.ndarray | None = None  # (N, P): per antipodal pair of ``axes`` (NaN if unreachable)
    # with configuration labels: the same per configuration, (N, C) / (N, C, P), NaN where the point has no
    # IK solution of that configuration; config_binding (N, C) -1 there
    config_capacity_kg: np.ndarray | None = None
    config_axis_capacity_kg: np.ndarray | None = None
    config_binding: np.ndarray | None = None
    config_branches: np.ndarray | None = None  # (N, C) int: the point's IK solutions of each configuration


def argmin_per_group(values: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """Rows (G,) of the smallest value (N,) of each group present in groups (N,) int, groups in
    ascending order; ties go to the first row."""
    order = np.lexsort((values, groups))
    first = np.ones(len(order), dtype=bool)
    first[1:] = groups[order][1:] != groups[order][:-1]
    return order[first]


def motion_features(u: np.ndarray, motion: Motion) -> np.ndarray:
    """Features (D, 10) of the motion states along u (D, 3) at v_max and a_max: [1, a u, v^2 phi(u)],
    so that y0 = C @ features with C (.., 10) the stacked coefficients [c0, L, Q]."""
    v, a = motion.v_max_mps, motion.a_max_mps2
    return np.concatenate([np.ones((len(u), 1)), a * u, v**2 * direction_features(u)], axis=1)  # (D, 10)
