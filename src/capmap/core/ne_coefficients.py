"""The coefficients of a batch of configurations (compiled), from the recursions of
:mod:`capmap.core.ne_kernels`: per configuration the outputs' gravity term c0, their linear map L of
the end-effector acceleration, the quadratic form Q of its velocity (by polarisation) and the map S of
the force the arm applies to the payload (:class:`capmap.core.coefficients.Coefficients`)."""

from __future__ import annotations

import numba
import numpy as np

from capmap.core.ne_kernels import K, invert, kinematics, outputs_multi, rest_multi, velocity_multi, workspace

__all__ = ["batch_coefficients"]

_jit = numba.njit(cache=True)
_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))  # the polarisation's velocities e_r + e_s (r == s: e_r)


@_jit
def batch_coefficients(R0, p0, axis, mass, com, Ic, armature, ee_joint, ee_p, gravity, base_com, active, q, C, S, singular):
    """Fill C (B, n_out, 10) = [c0, L, Q] (c0 (B, n_out), L (B, n_out, 3), Q (B, n_out, 6): zero on entry),
    S (B, n_out, 3) and singular (B,) for the configurations q (B, n) rad (full joint vectors, the locked
    joint included); armature (n,) kg m^2: each joint's reflected rotor inertia, a torque armature_j qdd_j
    on its joint (Pinocchio's RNEA likewise; the rotor's reaction on the base is not modelled, as there).

    Per configuration: one RNEA at rest on 7 right-hand sides (gravity alone: c0; qdd = J^-1 e_c for
    the six Cartesian accelerations c: L6, whose linear columns are L) and one RNEA with velocities on
    6 right-hand sides (qd = J^-1 w for the polarisation's w, qdd = 0), whose forward pass also gives
    the drift Jdot qd. The velocity outputs at the consistent qdd = -J^-1 Jdot qd are, by linearity in
    qdd, Z(w) = y(w, qdd=0) - L6 Jdot qd; Q follows by polarisation."""
    B, n = q.shape
    na = len(active)
    Rl = np.empty((n, 3, 3))
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    J = np.empty((6, na))
    Jinv = np.zeros((na, 6))
    M = np.empty((6, 12))
    pee = np.empty(3)
    d = np.empty(3)
    LW, TW = workspace(n)
    LV, TV = workspace(n)
    qdd = np.zeros((n, K))
    a0 = np.zeros((3, K))
    qd = np.zeros((n, K))
    tau7 = np.empty((n, K))
    f7 = np.empty((6, K))
    y7 = np.empty((na + 6, K))
    tau6 = np.empty((n, K))
    f6 = np.empty((6, K))
    y6 = np.empty((na + 6, K))
    dd = np.empty((6, K))
    for b in range(3):
        a0[b, 0] = -gravity[b]
    for i in range(B):
        kinematics(R0, p0, axis, q[i], Rl, R, p)
        je = ee_joint
        for b in range(3):
            pee[b] = p[je, b] + R[je, b, 0] * ee_p[0] + R[je, b, 1] * ee_p[1] + R[je, b, 2] * ee_p[2]
        # world-aligned Jacobian of the end-effector point, active joints: [z x (pee - p_j); z]
        for k in range(na):
            j = active[k]
            z0 = R[j, 0, 0] * axis[j, 0] + R[j, 0, 1] * axis[j, 1] + R[j, 0, 2] * axis[j, 2]
            z1 = R[j, 1, 0] * axis[j, 0] + R[j, 1, 1] * axis[j, 1] + R[j, 1, 2] * axis[j, 2]
            z2 = R[j, 2, 0] * axis[j, 0] + R[j, 2, 1] * axis[j, 1] + R[j, 2, 2] * axis[j, 2]
            e0, e1, e2 = pee[0] - p[j, 0], pee[1] - p[j, 1], pee[2] - p[j, 2]
            J[0, k] = z1 * e2 - z2 * e1
            J[1, k] = z2 * e0 - z0 * e2
            J[2, k] = z0 * e1 - z1 * e0
            J[3, k] = z0
            J[4, k] = z1
            J[5, k] = z2
        # singular: a vanishing determinant or a 1-norm condition number above 1e12
        if invert(J, Jinv, M) < 1e-300:
            singular[i] = True
            continue
        nJ = 0.0
        nJi = 0.0
        for k in range(6):
            sJ = 0.0
            sJi = 0.0
            for r in range(6):
                sJ += abs(J[r, k])
                sJi += abs(Jinv[r, k])
            nJ = max(nJ, sJ)
            nJi = max(nJi, sJi)
        if nJ * nJi > 1e12:
            singular[i] = True
            continue
        # at rest: column 0 gravity alone (qdd = 0), column 1 + c: qdd = J^-1 e_c without gravity
        for c in range(6):
            for k in range(na):
                qdd[active[k], 1 + c] = Jinv[k, c]
        rest_multi(Rl, p0, axis, mass, com, Ic, qdd, a0, tau7, f7, LW, TW)
        for k in range(na):  # the drives' reflected rotor inertia: a joint torque armature_j qdd_j (no base wrench)
            j = active[k]
            for c in range(1, 7):
                tau7[j, c] += armature[j] * qdd[j, c]
        outputs_multi(tau7, f7, R, p, base_com, active, y7)
        for k in range(na + 6):
            for r in range(4):  # c0, then L
                C[i, k, r] = y7[k, r]
        # with velocities: qd = J^-1 w for the polarisation's w (linear velocity e_r + e_s), qdd = 0
        for pi in range(6):
            r1, r2 = _PAIRS[pi]
            for k in range(na):
                qd[active[k], pi] = Jinv[k, r1] + (Jinv[k, r2] if r2 != r1 else 0.0)
        velocity_multi(Rl, p0, axis, mass, com, Ic, qd, R, je, ee_p, tau6, f6, dd, LV, TV)
        outputs_multi(tau6, f6, R, p, base_com, active, y6)
        # Z(w) = y(w, 0) - L6 (Jdot qd), into y6; then Q by polarisation
        for k in range(na + 6):
            for pi in range(6):
                acc = y6[k, pi]
                for c in range(6):
                    acc -= y7[k, 1 + c] * dd[c, pi]
                y6[k, pi] = acc
            C[i, k, 4] = y6[k, 0]  # Q
            C[i, k, 5] = y6[k, 1]
            C[i, k, 6] = y6[k, 2]
            C[i, k, 7] = y6[k, 3] - y6[k, 0] - y6[k, 1]
            C[i, k, 8] = y6[k, 4] - y6[k, 0] - y6[k, 2]
            C[i, k, 9] = y6[k, 5] - y6[k, 1] - y6[k, 2]
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
