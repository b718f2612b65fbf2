"""Verification of a Cartesian path carried out by the locked arm (the spec's step 9).

The end effector follows straight segments with rest-to-rest trapezoidal timing
(:mod:`capmap.core.profiles`) at the fixed task orientation; the joint path is one IK
branch tracked continuously from the start configuration (:mod:`capmap.core.tracking`).
Joint rates are exact: qd = J^-1 [v; 0], qdd = J^-1 ([a; 0] - Jdot qd).

Every state's outputs are affine in the payload mass, y(m) = y0 + m s
(:func:`capmap.capacity.engine.joint_state_affine`), so a state's capacity, the loads at
the task payload and a segment's capacity (the minimum over its states) are all exact at
the samples. :func:`judge` turns a verified path into its verdicts: per segment and for
the path (capacity, margin over the payload, peak load, limits exceeded, joint range,
feasible = loads within every limit and every joint within its range).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmap.capacity.engine import Motion, joint_state_affine, margin_pct
from capmap.core.dynamics import ArmDynamics
from capmap.core.limits import AffineLimits
from capmap.core.profiles import Timeline, sample_segments
from capmap.core.reduction import LockedArm
from capmap.core.tracking import Tracking, range_excursions, track

__all__ = ["Loads", "loads", "group_min", "PathResult", "verify_path", "SegmentVerdict", "PathVerdict", "judge",
           "EXCEED_TOL"]

EXCEED_TOL = 1e-9  # a load exceeds its limit when |y| / L > 1 + EXCEED_TOL


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


def loads(dyn: ArmDynamics, q_active: np.ndarray, v: np.ndarray, a: np.ndarray, limits: AffineLimits) -> Loads:
    """Joint rates, outputs and state capacities along a tracked path.

    q_active (N, n_active) rad (NaN rows skipped); v, a (N, 3) end-effector linear velocity
    m/s and acceleration m/s^2; ``limits`` on the arm's outputs.
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
        cap[ok], binding[ok] = limits.largest(y0[ok], s[ok])
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


def verify_path(dyn: ArmDynamics, waypoints: np.ndarray, rotation: np.ndarray, q_start: np.ndarray, motion: Motion,
                dt_s: float, limits: AffineLimits) -> PathResult:
    """Time, track and load a waypoint path (W, 3) m at ``rotation`` (3, 3), starting on the IK
    branch nearest q_start (n_active,) rad, samples at most dt_s apart in each phase."""
    tl = sample_segments(waypoints, motion.v_max_mps, motion.a_max_mps2, dt_s)
    tr = track(dyn.arm, tl.p, rotation, q_start)
    ld = loads(dyn, tr.q, tl.v, tl.a, limits)
    cap, worst = group_min(tl.segment, ld.capacity_kg, len(tl.profiles))
    return PathResult(tl, tr, ld, cap, worst)


# --------------------------------------------------------------------------- verdicts


@dataclass(frozen=True)
class SegmentVerdict:
    """One segment of a verified path carrying ``payload``: its end points (m), length, duration,
    peak speed; capacity (kg) and binding output, the time of its weakest state, the margin of
    the capacity over the payload (%), the peak load (% of a limit), the limits exceeded at the
    payload, and whether every state was tracked and within the joint ranges."""

    segment: int
    x0_m: float
    y0_m: float
    z0_m: float
    x1_m: float
    y1_m: float
    z1_m: float
    length_m: float
    duration_s: float
    v_peak_mps: float
    capacity_kg: float
    binding: str
    t_worst_s: float
    margin_pct: float
    peak_load_pct: float
    exceeded_at_payload: str
    tracked: bool
    in_joint_range: bool


@dataclass(frozen=True)
class PathVerdict:
    """A verified path carrying ``payload``: its capacity is its weakest segment's; ``margin_pct``
    is the mean segment capacity over the payload (the spec's measure), ``min_margin_pct`` the
    weakest segment's; loads_ok: tracked and no limit exceeded; feasible: loads_ok and every
    joint within its range."""

    segments: int
    length_m: float
    duration_s: float
    tracking: str
    start_branch_offset_deg: float
    capacity_kg: float
    binding: str
    weakest_segment: int
    mean_segment_capacity_kg: float
    margin_pct: float
    min_margin_pct: float
    peak_load_pct: float
    peak_load: str
    limits_exceeded_at_payload: str
    loads_ok: bool
    joint_range: str
    feasible: bool


def _peak(ratio: np.ndarray, n: int) -> np.ndarray:
    """Per output, the largest |y|/L over the rows (NaN rows ignored; all NaN -> NaN)."""
    return np.nanmax(ratio, axis=0) if np.isfinite(ratio).any() else np.full(n, np.nan)


def _exceeded(names: tuple[str, ...], peak: np.ndarray) -> str:
    return ",".join(n for n, v in zip(names, peak) if v > 1 + EXCEED_TOL)


def _range_notes(res: PathResult, arm: LockedArm) -> str:
    tl, tr = res.timeline, res.tracking
    notes = []
    for c, a, b in range_excursions(tr.in_range):
        excursion = np.rad2deg(tr.q[a:b + 1, c])
        peak = excursion.max() if tr.q[a, c] > arm.q_upper[c] else excursion.min()  # the farthest beyond the stop
        notes.append(f"joint {arm.active_joint_numbers[c]} outside [{np.rad2deg(arm.q_lower[c]):g}, "
                     f"{np.rad2deg(arm.q_upper[c]):g}] deg for t = {tl.t_s[a]:.1f}..{tl.t_s[b]:.1f} s "
                     f"(peak {peak:.1f} deg)")
    return "; ".join(notes)


def judge(res: PathResult, arm: LockedArm, limits: AffineLimits, payload_kg: float) -> tuple[list[SegmentVerdict], PathVerdict]:
    """Verdicts of a verified path carrying payload_kg (see the dataclasses)."""
    tl, tr, ld = res.timeline, res.tracking, res.loads
    names = limits.names
    ratio = limits.ratio(ld.at(payload_kg))  # (N, n_out), NaN where untracked
    bind_names = np.array(list(names) + ["untracked"])
    tracked = ~np.isnan(tr.q).any(axis=1)
    in_range = tr.in_range.all(axis=1)
    wp = tl.p[tl.waypoint_rows()]
    segs = []
    for k, prof in enumerate(tl.profiles):
        rows = tl.segment == k
        w = res.segment_worst[k]
        peak = _peak(ratio[rows], len(names))
        segs.append(SegmentVerdict(
            k, *wp[k], *wp[k + 1], prof.length_m, prof.duration_s, prof.v_peak_mps,
            capacity_kg=res.segment_capacity_kg[k], binding=bind_names[ld.binding[w]] if w >= 0 else "",
            t_worst_s=tl.t_s[w] if w >= 0 else np.nan, margin_pct=margin_pct(res.segment_capacity_kg[k], payload_kg),
            peak_load_pct=100 * np.nanmax(peak), exceeded_at_payload=_exceeded(names, peak),
            tracked=bool(tracked[rows].all()), in_joint_range=bool(in_range[rows].all())))
    peak_all = _peak(ratio, len(names))
    exceeded = _exceeded(names, peak_all)
    worst = int(np.argmin(res.segment_capacity_kg))
    range_note = _range_notes(res, arm)
    loads_ok = tr.ok and not exceeded
    mean_cap = float(np.mean(res.segment_capacity_kg))
    path = PathVerdict(
        segments=len(tl.profiles), length_m=float(sum(p.length_m for p in tl.profiles)), duration_s=float(tl.t_s[-1]),
        tracking="ok" if tr.ok else f"failed at t = {tl.t_s[tr.failed_at]:.1f} s: {tr.failure}",
        start_branch_offset_deg=np.rad2deg(tr.start_offset_rad),
        capacity_kg=float(res.segment_capacity_kg[worst]), binding=segs[worst].binding, weakest_segment=worst,
        mean_segment_capacity_kg=mean_cap, margin_pct=margin_pct(mean_cap, payload_kg),
        min_margin_pct=margin_pct(res.segment_capacity_kg[worst], payload_kg),
        peak_load_pct=100 * float(np.nanmax(peak_all)), peak_load=names[int(np.nanargmax(peak_all))],
        limits_exceeded_at_payload=exceeded, loads_ok=loads_ok, joint_range=range_note or "ok",
        feasible=loads_ok and not range_note)
    return segs, path
