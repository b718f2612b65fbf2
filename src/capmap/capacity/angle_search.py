"""Between the grid angles of the healthy arm's search (:mod:`capmap.capacity.baseline`): a point's best
posture on the grid followed along its IK branch to the better of the angles a step either side, the
step halved each level (:func:`polish`; each posture reached by Newton's method from the last:
:func:`follow`), after a finer grid where the grid's best is 0 kg (:func:`between_grid_angles`)."""

from __future__ import annotations

import numpy as np

from capmap.capacity.engine import argmin_per_group
from capmap.capacity.self_motion import HealthyCapacity, HealthyProblem, SelfMotion, postures_capacity
from capmap.core import ik
from capmap.core.ik import polish as ik_polish
from capmap.core.ik.finish import RESIDUAL_TOL, wrap_to_range
from capmap.core.ik.polish import PolishSettings
from capmap.core.kinematics import pose_error

__all__ = ["FINER", "FINER_BESIDE", "EDGE_NEAR", "START_NEAR", "between_grid_angles", "edge_intervals", "polish", "follow"]

FINER = 6  # the grid intervals holding an edge (:func:`edge_intervals`), or where the grid's best is 0 kg: this many times finer
FINER_BESIDE = 2  # ...and those beside an edge
EDGE_NEAR = 0.05  # those at or next to an edge whose better end lies within this of the point's best
START_NEAR = 0.02  # an interval's best finer posture followed if it lies within this of the point's grid best
_STILL = 1e-3 * RESIDUAL_TOL  # a pose error this small: the next Newton step moves a joint by rounding only
_FOLLOW = PolishSettings(steps=8, done_tol=1e-3 * RESIDUAL_TOL, give_up=np.inf)  # as the numpy steps below
_NEWTON_STEPS = 8  # over half a 10 deg step, 400 postures of the default map: 385 meet the IK's tolerance (12 steps: 386)


def between_grid_angles(hp: HealthyProblem, points: np.ndarray, res: HealthyCapacity, rows: np.ndarray,
                        suspect: np.ndarray) -> None:
    """Between grid angles, in place, for points[rows] whose grid best is ``res``'s: in the grid intervals
    ``suspect`` (N, T) marks (:func:`edge_intervals`) finer angles first (:func:`_finer`: a narrow
    peak there lies between grid angles); then both the grid's best posture and each interval's finer best
    within :data:`START_NEAR` of it followed (:func:`polish`; the latter from a quarter step), the best kept."""
    if not len(rows):
        return
    alt = _finer(hp, points, res, rows, suspect) if hp.polish_levels else None
    polish(hp, points, res, rows)
    if alt is None:
        return
    owner, fine = alt  # starts: each interval's best finer posture
    polish(hp, points[owner], fine, np.arange(len(owner)), start_deg=hp.sm.step_deg / FINER_BESIDE / 2)
    k = argmin_per_group(-fine.capacity_kg, owner)
    k = k[fine.capacity_kg[k] > res.capacity_kg[owner[k]]]
    for f in ("capacity_kg", "angle_deg", "q_rad", "binding"):
        getattr(res, f)[owner[k]] = getattr(fine, f)[k]


def edge_intervals(sm: SelfMotion, pt: np.ndarray, tt: np.ndarray, value: np.ndarray, N: int) -> np.ndarray:
    """Where a point's best may lie between grid angles although no grid angle shows it, per grid interval
    [angle t, angle t + 1] (round the turn when the range spans one): (N, T) int8, the number of parts to
    split it into (0: none). From N points' grid postures (point pt (M,), angle index tt (M,), value (M,)
    kg or an upper bound of it): the intervals at an edge (an IK posture appears or goes, or one reaches
    0 kg: a joint limit or a singularity there; :data:`FINER` parts) or beside one (:data:`FINER_BESIDE`)
    whose better end lies within :data:`EDGE_NEAR` of the point's best; where that best is 0 kg (a plateau
    that shows no way up), every interval with a posture at an end (:data:`FINER`). A branch's capacity
    can rise steeply just before it ends: a narrow peak there lies between grid angles."""
    T = len(sm.angles_deg)
    m, c, z = np.full((N, T), -np.inf), np.zeros((N, T), dtype=int), np.zeros((N, T), dtype=int)
    np.maximum.at(m, (pt, tt), value)
    np.add.at(c, (pt, tt), 1)
    np.add.at(z, (pt, tt), (value <= 0).astype(int))
    nx = np.roll(np.arange(T), -1)
    valid = np.ones(T, dtype=bool)
    valid[-1] = sm.turns  # the last interval only round a turn
    edge = ((c != c[:, nx]) | (z != z[:, nx])) & valid
    beside = (np.roll(edge, 1, axis=1) | np.roll(edge, -1, axis=1)) & ~edge
    best = m.max(axis=1, initial=-np.inf)
    near = (np.maximum(m, m[:, nx]) >= np.where(best > 0, (1 - EDGE_NEAR) * best, 0.0)[:, None]) & valid
    parts = np.where(edge | (best <= 0)[:, None], FINER, np.where(beside, FINER_BESIDE, 0))
    return np.where(near, parts, 0).astype(np.int8)


def _finer(hp: HealthyProblem, points: np.ndarray, res: HealthyCapacity, rows: np.ndarray, suspect: np.ndarray
           ) -> tuple[np.ndarray, HealthyCapacity] | None:
    """Every IK solution of points[rows] at the angles splitting the grid intervals ``suspect`` (N, T) marks
    (:func:`edge_intervals`) into parts: each interval's best posture where it comes within
    :data:`START_NEAR` of the point's grid best (``res``; any, where that is 0 kg), as (their points (S,),
    the postures (S,)); None if there is none. ``res`` counts the candidates."""
    sm = hp.sm
    pp, ii = np.nonzero(suspect[rows])
    if not len(pp):
        return None
    n_of = suspect[rows][pp, ii]
    pp = rows[pp]
    a0 = sm.angles_deg
    a1 = np.roll(a0, -1) + np.where(np.arange(len(a0)) == len(a0) - 1, 360.0, 0.0)
    pr, ar, interval = [], [], []
    for n in np.unique(n_of):
        fine = n_of == n
        frac = np.arange(1, n) / n
        pr.append(np.repeat(pp[fine], len(frac)))
        interval.append(np.repeat(np.flatnonzero(fine), len(frac)))
        ar.append(sm.into_range((a0[ii[fine]][:, None] + (a1 - a0)[ii[fine]][:, None] * frac[None, :]).ravel()))
    owner, angles, interval = np.concatenate(pr), np.concatenate(ar), np.concatenate(interval)
    ok = np.isfinite(angles)
    k, qr = sm.solve(points[owner[ok]], angles[ok], hp.problem.rotation)
    pr, ar, interval = owner[ok][k], angles[ok][k], interval[ok][k]
    seen = np.bincount(pr, minlength=len(points))
    res.n_candidates[rows] += seen[rows]
    res.n_full[rows] += seen[rows]
    if not len(pr):
        return None
    cap, bnd = postures_capacity(sm, np.deg2rad(ar), qr, hp.problem.directions, hp.problem.motion)
    k = argmin_per_group(-cap, interval)  # each interval's best
    k = k[cap[k] >= (1 - START_NEAR) * np.maximum(res.capacity_kg[pr[k]], 0.0)]
    if not len(k):
        return None
    S = len(k)
    return pr[k], HealthyCapacity(cap[k], ar[k], qr[k], bnd[k], np.zeros(S, dtype=int), np.zeros(S, dtype=int),
                                  np.ones(S, dtype=bool))


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
    if sm.fold is not None:  # compiled Newton on the first grid angle's arm toward the moved targets
        T = sm.moved(points[rows], angle_deg[rows], rotation)
        qa, err = ik_polish.polish(arm.chain.X, q[rows], T, np.arange(len(rows)), _FOLLOW)
        qa, inside = wrap_to_range(qa, arm.q_lower, arm.q_upper)
        ok = (np.linalg.norm(err, axis=1) <= RESIDUAL_TOL) & inside.all(axis=1)
        return rows[ok], qa[ok]
    target = ik.targets(points[rows], rotation)
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


