"""Torque-limited following of a fixed Cartesian path, online, one control period at a time.

The end effector must stay on a straight segment (fixed orientation) while a jerk-limited
S-curve commands the path coordinate s (arc length, m). Along the path the joint torques
are exactly

    tau(s, sd, sdd) = a(s) sdd + b(s) sd^2 + c(s),
    a = M(q) q',   b = M(q) q'' + C(q, q') q',   c = g(q)

(q', q'' derivatives of the joint path by s; the payload is a point mass at the end
effector, added to the last body), so at a state (s, sd) each torque limit
|tau_i| <= T_i bounds sdd to an interval, and their intersection [lo, hi] is the set of
admissible path accelerations (the decomposition of time-optimal path parametrisation:
Bobrow et al. 1985, Shin & McKay 1985, Pfeiffer & Johanni 1987).

Each control period dt the follower

1. while in step with the command and the command's acceleration is admissible at the
   current state (inside [lo, hi], next speed under the ceiling of step 3), takes the
   command's next state: with no limit active it reproduces the command exactly;
2. otherwise asks for u_des = u_cmd + k_v (sd_cmd - sd) + k_p (s_cmd - s), u_cmd the
   command's mean acceleration over the period, k_p = w^2, k_v = 2 w (critically damped
   catch-up, w = 2 pi f); if the command has come to rest at the end before the
   follower, the follower approaches the end with at most the command's peak acceleration
   and half its torque headroom (accelerate, then brake on sqrt(2 a d)): no exponential
   tail and no torque pulse at the limit;
3. keeps the next path speed in [0, ceiling], ceiling = min(v_max, the velocity limit
   curve, the braking curve that can still stop at the end using 90 % of the braking
   capability the torque limits leave), all precomputed along the path (:func:`prepare`);
4. clips to [lo, hi] from the torque limits at its current (s, sd): the path stays
   exact, only the timing yields; when the limit releases, step 2 catches up, and within
   1 nm and 1 nm/s of the command it rejoins it (step 1);
5. integrates s, sd with that constant acceleration over the period.

The path preparation (:func:`line_path`, :func:`path_dynamics`) is done once per path on
a fine s grid; per period the follower interpolates a, b, c linearly, so its work is a
few dozen floating-point operations (see ``tests/benchmarks/bench_follow.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from capmap import ik
from capmap.dynamics import ArmDynamics
from capmap.errors import CapmapError
from capmap.locking import LockedArm
from capmap.trajectory import SCurve
from capmap.verification import track

END_TOL_M = 1e-6  # the follower has arrived within max(this, beta dt^2) of the end, at (almost) rest
END_TOL_MPS = 1e-6
SYNC_TOL_M = 1e-9  # a follower this close to the command (and its speed) rejoins it exactly
SYNC_TOL_MPS = 1e-9


@dataclass(frozen=True)
class JointPath:
    """A straight end-effector segment as a joint path on an s grid (G points).

    s (G,) m from the segment start; q, dq, ddq (G, n_active): joint angles rad and their
    first and second derivatives by s (rad/m, rad/m^2); p (G, 3) m positions."""

    s: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    p: np.ndarray

    @property
    def length_m(self) -> float:
        return float(self.s[-1])


def line_path(arm: LockedArm, p0: np.ndarray, p1: np.ndarray, rotation: np.ndarray, q_start: np.ndarray,
              s: np.ndarray | None = None, ds_m: float = 1e-3) -> JointPath:
    """Joint path of the segment p0 -> p1 (3,) m at a fixed rotation (3, 3), on the IK branch
    continuous from q_start (n_active,) rad; at the given arc lengths ``s`` (non-decreasing, m)
    or on a uniform grid no coarser than ds_m. Derivatives are exact: q' = J^-1 [u; 0],
    q'' = -J^-1 Jdot(q, q') q' (s is arc length, so the path has no Cartesian curvature)."""
    p0, p1 = np.asarray(p0, dtype=float), np.asarray(p1, dtype=float)
    L = float(np.linalg.norm(p1 - p0))
    if L == 0:
        raise CapmapError("a followed segment needs distinct end points")
    u = (p1 - p0) / L
    if s is None:
        s = np.linspace(0.0, L, max(2, math.ceil(L / ds_m) + 1))
    s = np.asarray(s, dtype=float)
    p = p0 + s[:, None] * u
    tr = track(arm, p, rotation, q_start)
    if not tr.ok:
        raise CapmapError(f"the segment {p0.round(4).tolist()} -> {p1.round(4).tolist()} cannot be followed: "
                          f"{tr.failure} at s = {s[tr.failed_at]:.4f} m")
    dq, ddq = _derivatives(arm, tr.q, u)
    return JointPath(s=s, q=tr.q, dq=dq, ddq=ddq, p=p)


def _derivatives(arm: LockedArm, q: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """q' = J^-1 [u; 0] and q'' = -J^-1 Jdot(q, q') q' along a straight line of direction u."""
    dyn = ArmDynamics(arm)
    twist = np.concatenate([u, np.zeros(3)])
    dq, ddq = np.empty_like(q), np.empty_like(q)
    for i, qa in enumerate(q):
        qf = arm.full_q(qa)
        J = dyn.ee_jacobian(qf)
        dq[i] = np.linalg.solve(J, twist)
        ddq[i] = np.linalg.solve(J, -dyn.drift(qf, arm.full_v(dq[i])))
    return dq, ddq


def interpolate_q(table: JointPath, s: np.ndarray) -> np.ndarray:
    """Joint angles (N, n) at arc lengths s (N,) by linear interpolation of the table (what
    the follower sends each period, with no IK at run time)."""
    return np.stack([np.interp(s, table.s, table.q[:, j]) for j in range(table.q.shape[1])], axis=1)


def path_at(arm: LockedArm, table: JointPath, s: np.ndarray, rotation: np.ndarray) -> JointPath:
    """The exact joint path at arc lengths s (N,): the table's interpolation polished by three
    batched Newton steps on the pose (residual ~1e-12), exact derivatives."""
    u = (table.p[-1] - table.p[0]) / table.length_m
    p = table.p[0] + np.asarray(s, dtype=float)[:, None] * u
    T = np.zeros((len(p), 4, 4))
    T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = rotation, p, 1.0
    q = ik.newton(arm.chain, interpolate_q(table, s), T, iters=3)
    dq, ddq = _derivatives(arm, q, u)
    return JointPath(s=np.asarray(s, dtype=float), q=q, dq=dq, ddq=ddq, p=p)


def payload_models(arm: LockedArm, payload_kg: float) -> tuple[pin.Model, pin.Model]:
    """Copies of the robot's models (with and without gravity) carrying a point mass at the
    end-effector origin, appended to the body that holds the end-effector frame."""
    out = []
    for base in (arm.robot.model, arm.robot.model_no_gravity):
        model = base.copy()
        frame = model.frames[arm.robot.ee_frame_id]
        model.appendBodyToJoint(frame.parentJoint, pin.Inertia(float(payload_kg), np.zeros(3), np.zeros((3, 3))),
                                frame.placement)
        out.append(model)
    return out[0], out[1]


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


def sdd_bounds_grid(a: np.ndarray, b: np.ndarray, c: np.ndarray, sd: np.ndarray,
                    tau_max: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Admissible path accelerations [lo, hi] (each (G,)) at path speeds sd (G,) for the
    torque model a, b, c (G, n) and limits |tau| <= tau_max (n,); lo > hi where none is."""
    r = b * (np.asarray(sd, dtype=float) ** 2)[:, None] + c
    with np.errstate(divide="ignore", invalid="ignore"):
        up = np.where(a > 0, (tau_max - r) / a, np.where(a < 0, (-tau_max - r) / a, np.inf))
        dn = np.where(a > 0, (-tau_max - r) / a, np.where(a < 0, (tau_max - r) / a, -np.inf))
    lo, hi = dn.max(axis=1), up.min(axis=1)
    bad = ((a == 0) & (np.abs(r) > tau_max)).any(axis=1)
    lo[bad], hi[bad] = np.inf, -np.inf
    return lo, hi


def sdd_bounds(a: np.ndarray, b: np.ndarray, c: np.ndarray, sd: float, tau_max: np.ndarray) -> tuple[float, float]:
    """Admissible path accelerations [lo, hi] at one state: a, b, c, tau_max (n,), path speed sd.
    lo > hi when no acceleration is admissible (the state is beyond the velocity limit curve)."""
    r = b * (sd * sd) + c
    lo, hi = -np.inf, np.inf
    for ai, ri, ti in zip(a.tolist(), r.tolist(), tau_max.tolist()):
        if ai > 0:
            hi = min(hi, (ti - ri) / ai)
            lo = max(lo, (-ti - ri) / ai)
        elif ai < 0:
            hi = min(hi, (-ti - ri) / ai)
            lo = max(lo, (ti - ri) / ai)
        elif abs(ri) > ti:
            return np.inf, -np.inf
    return lo, hi


@dataclass(frozen=True)
class PreparedPath:
    """A path ready to follow: its torque model ``pd``, the torque limits tau_max (n,) N m and
    the speed ceiling v_limit (G,) m/s on the same grid = min(v_max, the velocity limit
    curve, the braking curve that still stops at the end under the torque limits)."""

    pd: PathDynamics
    tau_max: np.ndarray
    v_limit: np.ndarray
    v_max_mps: float
    brake_end_mps2: float  # the braking curve's deceleration at the end


def prepare(pd: PathDynamics, tau_max: np.ndarray, v_max_mps: float, brake_margin: float = 0.9) -> PreparedPath:
    """Speed ceiling along the path (done once per path, before following).

    Velocity limit curve: the largest sd <= v_max with an admissible acceleration (bisection).
    Braking curve: integrated backwards from rest at the end with ``brake_margin`` x the
    largest admissible deceleration, so a follower under it can always stop in time.
    Raises CapmapError when the path cannot be held even at rest (static torques above limits).
    """
    tau_max = np.asarray(tau_max, dtype=float)
    G = len(pd.s)
    lo0, hi0 = sdd_bounds_grid(pd.a, pd.b, pd.c, np.zeros(G), tau_max)
    if (lo0 > hi0).any() or (lo0 > 0).any() or (hi0 < 0).any():
        k = int(np.argmax((lo0 > hi0) | (lo0 > 0) | (hi0 < 0)))
        over = np.abs(pd.c[k]) / tau_max
        j = int(np.argmax(over))
        raise CapmapError(f"joint column {j}: holding the path at rest at s = {pd.s[k]:.4f} m needs "
                          f"{abs(pd.c[k, j]):.2f} N m, above its limit {tau_max[j]:g} N m")
    # velocity limit curve by bisection on sd in [0, v_max]
    lo_v, hi_v = np.zeros(G), np.full(G, float(v_max_mps))
    lo_m, hi_m = sdd_bounds_grid(pd.a, pd.b, pd.c, hi_v, tau_max)
    ok_top = lo_m <= hi_m
    for _ in range(60):
        mid = 0.5 * (lo_v + hi_v)
        lo_m, hi_m = sdd_bounds_grid(pd.a, pd.b, pd.c, mid, tau_max)
        feas = lo_m <= hi_m
        lo_v = np.where(feas, mid, lo_v)
        hi_v = np.where(feas, hi_v, mid)
    mvc = np.where(ok_top, float(v_max_mps), lo_v)
    # braking curve: (sd^2)' = 2 sdd with sdd = margin * lo, backwards from (L, 0)
    brake = np.empty(G)
    brake[-1] = 0.0
    for i in range(G - 2, -1, -1):
        v = brake[i + 1]
        lo, hi = sdd_bounds(pd.a[i + 1], pd.b[i + 1], pd.c[i + 1], v, tau_max)
        dec = brake_margin * min(lo, 0.0) if lo <= hi else 0.0
        brake[i] = min(math.sqrt(v * v - 2 * dec * (pd.s[i + 1] - pd.s[i])), mvc[i])
    lo_end, _ = sdd_bounds(pd.a[-1], pd.b[-1], pd.c[-1], 0.0, tau_max)
    return PreparedPath(pd, tau_max, np.minimum(mvc, brake), float(v_max_mps), brake_margin * abs(min(lo_end, 0.0)))


@dataclass(frozen=True)
class FollowResult:
    """Per control period k (K rows): t_s; the command s_cmd, sd_cmd, sdd_cmd (at t_k); the
    follower's s, sd at t_k and the acceleration sdd it applies over [t_k, t_k + dt];
    limited: the torque limits clipped the requested acceleration (a speed ceiling alone
    does not count); infeasible: no admissible acceleration existed (the midpoint of the
    crossed bounds was applied)."""

    t_s: np.ndarray
    s_cmd: np.ndarray
    sd_cmd: np.ndarray
    sdd_cmd: np.ndarray
    s: np.ndarray
    sd: np.ndarray
    sdd: np.ndarray
    limited: np.ndarray
    infeasible: np.ndarray

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1])


def follow(prep: PreparedPath, command: SCurve, period_s: float, catch_up_hz: float,
           max_time_factor: float = 20.0) -> FollowResult:
    """Run the follower from rest at s = 0 until it rests at the end of the path (see the module
    docstring). Raises CapmapError if it has not arrived within max_time_factor x the
    command's duration."""
    dt = float(period_s)
    if not dt > 0:
        raise CapmapError(f"follow.period_s = {period_s!r} must be > 0")
    if not catch_up_hz > 0:
        raise CapmapError(f"follow catch_up_hz = {catch_up_hz!r} must be > 0")
    pd, tau_max, v_max = prep.pd, prep.tau_max, prep.v_max_mps
    L = command.length_m
    if abs(L - pd.s[-1]) > 1e-9 * max(1.0, L):
        raise CapmapError(f"command length {L} m differs from the path length {pd.s[-1]} m")
    w = 2 * math.pi * catch_up_hz
    kp, kv = w * w, 2 * w
    n_max = math.ceil(max_time_factor * command.duration_s / dt) + 2
    n_cmd = math.ceil(command.duration_s / dt) + 2
    sc_all, sdc_all, sddc_all = (x.tolist() for x in command.evaluate(np.arange(n_cmd + 1) * dt))
    grid_a, grid_b, grid_c, h = pd.a, pd.b, pd.c, float(pd.s[1] - pd.s[0])
    vlim2 = (prep.v_limit**2).tolist()  # interpolate squared speeds: exact on a constant-deceleration braking curve
    G = len(pd.s) - 1
    # a discrete follower braking at beta can stop only within ~beta dt^2 of the end
    end_tol = max(END_TOL_M, prep.brake_end_mps2 * dt * dt)
    a_end = command.a_peak_mps2

    def ceiling(s_next: float) -> float:
        """Speed ceiling (v_max, velocity limit and braking curves) at a position."""
        x = max(s_next / h, 0.0)
        if x >= G:
            return math.sqrt(vlim2[G])  # at or past the end: rest
        i = int(x)
        return min(math.sqrt(vlim2[i] + (x - i) * (vlim2[i + 1] - vlim2[i])), v_max)

    rows = []
    s = sd = 0.0
    in_sync = True  # on the command exactly: take its state
    for k in range(n_max):
        if k < n_cmd:
            s_c, sd_c, sdd_c = sc_all[k], sdc_all[k], sddc_all[k]
            u_c = (sdc_all[k + 1] - sd_c) / dt
        else:
            s_c, sd_c, sdd_c, u_c = L, 0.0, 0.0, 0.0
        if k >= n_cmd - 1 and abs(L - s) < end_tol and abs(sd) < END_TOL_MPS:
            rows.append((k * dt, s_c, sd_c, sdd_c, s, sd, sdd_c if in_sync else 0.0, False, False))
            break
        # torque limits at the current state (interpolated path dynamics)
        x = min(max(s / h, 0.0), G - 1e-9)
        i = int(x)
        f = x - i
        a = grid_a[i] + f * (grid_a[i + 1] - grid_a[i])
        b = grid_b[i] + f * (grid_b[i + 1] - grid_b[i])
        c = grid_c[i] + f * (grid_c[i + 1] - grid_c[i])
        lo, hi = sdd_bounds(a, b, c, sd, tau_max)
        if in_sync and k + 1 < n_cmd:
            if lo <= sdd_c <= hi and sdc_all[k + 1] <= ceiling(sc_all[k + 1]) + 1e-12:
                rows.append((k * dt, s_c, sd_c, sdd_c, s, sd, sdd_c, False, False))
                s, sd = sc_all[k + 1], sdc_all[k + 1]
                continue
            in_sync = False
        if k < n_cmd - 1:
            u_des = u_c + kv * (sd_c - sd) + kp * (s_c - s)
        else:  # the command rests at the end: approach it on sqrt(2 a d) with half the torque headroom
            a_app = min(a_end, 0.5 * min(hi, -lo)) if lo < 0 < hi else 0.0
            d_next = max(L - s - sd * dt, 0.0)
            u_des = min(max((math.sqrt(2 * a_app * d_next) - sd) / dt, -a_app), a_app)
        # under the speed ceiling at the next position (two passes: the ceiling falls towards the
        # end, so the second, at the first pass's position, is safe); no reversing
        u = min(u_des, (ceiling(s + sd * dt) - sd) / dt)
        u = min(u, (ceiling(s + sd * dt + 0.5 * max(u, 0.0) * dt * dt) - sd) / dt)
        u = max(u, -sd / dt)
        infeasible = lo > hi
        if infeasible:
            u_lim = 0.5 * (lo + hi) if math.isfinite(lo + hi) else 0.0
        else:
            u_lim = min(max(u, lo), hi)
        rows.append((k * dt, s_c, sd_c, sdd_c, s, sd, u_lim, u_lim != u, infeasible))
        s = s + sd * dt + 0.5 * u_lim * dt * dt
        sd = sd + u_lim * dt
        if k + 1 < n_cmd and abs(s - sc_all[k + 1]) < SYNC_TOL_M and abs(sd - sdc_all[k + 1]) < SYNC_TOL_MPS:
            in_sync, s, sd = True, sc_all[k + 1], sdc_all[k + 1]  # rejoined the command
    else:
        raise CapmapError(f"the follower did not reach the end of the {L:.3f} m path within "
                          f"{max_time_factor:g} x the command's {command.duration_s:.2f} s "
                          f"(at s = {s:.9f} m, sd = {sd:.3g} m/s)")
    arr = np.array(rows, dtype=float)
    return FollowResult(t_s=arr[:, 0], s_cmd=arr[:, 1], sd_cmd=arr[:, 2], sdd_cmd=arr[:, 3], s=arr[:, 4],
                        sd=arr[:, 5], sdd=arr[:, 6], limited=arr[:, 7].astype(bool), infeasible=arr[:, 8].astype(bool))


@dataclass(frozen=True)
class FollowedSegment:
    """One straight segment followed: its grid table, prepared limits, command, the follower's
    run, and the exact evaluation at the follower's and the command's states:
    tau (K, n), tau_cmd (K, n) N m; q (K, n) rad (exact path at the follower's s);
    deviation_m (K,), deviation_rad (K,): pose error of the interpolated joint command."""

    table: JointPath
    prepared: PreparedPath
    command: SCurve
    result: FollowResult
    tau: np.ndarray
    tau_cmd: np.ndarray
    q: np.ndarray
    deviation_m: np.ndarray
    deviation_rad: np.ndarray


def exact_torques(arm: LockedArm, table: JointPath, rotation: np.ndarray, payload_kg: float, s: np.ndarray,
                  sd: np.ndarray, sdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact torques (K, n) at states (s, sd, sdd) (K,) on the exact path, and the exact q (K, n)."""
    us, inv = np.unique(s, return_inverse=True)
    jp = path_at(arm, table, us, rotation)
    pdx = path_dynamics(arm, jp, payload_kg)
    tau = pdx.a[inv] * sdd[:, None] + pdx.b[inv] * (sd**2)[:, None] + pdx.c[inv]
    return tau, jp.q[inv]


def follow_segment(arm: LockedArm, p0: np.ndarray, p1: np.ndarray, rotation: np.ndarray, q_start: np.ndarray,
                   payload_kg: float, tau_max: np.ndarray, v_max_mps: float, a_max_mps2: float, j_max_mps3: float,
                   period_s: float, catch_up_hz: float, ds_m: float = 1e-3) -> FollowedSegment:
    """Prepare, command, follow and evaluate one straight segment (rest to rest)."""
    from capmap.kinematics import pose_error
    from capmap.trajectory import scurve

    table = line_path(arm, p0, p1, rotation, q_start, ds_m=ds_m)
    prep = prepare(path_dynamics(arm, table, payload_kg), tau_max, v_max_mps)
    cmd = scurve(table.length_m, v_max_mps, a_max_mps2, j_max_mps3)
    res = follow(prep, cmd, period_s, catch_up_hz)
    # follower and command states in one evaluation (in step, they share their s values)
    K = len(res.s)
    tau_all, q_all = exact_torques(arm, table, rotation, payload_kg, np.concatenate([res.s, res.s_cmd]),
                                   np.concatenate([res.sd, res.sd_cmd]), np.concatenate([res.sdd, res.sdd_cmd]))
    tau, tau_cmd, q = tau_all[:K], tau_all[K:], q_all[:K]
    T = arm.fk(interpolate_q(table, res.s))
    T_line = np.zeros_like(T)
    T_line[:, :3, :3], T_line[:, :3, 3], T_line[:, 3, 3] = rotation, p0 + res.s[:, None] * (p1 - p0) / table.length_m, 1
    err = pose_error(T, T_line)
    return FollowedSegment(table, prep, cmd, res, tau, tau_cmd, q, np.linalg.norm(err[:, :3], axis=1),
                           np.linalg.norm(err[:, 3:], axis=1))
