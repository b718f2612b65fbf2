"""Time scaling (speed profiles) of straight Cartesian segments.

A rest-to-rest trapezoidal speed profile over a segment of length L with speed limit
v_max and acceleration limit a_max: accelerate at a_max, cruise at v_max, decelerate at
a_max; when L < v_max^2 / a_max the cruise vanishes and the peak speed is sqrt(a_max L)
(triangular profile). A jerk-limited "double S" profile (:func:`scurve`) adds a jerk
limit. Pure functions on arrays; units m, s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from capmap.errors import CapmapError

__all__ = ["PHASES", "Trapezoid", "trapezoid", "Timeline", "sample_segments", "SCurve", "scurve", "MIN_PHASE_INTERVALS"]

PHASES = ("accelerate", "cruise", "decelerate")


@dataclass(frozen=True)
class Trapezoid:
    """Profile of one segment: length_m, peak speed v_peak_mps, acceleration a_mps2,
    acceleration time t_acc_s (= deceleration time), cruise time t_cruise_s."""

    length_m: float
    v_peak_mps: float
    a_mps2: float
    t_acc_s: float
    t_cruise_s: float

    @property
    def duration_s(self) -> float:
        return 2 * self.t_acc_s + self.t_cruise_s

    def phase_bounds(self) -> np.ndarray:
        """(4,) s: start, end of acceleration, end of cruise, end."""
        return np.array([0.0, self.t_acc_s, self.t_acc_s + self.t_cruise_s, self.duration_s])

    def phase_state(self, phase: int, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(s, sd, sdd), each like t (segment time, s), using ``phase``'s own formula (so a phase
        boundary gets that phase's one-sided acceleration)."""
        t = np.asarray(t, dtype=float)
        a, v, ta = self.a_mps2, self.v_peak_mps, self.t_acc_s
        if phase == 0:
            return 0.5 * a * t**2, a * t, np.full_like(t, a)
        if phase == 1:
            return 0.5 * a * ta**2 + v * (t - ta), np.full_like(t, v), np.zeros_like(t)
        r = np.maximum(self.duration_s - t, 0.0)  # time to go
        return self.length_m - 0.5 * a * r**2, a * r, np.full_like(t, -a)


def trapezoid(length_m: float, v_max_mps: float, a_max_mps2: float) -> Trapezoid:
    """Rest-to-rest time-optimal profile under |sd| <= v_max, |sdd| <= a_max."""
    if not (v_max_mps > 0 and a_max_mps2 > 0):
        raise CapmapError(f"speed limit {v_max_mps!r} m/s and acceleration limit {a_max_mps2!r} m/s^2 must be > 0")
    if length_m < 0:
        raise CapmapError(f"segment length {length_m!r} m must be >= 0")
    if length_m * a_max_mps2 >= v_max_mps**2:  # reaches v_max
        ta = v_max_mps / a_max_mps2
        return Trapezoid(length_m, v_max_mps, a_max_mps2, ta, (length_m - v_max_mps * ta) / v_max_mps)
    v = math.sqrt(a_max_mps2 * length_m)
    return Trapezoid(length_m, v, a_max_mps2, v / a_max_mps2, 0.0)


@dataclass(frozen=True)
class Timeline:
    """Samples of a sequence of straight segments, N samples.

    t_s (N,) global time; segment (N,) int; phase (N,) int index into PHASES;
    p (N, 3) m, v (N, 3) m/s, a (N, 3) m/s^2 of the end effector. A phase's samples
    include both of its ends, so a phase boundary appears twice (once per side of the
    acceleration jump); ``t_s`` is non-decreasing.
    """

    t_s: np.ndarray
    segment: np.ndarray
    phase: np.ndarray
    p: np.ndarray
    v: np.ndarray
    a: np.ndarray
    profiles: tuple[Trapezoid, ...]

    def __len__(self) -> int:
        return len(self.t_s)

    def waypoint_rows(self) -> np.ndarray:
        """(W,) the sample at each waypoint: the first, then the last of each segment."""
        last = np.flatnonzero(np.diff(self.segment) != 0)  # segments are sampled in order
        return np.concatenate([[0], last, [len(self.t_s) - 1]]).astype(int)


MIN_PHASE_INTERVALS = 10  # a phase is never sampled coarser than this: a verdict never comes from two samples


def sample_segments(waypoints: np.ndarray, v_max_mps: float, a_max_mps2: float, dt_s: float) -> Timeline:
    """Rest-to-rest trapezoidal motion through waypoints (W, 3) m, sampled every <= dt_s in each
    phase and at least ``MIN_PHASE_INTERVALS`` intervals per phase (short phases of short segments)."""
    waypoints = np.asarray(waypoints, dtype=float)
    if len(waypoints) < 2:
        raise CapmapError("a path needs at least two distinct waypoints")
    if not dt_s > 0:
        raise CapmapError(f"{{dt}} = {dt_s!r} must be > 0", dt="the sample spacing dt_s")
    parts = {k: [] for k in ("t", "seg", "ph", "s", "sd", "sdd", "dir", "p0")}
    profiles = []
    t0 = 0.0
    for k in range(len(waypoints) - 1):
        d = waypoints[k + 1] - waypoints[k]
        L = float(np.linalg.norm(d))
        prof = trapezoid(L, v_max_mps, a_max_mps2)
        profiles.append(prof)
        if L == 0:
            continue
        u = d / L
        bounds = prof.phase_bounds()
        for ph in range(3):
            T = bounds[ph + 1] - bounds[ph]
            if T <= 0:
                continue
            t = np.linspace(bounds[ph], bounds[ph + 1], max(MIN_PHASE_INTERVALS, math.ceil(T / dt_s - 1e-9)) + 1)
            s, sd, sdd = prof.phase_state(ph, t)
            n = len(t)
            parts["t"].append(t0 + t)
            parts["seg"].append(np.full(n, k))
            parts["ph"].append(np.full(n, ph))
            parts["s"].append(s)
            parts["sd"].append(sd)
            parts["sdd"].append(sdd)
            parts["dir"].append(np.broadcast_to(u, (n, 3)))
            parts["p0"].append(np.broadcast_to(waypoints[k], (n, 3)))
        t0 += prof.duration_s
    cat = {k: np.concatenate(v) for k, v in parts.items()}
    u = cat["dir"]
    return Timeline(t_s=cat["t"], segment=cat["seg"], phase=cat["ph"], p=cat["p0"] + cat["s"][:, None] * u,
                    v=cat["sd"][:, None] * u, a=cat["sdd"][:, None] * u, profiles=tuple(profiles))


@dataclass(frozen=True)
class SCurve:
    """Rest-to-rest jerk-limited ("double S") profile over length_m: piecewise-constant jerk.

    durations_s (P,), jerks (P,) m/s^3 of its phases; t0_s, s0, v0, a0 (P,) state at each
    phase start. Peak speed v_peak_mps, peak acceleration a_peak_mps2.
    """

    length_m: float
    durations_s: np.ndarray
    jerks: np.ndarray
    t0_s: np.ndarray
    s0: np.ndarray
    v0: np.ndarray
    a0: np.ndarray
    v_peak_mps: float
    a_peak_mps2: float

    @property
    def duration_s(self) -> float:
        return float(self.t0_s[-1] + self.durations_s[-1])

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(s, sd, sdd) at times t (any shape, s); constant at the ends outside [0, duration]."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration_s)
        k = np.clip(np.searchsorted(self.t0_s, t, side="right") - 1, 0, len(self.t0_s) - 1)
        tau = t - self.t0_s[k]
        j, a, v, s = self.jerks[k], self.a0[k], self.v0[k], self.s0[k]
        return (s + v * tau + a * tau**2 / 2 + j * tau**3 / 6, v + a * tau + j * tau**2 / 2, a + j * tau)


def scurve(length_m: float, v_max_mps: float, a_max_mps2: float, j_max_mps3: float) -> SCurve:
    """Time-optimal rest-to-rest profile under |sd| <= v_max, |sdd| <= a_max, |jerk| <= j_max.

    Acceleration part: jerk +j for Tj, 0 for Ta - 2 Tj, -j for Tj; then cruise Tv; then the
    mirror image. Its distance is v_peak Ta, so a short segment lowers v_peak to fit.
    """
    v, a, j, L = float(v_max_mps), float(a_max_mps2), float(j_max_mps3), float(length_m)
    if not (v > 0 and a > 0 and j > 0):
        raise CapmapError(f"S-curve limits v_max = {v!r}, a_max = {a!r}, j_max = {j!r} must all be > 0")
    if L < 0:
        raise CapmapError(f"segment length {L!r} m must be >= 0")

    def accel_time(vp):  # (Ta, Tj) to reach vp from rest
        if vp * j >= a * a:
            return vp / a + a / j, a / j
        tj = math.sqrt(vp / j)
        return 2 * tj, tj

    vp = v
    Ta, Tj = accel_time(vp)
    if vp * Ta > L:  # no cruise: the largest vp with vp * Ta(vp) = L
        vp = a / 2 * (-a / j + math.sqrt(a * a / (j * j) + 4 * L / a))
        if vp * j < a * a:
            vp = (L * math.sqrt(j) / 2) ** (2 / 3)
        Ta, Tj = accel_time(vp)
    Tv = max(L / vp - Ta, 0.0) if vp > 0 else 0.0
    d = np.array([Tj, Ta - 2 * Tj, Tj, Tv, Tj, Ta - 2 * Tj, Tj])
    jk = np.array([j, 0, -j, 0, -j, 0, j])
    keep = d > 1e-15
    d, jk = d[keep], jk[keep]
    t0, s0, v0, a0 = (np.zeros(len(d)) for _ in range(4))
    for k in range(1, len(d)):
        T, jj = d[k - 1], jk[k - 1]
        t0[k] = t0[k - 1] + T
        s0[k] = s0[k - 1] + v0[k - 1] * T + a0[k - 1] * T**2 / 2 + jj * T**3 / 6
        v0[k] = v0[k - 1] + a0[k - 1] * T + jj * T**2 / 2
        a0[k] = a0[k - 1] + jj * T
    return SCurve(L, d, jk, t0, s0, v0, a0, vp, min(a, j * Tj))
