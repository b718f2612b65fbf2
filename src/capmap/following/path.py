"""A straight end-effector segment as a joint path: exact IK samples and their derivatives by
arc length, tabulated once per path (the follower interpolates, with no IK at run time)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import LockedArm
from capmap.core.tracking import track
from capmap.errors import CapmapError, TrackingLost

__all__ = ["JointPath", "line_path", "path_derivatives", "interpolate_q", "path_at"]


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
        raise TrackingLost(f"the segment {p0.round(4).tolist()} -> {p1.round(4).tolist()} cannot be followed: "
                           f"{tr.failure} at s = {s[tr.failed_at]:.4f} m")
    dq, ddq = path_derivatives(arm, tr.q, u)
    return JointPath(s=s, q=tr.q, dq=dq, ddq=ddq, p=p)


def path_derivatives(arm: LockedArm, q: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """q' = J^-1 [u; 0] and q'' = -J^-1 Jdot(q, q') q' (each (G, n_active)) at joint angles q
    (G, n_active) along a straight line of direction u (3,) at fixed orientation."""
    if len(q) == 0:
        return np.empty_like(q), np.empty_like(q)
    dyn = ArmDynamics(arm)
    qf = arm.full_q(q)
    J = np.stack([dyn.ee_jacobian(x) for x in qf])  # (G, 6, n_active)
    twist = np.broadcast_to(np.concatenate([u, np.zeros(3)]), (len(q), 6))
    dq = np.linalg.solve(J, twist[..., None])[..., 0]
    drift = np.stack([dyn.drift(x, v) for x, v in zip(qf, arm.full_v(dq))])  # (G, 6)
    return dq, np.linalg.solve(J, -drift[..., None])[..., 0]


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
    dq, ddq = path_derivatives(arm, q, u)
    return JointPath(s=np.asarray(s, dtype=float), q=q, dq=dq, ddq=ddq, p=p)
