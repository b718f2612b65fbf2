"""Joint torques along a fixed path, tau = a(s) sdd + b(s) sd^2 + c(s) + friction, and the speed ceiling.

With q(s) the joint path, q' and q'' its derivatives by arc length s (:mod:`.path`):

    a = M(q) q',   b = M(q) q'' + C(q, q') q',   c = g(q)

with M including the drives' reflected rotor inertia (Pinocchio's armature: :mod:`capmap.core.drives`;
the payload is a point mass at the end effector, appended to the last body), and the drives' friction

    F_v q'(s) sd + F_c sign(q'(s) sd)

The follower never reverses (sd >= 0), so while it moves the Coulomb term's sign is sign(q'(s)) and
the whole friction is affine in sd: known at each state. At rest (sd = 0) it starts forward
(sdd > 0): friction then opposes that motion, sign(q'(s)) again (breakaway); held at rest (sdd = 0)
static friction is a band (:func:`capmap.core.drives.friction_torque`). At a state (s, sd) each
torque limit |tau_i| <= T_i is then a limit on outputs affine in the path acceleration sdd
(y0 = b sd^2 + c + friction(s, sd), slope a: :class:`capmap.core.limits.AffineLimits`), and their
intersection is the interval of admissible sdd (the decomposition of time-optimal path
parametrisation: Bobrow et al. 1985, Shin & McKay 1985, Pfeiffer & Johanni 1987). Friction always
opposes the motion, so it helps braking: the braking curve counts on it (the same model as the
follower's; its 90 % margin is what covers friction lower than stated).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from capmap.core.drives import motor_torque, path_motion
from capmap.core.dynamics import payload_models
from capmap.core.limits import AffineLimits
from capmap.core.reduction import LockedArm
from capmap.errors import LimitInfeasible
from capmap.following.path import JointPath

__all__ = ["PathDynamics", "path_dynamics", "PreparedPath", "prepare", "forward_friction", "Shortfall"]


@dataclass(frozen=True)
class Shortfall:
    """Where a path cannot be held or started under its torque limits: the output (e.g. ``tau_j1_nm``),
    the torque it needs and its limit (N m), the path coordinate (m) and what was asked (holding at
    rest, or starting forward from rest against friction)."""

    output: str
    needed_nm: float
    limit_nm: float
    s_m: float
    what: str


def forward_friction(dq: np.ndarray, sd, coulomb_nm: np.ndarray, viscous_nms: np.ndarray) -> np.ndarray:
    """Friction torques (..., n) N m moving forward along the path (or starting to): viscous q' sd +
    coulomb sign(q'), for q' = dq (..., n) rad/m at path speed sd >= 0 m/s (a float, or (..., 1))."""
    return viscous_nms * dq * sd + coulomb_nm * np.sign(dq)


@dataclass(frozen=True)
class PathDynamics:
    """tau = a sdd + b sd^2 + c + viscous dq sd + coulomb sign(dq sd) on a uniform s grid: s (G,) m;
    a (G, n) N m s^2/m; b (G, n) N m s^2/m^2; c (G, n) N m; for the n limited (active) joints; the
    drives' friction: dq (G, n) rad/m the joint path's q'(s), coulomb_nm (n,) N m, viscous_nms (n,)
    N m s/rad (None: no friction)."""

    s: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    dq: np.ndarray | None = None
    coulomb_nm: np.ndarray | None = None
    viscous_nms: np.ndarray | None = None

    @property
    def has_friction(self) -> bool:
        return self.dq is not None and bool(np.any(self.coulomb_nm > 0) or np.any(self.viscous_nms > 0))

    def friction(self, sd: np.ndarray) -> np.ndarray:
        """Friction torques (G, n) N m on the grid moving forward at path speeds sd (G,) >= 0 m/s (at 0: starting
        forward): viscous q' sd + coulomb sign(q')."""
        if not self.has_friction:
            return np.zeros_like(self.c)
        return forward_friction(self.dq, np.asarray(sd, dtype=float)[:, None], self.coulomb_nm, self.viscous_nms)

    def torques(self, s: np.ndarray, sd: np.ndarray, sdd: np.ndarray) -> np.ndarray:
        """Torques (N, n) at states (N,) by linear interpolation of the tables (friction at rest and not
        accelerating: the static band, :func:`capmap.core.drives.friction_torque`)."""
        a, b, c = (np.stack([np.interp(s, self.s, t[:, i]) for i in range(t.shape[1])], axis=1)
                   for t in (self.a, self.b, self.c))
        tau = a * sdd[:, None] + b * (sd**2)[:, None] + c
        if not self.has_friction:
            return tau
        dq = np.stack([np.interp(s, self.s, self.dq[:, i]) for i in range(self.dq.shape[1])], axis=1)
        return motor_torque(tau, dq * sd[:, None], path_motion(dq, sd, sdd), self.coulomb_nm, self.viscous_nms)

    def sdd_interval(self, limits: AffineLimits, sd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Admissible path accelerations [lo, hi] (each (G,)) at path speeds sd (G,) >= 0 on the grid, moving
        forward; lo > hi where none is."""
        sd = np.asarray(sd, dtype=float)
        return limits.interval(self.b * (sd**2)[:, None] + self.c + self.friction(sd), self.a)


def path_dynamics(arm: LockedArm, path: JointPath, payload_kg: float) -> PathDynamics:
    """Exact a, b, c at the path's grid points (three RNEA calls each, payload and the drives' armature
    included) and the drives' friction of the active joints (the robot's ``coulomb_nm``, ``viscous_nms``)."""
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
    robot = arm.robot
    if not robot.has_friction:
        return PathDynamics(path.s.copy(), a, b, c)
    return PathDynamics(path.s.copy(), a, b, c, path.dq.copy(), robot.coulomb_nm[act], robot.viscous_nms[act])


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
    Raises LimitInfeasible when the path cannot be held even at rest (static torques above limits), or
    with friction cannot be crept along forward (gravity and friction against the motion above them).
    """
    G = len(pdyn.s)
    lo0, hi0 = pdyn.sdd_interval(limits, np.zeros(G))
    if (lo0 > hi0).any() or (lo0 > 0).any() or (hi0 < 0).any():
        k = int(np.argmax((lo0 > hi0) | (lo0 > 0) | (hi0 < 0)))
        creep = pdyn.c[k] + pdyn.friction(np.zeros(G))[k]
        j = int(np.argmax(np.abs(creep) / limits.limit))
        hold = abs(pdyn.c[k, j]) > limits.limit[j]
        what = "holding the path at rest" if hold or not pdyn.has_friction else "starting forward from rest (friction)"
        needed = float(abs(pdyn.c[k, j] if hold else creep[j]))
        exc = LimitInfeasible(f"{limits.names[j]}: {what} at s = {pdyn.s[k]:.4f} m needs "
                              f"{needed:.2f} N m, above its limit {limits.limit[j]:g} N m")
        exc.shortfall = Shortfall(limits.names[j], needed, float(limits.limit[j]), float(pdyn.s[k]), what)
        raise exc
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
    y0 = pdyn.b[i] * (sd * sd) + pdyn.c[i]
    if pdyn.has_friction:
        y0 = y0 + forward_friction(pdyn.dq[i], sd, pdyn.coulomb_nm, pdyn.viscous_nms)
    return limits.interval_one(y0.tolist(), pdyn.a[i].tolist())
