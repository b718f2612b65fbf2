"""Compiled kernel of the semi-analytical IK (see :mod:`capmap.core.ik`): for a target pose and
a joint-0 angle, the four branches of joints 1-5 in closed form and the residual of the planar
2R group. The 1-D search evaluates it about 1,500 times per target (the resultant polynomial of
:mod:`capmap.core.ik.semi.resultant` once per root), so it is a scalar loop
compiled with numba, and carries angles as cosines and sines (about 0.3 us per evaluation
against 13 us for the same steps in numpy).

Chain constants (:class:`SemiConstants`) are packed by :func:`pack` into one float array ``c`` so
the kernel takes plain arrays:
    c[0:112]    X (7, 4, 4), the chain's fixed transforms
    c[112:115]  u: the wrist point in the tip frame (X[6]^-1 (0, 0, s*))
    c[115:118]  wc: the wrist point in the link of joint 3
    c[118:121]  n1, c[121:124] t1: axis and origin of joint 2 in frame 1
    c[124:127]  a: the parallel axis in frame 4
    c[127] h, c[128] sigma, c[129] reach
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from capmap.core.kinematics import inverse_transform

__all__ = ["SemiConstants", "pack", "evaluate", "evaluate_grid", "evaluate_branch", "residuals", "branch_angles"]

_jit = numba.njit(cache=True)
_inline = numba.njit(cache=True, inline="always")


@dataclass(frozen=True)
class SemiConstants:
    """Fixed quantities of a ``semi_analytic_shape`` chain (all but s* packed into the kernel's array)."""

    s_star: float  # axis 5 meets axis 4 at (0, 0, s*) in frame 5
    wc: np.ndarray  # (3,) that point in the link of joint 3
    h: float  # its coordinate along the parallel axes (frame 2)
    n1: np.ndarray  # (3,) axis of joint 2 in frame 1
    t1: np.ndarray  # (3,) origin of frame 2 in frame 1
    sigma: float  # +-1: axis 3 along or against axis 2
    a: np.ndarray  # (3,) the parallel axis in frame 4 coordinates
    reach: float  # m, in-plane distance from axis 2 to axis 3

    def packed(self, X: np.ndarray) -> np.ndarray:
        """The kernel's constant array (130,) of the chain with fixed transforms X (7, 4, 4) (:func:`pack`)."""
        u = (inverse_transform(X[6]) @ np.array([0, 0, self.s_star, 1.0]))[:3]
        return pack(X, u, self)

    @classmethod
    def of(cls, X: np.ndarray) -> "SemiConstants":
        """From the chain's fixed transforms X (7, 4, 4)."""
        p5, d5 = X[5][:3, 3], X[5][:3, 2]
        s_star = -(p5[:2] @ d5[:2]) / (d5[:2] @ d5[:2])
        wc = (X[4] @ np.array([0, 0, p5[2] + s_star * d5[2], 1.0]))[:3]
        return cls(s_star=float(s_star), wc=wc, h=float((X[3] @ np.append(wc, 1.0))[2]), n1=X[2][:3, 2],
                   t1=X[2][:3, 3], sigma=float(X[3][2, 2]), a=X[4][2, :3], reach=float(np.hypot(*X[3][:2, 3])))


def pack(X: np.ndarray, u: np.ndarray, semi: SemiConstants) -> np.ndarray:
    """The kernel's constant array (130,) from the chain transforms X (7, 4, 4), the wrist point u (3,) m
    in the tip frame and the chain's constants ``semi``."""
    return np.concatenate([np.asarray(X, dtype=float).ravel(), u, semi.wc, semi.n1, semi.t1, semi.a,
                           [semi.h, semi.sigma, semi.reach]])


@_inline
def _roots(A, B, C, slack):
    """A cos x + B sin x = C, as ``capmap.core.ik.closed._trig_roots`` but as cosines and sines of the
    two roots phi + delta, phi - delta: (c1, s1, c2, s2, ok); |C| / hypot(A, B) up to 1 + slack counts
    as a (double) root."""
    rho = math.hypot(A, B)
    ok = rho > 1e-12
    cp, sp, ratio = (A / rho, B / rho, C / rho) if ok else (1.0, 0.0, C)
    ok = ok and abs(ratio) <= 1 + slack
    cd = min(1.0, max(-1.0, ratio))
    sd = math.sqrt(1.0 - cd * cd)
    return cp * cd - sp * sd, sp * cd + cp * sd, cp * cd + sp * sd, sp * cd - cp * sd, ok


@_inline
def _rz_right(A, c, s, out):
    """out = A Rz(q) for 3x3 A, with c = cos q, s = sin q."""
    for i in range(3):
        a0, a1 = A[i, 0], A[i, 1]
        out[i, 0] = c * a0 + s * a1
        out[i, 1] = -s * a0 + c * a1
        out[i, 2] = A[i, 2]


@_inline
def _mm(A, B, out):
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@_inline
def _mtm(A, B, out):
    """out = A^T B."""
    for i in range(3):
        for j in range(3):
            out[i, j] = A[0, i] * B[0, j] + A[1, i] * B[1, j] + A[2, i] * B[2, j]


@_inline
def _one(X, c, T, q0, theta, ok, f, s, sv, angles, only, slack=1e-10):
    """Branches at one (target T (4, 4), q0): theta (4, 6) (only when ``angles``), ok (4,), f (4,).
    X (7, 4, 4) and the constants c (130,); s: scratch (8, 3, 3), sv: scratch (5, 3); only:
    the one branch to evaluate (0-3), or -1 for all four (others are left untouched); slack: see
    :func:`_roots` (1e-10; more where the angle q0 is a root known only approximately). Joint
    angles are carried as cosines and sines (no trigonometric call but for q0 and the output)."""
    u, wc, n1, t1, a = c[112:115], c[115:118], c[118:121], c[121:124], c[124:127]
    h, sigma, reach = c[127], c[128], c[129]
    RF, V, P2, W, Rg, tmp, G = s[0], s[2], s[3], s[4], s[5], s[6], s[7]
    w, tF, r, tP, w2 = sv[0], sv[1], sv[2], sv[3], sv[4]
    for i in range(3):
        w[i] = T[i, 0] * u[0] + T[i, 1] * u[1] + T[i, 2] * u[2] + T[i, 3]
    # F0 = X0 Rz(q0) X1
    c0, s0 = math.cos(q0), math.sin(q0)
    _rz_right(X[0, :3, :3], c0, s0, tmp)
    _mm(tmp, X[1, :3, :3], RF)
    for i in range(3):
        tF[i] = tmp[i, 0] * X[1, 0, 3] + tmp[i, 1] * X[1, 1, 3] + tmp[i, 2] * X[1, 2, 3] + X[0, i, 3]
    for i in range(3):
        r[i] = RF[0, i] * (w[0] - tF[0]) + RF[1, i] * (w[1] - tF[1]) + RF[2, i] * (w[2] - tF[2])
    # V = T_R X6_R^T
    for i in range(3):
        for j in range(3):
            V[i, j] = T[i, 0] * X[6, j, 0] + T[i, 1] * X[6, j, 1] + T[i, 2] * X[6, j, 2]
    # 1. joint 1
    A1 = n1[0] * r[0] + n1[1] * r[1]
    B1 = n1[0] * r[1] - n1[1] * r[0]
    C1 = h + n1[0] * t1[0] + n1[1] * t1[1] + n1[2] * t1[2] - n1[2] * r[2]
    c1a, s1a, c1b, s1b, ok1 = _roots(A1, B1, C1, slack)
    d5 = X[5, :3, 2]
    A4 = d5[0] * a[0] + d5[1] * a[1]
    B4 = d5[0] * a[1] - d5[1] * a[0]
    t3x, t3y = X[3, 0, 3], X[3, 1, 3]
    for i1 in range(2):
        if only >= 0 and only // 2 != i1:
            continue
        c1, s1 = (c1a, s1a) if i1 == 0 else (c1b, s1b)
        _rz_right(RF, c1, s1, tmp)
        _mm(tmp, X[2, :3, :3], P2)
        for i in range(3):
            tP[i] = tmp[i, 0] * X[2, 0, 3] + tmp[i, 1] * X[2, 1, 3] + tmp[i, 2] * X[2, 2, 3] + tF[i]
        _mtm(P2, V, W)
        b0, b1, b2 = sigma * W[2, 0], sigma * W[2, 1], sigma * W[2, 2]
        # 2. joints 4, 5
        c4a, s4a, c4b, s4b, ok4 = _roots(A4, B4, b2 - d5[2] * a[2], slack)
        nb = math.hypot(b0, b1)
        okb = nb > 1e-12
        for i in range(3):
            w2[i] = P2[0, i] * (w[0] - tP[0]) + P2[1, i] * (w[1] - tP[1]) + P2[2, i] * (w[2] - tP[2])
        for i4 in range(2):
            k = 2 * i1 + i4
            if only >= 0 and only != k:
                continue
            c4, s4 = (c4a, s4a) if i4 == 0 else (c4b, s4b)
            # v = R5^T Rz(-q4) a
            ra0, ra1, ra2 = c4 * a[0] + s4 * a[1], -s4 * a[0] + c4 * a[1], a[2]
            v0 = X[5, 0, 0] * ra0 + X[5, 1, 0] * ra1 + X[5, 2, 0] * ra2
            v1 = X[5, 0, 1] * ra0 + X[5, 1, 1] * ra1 + X[5, 2, 1] * ra2
            # q5 = atan2(v1, v0) - atan2(b1, b0)
            nvb = math.hypot(v0, v1) * nb
            nvb = nvb if nvb > 0 else 1.0
            c5, s5 = (v0 * b0 + v1 * b1) / nvb, (v1 * b0 - v0 * b1) / nvb
            # 3. Rg = W Rz(-q5) R5^T Rz(-q4) R4^T
            _rz_right(W, c5, -s5, tmp)
            for i in range(3):
                for j in range(3):
                    G[i, j] = tmp[i, 0] * X[5, j, 0] + tmp[i, 1] * X[5, j, 1] + tmp[i, 2] * X[5, j, 2]
            _rz_right(G, c4, -s4, tmp)
            for i in range(3):
                for j in range(3):
                    Rg[i, j] = tmp[i, 0] * X[4, j, 0] + tmp[i, 1] * X[4, j, 1] + tmp[i, 2] * X[4, j, 2]
            e0 = w2[0] - (Rg[0, 0] * wc[0] + Rg[0, 1] * wc[1] + Rg[0, 2] * wc[2])
            e1 = w2[1] - (Rg[1, 0] * wc[0] + Rg[1, 1] * wc[1] + Rg[1, 2] * wc[2])
            f[k] = math.hypot(e0, e1) - reach
            ok[k] = ok1 and ok4 and okb
            if not angles:
                continue
            q2 = math.atan2(e1, e0) - math.atan2(t3y, t3x)
            # q3 from (Rz(q2) R3)^T Rg: its first column's entries 0 and 1
            c2, s2 = math.cos(q2), math.sin(q2)
            g00 = 0.0
            g10 = 0.0
            for m in range(2):
                rz0 = c2 * X[3, 0, m] - s2 * X[3, 1, m]  # (Rz(q2) R3)[:, m]
                rz1 = s2 * X[3, 0, m] + c2 * X[3, 1, m]
                col = rz0 * Rg[0, 0] + rz1 * Rg[1, 0] + X[3, 2, m] * Rg[2, 0]
                if m == 0:
                    g00 = col
                else:
                    g10 = col
            theta[k, 0], theta[k, 1], theta[k, 2] = q0, math.atan2(s1, c1), q2
            theta[k, 3], theta[k, 4], theta[k, 5] = math.atan2(g10, g00), math.atan2(s4, c4), math.atan2(s5, c5)


@_jit
def evaluate(c, T, q0, theta, ok, f, slack=1e-10):
    """Rows m: target T[m] (M, 4, 4) at q0[m] (M,) -> theta (M, 4, 6), ok (M, 4), f (M, 4); slack: see
    :func:`_roots`."""
    s, sv = np.empty((8, 3, 3)), np.empty((5, 3))
    X = c[:112].reshape(7, 4, 4)
    for m in range(len(q0)):
        _one(X, c, T[m], q0[m], theta[m], ok[m], f[m], s, sv, True, -1, slack)


@_jit
def evaluate_grid(c, T, grid, ok, f):
    """Every target T (N, 4, 4) at every grid angle (G,) -> ok (N, G, 4), f (N, G, 4)."""
    s, sv = np.empty((8, 3, 3)), np.empty((5, 3))
    X = c[:112].reshape(7, 4, 4)
    theta = np.empty((4, 6))
    for n in range(T.shape[0]):
        for g in range(len(grid)):
            _one(X, c, T[n], grid[g], theta, ok[n, g], f[n, g], s, sv, False, -1)


@_jit
def evaluate_branch(c, T, target, q0, branch, ok, f):
    """Rows m: branch ``branch[m]`` of target T[target[m]] at q0[m] -> ok (M,), f (M,) (no angles)."""
    s, sv = np.empty((8, 3, 3)), np.empty((5, 3))
    X = c[:112].reshape(7, 4, 4)
    theta, ok4, f4 = np.empty((4, 6)), np.zeros(4, dtype=np.bool_), np.zeros(4)
    for m in range(len(q0)):
        b = branch[m]
        _one(X, c, T[target[m]], q0[m], theta, ok4, f4, s, sv, False, b)
        ok[m], f[m] = ok4[b], f4[b]


@_jit
def residuals(c, T, q0, ok, f, slack):
    """Rows m: target T[m] (M, 4, 4) at q0[m] (M,) -> ok (M, 4), f (M, 4) (no angles); slack: see :func:`_roots`."""
    s, sv = np.empty((8, 3, 3)), np.empty((5, 3))
    X = c[:112].reshape(7, 4, 4)
    theta = np.empty((4, 6))
    for m in range(len(q0)):
        _one(X, c, T[m], q0[m], theta, ok[m], f[m], s, sv, False, -1, slack)


@_jit
def branch_angles(c, T, q0, branch, theta, slack):
    """Rows m: branch ``branch[m]`` of target T[m] (M, 4, 4) at q0[m] (M,) -> theta (M, 6) rad."""
    s, sv = np.empty((8, 3, 3)), np.empty((5, 3))
    X = c[:112].reshape(7, 4, 4)
    th4, ok4, f4 = np.empty((4, 6)), np.zeros(4, dtype=np.bool_), np.zeros(4)
    for m in range(len(q0)):
        b = branch[m]
        _one(X, c, T[m], q0[m], th4, ok4, f4, s, sv, True, b, slack)
        theta[m] = th4[b]
