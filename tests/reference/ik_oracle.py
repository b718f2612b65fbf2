"""Independent inverse kinematics by dense random restarts, straight from a robot file's DH rows
(no Pinocchio, no capmap chain): every converged restart is an exact solution, and with enough
restarts the set of distinct solutions is the set of IK branches. Slow but simple."""

from __future__ import annotations

import numpy as np


def _dh(alpha, a, theta, d, modified):
    """DH transforms (..., 4, 4) with every argument broadcast."""
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
    shape = np.broadcast(ca, ct, a, d).shape
    T = np.zeros(shape + (4, 4))
    if modified:  # Rx(alpha) Tx(a) Rz(theta) Tz(d)
        T[..., 0, :] = np.stack(np.broadcast_arrays(ct, -st, 0 * ct, a + 0 * ct), -1)
        T[..., 1, :] = np.stack(np.broadcast_arrays(st * ca, ct * ca, -sa + 0 * ct, -sa * d), -1)
        T[..., 2, :] = np.stack(np.broadcast_arrays(st * sa, ct * sa, ca + 0 * ct, ca * d), -1)
    else:  # Rz(theta) Tz(d) Tx(a) Rx(alpha)
        T[..., 0, :] = np.stack(np.broadcast_arrays(ct, -st * ca, st * sa, a * ct), -1)
        T[..., 1, :] = np.stack(np.broadcast_arrays(st, ct * ca, -ct * sa, a * st), -1)
        T[..., 2, :] = np.stack(np.broadcast_arrays(0 * ct, sa + 0 * ct, ca + 0 * ct, d + 0 * ct), -1)
    T[..., 3, 3] = 1.0
    return T


class DHArm:
    """A revolute DH arm from a robot-file document (degrees, metres), one joint optionally locked."""

    def __init__(self, doc: dict, locked: int = 0, locked_deg: float = 0.0):
        rows = np.asarray(doc["dh"]["rows"], dtype=float)
        self.modified = doc["dh"].get("convention", "modified") == "modified"
        self.alpha, self.a = np.deg2rad(rows[:, 0]), rows[:, 1]
        self.offset, self.d = np.deg2rad(rows[:, 2]), rows[:, 3]
        tool = doc.get("tool", {"xyz_m": [0, 0, 0], "rpy_deg": [0, 0, 0]})
        r, p, y = np.deg2rad(tool["rpy_deg"])
        Rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
        Ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
        Rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
        self.tool = np.eye(4)
        self.tool[:3, :3], self.tool[:3, 3] = Rz @ Ry @ Rx, tool["xyz_m"]
        self.n = len(rows)
        self.locked, self.locked_rad = locked, np.deg2rad(locked_deg)
        self.active = [i for i in range(self.n) if i != locked - 1]

    def full(self, q_act):
        q = np.zeros(q_act.shape[:-1] + (self.n,))
        q[..., self.active] = q_act
        if self.locked:
            q[..., self.locked - 1] = self.locked_rad
        return q

    def frames(self, q_act):
        """Joint frames (M, n, 4, 4) and the tool pose (M, 4, 4) for active angles (M, n_act)."""
        q = self.full(q_act)
        T = np.broadcast_to(np.eye(4), q.shape[:-1] + (4, 4)).copy()
        out = []
        for i in range(self.n):
            T = T @ _dh(self.alpha[i], self.a[i], q[..., i] + self.offset[i], self.d[i], self.modified)
            out.append(T)
        return np.stack(out, -3), T @ self.tool

    def fk(self, q_act):
        return self.frames(q_act)[1]

    def jacobian(self, q_act):
        """Geometric Jacobian (M, 6, n_act) [v; w] of the tool point; the z axes of the joint
        frames are the joint axes (both DH conventions: the axis of joint i is z of the frame
        that rotates with it, placed before (modified) or after (standard) its own rotation)."""
        F, T = self.frames(q_act)
        if self.modified:
            z, o = F[..., :3, 2], F[..., :3, 3]
        else:  # joint i turns about z of frame i-1
            prev = np.concatenate([np.broadcast_to(np.eye(4), F[..., :1, :, :].shape), F[..., :-1, :, :]], -3)
            z, o = prev[..., :3, 2], prev[..., :3, 3]
        z, o = z[..., self.active, :], o[..., self.active, :]
        Jv = np.cross(z, T[..., None, :3, 3] - o)
        return T, np.concatenate([np.swapaxes(Jv, -1, -2), np.swapaxes(z, -1, -2)], -2)


def _log_err(T, Tt):
    dp = Tt[..., :3, 3] - T[..., :3, 3]
    R = Tt[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)
    w = 0.5 * np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    return np.concatenate([dp, w], -1)  # small-angle rotation error: fine near convergence


def solve_all(arm: DHArm, T_target: np.ndarray, restarts: int, rng: np.random.Generator, tol=1e-9):
    """Distinct solutions (list of (K_i, n_act) arrays, angles in (-pi, pi]) for targets (N, 4, 4)."""
    N, m = len(T_target), len(arm.active)
    q = rng.uniform(-np.pi, np.pi, (N, restarts, m)).reshape(-1, m)
    Tt = np.repeat(T_target, restarts, axis=0)
    for it in range(50):
        T, J = arm.jacobian(q)
        e = _log_err(T, Tt)
        # Final damping 1e-5 m: lam^2 = 1e-10 m^2, about 1e3 x the rounding of J J^T (n eps |J J^T| ~ 6e-14 m^2 at
        # the arm's 47 m^2). At 1e-9, lam^2 = 1e-18 was below rounding, so a restart stuck at a singular
        # configuration gave an exactly singular matrix on some BLAS kernels (OPENBLAS_CORETYPE=Prescott, joint 5).
        # The damping leaves the solutions unchanged and scales a step's error by lam^2 / (lam^2 + sigma^2) at most
        # (1e-4 at sigma_min(J) = 1e-3): the test's branch counts are the same with 1e-9, 1e-6 and 1e-5 (default kernel
        # and Prescott: 1456, 1482, 1259, 1303, 1251, 1434, 1506 for joints 1-7).
        lam = 1e-2 if it < 38 else 1e-5
        JJt = J @ np.swapaxes(J, -1, -2) + lam**2 * np.eye(6)
        step = np.einsum("mji,mj->mi", J, np.linalg.solve(JJt, e[..., None])[..., 0])
        q = q + np.clip(step, -0.4, 0.4)
    T = arm.fk(q)
    dp = np.linalg.norm(T[:, :3, 3] - Tt[:, :3, 3], axis=1)
    dR = np.linalg.norm(T[:, :3, :3] - Tt[:, :3, :3], axis=(1, 2))
    good = (dp < tol) & (dR < tol)
    q = np.mod(q + np.pi, 2 * np.pi) - np.pi
    out = []
    for i in range(N):
        cand = q[i * restarts:(i + 1) * restarts][good[i * restarts:(i + 1) * restarts]]
        keep = []
        for c in cand:
            if all(np.abs(np.mod(c - k + np.pi, 2 * np.pi) - np.pi).max() > 1e-6 for k in keep):
                keep.append(c)
        out.append(np.array(keep).reshape(-1, m))
    return out
