"""Independent inverse-kinematics oracles for serial 6R chains built from a Pinocchio model
(they import nothing of capmap's IK or kinematics).

* :func:`random_restart`: Levenberg-Marquardt from many uniformly random starts within the joint
  ranges, batched with numpy over targets and starts. The forward kinematics and Jacobian it
  iterates on are a product of exponentials (:class:`PoE`) read off the Pinocchio model at q = 0
  (joint screws from ``pin.forwardKinematics`` and each joint's motion subspace), a different
  parametrisation from capmap's ``X0 Rz(q1) X1 ...``. Converged starts are polished by undamped Newton
  steps to <= 1e-12, and every distinct one is then
  checked by Pinocchio's own FK (``pin.framesForwardKinematics``, ``pin.log6``): position and
  orientation error <= 1e-9. With enough starts the set is every IK branch, but a random-restart
  search can only ever under-report, never invent: it is the reference for "nothing missed".
* :class:`EAIKOracle`: the EAIK library (Ostermeier et al., RA-L 2025; pip ``eaik``), which derives a
  closed form (subproblem decomposition) for the chains it recognises (spherical wrist, three
  parallel axes, ...) and refuses the others (``covered`` False). Its solutions are flagged exact or
  least-squares; the exact ones are polished (Newton on the PoE) and checked by Pinocchio as above.

Solutions of both are wrapped the way capmap reports them (:func:`wrap_like_capmap`: one
representative per 2 pi, the one nearest 0 inside [lower, upper]) and de-duplicated.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["PoE", "random_restart", "wrap_like_capmap", "dedupe", "wrapped_distance", "missing", "pin_errors",
           "EAIKOracle", "EXACT_TOL", "DEDUPE_TOL", "MATCH_TOL"]

EXACT_TOL = 1e-9  # m and rad: a solution is exact when Pinocchio's FK puts the frame this close to the target
DEDUPE_TOL = 1e-6  # rad (wrapped, max over joints): two solutions of one solver closer than this are one
MATCH_TOL = 1e-5  # rad: matching the solutions of two different solvers (their rounding differs)
PATH_TOL = 1e-8  # m and rad: two solutions joined by a segment this close to the target are one branch (see missing)
_CONVERGED = 1e-12  # |error| (m, rad) on the PoE at which a start stops iterating


# --------------------------------------------------------------------------- product of exponentials


def _skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


class PoE:
    """``T(q) = exp([S1] q1) ... exp([Sn] qn) M`` of the frame ``frame_id`` of a serial Pinocchio model of
    1-DOF revolute joints; axes w_i (unit) through points r_i, all at q = 0 in the world frame."""

    def __init__(self, model: pin.Model, data: pin.Data, frame_id: int):
        q0 = np.zeros(model.nq)
        if model.nq != model.nv or model.nq != model.njoints - 1:
            raise ValueError("PoE needs a model of 1-DOF joints (nq == nv == number of joints)")
        pin.forwardKinematics(model, data, q0)
        pin.updateFramePlacements(model, data)
        w, r = [], []
        for j in range(1, model.njoints):
            S = np.asarray(data.joints[j].S).reshape(6, -1)  # motion subspace [v; w] in the joint frame
            if S.shape[1] != 1 or np.abs(S[:3, 0]).max() > 1e-12 or abs(np.linalg.norm(S[3:, 0]) - 1) > 1e-12:
                raise ValueError(f"joint {model.names[j]} is not a 1-DOF revolute joint")
            w.append(data.oMi[j].rotation @ S[3:, 0])
            r.append(data.oMi[j].translation.copy())
        self.n = model.njoints - 1
        self.w, self.r = np.array(w), np.array(r)  # (n, 3)
        self.K = np.array([_skew(a) for a in self.w])  # (n, 3, 3)
        self.K2 = self.K @ self.K
        self.M = data.oMf[frame_id].homogeneous.copy()

    def fk_jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For q (B, n): rotation (B, 3, 3), position (B, 3) of the frame, and the geometric Jacobian
        (B, 6, n) [v of the frame's origin; w], both in world-aligned axes."""
        B = len(q)
        R = np.broadcast_to(np.eye(3), (B, 3, 3)).copy()
        p = np.zeros((B, 3))
        J = np.empty((B, 6, self.n))
        points = np.empty((B, 3, self.n))
        s, c = np.sin(q)[:, :, None], (1 - np.cos(q))[:, :, None]
        for i in range(self.n):
            rows = R.reshape(-1, 3)  # R @ (constant) as one matrix product over the batch
            J[:, 3:, i] = (rows @ self.w[i]).reshape(B, 3)
            points[:, :, i] = (rows @ self.r[i]).reshape(B, 3) + p
            # Rodrigues: Ri = I + s K + (1 - c) K^2, a rotation about the axis through r_i: t_i = (I - Ri) r_i
            Kr, K2r = self.K[i] @ self.r[i], self.K2[i] @ self.r[i]
            p = p - s[:, i] * (rows @ Kr).reshape(B, 3) - c[:, i] * (rows @ K2r).reshape(B, 3)
            RK, RK2 = (rows @ self.K[i]).reshape(B, 3, 3), (rows @ self.K2[i]).reshape(B, 3, 3)
            R = R + s[:, i, :, None] * RK + c[:, i, :, None] * RK2
        rows = R.reshape(-1, 3)
        p_tip = p + (rows @ self.M[:3, 3]).reshape(B, 3)
        R_tip = (rows @ self.M[:3, :3]).reshape(B, 3, 3)
        d, a = p_tip[:, :, None] - points, J[:, 3:]
        J[:, 0] = a[:, 1] * d[:, 2] - a[:, 2] * d[:, 1]
        J[:, 1] = a[:, 2] * d[:, 0] - a[:, 0] * d[:, 2]
        J[:, 2] = a[:, 0] * d[:, 1] - a[:, 1] * d[:, 0]
        return R_tip, p_tip, J

    def fk(self, q: np.ndarray) -> np.ndarray:
        """Poses (B, 4, 4) for q (B, n)."""
        R, p, _ = self.fk_jacobian(np.atleast_2d(q))
        T = np.zeros((len(R), 4, 4))
        T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = R, p, 1.0
        return T


def _rotvec(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (B, 3) of rotations (B, 3, 3), through the quaternion (robust at any angle)."""
    tr = np.trace(R, axis1=1, axis2=2)
    cand = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], 1)
    k = np.argmax(cand, axis=1)
    quat = np.empty((len(R), 4))  # w, x, y, z (unnormalised, sign fixed below)
    m = k == 0
    quat[m] = np.stack([1 + tr[m], R[m, 2, 1] - R[m, 1, 2], R[m, 0, 2] - R[m, 2, 0], R[m, 1, 0] - R[m, 0, 1]], 1)
    m = k == 1
    quat[m] = np.stack([R[m, 2, 1] - R[m, 1, 2], 1 + 2 * R[m, 0, 0] - tr[m], R[m, 0, 1] + R[m, 1, 0], R[m, 0, 2] + R[m, 2, 0]], 1)
    m = k == 2
    quat[m] = np.stack([R[m, 0, 2] - R[m, 2, 0], R[m, 0, 1] + R[m, 1, 0], 1 + 2 * R[m, 1, 1] - tr[m], R[m, 1, 2] + R[m, 2, 1]], 1)
    m = k == 3
    quat[m] = np.stack([R[m, 1, 0] - R[m, 0, 1], R[m, 0, 2] + R[m, 2, 0], R[m, 1, 2] + R[m, 2, 1], 1 + 2 * R[m, 2, 2] - tr[m]], 1)
    quat *= np.where(quat[:, :1] < 0, -1.0, 1.0)
    v = quat[:, 1:]
    nv = np.linalg.norm(v, axis=1)
    angle = 2 * np.arctan2(nv, quat[:, 0])
    scale = np.where(nv > 1e-300, angle / np.where(nv > 1e-300, nv, 1.0), 2.0 / np.maximum(quat[:, 0], 1e-300))
    return v * scale[:, None]


def _error(R, p, R_t, p_t):
    """World-aligned pose error [p_t - p; rotvec(R_t R^T)] (B, 6)."""
    return np.concatenate([p_t - p, _rotvec(R_t @ np.swapaxes(R, 1, 2))], axis=1)


# --------------------------------------------------------------------------- helpers shared by the oracles


def wrap_like_capmap(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                     slack: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
    """(theta', inside): each angle shifted by a multiple of 2 pi into [lower - slack, upper + slack], the
    representative nearest 0 where there are several (a range wider than 2 pi); NaN and False where none is."""
    theta = np.asarray(theta, dtype=float)
    base = np.arctan2(np.sin(theta), np.cos(theta))
    best = np.full_like(base, np.nan)
    for k in range(-3, 4):
        cand = base + 2 * np.pi * k
        ok = (cand >= lower - slack) & (cand <= upper + slack) & (np.isnan(best) | (np.abs(cand) < np.abs(best)))
        best = np.where(ok, cand, best)
    return best, ~np.isnan(best)


def wrapped_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Max-over-joints angular distance (modulo 2 pi) between the rows of a (K, n) and b (L, n): (K, L)."""
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    d = np.mod(a[:, None, :] - b[None, :, :] + np.pi, 2 * np.pi) - np.pi
    return np.abs(d).max(axis=-1, initial=0.0)


def dedupe(q: np.ndarray, tol: float = DEDUPE_TOL) -> np.ndarray:
    """The rows of q (K, n) with the later ones closer than tol (wrapped) to an earlier kept one removed."""
    keep: list[np.ndarray] = []
    for row in np.atleast_2d(q):
        if not keep or wrapped_distance(row[None], np.array(keep)).min() > tol:
            keep.append(row)
    return np.array(keep).reshape(-1, q.shape[-1] if np.ndim(q) == 2 else 0)


def missing(required: np.ndarray, found: np.ndarray, tol: float = MATCH_TOL, poe: PoE | None = None,
            T_target: np.ndarray | None = None, path_tol: float = PATH_TOL, reach: float = 0.05) -> np.ndarray:
    """The rows of ``required`` (K, n) that no row of ``found`` (L, n) matches: within ``tol`` (wrapped), or,
    given the chain (``poe``) and its target, joined to it by a straight joint-space segment (at most
    ``reach`` rad long) on which the pose error stays <= ``path_tol`` (m and rad).

    The second test is for ill-conditioned poses (near a singularity): there the points within a solver's
    tolerance of the target form a curve up to ~1e-3 rad long, and two solvers return different points on it
    (or two roots 1e-4 rad apart, which no tolerance tells from one branch). Distinct branches are never
    joined that way: between two roots a straight segment leaves the target by ~ sigma_min(J) * distance."""
    required = np.atleast_2d(required)
    found = np.atleast_2d(found)
    if len(required) == 0 or found.size == 0:
        return required
    d = wrapped_distance(required, found)
    gone = d.min(axis=1) > tol
    if poe is None or not gone.any():
        return required[gone]
    t = np.linspace(0.0, 1.0, 33)[:, None]
    for k in np.flatnonzero(gone):
        for m in np.flatnonzero(d[k] <= reach):
            step = np.mod(found[m] - required[k] + np.pi, 2 * np.pi) - np.pi
            path = required[k] + t * step
            R, p, _ = poe.fk_jacobian(path)
            e = _error(R, p, np.broadcast_to(T_target[:3, :3], R.shape), np.broadcast_to(T_target[:3, 3], p.shape))
            if np.linalg.norm(e[:, :3], axis=1).max() <= path_tol and np.linalg.norm(e[:, 3:], axis=1).max() <= path_tol:
                gone[k] = False
                break
    return required[gone]


def pin_errors(model: pin.Model, data: pin.Data, frame_id: int, q: np.ndarray, T_target: np.ndarray) -> np.ndarray:
    """(K, 2): position (m) and orientation (rad) error of Pinocchio's FK at each row of q (K, n) against T_target (4, 4)."""
    target = pin.SE3(T_target[:3, :3], T_target[:3, 3])
    out = np.empty((len(q), 2))
    for k, qk in enumerate(q):
        pin.framesForwardKinematics(model, data, np.asarray(qk, dtype=float))
        oMf = data.oMf[frame_id]
        out[k, 0] = np.linalg.norm(oMf.translation - target.translation)
        out[k, 1] = np.linalg.norm(pin.log6(oMf.actInv(target)).angular)
    return out


def _exact_set(model, data, frame_id, q, T_target, lower, upper):
    """Wrap into the ranges, drop those outside, de-duplicate, keep those Pinocchio confirms exact."""
    if len(q) == 0:
        return np.zeros((0, model.nq))
    w, inside = wrap_like_capmap(q, lower, upper)
    w = dedupe(w[inside.all(axis=1)])
    if len(w) == 0:
        return w
    err = pin_errors(model, data, frame_id, w, T_target)
    return w[(err[:, 0] <= EXACT_TOL) & (err[:, 1] <= EXACT_TOL)]


# --------------------------------------------------------------------------- oracle 1: random restarts


def _levenberg_marquardt(poe: PoE, q: np.ndarray, R_t: np.ndarray, p_t: np.ndarray, iters: int) -> tuple[np.ndarray, np.ndarray]:
    """LM with adaptive damping per start; (q, converged) with converged = |error| <= EXACT_TOL (a start stops
    at _CONVERGED; one near a singular solution, where the convergence is slow, still counts at EXACT_TOL)."""
    B, n = q.shape
    lam = np.full(B, 1e-2)
    R, p, J = poe.fk_jacobian(q)
    e = _error(R, p, R_t, p_t)
    cost = np.einsum("bi,bi->b", e, e)
    active = np.arange(B)
    eye = np.eye(n)
    for _ in range(iters):
        done = cost[active] <= _CONVERGED**2
        stalled = lam[active] > 1e8  # no descent at any damping: a local minimum (singular J), give up
        active = active[~(done | stalled)]
        if len(active) == 0:
            break
        Ja, ea = J[active], e[active]
        JtJ = np.swapaxes(Ja, 1, 2) @ Ja
        g = np.einsum("bji,bj->bi", Ja, ea)
        # Levenberg's damping, relative to the scale of J^T J (so it works for metre and radian rows alike)
        scale = np.trace(JtJ, axis1=1, axis2=2) / n
        A = JtJ + (lam[active] * scale)[:, None, None] * eye
        dq = np.linalg.solve(A, g[..., None])[..., 0]
        big = np.abs(dq).max(axis=1, keepdims=True)
        dq *= np.minimum(1.0, 0.5 / np.maximum(big, 1e-300))  # at most 0.5 rad per step
        qn = q[active] + dq
        Rn, pn, Jn = poe.fk_jacobian(qn)
        en = _error(Rn, pn, R_t[active], p_t[active])
        cn = np.einsum("bi,bi->b", en, en)
        better = cn < cost[active]
        acc = active[better]
        q[acc], J[acc], e[acc], cost[acc] = qn[better], Jn[better], en[better], cn[better]
        lam[acc] = np.maximum(lam[acc] / 5, 1e-15)
        lam[active[~better]] *= 4
    return q, cost <= EXACT_TOL**2


def _newton_polish(poe: PoE, q: np.ndarray, R_t: np.ndarray, p_t: np.ndarray, steps: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Undamped Newton steps (each kept only where it lowers the error), then (q, |error| <= _CONVERGED).

    An LM start stopped at EXACT_TOL near a singular solution can sit up to ~1e-4 rad from the root on a
    flat valley; the Newton steps take it to the root, so such points neither pose as extra solutions nor
    stay apart from the root they belong to."""
    R, p, J = poe.fk_jacobian(q)
    e = _error(R, p, R_t, p_t)
    cost = np.einsum("bi,bi->b", e, e)
    for _ in range(steps):
        try:
            dq = np.linalg.solve(J, e[..., None])[..., 0]
        except np.linalg.LinAlgError:  # an exactly singular J somewhere in the batch
            dq = np.array([np.linalg.lstsq(Jk, ek, rcond=None)[0] for Jk, ek in zip(J, e)]).reshape(q.shape)
        ok = np.all(np.isfinite(dq), axis=1)
        qn = np.where(ok[:, None], q + np.where(ok[:, None], dq, 0.0), q)
        Rn, pn, Jn = poe.fk_jacobian(qn)
        en = _error(Rn, pn, R_t, p_t)
        cn = np.einsum("bi,bi->b", en, en)
        better = ok & (cn < cost)
        q[better], J[better], e[better], cost[better] = qn[better], Jn[better], en[better], cn[better]
    return q, cost <= _CONVERGED**2


def random_restart(model: pin.Model, data: pin.Data, frame_id: int, T_target: np.ndarray, lower: np.ndarray,
                   upper: np.ndarray, rng: np.random.Generator, n_starts: int, iters: int = 150) -> list[np.ndarray]:
    """Every distinct solution found from ``n_starts`` uniformly random starts in [lower, upper] per target.

    T_target (4, 4) or (N, 4, 4). Returns one array (K_i, n) rad per target: wrapped as capmap wraps
    (:func:`wrap_like_capmap`), inside the ranges, distinct (> DEDUPE_TOL apart), each exact by
    Pinocchio's FK (position and orientation error <= EXACT_TOL).
    """
    T = np.asarray(T_target, dtype=float).reshape(-1, 4, 4)
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    poe = PoE(model, data, frame_id)
    N, n = len(T), poe.n
    q = rng.uniform(lower, upper, (N * n_starts, n))
    R_t = np.repeat(T[:, :3, :3], n_starts, axis=0)
    p_t = np.repeat(T[:, :3, 3], n_starts, axis=0)
    out = []
    chunk = max(1, 40000 // n_starts)  # targets per batch: bounded memory
    for a in range(0, N, chunk):
        sl = slice(a * n_starts, min(N, a + chunk) * n_starts)
        qa, conv = _levenberg_marquardt(poe, q[sl].copy(), R_t[sl], p_t[sl], iters)
        qa[conv], conv[conv] = _newton_polish(poe, qa[conv], R_t[sl][conv], p_t[sl][conv])
        for i in range(a, min(N, a + chunk)):
            rows = slice((i - a) * n_starts, (i - a + 1) * n_starts)
            out.append(_exact_set(model, data, frame_id, qa[rows][conv[rows]], T[i], lower, upper))
    return out


# --------------------------------------------------------------------------- oracle 2: EAIK


class EAIKOracle:
    """EAIK's closed form for the chain of a serial 6R Pinocchio model (axes H and offsets P at q = 0)."""

    def __init__(self, model: pin.Model, data: pin.Data, frame_id: int):
        from eaik.IK_HP import HPRobot

        self.model, self.data, self.frame_id = model, data, frame_id
        self.poe = PoE(model, data, frame_id)
        H = self.poe.w
        P = np.vstack([self.poe.r[:1], np.diff(self.poe.r, axis=0), self.poe.M[None, :3, 3] - self.poe.r[-1:]])
        self.R_home = self.poe.M[:3, :3]
        try:
            self.robot = HPRobot(H, P)  # its tool frame is the base frame's orientation at q = 0
        except RuntimeError as exc:  # EAIK refuses some geometries outright (e.g. parallel axes it meant to intersect)
            self.robot, self.covered, self.family = None, False, f"refused: {exc}"
            return
        self.family = str(self.robot.getKinematicFamily())
        self.covered = bool(self.robot.hasKnownDecomposition()) and self._probe()

    def _probe(self, n: int = 4) -> bool:
        """Whether EAIK demonstrably solves the chain: at n seeded random configurations (joint ranges
        +-pi) the configuration itself is among its exact solutions. (EAIK 1.2.2 classifies some chains,
        e.g. ``6R-SPHERICAL_NO_PARALLEL_NO_INTERSECTING``, as known and then returns no solution at all.)"""
        q = np.random.default_rng(0).uniform(-np.pi, np.pi, (n, self.poe.n))
        lim = np.full(self.poe.n, np.pi)
        for qk, found in zip(q, self.solve(self.poe.fk(q), -lim, lim)):
            if len(missing(qk[None], found)):
                self.family += " (claimed, but does not return the configuration a pose came from)"
                return False
        return True

    def to_eaik(self, T: np.ndarray) -> np.ndarray:
        """A target of the model's frame as the pose EAIK's tool frame must reach."""
        out = np.array(T, dtype=float)
        out[..., :3, :3] = out[..., :3, :3] @ self.R_home.T
        return out

    def raw(self, T: np.ndarray) -> np.ndarray:
        """EAIK's solutions (K, 6) not flagged least-squares, unchecked."""
        sol = self.robot.IK(self.to_eaik(T))
        Q = np.asarray(sol.Q, dtype=float).reshape(-1, self.poe.n)
        ls = np.asarray(sol.is_LS, dtype=bool).reshape(-1)
        return Q[~ls] if len(ls) == len(Q) else Q

    def solve(self, T_target: np.ndarray, lower: np.ndarray, upper: np.ndarray, polish: int = 3) -> list[np.ndarray]:
        """Per target (4, 4) or (N, 4, 4): EAIK's exact solutions, polished by ``polish`` Newton steps on
        the PoE (from 1e-6 at most: a branch cannot change), checked by Pinocchio, wrapped, de-duplicated."""
        T = np.asarray(T_target, dtype=float).reshape(-1, 4, 4)
        out = []
        for Ti in T:
            Q = self.raw(Ti)
            if len(Q):
                R_t, p_t = np.broadcast_to(Ti[:3, :3], (len(Q), 3, 3)), np.broadcast_to(Ti[:3, 3], (len(Q), 3))
                R, p, _ = self.poe.fk_jacobian(Q)
                close = np.abs(_error(R, p, R_t, p_t)).max(axis=1) <= 1e-6
                Q = Q[close]
                for _ in range(polish):
                    R, p, J = self.poe.fk_jacobian(Q)
                    e = _error(R, p, R_t[: len(Q)], p_t[: len(Q)])
                    Q = Q + np.array([np.linalg.lstsq(Jk, ek, rcond=None)[0] for Jk, ek in zip(J, e)]).reshape(Q.shape)
            out.append(_exact_set(self.model, self.data, self.frame_id, Q, Ti, lower, upper))
        return out
