"""Verification of a Cartesian path carried out by the locked arm (the spec's step 9).

The end effector follows straight segments with rest-to-rest trapezoidal timing
(:mod:`capmap.trajectory`) at the fixed task orientation. The joint path is tracked by
inverse kinematics, keeping the branch continuous from the initial configuration: at
every sample the IK branch nearest the previous configuration is taken (each joint angle
shifted by the multiple of 2 pi nearest the previous one, so a revolute joint may pass
+-180 deg), and a jump larger than ``max_step_rad`` (a singularity, or a branch that
left the joint range) ends the tracking. Angles outside the joint range are kept and
flagged (``Tracking.in_range``): a joint that must pass its stop makes the motion
infeasible whatever the payload, and the verification says so. Joint rates are exact:
qd = J^-1 [v; 0], qdd = J^-1 ([a; 0] - Jdot qd).

Every state's outputs are affine in the payload mass, y(m) = y0 + m s
(:func:`capmap.capacity.joint_state_affine`), so a state's capacity, the loads at the
task payload and a segment's capacity (the minimum over its states) are all exact at
the samples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap import ik
from capmap.capacity import capacity_from_affine, joint_state_affine
from capmap.dynamics import ArmDynamics
from capmap.errors import CapmapError
from capmap.locking import LockedArm
from capmap.trajectory import Timeline, sample_segments

START_TOL_RAD = np.deg2rad(2.0)  # q_ini may be rounded: allow 2 deg to the nearest exact branch
MAX_STEP_RAD = np.deg2rad(5.0)  # largest joint change between consecutive samples on one branch


@dataclass(frozen=True)
class Tracking:
    """q (N, n_active) rad, continuous (NaN from ``failed_at`` on); failed_at: first failed
    sample (-1: none); failure: reason ('' if none); start_offset_rad: max |q_ini - start
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


def start_branch(arm: LockedArm, position: np.ndarray, rotation: np.ndarray, q_ini_active: np.ndarray,
                 tol_rad: float = START_TOL_RAD) -> tuple[np.ndarray, float]:
    """The exact IK branch at ``position`` nearest q_ini_active (n_active,) rad, and its max joint
    offset; a one-line CapmapError if q_ini is not within tol_rad of any branch."""
    sol = ik.solve(arm, np.asarray(position)[None], rotation)
    n = int(sol.n_solutions[0])
    if n == 0:
        raise CapmapError("task.start_m is not reachable at the task orientation")
    cand = sol.q[0, :n]
    cand = nearest_turn(cand, q_ini_active)
    off = np.abs(cand - q_ini_active).max(axis=1)
    k = int(np.argmin(off))
    if off[k] > tol_rad:
        raise CapmapError(f"task.q_ini_deg is {np.rad2deg(off[k]):.2f} deg from the nearest of the {n} IK solutions at "
                          f"task.start_m (allowed {np.rad2deg(tol_rad):g} deg): it does not put the end effector at the start")
    return cand[k], float(off[k])


def track(arm: LockedArm, positions: np.ndarray, rotation: np.ndarray, q_ini_active: np.ndarray,
          max_step_rad: float = MAX_STEP_RAD) -> Tracking:
    """Continuous-branch IK along positions (N, 3) m at a fixed rotation (3, 3).

    The first position must be the start; its branch is the one nearest q_ini_active.
    """
    positions = np.asarray(positions, dtype=float)
    q_prev, offset = start_branch(arm, positions[0], rotation, q_ini_active)
    sol = ik.solve(arm, positions, rotation)
    N = len(positions)
    q = np.full((N, arm.n_active), np.nan)

    def result(failed_at: int, failure: str) -> Tracking:
        in_range = (q >= arm.q_lower - 1e-9) & (q <= arm.q_upper + 1e-9)
        return Tracking(q, failed_at, failure, offset, in_range | np.isnan(q))

    for i in range(N):
        n = int(sol.n_solutions[i])
        if n == 0:
            return result(i, "no IK solution at the task orientation (outside the workspace)")
        cand = sol.q[i, :n]
        cand = nearest_turn(cand, q_prev)
        jump = np.abs(cand - q_prev).max(axis=1)
        k = int(np.argmin(jump))
        if jump[k] > max_step_rad:
            return result(i, f"branch lost: nearest solution {np.rad2deg(jump[k]):.1f} deg away "
                             "(singularity or joint range)")
        q[i] = q_prev = cand[k]
    return result(-1, "")


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


@dataclass(frozen=True)
class Loads:
    """Per sample (N rows; NaN where the tracking failed): qd, qdd (N, n_active) rad/s, rad/s^2;
    y0, s (N, n_out) outputs with no payload and per kg of payload; capacity_kg (N,) of each
    state and binding (N,) index of its binding output (-1 where not tracked)."""

    qd: np.ndarray
    qdd: np.ndarray
    y0: np.ndarray
    s: np.ndarray
    capacity_kg: np.ndarray
    binding: np.ndarray

    def at(self, payload_kg: float) -> np.ndarray:
        """Outputs (N, n_out) carrying payload_kg."""
        return self.y0 + payload_kg * self.s


def loads(dyn: ArmDynamics, q_active: np.ndarray, v: np.ndarray, a: np.ndarray, limit: np.ndarray) -> Loads:
    """Joint rates, outputs and state capacities along a tracked path.

    q_active (N, n_active) rad (NaN rows skipped); v, a (N, 3) end-effector linear velocity
    m/s and acceleration m/s^2; limit (n_out,) in the order of ``output_names``.
    """
    arm = dyn.arm
    N, n = q_active.shape
    qd, qdd = np.full((N, n), np.nan), np.full((N, n), np.nan)
    y0, s = np.full((N, dyn.n_out), np.nan), np.full((N, dyn.n_out), np.nan)
    for i in np.flatnonzero(~np.isnan(q_active).any(axis=1)):
        try:
            qf, qdf, qddf = dyn.motion(q_active[i], v[i], a[i])
        except np.linalg.LinAlgError:  # an exactly singular Jacobian: left untracked (capacity 0)
            continue
        qd[i], qdd[i] = qdf[arm.active], qddf[arm.active]
        y0[i], s[i] = joint_state_affine(dyn, qf, qdf, qddf, a[i])
    ok = ~np.isnan(y0).any(axis=1)
    cap = np.full(N, np.nan)
    binding = np.full(N, -1)
    if ok.any():
        cap[ok], binding[ok] = capacity_from_affine(y0[ok], s[ok], limit)
    return Loads(qd, qdd, y0, s, cap, binding)


def group_min(groups: np.ndarray, values: np.ndarray, n_groups: int) -> tuple[np.ndarray, np.ndarray]:
    """Per group g in 0..n_groups-1: min of values (NaN counts as 0: an untracked state carries
    nothing) and the row attaining it (-1 for an empty group; inf for a group of states with
    no load at all)."""
    v = np.nan_to_num(np.asarray(values, dtype=float), nan=0.0)
    out = np.full(n_groups, np.inf)
    arg = np.full(n_groups, -1)
    for k in range(n_groups):
        rows = np.flatnonzero(groups == k)
        if len(rows):
            j = rows[np.argmin(v[rows])]
            out[k], arg[k] = v[j], j
    return out, arg


@dataclass(frozen=True)
class PathResult:
    """A verified path: its timeline, tracking and loads; per segment (S,) the capacity kg
    (min over its states; 0 if any state is untracked) and the sample attaining it."""

    timeline: Timeline
    tracking: Tracking
    loads: Loads
    segment_capacity_kg: np.ndarray
    segment_worst: np.ndarray


def verify_path(dyn: ArmDynamics, waypoints: np.ndarray, rotation: np.ndarray, q_ini_active: np.ndarray,
                v_max_mps: float, a_max_mps2: float, dt_s: float, limit: np.ndarray) -> PathResult:
    """Time, track and load a waypoint path (W, 3) m; see the module docstring."""
    tl = sample_segments(waypoints, v_max_mps, a_max_mps2, dt_s)
    tr = track(dyn.arm, tl.p, rotation, q_ini_active)
    ld = loads(dyn, tr.q, tl.v, tl.a, limit)
    cap, worst = group_min(tl.segment, ld.capacity_kg, len(tl.profiles))
    return PathResult(tl, tr, ld, cap, worst)
