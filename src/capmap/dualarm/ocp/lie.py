"""SO(3) and SE(3) logarithms and their Jacobians as compiled kernels (numba), for the node models.

The formulas are Pinocchio's (``pinocchio/spatial/log.hxx``: ``log3``, ``Jlog3``, ``log6``,
``Jlog6``), written for one 3x3 rotation R and translation p at a time, so a node model can call
them without leaving compiled code. ``Jlog3(theta, w)`` is the derivative of log3(R) by a right
(local) perturbation of R; ``Jlog6`` likewise for SE(3), rows (linear; angular), columns the local
twist (linear; angular). Tests: tests/dualarm/test_lie.py against Pinocchio, near 0 and pi too.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["log3", "jlog3", "log6", "jlog6", "PREC2", "PREC3"]

_EPS = np.finfo(float).eps
PREC2 = _EPS ** (1.0 / 3.0)  # Pinocchio's TaylorSeriesExpansion<double>::precision<2>()
PREC3 = _EPS ** (1.0 / 4.0)  # precision<3>()
_jit = numba.njit(cache=True)  # plain calls (numba's IR inlining, inline="always", compiles several times slower)


@_jit
def _theta_axis(i0, val, R, axis):
    """Angle and unit axis from the symmetric part of R near theta = pi (Pinocchio's
    compute_theta_axis); writes axis, returns the angle."""
    i1, i2 = (i0 + 1) % 3, (i0 + 2) % 3
    s = np.sqrt(val + _EPS + _EPS * _EPS) * (1.0 if R[i2, i1] >= R[i1, i2] else -1.0)
    axis[i0] = s / 2.0
    axis[i1] = (R[i1, i0] + R[i0, i1]) / (2.0 * s)
    axis[i2] = (R[i2, i0] + R[i0, i2]) / (2.0 * s)
    w = (R[i2, i1] - R[i1, i2]) / (2.0 * s)
    n = np.sqrt(axis[0] ** 2 + axis[1] ** 2 + axis[2] ** 2)
    axis[0] /= n
    axis[1] /= n
    axis[2] /= n
    return 2.0 * np.arctan2(n, w)


@_jit
def log3(R, out):
    """out (3,) = log3(R) for a rotation R (3, 3); returns theta = |out| in [0, pi]."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    c = (tr - 1.0) / 2.0
    ax, ay, az = (R[2, 1] - R[1, 2]) / 2.0, (R[0, 2] - R[2, 0]) / 2.0, (R[1, 0] - R[0, 1]) / 2.0
    if c < -1.0 + PREC2:  # near pi: the axis from the symmetric part
        best, i0 = -np.inf, 0
        for i in range(3):
            v = 2.0 * R[i, i] - tr + 1.0
            if v > best:
                best, i0 = v, i
        theta = _theta_axis(i0, best, R, out)
        for i in range(3):
            out[i] *= theta
        return theta
    e = np.sqrt(2.0 * (1.0 - c) + _EPS * _EPS)
    if tr > 3.0 - PREC2:
        theta = e
    elif tr < -1.0 + PREC2:
        theta = np.pi - e
    else:
        theta = np.arccos(c)
    if theta >= PREC2:
        t = theta / np.sin(theta)
    else:
        n2 = ax * ax + ay * ay + az * az
        t = 1.0 + n2 / 6.0 + n2 * n2 * 3.0 / 40.0
    out[0], out[1], out[2] = t * ax, t * ay, t * az
    return theta


@_jit
def _add_half_skew(v, M):
    """M (3, 3) += skew(v) / 2 (Pinocchio's addSkew(0.5 v, M))."""
    M[0, 1] -= 0.5 * v[2]
    M[0, 2] += 0.5 * v[1]
    M[1, 0] += 0.5 * v[2]
    M[1, 2] -= 0.5 * v[0]
    M[2, 0] -= 0.5 * v[1]
    M[2, 1] += 0.5 * v[0]


@_jit
def jlog3(theta, w, J):
    """J (3, 3) = Jlog3 at log w (3,) of angle theta."""
    st, ct = np.sin(theta), np.cos(theta)
    if theta < PREC3:
        alpha = 1.0 / 12.0 + theta * theta / 720.0
        diag = 0.5 * (2.0 - theta * theta / 6.0)
    else:
        st_1mct = st / (1.0 - ct)
        alpha = 1.0 / (theta * theta) - st_1mct / (2.0 * theta)
        diag = 0.5 * theta * st_1mct
    for i in range(3):
        for j in range(3):
            J[i, j] = alpha * w[i] * w[j]
        J[i, i] += diag
    _add_half_skew(w, J)


@_jit
def log6(R, p, out):
    """out (6,) = log6(R, p) (linear; angular); returns theta."""
    w = out[3:]
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    ax, ay, az = (R[2, 1] - R[1, 2]) / 2.0, (R[0, 2] - R[2, 0]) / 2.0, (R[1, 0] - R[0, 1]) / 2.0
    t2 = ax * ax + ay * ay + az * az
    theta = log3(R, w)
    if tr >= 3.0 - PREC2:
        alpha = 1.0 - t2 / 12.0 - t2 * t2 / 720.0
        beta = 1.0 / 12.0 + t2 / 720.0
    else:
        st, ct = np.sin(theta), np.cos(theta)
        alpha = theta * st / (2.0 * (1.0 - ct))
        beta = 1.0 / (theta * theta) - st / (2.0 * theta * (1.0 - ct))
    wp = w[0] * p[0] + w[1] * p[1] + w[2] * p[2]
    out[0] = alpha * p[0] - 0.5 * (w[1] * p[2] - w[2] * p[1]) + beta * wp * w[0]
    out[1] = alpha * p[1] - 0.5 * (w[2] * p[0] - w[0] * p[2]) + beta * wp * w[1]
    out[2] = alpha * p[2] - 0.5 * (w[0] * p[1] - w[1] * p[0]) + beta * wp * w[2]
    return theta


@_jit
def jlog6(R, p, J):
    """J (6, 6) = Jlog6 of (R, p): [[A, C A], [0, A]] with A = Jlog3 (Pinocchio's Jlog6)."""
    w = np.empty(3)
    t = log3(R, w)
    A = np.empty((3, 3))
    jlog3(t, w, A)
    t2 = t * t
    if t < PREC3:
        beta = 1.0 / 12.0 + t2 / 720.0
        bdot = 1.0 / 360.0
    else:
        st, ct = np.sin(t), np.cos(t)
        tinv = 1.0 / t
        t2inv = tinv * tinv
        inv_2_2ct = 1.0 / (2.0 * (1.0 - ct))
        beta = t2inv - st * tinv * inv_2_2ct
        bdot = -2.0 * t2inv * t2inv + (1.0 + st * tinv) * t2inv * inv_2_2ct
    wp = w[0] * p[0] + w[1] * p[1] + w[2] * p[2]
    C = np.empty((3, 3))
    for i in range(3):
        v3 = bdot * wp * w[i] - (t2 * bdot + 2.0 * beta) * p[i]
        for j in range(3):
            C[i, j] = v3 * w[j] + beta * w[i] * p[j]
        C[i, i] += wp * beta
    _add_half_skew(p, C)
    for i in range(3):
        for j in range(3):
            b = 0.0
            for k in range(3):
                b += C[i, k] * A[k, j]
            J[i, j] = A[i, j]
            J[i + 3, j + 3] = A[i, j]
            J[i, j + 3] = b
            J[i + 3, j] = 0.0
