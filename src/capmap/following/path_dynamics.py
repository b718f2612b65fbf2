"""Joint torques along a fixed path, tau = a(s) sdd + b(s) sd^2 + c(s), and the speed ceiling.

With q(s) the joint path, q' and q'' its derivatives by arc length s (:mod:`.path`):

    a = M(q) q',   b = M(q) q'' + C(q, q') q',   c = g(q)

(the payload is a point mass at the end effector, appended to the last body). At a state
(s, sd) each torque limit |tau_i| <= T_i is then a limit on outputs affine in the path
acceleration sdd (y0 = b sd^2 + c, slope a: :class:`capmap.core.limits.AffineLimits`), and
their intersection is the interval of admissible sdd (the decomposition of time-optimal
path parametrisation: Bobrow et al. 1985, Shin & McKay 1985, Pfeiffer & Johanni 1987).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from capmap.core.dynamics import payload_models
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm
from capmap.errors import LimitInfeasible
from capmap.following.path import JointPath

__all__ = ["PathDynamics", "path_dynamics", "PreparedPath", "prepare"]


@dataclass(frozen=True)
class PathDynamics:
    """tau = a sdd + b sd^2 + c on a uniform s grid: s (G,) m; a (G, n) N m s^2/m; b (G, n)
    N m s^2/m^2; c (G, n) N m; for the n limited (active) joints."""

    s: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray

    def torques(self, s: np.ndarray, sd: np.ndarray, sdd: np.ndarray) -> np.ndarray:
        """Torques (N, n) at states (N,) by linear interpolation of the tables."""
        a, b, c = (np.stack([np.interp(s, self.s, t[:, i]) for i in range(t.shape[1])], axis=1)
                   for t in (self.a, self.b, self.c))
        return a * sdd[:, None] + b * (sd**2)[:, None] + c

    def sdd_interval(self, limits: AffineLimits, sd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Admissible path accelerations [lo, hi] (each (G,)) at path speeds sd (G,) on the grid;
        lo > hi where none is."""
        return limits.interval(self.b * (np.asarray(sd, dtype=float) ** 2)[:, None] + self.c, self.a)


def path_dynamics(arm: LockedArm, path: JointPath, payload_kg: float) -> PathDynamics:
    """Exact a, b, c at the path's grid points (three RNEA calls each, payload included)."""
    model, model_ng = payload_models(arm, payload_kg)
    data, data_ng = model.createData(), model_ng.createData()
    zero = np.zeros(model.nv)
    act = arm.active
    a, b, c = (np.empty_like(path.q) for _ in range(3))
    for i in range(len(path.s)):
        q, dq, ddq = arm.full_q(path.q[i]), arm.full_v(path.dq[i]), arm.full_v(path.ddq[i])
        a[i] = pin.rnea(model_ng, data_ng, q, zero, dq)[act]
        b[i] = pin.rnea(model_ng, data_ng, q, dq, ddq)[act]
        c[i] = pin.rnea(model, data, q, zero, zero)[act]
    return PathDynamics(path.s.copy(), a, b, c)


@dataclass(frozen=True)
class PreparedPath:
    """A path ready to follow: its torque model ``dynamics``, the torque ``limits`` and the speed
    ceiling v_limit (G,) m/s on the same grid = min(v_max, the velocity limit curve, the
    braking curve that still stops at the end under the torque limits)."""

    dynamics: PathDynamics
    limits: AffineLimits
    v_limit: np.ndarray
    v_max_mps: float
    brake_end_mps2: float  # the braking curve's deceleration at the end


def prepare(pdyn: PathDynamics, limits: AffineLimits, v_max_mps: float, brake_margin: float = 0.9) -> PreparedPath:
    """Speed ceiling along the path (done once per path, before following).

    Velocity limit curve: the largest sd <= v_max with an admissible acceleration (bisection).
    Braking curve: integrated backwards from rest at the end with ``brake_margin`` x the
    largest admissible deceleration, so a follower under it can always stop in time.
    Raises LimitInfeasible when the path cannot be held even at rest (static torques above limits).
    """
    G = len(pdyn.s)
    lo0, hi0 = pdyn.sdd_interval(limits, np.zeros(G))
    if (lo0 > hi0).any() or (lo0 > 0).any() or (hi0 < 0).any():
        k = int(np.argmax((lo0 > hi0) | (lo0 > 0) | (hi0 < 0)))
        over = np.abs(pdyn.c[k]) / limits.limit
        j = int(np.argmax(over))
        raise LimitInfeasible(f"{limits.names[j]}: holding the path at rest at s = {pdyn.s[k]:.4f} m needs "
                              f"{abs(pdyn.c[k, j]):.2f} N m, above its limit {limits.limit[j]:g} N m")
    # velocity limit curve by bisection on sd in [0, v_max]
    lo_v, hi_v = np.zeros(G), np.full(G, float(v_max_mps))
    lo_m, hi_m = pdyn.sdd_interval(limits, hi_v)
    ok_top = lo_m <= hi_m
    for _ in range(60):
        mid = 0.5 * (lo_v + hi_v)
        lo_m, hi_m = pdyn.sdd_interval(limits, mid)
        feas = lo_m <= hi_m
        lo_v = np.where(feas, mid, lo_v)
        hi_v = np.where(feas, hi_v, mid)
    mvc = np.where(ok_top, float(v_max_mps), lo_v)
    # braking curve: (sd^2)' = 2 sdd with sdd = margin * lo, backwards from (L, 0)
    brake = np.empty(G)
    brake[-1] = 0.0
    for i in range(G - 2, -1, -1):
        v = brake[i + 1]
        lo, hi = _interval_at(pdyn, limits, i + 1, v)
        dec = brake_margin * min(lo, 0.0) if lo <= hi else 0.0
        brake[i] = min(math.sqrt(v * v - 2 * dec * (pdyn.s[i + 1] - pdyn.s[i])), mvc[i])
    lo_end, _ = _interval_at(pdyn, limits, G - 1, 0.0)
    return PreparedPath(pdyn, limits, np.minimum(mvc, brake), float(v_max_mps), brake_margin * abs(min(lo_end, 0.0)))


def _interval_at(pdyn: PathDynamics, limits: AffineLimits, i: int, sd: float) -> tuple[float, float]:
    """Admissible [lo, hi] at grid point i and path speed sd (Python floats)."""
    return limits.interval_one((pdyn.b[i] * (sd * sd) + pdyn.c[i]).tolist(), pdyn.a[i].tolist())
