"""Compiled recursions of :mod:`capmap.core.batch_dynamics`: forward kinematics, Pinocchio's
recursive Newton-Euler (local joint frames, spatial motion (v, w) at the frame origin, force
(f, n) about it) in general and at rest, the end-effector drift Jdot qd, and the outputs (active
torques, base wrench); :mod:`capmap.core.ne_coefficients` puts them together per configuration."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["cross", "kinematics", "rnea", "rnea_rest", "drift", "outputs", "workspace"]

_jit = numba.njit(cache=True)
_inline = numba.njit(cache=True, inline="always")



@_inline
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@_inline
def _inertia(m, c, Ic, lin, ang, out_l, out_a, tmp):
    """Spatial inertia (mass m, com c, Ic about the com) times the motion (lin, ang):
    linear m (lin + ang x c), angular Ic ang + c x (m (lin + ang x c))."""
    _cross(ang, c, tmp)
    for b in range(3):
        out_l[b] = m * (lin[b] + tmp[b])
    _cross(c, out_l, tmp)
    for b in range(3):
        out_a[b] = Ic[b, 0] * ang[0] + Ic[b, 1] * ang[1] + Ic[b, 2] * ang[2] + tmp[b]


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


@_inline
def _backward(Rl, p0, axis, fl, fn, tau, f1, tmp, tmp2, pf):
    """The RNEA's backward pass over the link forces (fl, fn) (n, 3), in place: tau_j = axis . n_j; parent +=
    X^T f: f_p = Rl f, n_p = Rl n + p x (Rl f); f1 (6,) = joint 1's [f; n]. tmp, tmp2, pf: 3-vectors."""
    for j in range(len(tau) - 1, -1, -1):
        tau[j] = axis[j, 0] * fn[j, 0] + axis[j, 1] * fn[j, 1] + axis[j, 2] * fn[j, 2]
        if j > 0:
            for b in range(3):
                tmp[b] = Rl[j, b, 0] * fl[j, 0] + Rl[j, b, 1] * fl[j, 1] + Rl[j, b, 2] * fl[j, 2]
                tmp2[b] = Rl[j, b, 0] * fn[j, 0] + Rl[j, b, 1] * fn[j, 1] + Rl[j, b, 2] * fn[j, 2]
            _cross(p0[j], tmp, pf)
            for b in range(3):
                fl[j - 1, b] += tmp[b]
                fn[j - 1, b] += tmp2[b] + pf[b]
    for b in range(3):
        f1[b] = fl[0, b]
        f1[3 + b] = fn[0, b]


@_jit
def _rnea(Rl, p0, axis, mass, com, Ic, qd, qdd, a0, ee_joint, ee_p, fext_w, R, tau, f1, W):
    """Pinocchio's RNEA (local frames): joint torques tau (n,) and the spatial force f1 (6,) =
    [f; n] of joint 1 in its local frame. a0: the base's linear acceleration (-gravity);
    fext_w: a force (3,) (world) that the payload applies at the end-effector point.
    W: workspace (7 + n, ... ) of :func:`_workspace` (no allocation here)."""
    n = len(qd)
    v, w, a, al, fl, fn = W[0], W[1], W[2], W[3], W[4], W[5]
    small = W[6]
    tmp, tmp2, hl, ha, gl, ga, pf, fe = small[0], small[1], small[2], small[3], small[4], small[5], small[6], small[7]
    zero3 = small[8]
    for b in range(3):
        zero3[b] = 0.0
    for j in range(n):
        # parent quantities expressed in joint j's frame: X = (Rl^T, p) : v_j = Rl^T (v_p + w_p x p), w_j = Rl^T w_p
        if j == 0:
            vp, wp, ap, alp = zero3, zero3, a0, zero3
        else:
            vp, wp, ap, alp = v[j - 1], w[j - 1], a[j - 1], al[j - 1]
        _cross(wp, p0[j], tmp)
        _cross(alp, p0[j], tmp2)
        for b in range(3):
            sv = 0.0
            sw = 0.0
            sa = 0.0
            sal = 0.0
            for c in range(3):
                sv += Rl[j, c, b] * (vp[c] + tmp[c])
                sw += Rl[j, c, b] * wp[c]
                sa += Rl[j, c, b] * (ap[c] + tmp2[c])
                sal += Rl[j, c, b] * alp[c]
            v[j, b] = sv
            w[j, b] = sw + axis[j, b] * qd[j]
            a[j, b] = sa
            al[j, b] = sal + axis[j, b] * qdd[j]
        # + v_j x (S qd): (v x s, w x s) with s = axis qd (w before adding its own rate: same, s x s = 0)
        for b in range(3):
            tmp[b] = axis[j, b] * qd[j]
        _cross(v[j], tmp, tmp2)
        for b in range(3):
            a[j, b] += tmp2[b]
        _cross(w[j], tmp, tmp2)
        for b in range(3):
            al[j, b] += tmp2[b]
        # f = I a + v x* (I v); I: mass m, com c, Ic about the com
        m = mass[j]
        c = com[j]
        _inertia(m, c, Ic[j], v[j], w[j], hl, ha, tmp)  # h = I v
        _inertia(m, c, Ic[j], a[j], al[j], gl, ga, tmp)  # I a
        # v x* h = (w x hl, w x ha + v x hl)
        _cross(w[j], hl, tmp)
        for b in range(3):
            fl[j, b] = gl[b] + tmp[b]
        _cross(w[j], ha, tmp)
        _cross(v[j], hl, tmp2)
        for b in range(3):
            fn[j, b] = ga[b] + tmp[b] + tmp2[b]
    # the payload's force at the end-effector point, into the ee joint's frame (about its origin)
    je = ee_joint
    for b in range(3):
        fe[b] = R[je, 0, b] * fext_w[0] + R[je, 1, b] * fext_w[1] + R[je, 2, b] * fext_w[2]
    _cross(ee_p, fe, tmp)
    for b in range(3):
        fl[je, b] -= fe[b]
        fn[je, b] -= tmp[b]
    _backward(Rl, p0, axis, fl, fn, tau, f1, tmp, tmp2, pf)


@_jit
def _rnea_rest(Rl, p0, axis, mass, com, Ic, qdd, a0, tau, f1, W):
    """:func:`_rnea` at rest (qd = 0) and without an external force: the velocity terms vanish, so
    only the accelerations go forward and f = I a comes back (the same recursion, a third of the work)."""
    n = len(qdd)
    a, al, fl, fn = W[2], W[3], W[4], W[5]
    small = W[6]
    tmp, tmp2, gl, ga, pf = small[0], small[1], small[4], small[5], small[6]
    for j in range(n):
        if j == 0:
            for b in range(3):
                tmp2[b] = a0[b]
                tmp[b] = 0.0
        else:
            _cross(al[j - 1], p0[j], tmp2)
            for b in range(3):
                tmp2[b] += a[j - 1, b]
                tmp[b] = al[j - 1, b]
        for b in range(3):
            a[j, b] = Rl[j, 0, b] * tmp2[0] + Rl[j, 1, b] * tmp2[1] + Rl[j, 2, b] * tmp2[2]
            al[j, b] = Rl[j, 0, b] * tmp[0] + Rl[j, 1, b] * tmp[1] + Rl[j, 2, b] * tmp[2] + axis[j, b] * qdd[j]
        _inertia(mass[j], com[j], Ic[j], a[j], al[j], gl, ga, tmp)
        for b in range(3):
            fl[j, b] = gl[b]
            fn[j, b] = ga[b]
    _backward(Rl, p0, axis, fl, fn, tau, f1, tmp, tmp2, pf)


@_jit
def _workspace(n):
    """Work arrays of :func:`_rnea`: six (n, 3) recursions and nine 3-vectors (padded to (n, 3))."""
    return np.zeros((7, max(n, 9), 3))


@_jit
def _drift(Rl, p0, axis, qd, R, ee_joint, ee_p, out, V):
    """Jdot qd: the end-effector point's classical linear acceleration and the body's angular
    acceleration (6,) at qdd = 0, world axes. V: workspace (8, 3)."""
    v, w, a, al, nv, nw, tmp, tmp2 = V[0], V[1], V[2], V[3], V[4], V[5], V[6], V[7]
    for b in range(3):
        v[b] = 0.0
        w[b] = 0.0
        a[b] = 0.0
        al[b] = 0.0
    for j in range(ee_joint + 1):
        _cross(w, p0[j], tmp)
        _cross(al, p0[j], tmp2)
        for b in range(3):
            nv[b] = Rl[j, 0, b] * (v[0] + tmp[0]) + Rl[j, 1, b] * (v[1] + tmp[1]) + Rl[j, 2, b] * (v[2] + tmp[2])
            nw[b] = Rl[j, 0, b] * w[0] + Rl[j, 1, b] * w[1] + Rl[j, 2, b] * w[2] + axis[j, b] * qd[j]
        for b in range(3):  # a, al into the new frame (tmp2 = al_p x p), in place after use
            x = Rl[j, 0, b] * (a[0] + tmp2[0]) + Rl[j, 1, b] * (a[1] + tmp2[1]) + Rl[j, 2, b] * (a[2] + tmp2[2])
            tmp[b] = x
        for b in range(3):
            a[b] = tmp[b]
        for b in range(3):
            tmp[b] = Rl[j, 0, b] * al[0] + Rl[j, 1, b] * al[1] + Rl[j, 2, b] * al[2]
        for b in range(3):
            al[b] = tmp[b]
        for b in range(3):
            tmp[b] = axis[j, b] * qd[j]
        _cross(nv, tmp, tmp2)
        for b in range(3):
            a[b] += tmp2[b]
        _cross(nw, tmp, tmp2)
        for b in range(3):
            al[b] += tmp2[b]
            v[b] = nv[b]
            w[b] = nw[b]
    # at the ee point e (local): v_e = v + w x e, a_e(spatial) = a + al x e; classical = a_e + w x v_e
    _cross(w, ee_p, tmp)
    for b in range(3):
        nv[b] = v[b] + tmp[b]  # v_e
    _cross(al, ee_p, tmp)
    _cross(w, nv, tmp2)
    for b in range(3):
        nw[b] = a[b] + tmp[b] + tmp2[b]  # classical, local
    for b in range(3):
        out[b] = R[ee_joint, b, 0] * nw[0] + R[ee_joint, b, 1] * nw[1] + R[ee_joint, b, 2] * nw[2]
        out[3 + b] = R[ee_joint, b, 0] * al[0] + R[ee_joint, b, 1] * al[1] + R[ee_joint, b, 2] * al[2]


@_jit
def _outputs(tau, f1, R, p, base_com, active, out, V):
    """[tau_active; base force; base moment about base_com] from RNEA results; V: workspace (>= 3, 3)."""
    na = len(active)
    for k in range(na):
        out[k] = tau[active[k]]
    F, M, tmp = V[0], V[1], V[2]
    for b in range(3):
        F[b] = R[0, b, 0] * f1[0] + R[0, b, 1] * f1[1] + R[0, b, 2] * f1[2]
    _cross(p[0], F, tmp)
    for b in range(3):
        M[b] = R[0, b, 0] * f1[3] + R[0, b, 1] * f1[4] + R[0, b, 2] * f1[5] + tmp[b]
    _cross(base_com, F, tmp)
    for b in range(3):
        out[na + b] = -F[b]
        out[na + 3 + b] = -M[b] + tmp[b]


cross, kinematics, rnea, rnea_rest = _cross, _kinematics, _rnea, _rnea_rest  # the names other modules call
drift, outputs, workspace = _drift, _outputs, _workspace
