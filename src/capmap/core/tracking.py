"""Branch following: inverse kinematics along a sampled Cartesian path, one continuous branch.

At every sample the IK branch nearest the previous configuration is taken (each joint
angle shifted by the multiple of 2 pi nearest the previous one, so a revolute joint may
pass +-180 deg), starting from the branch nearest a given configuration. A jump larger
than ``max_step_rad`` (a singularity, or a branch that left the joint range) ends the
tracking. Angles outside the joint range are kept and flagged (``Tracking.in_range``): a
joint that must pass its stop makes the motion infeasible whatever the payload, and the
caller says so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.core import ik
from capmap.core.reduction import LockedArm
from capmap.errors import CapmapError

__all__ = ["Tracking", "nearest_turn", "nearest_branch", "start_branch", "follow_branches", "in_joint_range", "track",
           "range_excursions", "START_TOL_RAD", "MAX_STEP_RAD", "RANGE_TOL_RAD"]

START_TOL_RAD = np.deg2rad(2.0)  # a start configuration may be rounded: allow 2 deg to the nearest exact branch
MAX_STEP_RAD = np.deg2rad(5.0)  # largest joint change between consecutive samples on one branch
RANGE_TOL_RAD = 1e-9  # a joint at its stop up to rounding is within its range


@dataclass(frozen=True)
class Tracking:
    """q (N, n_active) rad, continuous (NaN from ``failed_at`` on); failed_at: first failed
    sample (-1: none); failure: reason ('' if none); start_offset_rad: max |q_start - start
    branch| over joints; in_range (N, n_active) bool: angle within the joint range."""

    q: np.ndarray
    failed_at: int
    failure: str
    start_offset_rad: float
    in_range: np.ndarray

    @property
    def ok(self) -> bool:
        return self.failed_at < 0


def nearest_turn(q: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """q (..., n) rad with each joint shifted by the multiple of 2 pi that brings it nearest ref (n,)."""
    return q + 2 * np.pi * np.round((ref - q) / (2 * np.pi))


def nearest_branch(branches: np.ndarray, ref: np.ndarray) -> tuple[int, np.ndarray, float]:
    """Of IK branches (n, m) rad, the one nearest ref (m,) after whole turns (largest joint
    difference): its index, its angles shifted nearest ref (m,) rad and that difference (rad)."""
    cand = nearest_turn(branches, ref)
    off = np.abs(cand - ref).max(axis=1)
    k = int(np.argmin(off))
    return k, cand[k], float(off[k])


def start_branch(arm: LockedArm, position: np.ndarray, rotation: np.ndarray, q_start: np.ndarray,
                 tol_rad: float = START_TOL_RAD) -> tuple[np.ndarray, float]:
    """The exact IK branch at ``position`` (3,) m, ``rotation`` (3, 3) nearest q_start (n_active,) rad,
    and its max joint offset (rad). A one-line CapmapError (roles ``start``, ``q_ini``) if the
    position is unreachable or q_start is not within tol_rad of any branch."""
    sol = ik.solve(arm, np.asarray(position)[None], rotation)
    n = int(sol.n_solutions[0])
    if n == 0:
        raise CapmapError("{start} is not reachable at the task orientation", start="the start position")
    _, q, off = nearest_branch(sol.q[0, :n], q_start)
    if off > tol_rad:
        raise CapmapError(f"{{q_ini}} is {np.rad2deg(off):.2f} deg from the nearest of the {n} IK solutions at "
                          f"{{start}} (allowed {np.rad2deg(tol_rad):g} deg): it does not put the end effector at "
                          "the start", q_ini="the start configuration", start="the start position")
    return q, off


def follow_branches(sets: np.ndarray, counts: np.ndarray, q0: np.ndarray,
                    max_step_rad: float = MAX_STEP_RAD) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Follow E branches through IK sets, sample by sample: at each sample the solution nearest
    the previous configuration (:func:`nearest_branch`, whole turns allowed).

    sets (E, S, K, n) rad, NaN-padded beyond counts (E, S); q0 (E, n) rad, the configurations
    before the first sample. Returns q (E, S, n) rad (NaN from the failed sample on), failed_at
    (E,) the first sample without a solution within max_step_rad (-1: none) and jump (E,) rad
    the nearest solution's distance there (inf: no solution at all; 0 where none failed)."""
    E, S, K, n = sets.shape
    q = np.full((E, S, n), np.nan)
    failed_at = np.full(E, -1)
    jump_at = np.zeros(E)
    alive = np.ones(E, dtype=bool)
    q_prev = np.array(q0, dtype=float)
    absent = np.arange(K)[None, None, :] >= np.asarray(counts)[:, :, None]  # (E, S, K)
    rows = np.arange(E)
    for s in range(S):
        cand = nearest_turn(np.nan_to_num(sets[:, s]), q_prev[:, None, :])  # (E, K, n)
        off = np.where(absent[:, s], np.inf, np.abs(cand - q_prev[:, None, :]).max(axis=2))
        k = np.argmin(off, axis=1)
        jump = off[rows, k]
        fail = alive & ~(jump <= max_step_rad)
        failed_at[fail], jump_at[fail] = s, jump[fail]
        alive &= ~fail
        q_prev = np.where(alive[:, None], cand[rows, k], q_prev)
        q[alive, s] = q_prev[alive]
    return q, failed_at, jump_at


def in_joint_range(arm: LockedArm, q: np.ndarray) -> np.ndarray:
    """(..., n_active) bool: each joint of configurations q (..., n_active) rad within its range
    (up to :data:`RANGE_TOL_RAD`; False where q is NaN)."""
    return (q >= arm.q_lower - RANGE_TOL_RAD) & (q <= arm.q_upper + RANGE_TOL_RAD)


def track(arm: LockedArm, positions: np.ndarray, rotation: np.ndarray, q_start: np.ndarray,
          max_step_rad: float = MAX_STEP_RAD) -> Tracking:
    """Continuous-branch IK along positions (N, 3) m at a fixed rotation (3, 3).

    The first position is the start; its branch is the one nearest q_start (n_active,) rad.
    """
    positions = np.asarray(positions, dtype=float)
    q_prev, offset = start_branch(arm, positions[0], rotation, q_start)
    sol = ik.solve(arm, positions, rotation)
    q, failed_at, jump = follow_branches(sol.q[None], sol.n_solutions[None], q_prev[None], max_step_rad)
    q, failed_at, jump = q[0], int(failed_at[0]), float(jump[0])
    failure = ""
    if failed_at >= 0:
        failure = ("no IK solution at the task orientation (outside the workspace)" if np.isinf(jump) else
                   f"branch lost: nearest solution {np.rad2deg(jump):.1f} deg away (singularity or joint range)")
    return Tracking(q, failed_at, failure, offset, in_joint_range(arm, q) | np.isnan(q))


def range_excursions(in_range: np.ndarray) -> list[tuple[int, int, int]]:
    """(joint column, first row, last row) of each run of samples outside the joint range;
    in_range (N, n_active) bool."""
    out = []
    for c in range(in_range.shape[1]):
        bad = np.flatnonzero(~in_range[:, c])
        if len(bad):
            breaks = np.flatnonzero(np.diff(bad) > 1)
            starts = np.concatenate([[bad[0]], bad[breaks + 1]])
            ends = np.concatenate([bad[breaks], [bad[-1]]])
            out += [(c, int(a), int(b)) for a, b in zip(starts, ends)]
    return sorted(out, key=lambda r: r[1])
