"""The coefficients of a batch of configurations (compiled), from the recursions of
:mod:`capmap.core.ne_kernels`: per configuration the outputs' gravity term c0, their linear map L of
the end-effector acceleration, the quadratic form Q of its velocity (by polarisation) and the map S of
the force the arm applies to the payload (:class:`capmap.core.coefficients.Coefficients`)."""

from __future__ import annotations

import numba
import numpy as np

from capmap.core.ne_kernels import cross, drift, kinematics, outputs, rnea, rnea_rest, workspace

__all__ = ["batch_coefficients"]

_jit = numba.njit(cache=True)


@_jit
def batch_coefficients(R0, p0, axis, mass, com, Ic, ee_joint, ee_p, gravity, base_com, active, q, c0, L, Q, S, singular):
    B, n = q.shape
    na = len(active)
    Rl = np.empty((n, 3, 3))
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    tau = np.empty(n)
    f1 = np.empty(6)
    y = np.empty(na + 6)
    zero = np.zeros(n)
    zero3 = np.zeros(3)
    ng = -gravity
    J = np.empty((6, na))
    A = np.zeros((3, n))
    Z = np.empty((6, na + 6))
    pee = np.empty(3)
    d = np.empty(3)
    tmp = np.empty(3)
    W = workspace(n)
    V = np.zeros((8, 3))
    dd = np.zeros(6)
    wv = np.zeros(n)
    qdd = np.zeros(n)
    for i in range(B):
        kinematics(R0, p0, axis, q[i], Rl, R, p)
        je = ee_joint
        for b in range(3):
            pee[b] = p[je, b] + R[je, b, 0] * ee_p[0] + R[je, b, 1] * ee_p[1] + R[je, b, 2] * ee_p[2]
        # world-aligned Jacobian of the end-effector point, active joints
        for k in range(na):
            j = active[k]
            z = V[3]
            for b in range(3):
                z[b] = R[j, b, 0] * axis[j, 0] + R[j, b, 1] * axis[j, 1] + R[j, b, 2] * axis[j, 2]
            for b in range(3):
                d[b] = pee[b] - p[j, b]
            cross(z, d, tmp)
            for b in range(3):
                J[b, k] = tmp[b]
                J[3 + b, k] = z[b]
        norm_J = np.abs(J).sum(axis=0).max()
        ok = True
        Jinv = np.zeros((na, 6))
        if np.abs(np.linalg.det(J)) < 1e-300:
            ok = False
        else:
            Jinv = np.linalg.inv(J)
            if norm_J * np.abs(Jinv).sum(axis=0).max() > 1e12:
                ok = False
        if not ok:
            singular[i] = True
            continue
        for r in range(3):
            for k in range(n):
                A[r, k] = 0.0
            for k in range(na):
                A[r, active[k]] = Jinv[k, r]
        # c0: gravity only
        rnea_rest(Rl, p0, axis, mass, com, Ic, zero, ng, tau, f1, W)
        outputs(tau, f1, R, p, base_com, active, y, V)
        c0[i] = y
        # L: qdd = J^-1 e_r, no gravity
        for r in range(3):
            rnea_rest(Rl, p0, axis, mass, com, Ic, A[r], zero3, tau, f1, W)
            outputs(tau, f1, R, p, base_com, active, y, V)
            L[i, :, r] = y
        # Z(w) for the polarisation pairs: qd = w, qdd = -J^-1 Jdot w
        for pidx in range(6):
            if pidx < 3:
                for k in range(n):
                    wv[k] = A[pidx, k]
            else:
                r1, r2 = (0, 1) if pidx == 3 else ((0, 2) if pidx == 4 else (1, 2))
                for k in range(n):
                    wv[k] = A[r1, k] + A[r2, k]
            drift(Rl, p0, axis, wv, R, je, ee_p, dd, V)
            for k in range(n):
                qdd[k] = 0.0
            for k in range(na):
                acc = 0.0
                for c in range(6):
                    acc += Jinv[k, c] * dd[c]
                qdd[active[k]] = -acc
            rnea(Rl, p0, axis, mass, com, Ic, wv, qdd, zero3, je, ee_p, zero3, R, tau, f1, W)
            outputs(tau, f1, R, p, base_com, active, Z[pidx], V)
        for k in range(na + 6):
            Q[i, k, 0] = Z[0, k]
            Q[i, k, 1] = Z[1, k]
            Q[i, k, 2] = Z[2, k]
            Q[i, k, 3] = Z[3, k] - Z[0, k] - Z[1, k]
            Q[i, k, 4] = Z[4, k] - Z[0, k] - Z[2, k]
            Q[i, k, 5] = Z[5, k] - Z[1, k] - Z[2, k]
        # S: the arm applies a unit force e_r to the payload (the payload pushes back with -e_r). At rest and
        # without gravity the RNEA's only force is e_r carried from the end-effector point to the base:
        # tau_j = z_j . ((pee - p_j) x e_r) = J[r, k] (joints up to the end effector's), base force -e_r,
        # base moment about base_com (base_com - pee) x e_r
        for b in range(3):
            d[b] = base_com[b] - pee[b]
        for r in range(3):
            for k in range(na):
                S[i, k, r] = J[r, k] if active[k] <= je else 0.0
            for b in range(3):
                S[i, na + b, r] = -1.0 if b == r else 0.0
        S[i, na + 3, 0], S[i, na + 4, 0], S[i, na + 5, 0] = 0.0, d[2], -d[1]
        S[i, na + 3, 1], S[i, na + 4, 1], S[i, na + 5, 1] = -d[2], 0.0, d[0]
        S[i, na + 3, 2], S[i, na + 4, 2], S[i, na + 5, 2] = d[1], -d[0], 0.0
