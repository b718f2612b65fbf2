"""Joint torques of a dual-arm motion that holds a rigid part in both grippers: inverse dynamics with
the part's inertia and weight and the internal force of the closed chain.

At each node, with the arms' q, v, a (the optimiser's input is the acceleration; the held part's
weight and the internal force are not in its model, so the torques are checked here, afterwards):

1. the part's motion from the left arm (the closed chain holds to ~1e-8 m): its spatial velocity v_P
   and acceleration a_P in its own frame, and the wrench the grippers must apply to it,
   f_P = I (a_P - g_P) + v_P x* (I v_P)  (g_P: gravity as a base acceleration, in the part's frame);
2. the grippers' wrenches W = [w_L; w_R] (each the wrench a gripper applies to the part, in the
   gripper's frame) satisfy the grasp map G W = f_P, G = [X_L*, X_R*] (the dual action matrices
   that carry a wrench from a gripper's frame to the part's): six equations for twelve unknowns,
   the other six the internal (squeezing and twisting) wrench of the closed chain;
3. joint torques tau = RNEA(q, v, a) + J_L' w_L + J_R' w_R (frame Jacobians in the grippers' own
   frames: the part pushes back on each gripper with -w).

The internal wrench is the one a torque-sharing controller would apply: W = W_0 + N z with W_0 =
G^+ f_P (the least-norm distribution) and N a basis of G's null space, z minimising the largest
torque relative to its limit, max_j |tau_j| / limit_j (a linear programme in z and the bound: the
smallest peak any internal wrench allows at that node). The least-norm distribution's torques are
returned as well (what a controller that ignores the internal force would see)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy import sparse
from scipy.optimize import linprog

__all__ = ["HeldPart", "HeldTorques", "held_torques", "part_wrench"]


@dataclass(frozen=True)
class HeldPart:
    """The held part: its frame id in the model, mass kg, centre of mass (3,) m and inertia (3, 3)
    kg m^2 about it, both in the part's frame."""

    frame: int
    mass_kg: float
    com_m: np.ndarray
    inertia_kgm2: np.ndarray

    def inertia(self) -> pin.Inertia:
        return pin.Inertia(self.mass_kg, np.asarray(self.com_m, float), np.asarray(self.inertia_kgm2, float))


@dataclass(frozen=True)
class HeldTorques:
    """Per node (K nodes, nv joints): tau_nm (K, nv) with the peak-minimising internal wrench and
    tau_least_norm_nm (K, nv) with the least-norm one; the grippers' wrenches on the part w_left,
    w_right (K, 6) [force N; moment N m] in their frames; the part's required wrench f_part (K, 6)
    in its frame; the grasp-map residual |G W - f_P| (K,)."""

    tau_nm: np.ndarray
    tau_least_norm_nm: np.ndarray
    w_left: np.ndarray
    w_right: np.ndarray
    f_part: np.ndarray
    residual: np.ndarray


def part_wrench(model: pin.Model, data: pin.Data, part: HeldPart) -> np.ndarray:
    """The wrench (6,) [f; n] in the part's frame that moves it as the model's kinematics (already
    computed with q, v, a: :func:`pinocchio.forwardKinematics`) say, against gravity."""
    vP = pin.getFrameVelocity(model, data, part.frame, pin.ReferenceFrame.LOCAL)
    aP = pin.getFrameAcceleration(model, data, part.frame, pin.ReferenceFrame.LOCAL)
    R = data.oMf[part.frame].rotation
    a = aP - pin.Motion(R.T @ model.gravity.linear, np.zeros(3))
    inertia = part.inertia()
    return (inertia * a + vP.cross(inertia * vP)).vector


def _minimax_lp(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z (K, m) minimising max_i |A[k] z[k] + b[k]|_i for each k (A (K, n, m), b (K, n)): the linear
    programmes min t_k s.t. -t_k <= A[k] z[k] + b[k] <= t_k, independent, solved as one block-diagonal
    programme (HiGHS; minimising the sum of the t_k minimises each); if that fails, each alone, and
    z[k] = 0 where one fails (the least-norm distribution)."""
    K, n, m = A.shape
    if K == 0:
        return np.zeros((0, m))
    block = np.concatenate([np.concatenate([A, -A], axis=1), -np.ones((K, 2 * n, 1))], axis=2)  # (K, 2n, m + 1)
    rows = np.broadcast_to(np.arange(K)[:, None, None] * 2 * n + np.arange(2 * n)[None, :, None], block.shape)
    cols = np.broadcast_to(np.arange(K)[:, None, None] * (m + 1) + np.arange(m + 1)[None, None, :], block.shape)
    A_ub = sparse.csr_matrix((block.ravel(), (rows.ravel(), cols.ravel())), shape=(2 * n * K, (m + 1) * K))
    c = np.tile(np.r_[np.zeros(m), 1.0], K)
    res = linprog(c, A_ub=A_ub, b_ub=np.concatenate([-b, b], axis=1).ravel(),
                  bounds=([(None, None)] * m + [(0, None)]) * K, method="highs")
    if res.status == 0:
        return res.x.reshape(K, m + 1)[:, :m]
    if K == 1:
        return np.zeros((1, m))
    return np.vstack([_minimax_lp(A[k:k + 1], b[k:k + 1]) for k in range(K)])  # each alone: one failure costs one


VERTEX_TOL = 1e-9  # relative: a vertex's dual multipliers >= -tol, its rows within (1 + tol) t (HiGHS's own: 1e-7)


def _vertex(A: np.ndarray, b: np.ndarray, rows: np.ndarray, signs: np.ndarray) -> np.ndarray | None:
    """The z (m,) of the vertex of min t s.t. |A z + b| <= t (A (n, m), b (n,)) where the m + 1 ``rows`` hold
    with ``signs`` (sigma_i (a_i z + b_i) = t), when it is the optimum: every row within t and the dual
    multipliers (sum lambda_i sigma_i a_i = 0, sum lambda_i = 1) >= 0, the programme's KKT conditions; else
    None."""
    m = A.shape[1]
    M = np.hstack([signs[:, None] * A[rows], -np.ones((m + 1, 1))])
    try:
        x = np.linalg.solve(M, -signs * b[rows])
        lam = np.linalg.solve(M.T, np.r_[np.zeros(m), -1.0])
    except np.linalg.LinAlgError:
        return None
    z, t = x[:m], x[m]
    if not (lam >= -VERTEX_TOL).all() or not (np.abs(A @ z + b) <= t * (1 + VERTEX_TOL) + VERTEX_TOL).all():
        return None
    return z


def _minimax(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`_minimax_lp`'s z (K, m), the nodes in order: each node first tries the vertex of the previous
    node's active rows (:func:`_vertex`: the optimum when its KKT conditions hold); where they do not, its
    own linear programme, whose active rows (m + 1 of them when not degenerate) the next nodes try. Along a
    motion the active rows change a few times (8 times in 501 nodes on the default task)."""
    K, n, m = A.shape
    z = np.zeros((K, m))
    rows = signs = None
    for k in range(K):
        zk = None if rows is None else _vertex(A[k], b[k], rows, signs)
        if zk is None:
            zk = _minimax_lp(A[k:k + 1], b[k:k + 1])[0]
            r = A[k] @ zk + b[k]
            t = np.abs(r).max()
            act = np.flatnonzero(np.abs(r) >= t * (1 - VERTEX_TOL) - VERTEX_TOL)
            rows, signs = (act, np.sign(r[act])) if len(act) == m + 1 else (None, None)
        z[k] = zk
    return z


def held_torques(model: pin.Model, grippers: tuple[int, int], part: HeldPart, q: np.ndarray, v: np.ndarray,
                 a: np.ndarray, effort_nm: np.ndarray) -> HeldTorques:
    """Joint torques (see the module docstring) of K nodes q, v, a (K, nv) rad, rad/s, rad/s^2;
    ``grippers``: the left and right gripper frame ids; ``effort_nm`` (nv,) the limits that weight
    the internal wrench's choice."""
    q, v, a = (np.atleast_2d(x) for x in (q, v, a))
    K, nv = v.shape
    data = model.createData()
    D = 1.0 / np.asarray(effort_nm, float)
    tau0, base, fp = np.zeros((K, nv)), np.zeros((K, nv)), np.zeros((K, 6))
    W0, N, JT, G = np.zeros((K, 12)), np.zeros((K, 12, 6)), np.zeros((K, nv, 12)), np.zeros((K, 6, 12))
    for k in range(K):
        pin.forwardKinematics(model, data, q[k], v[k], a[k])
        pin.updateFramePlacements(model, data)
        pin.computeJointJacobians(model, data, q[k])
        tau0[k] = pin.rnea(model, data, q[k], v[k], a[k])
        fp[k] = part_wrench(model, data, part)
        oMp = data.oMf[part.frame]
        G[k] = np.hstack([oMp.actInv(data.oMf[g]).toDualActionMatrix() for g in grippers])
        JT[k] = np.hstack([pin.getFrameJacobian(model, data, g, pin.ReferenceFrame.LOCAL).T for g in grippers])
        U, s, Vt = np.linalg.svd(G[k])
        W0[k] = Vt[:6].T @ ((U.T @ fp[k]) / s)  # least norm: G has full row rank (the grippers are distinct frames)
        N[k] = Vt[6:].T  # (12, 6) the internal wrenches
        base[k] = tau0[k] + JT[k] @ W0[k]
    W = W0 + np.einsum("kij,kj->ki", N, _minimax(D[:, None] * (JT @ N), D * base))  # the best internal wrenches
    tau = tau0 + np.einsum("kij,kj->ki", JT, W)
    res = np.linalg.norm(np.einsum("kij,kj->ki", G, W) - fp, axis=1)
    return HeldTorques(tau, base, W[:, :6], W[:, 6:], fp, res)
