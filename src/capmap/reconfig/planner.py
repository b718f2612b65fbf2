"""Reconfiguration of one boom: the long side follows the motion law, singularities avoided in
its null space (or the plain pseudo-inverse as a baseline).

The moving end's twist xdot(t) comes from the law (:mod:`.law`, :meth:`.LoopSplit.twist`);
the long side's joint rates are

    qdot = J^+ xdot + (I - J^+ J) k,   k = kappa grad m

(``pinv``: k = 0). With alpha = grad m . J^+ xdot and beta = |N grad m|^2,
dm/dt = grad m . qdot = alpha + kappa beta, so kappa = kappa0 w + max(0, -alpha) / beta
keeps dm/dt >= kappa0 w beta >= 0 at every instant (w: the law's speed over its peak,
so the kappa0 part fades at both ends and the motion is rest to rest; the other part
scales with the law's speed).

Limits: joint rates are held at every step by time scaling: all rates but the kappa0 part
scale with the law's speed, so the step uses the largest fraction sigma <= 1 of the law's
speed that keeps |qdot_i| <= the limit (the kappa0 part is shrunk first if it alone would
exceed half a limit); below ``min_time_scale`` the run stops and says why (e.g. m at a
maximum over the self-motion while the law pushes it down: beta -> 0, kappa -> inf). A
joint that would leave its range stops the run, reported likewise: nothing is exceeded
silently.

Integration: classical RK4 in time on (q, law phase u) with sigma fixed over a step, then
one Newton step of the long side onto the law's pose (closure correction).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from capmap.core.kinematics import pose_error
from capmap.core.limits import AffineLimits
from capmap.errors import CapmapError
from capmap.reconfig.law import QuinticLaw
from capmap.reconfig.loop import LoopSplit
from capmap.reconfig.redundancy import evaluate

__all__ = ["METHODS", "PlannerSettings", "Reconfiguration", "reconfigure"]

METHODS = ("nullspace", "pinv")
_TINY_BETA = 1e-300


@dataclass(frozen=True)
class PlannerSettings:
    """method: 'nullspace' | 'pinv'; dt_s: step; kappa0: the null-space gain at the law's peak
    speed; rate_limit (n,) rad/s and q_lower, q_upper (n,) rad of the moving side's joints;
    min_time_scale: the slowest fraction of the law's speed allowed before stopping."""

    method: str
    dt_s: float
    kappa0: float
    rate_limit: np.ndarray
    q_lower: np.ndarray
    q_upper: np.ndarray
    min_time_scale: float = 0.05

    def __post_init__(self):
        if self.method not in METHODS:
            raise CapmapError(f"method {self.method!r} is not one of {METHODS}")
        if not (np.isfinite(self.dt_s) and self.dt_s > 0):
            raise CapmapError(f"dt_s = {self.dt_s!r} must be finite and > 0")
        if not (np.isfinite(self.kappa0) and self.kappa0 >= 0):
            raise CapmapError(f"kappa0 = {self.kappa0!r} must be finite and >= 0")
        if not 0 < self.min_time_scale <= 1:
            raise CapmapError(f"min_time_scale = {self.min_time_scale!r} must be in (0, 1]")


@dataclass(frozen=True)
class Reconfiguration:
    """Per recorded step k (K rows): t_s, law phase u, q and qd (K, n) rad and rad/s of the
    moving side, theta (rad) and d (m) of the unlocked joint, m, dm_dt (1/s), the smallest
    singular value of J, the applied kappa, the time scale sigma, and the pose error of the
    moving end against the law (K, 6). status: 'completed' | 'stopped'; message: why it stopped."""

    t_s: np.ndarray
    u: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    theta: np.ndarray
    d: np.ndarray
    m: np.ndarray
    dm_dt: np.ndarray
    min_singular_value: np.ndarray
    kappa: np.ndarray
    time_scale: np.ndarray
    task_error: np.ndarray
    status: str
    message: str

    @property
    def steps(self) -> int:
        return len(self.t_s) - 1


class _Field:
    """qdot(q, u) = sigma a(q, u) + b(q, u): the part that scales with the law's speed and the
    kappa0 part (see the module docstring)."""

    def __init__(self, split: LoopSplit, fixed_end: np.ndarray, law: QuinticLaw, settings: PlannerSettings):
        self.split, self.fixed_end, self.law, self.st = split, fixed_end, law, settings
        self.limits = AffineLimits(settings.rate_limit, split.moving.joints)

    def parts(self, q: np.ndarray, u: float) -> tuple[np.ndarray, np.ndarray, float, "object"]:
        """(a, b, kappa at sigma = 1, evaluation) at a state."""
        ev = evaluate(self.split.moving.chain, q)
        _, _, dth, dd = self.law.at(u)
        xdot = self.split.twist(self.fixed_end, np.atleast_1d(dth / self.law.duration_s),
                                np.atleast_1d(dd / self.law.duration_s))[0]
        p = ev.pinv @ xdot
        if self.st.method == "pinv":
            return p, np.zeros_like(p), 0.0, ev
        alpha, beta = float(ev.grad @ p), float(ev.null_grad @ ev.null_grad)
        k_req = max(0.0, -alpha) / beta if beta > _TINY_BETA else (0.0 if alpha >= 0 else math.inf)
        b = self.st.kappa0 * float(self.law.speed_weight(u)) * ev.null_grad
        return p + k_req * ev.null_grad, b, k_req, ev

    def time_scale(self, a: np.ndarray, b: np.ndarray) -> tuple[float, np.ndarray]:
        """The largest sigma <= 1 with |sigma a + b| <= the rate limits, and b (shrunk if needed)."""
        ratio = self.limits.ratio(b).max() if len(b) else 0.0
        if ratio > 0.5:
            b = b * (0.5 / ratio)
        if not np.all(np.isfinite(a)):
            return 0.0, b
        lo, hi = self.limits.interval_one(b.tolist(), a.tolist())
        return (min(1.0, hi) if lo <= min(1.0, hi) and hi >= 0 else 0.0), b

    def rates(self, q: np.ndarray, u: float, sigma: float, shrink: float) -> np.ndarray:
        a, b, _, _ = self.parts(q, u)
        return sigma * a + shrink * b


def reconfigure(split: LoopSplit, fixed_end: np.ndarray, q0: np.ndarray, law: QuinticLaw,
                settings: PlannerSettings) -> Reconfiguration:
    """Integrate the reconfiguration from the long side's joint angles q0 (n,) rad (closing the
    loop at the law's start) with the moving end following ``law`` relative to ``fixed_end``
    (4, 4); see the module docstring."""
    field = _Field(split, fixed_end, law, settings)
    st = settings
    T_law = law.duration_s

    def target(u):
        theta, d, _, _ = law.at(u)
        return split.target(fixed_end, theta, d)[0]

    rows = []
    t, u, q = 0.0, 0.0, np.asarray(q0, dtype=float).copy()
    status, message = "completed", ""
    while True:
        a, b, k_req, ev = field.parts(q, u)
        sigma, b_used = field.time_scale(a, b)
        shrink = float(np.linalg.norm(b_used) / np.linalg.norm(b)) if np.linalg.norm(b) > 0 else 1.0
        qd = sigma * a + b_used
        theta, d, _, _ = law.at(u)
        kappa = sigma * k_req + (st.kappa0 * float(law.speed_weight(u)) * shrink if st.method == "nullspace" else 0)
        rows.append((t, u, q.copy(), qd, float(theta), float(d), ev.m, float(ev.grad @ qd), ev.singular_values.min(),
                     kappa, sigma, pose_error(ev.pose, target(u))))
        if u >= 1.0:
            break
        if sigma < st.min_time_scale:
            status = "stopped"
            message = (f"at t = {t:.2f} s the joint-rate limits allow only {sigma:.1%} of the law's speed "
                       f"(below min_time_scale {st.min_time_scale:g}): "
                       + ("m is at a maximum over the self-motion while the law pushes it down"
                          if st.method == "nullspace" and (not math.isfinite(k_req) or k_req > 1e6)
                          else "the task needs joint rates beyond the limits (near a singularity)"))
            break
        dt = min(st.dt_s, (1.0 - u) * T_law / sigma)
        du = sigma * dt / T_law
        k1 = qd
        k2 = field.rates(q + 0.5 * dt * k1, u + 0.5 * du, sigma, shrink)
        k3 = field.rates(q + 0.5 * dt * k2, u + 0.5 * du, sigma, shrink)
        k4 = field.rates(q + dt * k3, u + du, sigma, shrink)
        q_next = q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        u_next = 1.0 if 1.0 - (u + du) < 1e-12 else u + du
        ev = evaluate(split.moving.chain, q_next)  # closure correction: one Newton step onto the law's pose
        q_next = q_next + ev.pinv @ pose_error(ev.pose, target(u_next))
        out = (q_next < st.q_lower) | (q_next > st.q_upper)
        if out.any():  # the run ends at the last state within the ranges
            j = int(np.argmax(out))
            status = "stopped"
            message = (f"at t = {t + dt:.2f} s joint {split.moving.joints[j]} would reach "
                       f"{np.rad2deg(q_next[j]):.2f} deg, outside its range [{np.rad2deg(st.q_lower[j]):g}, "
                       f"{np.rad2deg(st.q_upper[j]):g}] deg")
            break
        t, u, q = t + dt, u_next, q_next
    cols = list(zip(*rows))
    arr = [np.array(c) for c in cols]
    return Reconfiguration(t_s=arr[0], u=arr[1], q=arr[2], qd=arr[3], theta=arr[4], d=arr[5], m=arr[6],
                           dm_dt=arr[7], min_singular_value=arr[8], kappa=arr[9], time_scale=arr[10],
                           task_error=arr[11], status=status, message=message)
