"""Torque-limited following of a fixed Cartesian path, online, one control period at a time.

The end effector must stay on a straight segment (fixed orientation) while a jerk-limited
S-curve commands the path coordinate s (arc length, m). At a state (s, sd) the torque
limits bound the path acceleration to an interval [lo, hi] (:mod:`.path_dynamics`).

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
   capability the torque limits leave), all precomputed along the path (:func:`.prepare`);
4. clips to [lo, hi] from the torque limits at its current (s, sd), the drives' friction at
   that speed included (:mod:`.path_dynamics`): the path stays
   exact, only the timing yields; when the limit releases, step 2 catches up, and within
   1 nm and 1 nm/s of the command it rejoins it (step 1);
5. integrates s, sd with that constant acceleration over the period.

The path preparation (:func:`.line_path`, :func:`.path_dynamics`) is done once per path on
a fine s grid; per period the follower interpolates a, b, c linearly, so its work is a
few dozen floating-point operations (see ``tests/benchmarks/bench_follow.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from capmap.core.drives import friction_torque, path_motion
from capmap.core.dynamics import payload_models, torque_names
from capmap.core.kinematics import pose_error
from capmap.core.limits import AffineLimits
from capmap.core.profiles import SCurve, scurve
from capmap.core.reduction import LockedArm
from capmap.errors import CapmapError, SolverFailed
from capmap.following.path import JointPath, interpolate_q, line_path, path_at
from capmap.following.path_dynamics import PreparedPath, forward_friction, path_dynamics, prepare

__all__ = ["FollowResult", "follow", "FollowSettings", "FollowedSegment", "ExactTorques", "exact_torques",
           "follow_segment", "SATURATED"]

END_TOL_M = 1e-6  # the follower has arrived within max(this, beta dt^2) of the end, at (almost) rest
END_TOL_MPS = 1e-6
SYNC_TOL_M = 1e-9  # a follower this close to the command (and its speed) rejoins it exactly
SYNC_TOL_MPS = 1e-9
SATURATED = 0.999  # a joint whose peak torque reaches this fraction of its limit is saturated


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


@dataclass(frozen=True)
class _LoopData:
    """What the follower's loop reads, computed once: the control period dt, path length L, speed limit,
    torque limits, the end tolerance and approach acceleration, the catch-up gains, the step counts, the
    command sampled at every period, the path dynamics' grid (a, b, c, dq, spacing h, G intervals), the
    squared speed ceiling on it and the friction terms."""

    dt: float
    L: float
    v_max: float
    limits: AffineLimits
    end_tol: float
    a_end: float
    kp: float
    kv: float
    n_max: int
    n_cmd: int
    sc_all: list
    sdc_all: list
    sddc_all: list
    grid_a: np.ndarray
    grid_b: np.ndarray
    grid_c: np.ndarray
    h: float
    G: int
    vlim2: list
    friction: bool
    grid_dq: np.ndarray | None
    f_c: np.ndarray | None
    f_v: np.ndarray | None


def _loop_data(prep: PreparedPath, command: SCurve, period_s: float, catch_up_hz: float,
               max_time_factor: float) -> _LoopData:
    """The follower's inputs checked and laid out for its loop (see :class:`_LoopData`)."""
    dt = float(period_s)
    if not dt > 0:
        raise CapmapError(f"period_s = {period_s!r} must be > 0")
    if not catch_up_hz > 0:
        raise CapmapError(f"catch_up_hz = {catch_up_hz!r} must be > 0")
    pdyn = prep.dynamics
    L = command.length_m
    if abs(L - pdyn.s[-1]) > 1e-9 * max(1.0, L):
        raise CapmapError(f"command length {L} m differs from the path length {pdyn.s[-1]} m")
    w = 2 * math.pi * catch_up_hz
    n_cmd = math.ceil(command.duration_s / dt) + 2
    sc_all, sdc_all, sddc_all = (x.tolist() for x in command.evaluate(np.arange(n_cmd + 1) * dt))
    friction = pdyn.has_friction
    return _LoopData(
        dt=dt, L=L, v_max=prep.v_max_mps, limits=prep.limits,
        # a discrete follower braking at beta can stop only within ~beta dt^2 of the end
        end_tol=max(END_TOL_M, prep.brake_end_mps2 * dt * dt), a_end=command.a_peak_mps2, kp=w * w, kv=2 * w,
        n_max=math.ceil(max_time_factor * command.duration_s / dt) + 2, n_cmd=n_cmd, sc_all=sc_all, sdc_all=sdc_all,
        sddc_all=sddc_all, grid_a=pdyn.a, grid_b=pdyn.b, grid_c=pdyn.c, h=float(pdyn.s[1] - pdyn.s[0]),
        G=len(pdyn.s) - 1,
        vlim2=(prep.v_limit**2).tolist(),  # interpolate squared speeds: exact on a constant-deceleration braking curve
        friction=friction, grid_dq=pdyn.dq if friction else None, f_c=pdyn.coulomb_nm if friction else None,
        f_v=pdyn.viscous_nms if friction else None)


def follow(prep: PreparedPath, command: SCurve, period_s: float, catch_up_hz: float,
           max_time_factor: float = 20.0) -> FollowResult:
    """Run the follower from rest at s = 0 until it rests at the end of the path (see the module
    docstring). Raises SolverFailed if it has not arrived within max_time_factor x the
    command's duration."""
    lp = _loop_data(prep, command, period_s, catch_up_hz, max_time_factor)
    dt, L, v_max, limits, end_tol, a_end, kp, kv = lp.dt, lp.L, lp.v_max, lp.limits, lp.end_tol, lp.a_end, lp.kp, lp.kv
    n_max, n_cmd, sc_all, sdc_all, sddc_all = lp.n_max, lp.n_cmd, lp.sc_all, lp.sdc_all, lp.sddc_all
    grid_a, grid_b, grid_c, h, G, vlim2 = lp.grid_a, lp.grid_b, lp.grid_c, lp.h, lp.G, lp.vlim2
    friction, grid_dq, f_c, f_v = lp.friction, lp.grid_dq, lp.f_c, lp.f_v

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
        y0 = b * (sd * sd) + c
        if friction:  # moving forward (or starting to): F_v q' sd + F_c sign(q') at this s
            dq = grid_dq[i] + f * (grid_dq[i + 1] - grid_dq[i])
            y0 = y0 + forward_friction(dq, sd, f_c, f_v)
        lo, hi = limits.interval_one(y0.tolist(), a.tolist())
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
        raise SolverFailed(f"the follower did not reach the end of the {L:.3f} m path within "
                           f"{max_time_factor:g} x the command's {command.duration_s:.2f} s "
                           f"(at s = {s:.9f} m, sd = {sd:.3g} m/s)")
    arr = np.array(rows, dtype=float)
    return FollowResult(t_s=arr[:, 0], s_cmd=arr[:, 1], sd_cmd=arr[:, 2], sdd_cmd=arr[:, 3], s=arr[:, 4],
                        sd=arr[:, 5], sdd=arr[:, 6], limited=arr[:, 7].astype(bool), infeasible=arr[:, 8].astype(bool))


@dataclass(frozen=True)
class FollowedSegment:
    """One straight segment followed: its grid table, prepared limits, command, the follower's
    run, and the exact evaluation at the follower's and the command's states:
    tau (K, n), tau_cmd (K, n) N m (motor torques: links, armature, friction); q (K, n) rad (exact
    path at the follower's s); deviation_m (K,), deviation_rad (K,): pose error of the interpolated
    joint command; tau_armature (K, n), tau_friction (K, n) N m: the drives' parts of tau."""

    table: JointPath
    prepared: PreparedPath
    command: SCurve
    result: FollowResult
    tau: np.ndarray
    tau_cmd: np.ndarray
    q: np.ndarray
    deviation_m: np.ndarray
    deviation_rad: np.ndarray
    tau_armature: np.ndarray
    tau_friction: np.ndarray


@dataclass(frozen=True)
class ExactTorques:
    """Torques at states on the exact path: tau (K, n) N m the motor's (links, payload, armature,
    friction), its parts armature (K, n) and friction (K, n) N m, and the exact q (K, n) rad."""

    tau: np.ndarray
    armature: np.ndarray
    friction: np.ndarray
    q: np.ndarray


def exact_torques(arm: LockedArm, table: JointPath, rotation: np.ndarray, payload_kg: float, s: np.ndarray,
                  sd: np.ndarray, sdd: np.ndarray) -> ExactTorques:
    """Exact torques at states (s, sd, sdd) (K,) on the exact path (:class:`ExactTorques`), by inverse
    dynamics in joint space, not through the follower's path tables: the path polished by Newton at
    each s, joint velocities q' sd and accelerations q'' sd^2 + q' sdd, Pinocchio's RNEA there (payload
    and armature included) and the drives' friction of :func:`capmap.core.drives.friction_torque`."""
    us, inv = np.unique(s, return_inverse=True)
    jp = path_at(arm, table, us, rotation)
    q = jp.q[inv]
    qd, qdd = jp.dq[inv] * sd[:, None], jp.ddq[inv] * (sd**2)[:, None] + jp.dq[inv] * sdd[:, None]
    model, _ = payload_models(arm, payload_kg)
    data = model.createData()
    robot, act = arm.robot, arm.active
    qf, vf, af = arm.full_q(q), arm.full_v(qd), arm.full_v(qdd)
    rigid = np.array([pin.rnea(model, data, qf[k], vf[k], af[k])[act] for k in range(len(q))]).reshape(len(q), len(act))
    fric = friction_torque(rigid, qd, path_motion(jp.dq[inv], sd, sdd), robot.coulomb_nm[act], robot.viscous_nms[act])
    return ExactTorques(rigid + fric, robot.armature_kgm2[act] * qdd, fric, q)


@dataclass(frozen=True)
class FollowSettings:
    """What a follower needs besides its path: payload_kg (a point mass at the end effector),
    joint_torque_nm (n_active,) limits of the active joints, the S-curve command's limits
    v_max_mps, a_max_mps2, j_max_mps3, the control period_s, the catch-up bandwidth
    catch_up_hz, and the grid ds_m of the path tables."""

    payload_kg: float
    joint_torque_nm: np.ndarray
    v_max_mps: float
    a_max_mps2: float
    j_max_mps3: float
    period_s: float
    catch_up_hz: float
    ds_m: float = 1e-3

    def torque_limits(self, arm: LockedArm) -> AffineLimits:
        """The torque limits on ``arm``'s active joints."""
        return AffineLimits(np.asarray(self.joint_torque_nm, dtype=float), torque_names(arm))


def follow_segment(arm: LockedArm, p0: np.ndarray, p1: np.ndarray, rotation: np.ndarray, q_start: np.ndarray,
                   settings: FollowSettings) -> FollowedSegment:
    """Prepare, command, follow and evaluate one straight segment p0 -> p1 (3,) m at ``rotation``
    (3, 3), rest to rest, on the IK branch continuous from q_start (n_active,) rad."""
    st = settings
    table = line_path(arm, p0, p1, rotation, q_start, ds_m=st.ds_m)
    prep = prepare(path_dynamics(arm, table, st.payload_kg), st.torque_limits(arm), st.v_max_mps)
    cmd = scurve(table.length_m, st.v_max_mps, st.a_max_mps2, st.j_max_mps3)
    res = follow(prep, cmd, st.period_s, st.catch_up_hz)
    # follower and command states in one evaluation (in step, they share their s values)
    K = len(res.s)
    ex = exact_torques(arm, table, rotation, st.payload_kg, np.concatenate([res.s, res.s_cmd]),
                       np.concatenate([res.sd, res.sd_cmd]), np.concatenate([res.sdd, res.sdd_cmd]))
    tau, tau_cmd, q = ex.tau[:K], ex.tau[K:], ex.q[:K]
    T = arm.fk(interpolate_q(table, res.s))
    T_line = np.zeros_like(T)
    T_line[:, :3, :3], T_line[:, :3, 3], T_line[:, 3, 3] = rotation, p0 + res.s[:, None] * (p1 - p0) / table.length_m, 1
    err = pose_error(T, T_line)
    return FollowedSegment(table, prep, cmd, res, tau, tau_cmd, q, np.linalg.norm(err[:, :3], axis=1),
                           np.linalg.norm(err[:, 3:], axis=1), ex.armature[:K], ex.friction[:K])
