"""Between the grid angles of the healthy arm's search (:mod:`capmap.capacity.baseline`): a point's best
posture on the grid followed along its IK branch to the better of the angles a step either side, the
step halved each level (:func:`polish`; each posture reached by Newton's method from the last:
:func:`follow`), after a finer grid where the grid's best is 0 kg (:func:`between_grid_angles`)."""

from __future__ import annotations

import numpy as np

from capmap.capacity.engine import argmin_per_group
from capmap.capacity.self_motion import HealthyCapacity, HealthyProblem, SelfMotion, postures_capacity
from capmap.core.ik.finish import RESIDUAL_TOL, wrap_to_range
from capmap.core.kinematics import pose_error

__all__ = ["FINER", "between_grid_angles", "polish", "follow"]

FINER = 8  # a 0 kg plateau on the grid: its points searched again on a grid this many times finer
_STILL = 1e-3 * RESIDUAL_TOL  # a pose error this small: the next Newton step moves a joint by rounding only
_NEWTON_STEPS = 8  # over half a 10 deg step, 400 postures of the default map: 385 meet the IK's tolerance (12 steps: 386)


def between_grid_angles(hp: HealthyProblem, points: np.ndarray, res: HealthyCapacity, rows: np.ndarray) -> None:
    """Between grid angles, in place, for points[rows] whose grid best is ``res``'s: where that best is 0
    kg (every grid posture at a limit or singular: a plateau that shows no way up) the angles
    1/:data:`FINER` of a step apart first (:func:`_finer`; a peak a few degrees wide, e.g. where a pair of IK branches
    is born, lies between grid angles), then the best posture followed (:func:`polish`; from half the finer
    grid's step where that grid found it: such a peak is narrow)."""
    finer = np.zeros(0, dtype=int)
    if hp.polish_levels and len(rows):
        plateau = rows[res.capacity_kg[rows] <= 0]
        _finer(hp, points, res, plateau)
        finer = plateau[res.capacity_kg[plateau] > 0]
        polish(hp, points, res, finer, start_deg=hp.sm.step_deg / FINER / 2)
    polish(hp, points, res, np.setdiff1d(rows, finer))


def _finer(hp: HealthyProblem, points: np.ndarray, res: HealthyCapacity, rows: np.ndarray) -> None:
    """Every IK solution of points[rows] at the angles 1/:data:`FINER` of a step apart between the grid
    angles, the best posture kept where it beats ``res``'s (in place)."""
    sm = hp.sm
    if not len(rows):
        return
    off = sm.step_deg * np.arange(1, FINER) / FINER
    angles = sm.into_range((sm.angles_deg[:, None] + off[None, :]).ravel())
    angles = np.unique(np.round(angles[np.isfinite(angles)], 9))
    k, qr = sm.solve(points[np.repeat(rows, len(angles))], np.tile(angles, len(rows)), hp.problem.rotation)
    pr, ar = np.repeat(rows, len(angles))[k], np.tile(angles, len(rows))[k]
    if not len(pr):
        return
    cap, bnd = postures_capacity(sm, np.deg2rad(ar), qr, hp.problem.directions, hp.problem.motion)
    k = argmin_per_group(-cap, pr)
    k = k[cap[k] > res.capacity_kg[pr[k]]]
    r = pr[k]
    res.capacity_kg[r], res.angle_deg[r], res.q_rad[r], res.binding[r] = cap[k], ar[k], qr[k], bnd[k]
    res.n_candidates[r] += np.bincount(pr, minlength=len(points))[r]
    res.n_full[r] += np.bincount(pr, minlength=len(points))[r]


def polish(hp: HealthyProblem, points: np.ndarray, res: HealthyCapacity, rows: np.ndarray,
            levels: int | None = None, start_deg: float | None = None) -> None:
    """Follow the best posture of points[rows] (``res``: its angle and joints) between grid angles, in
    place: ``levels`` (default ``hp.polish_levels``) levels, from ``start_deg`` (default half the grid's step),
    halving it; at each level the angles a
    step either side, each reached from the current posture along its IK branch (:func:`follow`), the
    best of the three kept. Values only rise; each is the posture's it records."""
    sm, directions, motion = hp.sm, hp.problem.directions, hp.problem.motion
    h = sm.step_deg / 2 if start_deg is None else start_deg
    for _ in range((hp.polish_levels if levels is None else levels) if len(rows) else 0):
        best, angle, q, bnd = (res.capacity_kg[rows].copy(), res.angle_deg[rows].copy(), res.q_rad[rows].copy(),
                               res.binding[rows].copy())
        for sign in (-1.0, 1.0):
            a = sm.into_range(res.angle_deg[rows] + sign * h)
            r, qs = follow(sm, hp.problem.rotation, points[rows], a, res.q_rad[rows])
            if not len(r):
                continue
            val, b = postures_capacity(sm, np.deg2rad(a[r]), qs, directions, motion)
            up = val > best[r]
            best[r[up]], angle[r[up]], q[r[up]], bnd[r[up]] = val[up], a[r[up]], qs[up], b[up]
        res.capacity_kg[rows], res.angle_deg[rows], res.q_rad[rows], res.binding[rows] = best, angle, q, bnd
        h /= 2


def follow(sm: SelfMotion, rotation: np.ndarray, points: np.ndarray, angle_deg: np.ndarray, q: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """Per point (N, 3) with the joint moved to angle_deg (N,) (NaN: none) from the posture q (N, n_active)
    rad (at the rotation (3, 3)), the posture of the same IK branch there: Newton's method on the active
    joints from q (damped least squares on the arm's Jacobian without the held joint's column), accepted
    where the pose is met to the IK's tolerance and every active joint lies in its range. (The points that
    reach one (M,), their active joints (M, n_active).)"""
    arm = sm.arms[0]
    chain, act, j = sm.free_chain, arm.active, arm.locked_joint - 1
    rows = np.flatnonzero(np.isfinite(angle_deg) & np.all(np.isfinite(q), axis=1))
    target = np.broadcast_to(np.eye(4), (len(rows), 4, 4)).copy()
    target[:, :3, :3], target[:, :3, 3] = rotation, points[rows]
    full = np.zeros((len(rows), arm.robot.n_joints))
    full[:, act], full[:, j] = q[rows], np.deg2rad(angle_deg[rows])
    go = np.arange(len(rows))  # the rows still moving: a row stops once its step is below rounding
    for _ in range(_NEWTON_STEPS):
        T, J = chain.jacobian(full[go])
        e = pose_error(T, target[go])
        Ja = J[:, :, act]
        JtJ = np.swapaxes(Ja, 1, 2) @ Ja + 1e-12 * np.eye(len(act))
        full[np.ix_(go, act)] += np.linalg.solve(JtJ, (np.swapaxes(Ja, 1, 2) @ e[..., None]))[..., 0]
        go = go[np.linalg.norm(e, axis=1) > _STILL]
        if not len(go):
            break
    err = np.linalg.norm(pose_error(chain.fk(full), target), axis=1)
    qa, inside = wrap_to_range(full[:, act], arm.q_lower, arm.q_upper)
    ok = (err <= RESIDUAL_TOL) & inside.all(axis=1)
    return rows[ok], qa[ok]


