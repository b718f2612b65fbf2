"""Compiled recursions of :mod:`capmap.core.batch_dynamics`: forward kinematics, Pinocchio's
recursive Newton-Euler (local joint frames, spatial motion (v, w) at the frame origin, force
(f, n) about it) on :data:`K` right-hand sides at once, at rest or with velocities, the outputs (active
torques, base wrench) and a 6x6 inverse; :mod:`capmap.core.ne_coefficients` puts them together per
configuration.

Layout: every per-link quantity is (n, 3, K) and every temporary (3, K), the right-hand sides on the
last, contiguous axis, so that each step of the recursion (a 3x3 rotation, a cross product) runs as
one short loop over K that the compiler vectorises: the transforms of a joint are read once for all
K columns instead of once per call.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["K", "kinematics", "rest_multi", "velocity_multi", "outputs_multi", "invert", "workspace"]

_jit = numba.njit(cache=True)  # plain calls (numba's IR inlining, inline="always", compiles several times slower)
# K, the right-hand sides of every recursion: a constant of the compiled code, so that each loop over them has a
# known trip count and is unrolled and vectorised whole (no remainder loop; 12 % fewer seconds per configuration
# than the same loops over a run-time K of 7 and 6). Callers fill the columns they need and leave the rest zero.
K = 8


@_jit
def _kinematics(R0, p0, axis, q, Rl, R, p):
    """Local rotations Rl (n,3,3) (parent -> joint), world rotations R and positions p of every joint."""
    n = len(q)
    for j in range(n):
        # Rl = R0[j] Rot(axis_j, q_j) (Rodrigues)
        x, y, z = axis[j, 0], axis[j, 1], axis[j, 2]
        c, s = np.cos(q[j]), np.sin(q[j])
        t = 1.0 - c
        Rot = Rl[j]  # the joint rotation first, then R0[j] Rot in place (row by row)
        Rot[0, 0], Rot[0, 1], Rot[0, 2] = t * x * x + c, t * x * y - s * z, t * x * z + s * y
        Rot[1, 0], Rot[1, 1], Rot[1, 2] = t * x * y + s * z, t * y * y + c, t * y * z - s * x
        Rot[2, 0], Rot[2, 1], Rot[2, 2] = t * x * z - s * y, t * y * z + s * x, t * z * z + c
        r00, r01, r02 = Rot[0, 0], Rot[0, 1], Rot[0, 2]
        r10, r11, r12 = Rot[1, 0], Rot[1, 1], Rot[1, 2]
        r20, r21, r22 = Rot[2, 0], Rot[2, 1], Rot[2, 2]
        for a in range(3):
            x0, x1, x2 = R0[j, a, 0], R0[j, a, 1], R0[j, a, 2]
            Rl[j, a, 0] = x0 * r00 + x1 * r10 + x2 * r20
            Rl[j, a, 1] = x0 * r01 + x1 * r11 + x2 * r21
            Rl[j, a, 2] = x0 * r02 + x1 * r12 + x2 * r22
        if j == 0:
            for a in range(3):
                for b in range(3):
                    R[0, a, b] = Rl[0, a, b]
                p[0, a] = p0[0, a]
        else:
            for a in range(3):
                p[j, a] = p[j - 1, a] + R[j - 1, a, 0] * p0[j, 0] + R[j - 1, a, 1] * p0[j, 1] + R[j - 1, a, 2] * p0[j, 2]
                for b in range(3):
                    R[j, a, b] = R[j - 1, a, 0] * Rl[j, 0, b] + R[j - 1, a, 1] * Rl[j, 1, b] + R[j - 1, a, 2] * Rl[j, 2, b]


@_jit
def _workspace(n):
    """Work arrays for :data:`K` right-hand sides: six per-link (n, 3, K) recursions and eight (3, K) temporaries."""
    return np.zeros((6, n, 3, K)), np.zeros((8, 3, K))


@_jit
def _cross_c(x, c, out, sign):
    """out = sign (x x c): x (3, K), c a constant 3-vector."""
    c0, c1, c2 = c[0], c[1], c[2]
    for r in range(K):
        out[0, r] = sign * (x[1, r] * c2 - x[2, r] * c1)
        out[1, r] = sign * (x[2, r] * c0 - x[0, r] * c2)
        out[2, r] = sign * (x[0, r] * c1 - x[1, r] * c0)


@_jit
def _add_cross(x, y, out):
    """out += x x y, all (3, K)."""
    for r in range(K):
        out[0, r] += x[1, r] * y[2, r] - x[2, r] * y[1, r]
        out[1, r] += x[2, r] * y[0, r] - x[0, r] * y[2, r]
        out[2, r] += x[0, r] * y[1, r] - x[1, r] * y[0, r]


@_jit
def _transform_in(Rj, x, y, out):
    """out = Rj' x + y: x (3, K) from the parent's frame into the joint's, plus y (3, K) already there."""
    for b in range(3):
        r0, r1, r2 = Rj[0, b], Rj[1, b], Rj[2, b]
        for r in range(K):
            out[b, r] = r0 * x[0, r] + r1 * x[1, r] + r2 * x[2, r] + y[b, r]


@_jit
def _inertia(m, c, Ic, lin, ang, out_l, out_a, tmp):
    """Spatial inertia (mass m, com c, Ic about the com) times the motions (lin, ang) (3, K):
    linear m (lin + ang x c), angular Ic ang + c x (m (lin + ang x c))."""
    _cross_c(ang, c, tmp, 1.0)
    for b in range(3):
        for r in range(K):
            out_l[b, r] = m * (lin[b, r] + tmp[b, r])
    _cross_c(out_l, c, tmp, -1.0)
    for b in range(3):
        i0, i1, i2 = Ic[b, 0], Ic[b, 1], Ic[b, 2]
        for r in range(K):
            out_a[b, r] = i0 * ang[0, r] + i1 * ang[1, r] + i2 * ang[2, r] + tmp[b, r]


@_jit
def _backward(Rl, p0, axis, fl, fn, tau, f1, t1, t2):
    """The RNEA's backward pass over the link forces (fl, fn) (n, 3, K), in place: tau_j = axis . n_j;
    parent += X' f: f_p = Rl f, n_p = Rl n + p x (Rl f); f1 (6, K) = joint 1's [f; n]."""
    n = fl.shape[0]
    for j in range(n - 1, -1, -1):
        x0, x1, x2 = axis[j, 0], axis[j, 1], axis[j, 2]
        for r in range(K):
            tau[j, r] = x0 * fn[j, 0, r] + x1 * fn[j, 1, r] + x2 * fn[j, 2, r]
        if j > 0:
            Rj = Rl[j]
            for b in range(3):
                r0, r1, r2 = Rj[b, 0], Rj[b, 1], Rj[b, 2]
                for r in range(K):
                    t1[b, r] = r0 * fl[j, 0, r] + r1 * fl[j, 1, r] + r2 * fl[j, 2, r]
                    t2[b, r] = r0 * fn[j, 0, r] + r1 * fn[j, 1, r] + r2 * fn[j, 2, r]
            px, py, pz = p0[j, 0], p0[j, 1], p0[j, 2]
            for r in range(K):
                for b in range(3):
                    fl[j - 1, b, r] += t1[b, r]
                fn[j - 1, 0, r] += t2[0, r] + py * t1[2, r] - pz * t1[1, r]
                fn[j - 1, 1, r] += t2[1, r] + pz * t1[0, r] - px * t1[2, r]
                fn[j - 1, 2, r] += t2[2, r] + px * t1[1, r] - py * t1[0, r]
    for b in range(3):
        for r in range(K):
            f1[b, r] = fl[0, b, r]
            f1[3 + b, r] = fn[0, b, r]


@_jit
def _rest_multi(Rl, p0, axis, mass, com, Ic, qdd, a0, tau, f1, L, T):
    """The RNEA at rest (qd = 0, no external force) for K right-hand sides: joint accelerations qdd
    (n, K) rad/s^2, the base's linear acceleration a0 (3, K) (-gravity, or 0) -> torques tau (n, K)
    and joint 1's spatial force f1 (6, K). Only the accelerations go forward and f = I a comes back.
    L, T: :func:`_workspace`."""
    n = qdd.shape[0]
    a, al, fl, fn = L[2], L[3], L[4], L[5]
    t1, t2 = T[0], T[1]
    zero = T[7]
    for b in range(3):
        for r in range(K):
            zero[b, r] = 0.0
    for j in range(n):
        Rj = Rl[j]
        if j == 0:
            _transform_in(Rj, a0, zero, a[0])
            _transform_in(Rj, zero, zero, al[0])
        else:
            _cross_c(al[j - 1], p0[j], t2, 1.0)  # the parent's a + al x p
            for b in range(3):
                for r in range(K):
                    t2[b, r] += a[j - 1, b, r]
            _transform_in(Rj, t2, zero, a[j])
            _transform_in(Rj, al[j - 1], zero, al[j])
        for b in range(3):
            x = axis[j, b]
            for r in range(K):
                al[j, b, r] += x * qdd[j, r]
        _inertia(mass[j], com[j], Ic[j], a[j], al[j], fl[j], fn[j], t1)
    _backward(Rl, p0, axis, fl, fn, tau, f1, t1, t2)


@_jit
def _velocity_multi(Rl, p0, axis, mass, com, Ic, qd, R, ee_joint, ee_p, tau, f1, dd, L, T):
    """The RNEA at joint velocities qd (n, K) rad/s with qdd = 0, no gravity and no external force ->
    torques tau (n, K) and f1 (6, K), and from the same forward pass the end-effector drift
    dd (6, K) = Jdot qd: the ee point's classical linear acceleration and the body's angular
    acceleration, world axes. L, T: :func:`_workspace`."""
    n = qd.shape[0]
    v, w, a, al, fl, fn = L[0], L[1], L[2], L[3], L[4], L[5]
    t1, t2, hl, ha = T[0], T[1], T[2], T[3]
    zero = T[7]
    for b in range(3):
        for r in range(K):
            zero[b, r] = 0.0
    for j in range(n):
        Rj = Rl[j]
        x0, x1, x2 = axis[j, 0], axis[j, 1], axis[j, 2]
        if j == 0:
            for b in range(3):
                for r in range(K):
                    v[0, b, r] = 0.0
                    a[0, b, r] = 0.0
                    al[0, b, r] = 0.0
                    w[0, b, r] = axis[0, b] * qd[0, r]
            continue  # v = 0 and w parallel to the axis: no velocity product, f = w x (Ic w) below
        # parent quantities in joint j's frame: v_j = Rl' (v_p + w_p x p), w_j = Rl' w_p + axis qd,
        # a_j = Rl' (a_p + al_p x p) + v_j x s, al_j = Rl' al_p + w_j x s with s = axis qd
        _cross_c(w[j - 1], p0[j], t1, 1.0)
        _cross_c(al[j - 1], p0[j], t2, 1.0)
        for b in range(3):
            for r in range(K):
                t1[b, r] += v[j - 1, b, r]
                t2[b, r] += a[j - 1, b, r]
        _transform_in(Rj, t1, zero, v[j])
        _transform_in(Rj, w[j - 1], zero, w[j])
        _transform_in(Rj, t2, zero, a[j])
        _transform_in(Rj, al[j - 1], zero, al[j])
        for r in range(K):
            s = qd[j, r]
            w[j, 0, r] += x0 * s
            w[j, 1, r] += x1 * s
            w[j, 2, r] += x2 * s
            a[j, 0, r] += (v[j, 1, r] * x2 - v[j, 2, r] * x1) * s
            a[j, 1, r] += (v[j, 2, r] * x0 - v[j, 0, r] * x2) * s
            a[j, 2, r] += (v[j, 0, r] * x1 - v[j, 1, r] * x0) * s
            al[j, 0, r] += (w[j, 1, r] * x2 - w[j, 2, r] * x1) * s
            al[j, 1, r] += (w[j, 2, r] * x0 - w[j, 0, r] * x2) * s
            al[j, 2, r] += (w[j, 0, r] * x1 - w[j, 1, r] * x0) * s
    for j in range(n):
        # f = I a + v x* (I v) = (gl + w x hl, ga + w x ha + v x hl)
        _inertia(mass[j], com[j], Ic[j], v[j], w[j], hl, ha, t1)
        _inertia(mass[j], com[j], Ic[j], a[j], al[j], fl[j], fn[j], t1)
        _add_cross(w[j], hl, fl[j])
        _add_cross(w[j], ha, fn[j])
        _add_cross(v[j], hl, fn[j])
    # the drift at the ee point e (local): v_e = v + w x e; classical a_e = a + al x e + w x v_e
    je = ee_joint
    _cross_c(w[je], ee_p, t1, 1.0)
    for b in range(3):
        for r in range(K):
            t1[b, r] += v[je, b, r]  # v_e
    _cross_c(al[je], ee_p, t2, 1.0)
    for b in range(3):
        for r in range(K):
            t2[b, r] += a[je, b, r]
    _add_cross(w[je], t1, t2)
    for b in range(3):
        r0, r1, r2 = R[je, b, 0], R[je, b, 1], R[je, b, 2]
        for r in range(K):
            dd[b, r] = r0 * t2[0, r] + r1 * t2[1, r] + r2 * t2[2, r]
            dd[3 + b, r] = r0 * al[je, 0, r] + r1 * al[je, 1, r] + r2 * al[je, 2, r]
    _backward(Rl, p0, axis, fl, fn, tau, f1, t1, t2)


@_jit
def _outputs_multi(tau, f1, R, p, base_com, active, out):
    """[tau_active; base force; base moment about base_com] (n_out, K) from RNEA results tau (n, K),
    f1 (6, K)."""
    na = len(active)
    for r in range(K):
        for k in range(na):
            out[k, r] = tau[active[k], r]
        F0 = R[0, 0, 0] * f1[0, r] + R[0, 0, 1] * f1[1, r] + R[0, 0, 2] * f1[2, r]
        F1 = R[0, 1, 0] * f1[0, r] + R[0, 1, 1] * f1[1, r] + R[0, 1, 2] * f1[2, r]
        F2 = R[0, 2, 0] * f1[0, r] + R[0, 2, 1] * f1[1, r] + R[0, 2, 2] * f1[2, r]
        M0 = R[0, 0, 0] * f1[3, r] + R[0, 0, 1] * f1[4, r] + R[0, 0, 2] * f1[5, r] + p[0, 1] * F2 - p[0, 2] * F1
        M1 = R[0, 1, 0] * f1[3, r] + R[0, 1, 1] * f1[4, r] + R[0, 1, 2] * f1[5, r] + p[0, 2] * F0 - p[0, 0] * F2
        M2 = R[0, 2, 0] * f1[3, r] + R[0, 2, 1] * f1[4, r] + R[0, 2, 2] * f1[5, r] + p[0, 0] * F1 - p[0, 1] * F0
        c0, c1, c2 = base_com[0], base_com[1], base_com[2]
        out[na, r] = -F0
        out[na + 1, r] = -F1
        out[na + 2, r] = -F2
        out[na + 3, r] = -M0 + c1 * F2 - c2 * F1
        out[na + 4, r] = -M1 + c2 * F0 - c0 * F2
        out[na + 5, r] = -M2 + c0 * F1 - c1 * F0


@_jit
def _invert(J, Jinv, M):
    """Jinv = J^-1 (n, n) by Gauss-Jordan elimination with partial pivoting (no allocation); returns
    |det J| (0 when a pivot vanishes; Jinv is then undefined). M: (n, 2n) workspace."""
    n = J.shape[0]
    for i in range(n):
        for k in range(n):
            M[i, k] = J[i, k]
            M[i, n + k] = 1.0 if i == k else 0.0
    det = 1.0
    for c in range(n):
        piv = c
        big = abs(M[c, c])
        for r in range(c + 1, n):
            if abs(M[r, c]) > big:
                big, piv = abs(M[r, c]), r
        if big == 0.0:
            return 0.0
        if piv != c:
            for k in range(2 * n):
                M[c, k], M[piv, k] = M[piv, k], M[c, k]
        d = M[c, c]
        det *= d
        inv = 1.0 / d
        for k in range(c, 2 * n):
            M[c, k] *= inv
        for r in range(n):
            if r != c:
                f = M[r, c]
                if f != 0.0:
                    for k in range(c, 2 * n):
                        M[r, k] -= f * M[c, k]
    for i in range(n):
        for k in range(n):
            Jinv[i, k] = M[i, n + k]
    return abs(det)


kinematics, rest_multi, velocity_multi = _kinematics, _rest_multi, _velocity_multi  # the names other modules call
outputs_multi, invert, workspace = _outputs_multi, _invert, _workspace
