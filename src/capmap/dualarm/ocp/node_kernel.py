"""The compiled node of :mod:`capmap.dualarm.ocp.compiled_nodes`: one function evaluating a node's cost,
constraints and (with ``diff``) their derivatives on the packed chain of :mod:`.chain`."""

from __future__ import annotations

import numba
import numpy as np

from capmap.dualarm.geometry.broadphase import group_bound
from capmap.dualarm.geometry.chain import fk, lower_bound, place_moving, static_bound
from capmap.dualarm.geometry.distance import segseg, segtri
from capmap.dualarm.ocp.lie import jlog3, jlog6, log3, log6

__all__ = ["node_eval"]


@numba.njit(cache=True)
def _compose(tg, i, R, p, Re, pe):
    """(Re, pe) = target_i (R, p) with target_i = tg[i] (R 9, p 3)."""
    for r in range(3):
        for c in range(3):
            Re[r, c] = tg[i, 3 * r] * R[0, c] + tg[i, 3 * r + 1] * R[1, c] + tg[i, 3 * r + 2] * R[2, c]
        pe[r] = tg[i, 9 + r] + tg[i, 3 * r] * p[0] + tg[i, 3 * r + 1] * p[1] + tg[i, 3 * r + 2] * p[2]


@numba.njit(cache=True)
def _pose_rows(Je, Jl, out, row, nv):
    """out[row:row + 6, :nv] = Je (6, 6) @ Jl (6, nv)."""
    for r in range(6):
        for c in range(nv):
            s = 0.0
            for k in range(6):
                s += Je[r, k] * Jl[k, c]
            out[row + r, c] = s


@numba.njit(cache=True)
def node_eval(chain_f, chain_i, moves, frame_f, frame_j, seg_f, seg_j, tri_f, tri_j, A, B, V, lever, ref_lb, ref_q,
              rows, rsum, order, groups, spheres, kind, tg, axis, par, lim, lam_eq, lam_in, x, u, mu, diff, c, C, g, Lx, Lxx,
              Lu, xnext):
    """One node: returns the cost; fills c (m,), g (p,) and without ``diff`` the next state xnext
    (2 nq,), with ``diff`` C (m, 2 nq), Lx (2 nq), Lxx (2 nq, 2 nq), Lu (nq). par: dt, w_velocity,
    w_panel, margin, scale, running (0/1), limits (0/1), al (0/1), bound (0/1: a pair with a zero
    multiplier and a lower bound above the margin gets that bound as g, exact distances otherwise);
    lim (4, nq): w_control, q_lower, q_upper, v_max; A, B (S, 3), V (T, 3, 3): the primitives' world
    coordinates, the static ones' given, the moving ones' written here; lever (S + T, nq): how far a point
    of each primitive moves per radian of each joint; ref_lb (P,), ref_q (nq,): the pairs' lower bounds
    at the configuration of the last evaluation with ``diff`` and ``bound`` (which writes them; ref_q nan:
    none), that bound them anywhere else less the primitives' motion since (a calc or calcDiff skips a
    pair whose multiplier is zero and whose bound so moved clears the margin: its g is that bound, and
    its penalty and derivatives are zero either way); order, groups, spheres: the pairs' groups
    (:func:`capmap.dualarm.geometry.broadphase.pair_groups`): with ``bound``, a group whose pairs all have zero
    multipliers and whose bound clears the margin gets that bound as every pair's g."""
    dt, wv, wp, margin, scale = par[0], par[1], par[2], par[3], par[4]
    running, limits, al = par[5] > 0.5, par[6] > 0.5, par[7] > 0.5
    bound = al and par[8] > 0.5
    nj, nq = chain_f.shape[0], chain_f.shape[0] - 1
    q, v = x[:nq], x[nq:]
    R, p = np.empty((nj, 3, 3)), np.empty((nj, 3))
    fk(chain_f, chain_i, q, R, p)
    # frames 0 left, 1 right, 2 panel: placements and local Jacobians (6, nq)
    FR, Fp = np.empty((3, 3, 3)), np.empty((3, 3))
    for f in range(3):
        j = frame_j[f]
        for r in range(3):
            for cc in range(3):
                FR[f, r, cc] = R[j, r, 0] * frame_f[f, cc] + R[j, r, 1] * frame_f[f, 3 + cc] + R[j, r, 2] * frame_f[f, 6 + cc]
            Fp[f, r] = p[j, r] + R[j, r, 0] * frame_f[f, 9] + R[j, r, 1] * frame_f[f, 10] + R[j, r, 2] * frame_f[f, 11]
    W = np.empty((nq, 3))  # world axis of each column
    O = np.empty((nq, 3))  # its joint's origin
    for j in range(1, nj):
        i = chain_i[j, 1]
        for r in range(3):
            W[i, r] = R[j, r, 0] * chain_f[j, 12] + R[j, r, 1] * chain_f[j, 13] + R[j, r, 2] * chain_f[j, 14]
            O[i, r] = p[j, r]
    JL = np.zeros((3, 6, nq))
    if diff:
        for f in range(3):
            jf = frame_j[f]
            for i in range(nq):
                if not moves[jf, i]:
                    continue
                dx, dy, dz = Fp[f, 0] - O[i, 0], Fp[f, 1] - O[i, 1], Fp[f, 2] - O[i, 2]
                vx = W[i, 1] * dz - W[i, 2] * dy
                vy = W[i, 2] * dx - W[i, 0] * dz
                vz = W[i, 0] * dy - W[i, 1] * dx
                for r in range(3):
                    JL[f, r, i] = FR[f, 0, r] * vx + FR[f, 1, r] * vy + FR[f, 2, r] * vz
                    JL[f, 3 + r, i] = FR[f, 0, r] * W[i, 0] + FR[f, 1, r] * W[i, 1] + FR[f, 2, r] * W[i, 2]
    Re, pe = np.empty((3, 3)), np.empty(3)
    Je = np.empty((6, 6))
    r6 = np.empty(6)
    m = c.shape[0]
    if diff:
        C[:, :] = 0.0
    # closed chain: log6(rel_ref^-1 ML^-1 MR), Jacobian Jlog6 (JR - Ad(rel^-1) JL) = Jlog6 Ad(MR^-1) (VR - VL)
    Rrel, prel = np.empty((3, 3)), np.empty(3)
    for r in range(3):
        for cc in range(3):
            Rrel[r, cc] = FR[0, 0, r] * FR[1, 0, cc] + FR[0, 1, r] * FR[1, 1, cc] + FR[0, 2, r] * FR[1, 2, cc]
        prel[r] = (FR[0, 0, r] * (Fp[1, 0] - Fp[0, 0]) + FR[0, 1, r] * (Fp[1, 1] - Fp[0, 1])
                   + FR[0, 2, r] * (Fp[1, 2] - Fp[0, 2]))
    _compose(tg, 0, Rrel, prel, Re, pe)
    log6(Re, pe, r6)
    for r in range(6):
        c[r] = r6[r]
    if diff:
        jlog6(Re, pe, Je)
        Jrel = np.zeros((6, nq))
        jr, jl = frame_j[1], frame_j[0]
        for i in range(nq):
            sgn = (1.0 if moves[jr, i] else 0.0) - (1.0 if moves[jl, i] else 0.0)
            if sgn == 0.0:
                continue
            dx, dy, dz = Fp[1, 0] - O[i, 0], Fp[1, 1] - O[i, 1], Fp[1, 2] - O[i, 2]
            vx = W[i, 1] * dz - W[i, 2] * dy
            vy = W[i, 2] * dx - W[i, 0] * dz
            vz = W[i, 0] * dy - W[i, 1] * dx
            for r in range(3):
                Jrel[r, i] = sgn * (FR[1, 0, r] * vx + FR[1, 1, r] * vy + FR[1, 2, r] * vz)
                Jrel[3 + r, i] = sgn * (FR[1, 0, r] * W[i, 0] + FR[1, 1, r] * W[i, 1] + FR[1, 2, r] * W[i, 2])
        _pose_rows(Je, Jrel, C, 0, nq)
    RP, pP = FR[2], Fp[2]
    if kind == 0:  # the panel's z axis vertical: (R_P e_z)_xy = 0
        c[6], c[7] = RP[0, 2], RP[1, 2]
        if diff:
            for i in range(nq):
                if moves[frame_j[2], i]:  # w_i x z
                    C[6, i] = W[i, 1] * RP[2, 2] - W[i, 2] * RP[1, 2]
                    C[7, i] = W[i, 2] * RP[0, 2] - W[i, 0] * RP[2, 2]
    elif kind == 1 or kind == 3:  # the panel's pose
        _compose(tg, 2, RP, pP, Re, pe)
        log6(Re, pe, r6)
        for r in range(6):
            c[6 + r] = r6[r]
        if diff:
            jlog6(Re, pe, Je)
            _pose_rows(Je, JL[2], C, 6, nq)
        if kind == 3:  # at rest
            for i in range(nq):
                c[12 + i] = v[i]
                if diff:
                    C[12 + i, nq + i] = 1.0
    else:  # insertion: on the axis, orientation fixed
        for a in range(2):
            s = 0.0
            for r in range(3):
                s += axis[1 + a, r] * (pP[r] - axis[0, r])
            c[6 + a] = s
            if diff:
                for i in range(nq):
                    if moves[frame_j[2], i]:
                        dx, dy, dz = pP[0] - O[i, 0], pP[1] - O[i, 1], pP[2] - O[i, 2]
                        C[6 + a, i] = (axis[1 + a, 0] * (W[i, 1] * dz - W[i, 2] * dy)
                                       + axis[1 + a, 1] * (W[i, 2] * dx - W[i, 0] * dz)
                                       + axis[1 + a, 2] * (W[i, 0] * dy - W[i, 1] * dx))
        _compose(tg, 2, RP, pP, Re, pe)  # its rotation: R_final^T R_P
        w3 = np.empty(3)
        th = log3(Re, w3)
        for r in range(3):
            c[8 + r] = w3[r]
        if diff:
            J3 = np.empty((3, 3))
            jlog3(th, w3, J3)
            for r in range(3):
                for i in range(nq):
                    C[8 + r, i] = J3[r, 0] * JL[2, 3, i] + J3[r, 1] * JL[2, 4, i] + J3[r, 2] * JL[2, 5, i]
    # inequalities: safety distances - margin, then the joint limits
    npair = rows.shape[0]
    P, Q = np.empty((npair, 3)), np.empty((npair, 3))
    if npair:
        done = np.zeros(npair, np.bool_)
        left = npair
        if bound and not np.isnan(ref_q[0]):
            # the bounds at ref_q less how far each primitive moved since (a point moves at most sum |dq_i| lever_i;
            # a static primitive's lever is 0)
            nS = seg_f.shape[0]
            dm = np.zeros(lever.shape[0])
            for e in range(lever.shape[0]):
                if (seg_j[e] if e < nS else tri_j[e - nS]) != 0:
                    for i in range(nq):
                        dm[e] += lever[e, i] * abs(q[i] - ref_q[i])
            for n in range(npair):
                if lam_in[n] == 0.0:
                    moved = dm[rows[n, 1]] + (dm[rows[n, 2]] if rows[n, 0] == 0 else dm[nS + rows[n, 2]])
                    lb = ref_lb[n] - moved - margin
                    if lb > 0.0:
                        g[n] = lb
                        done[n] = True
                        left -= 1
        if left:
            place_moving(seg_f, seg_j, tri_f, tri_j, R, p, A, B, V)
        for gi in range(groups.shape[0] if left else 0):
            s0, s1 = groups[gi, 0], groups[gi, 1]
            # pairs with no multiplier whose lower bound clears the margin contribute nothing to the cost
            # or its derivatives: their g is that (positive) bound, the exact distance is skipped
            if bound and groups[gi, 2] > 0:
                free = True
                for t in range(s0, s1):
                    if lam_in[order[t]] != 0.0:
                        free = False
                        break
                if free:
                    lb = group_bound(A, B, V, rows, order, groups, spheres, gi) - margin
                    if lb > 0.0:
                        for t in range(s0, s1):
                            g[order[t]] = lb
                        continue
            for t in range(s0, s1):
                n = order[t]
                if done[n]:
                    continue
                if bound and lam_in[n] == 0.0:
                    if rows[n, 0] == 1 and tri_j[rows[n, 2]] == 0:  # a static triangle: its centre, reach, plane
                        lb = static_bound(A, B, rows[n, 1], tri_f, rows[n, 2]) - rsum[n] - margin
                    else:
                        lb = lower_bound(A, B, V, rows[n, 0], rows[n, 1], rows[n, 2]) - rsum[n] - margin
                    if lb > 0.0:
                        g[n] = lb
                        continue
                if rows[n, 0] == 0:
                    core = segseg(A, rows[n, 1], B, rows[n, 1], A, rows[n, 2], B, rows[n, 2], P, Q, n)
                else:
                    core = segtri(A, rows[n, 1], B, rows[n, 1], V, rows[n, 2], P, Q, n)
                g[n] = core - rsum[n] - margin
        if bound and diff:  # every pair's g + margin is a lower bound of its safety distance here
            for n in range(npair):
                ref_lb[n] = g[n] + margin
            for i in range(nq):
                ref_q[i] = q[i]
    if limits:
        for i in range(nq):
            g[npair + i] = q[i] - lim[1, i]
            g[npair + nq + i] = lim[2, i] - q[i]
            g[npair + 2 * nq + i] = v[i] + lim[3, i]
            g[npair + 3 * nq + i] = lim[3, i] - v[i]
    # costs
    err = np.empty(6)
    _compose(tg, 1, RP, pP, Re, pe)
    log6(Re, pe, err)
    cost = 0.0
    for r in range(6):
        cost += err[r] * err[r]
    cost *= 0.5 * wp
    if running:
        ctrl, vel = 0.0, 0.0
        for i in range(nq):
            ctrl += lim[0, i] * u[i] * u[i]
            vel += v[i] * v[i]
        cost = dt * (cost + 0.5 * ctrl + 0.5 * wv * vel)
    pen = 0.0
    if al:
        for r in range(m):
            e = c[r] + lam_eq[r] / mu
            pen += e * e
        for n in range(g.shape[0]):
            s = lam_in[n] / mu - g[n]
            if s > 0.0:
                pen += s * s
        cost += scale * 0.5 * mu * pen
    if not diff:
        for i in range(nq):  # q+ = q + dt v + dt^2 u / 2, v+ = v + dt u; the terminal node keeps x
            xnext[i] = q[i] + (dt * v[i] + 0.5 * dt * dt * u[i] if running else 0.0)
            xnext[nq + i] = v[i] + (dt * u[i] if running else 0.0)
        return cost
    # derivatives: the panel term, then the running terms, then the penalties (Gauss-Newton)
    n2 = 2 * nq
    Lx[:] = 0.0
    Lxx[:, :] = 0.0
    jlog6(Re, pe, Je)
    Jee = np.zeros((6, nq))
    _pose_rows(Je, JL[2], Jee, 0, nq)
    f0 = dt if running else 1.0
    for a in range(nq):
        s = 0.0
        for r in range(6):
            s += Jee[r, a] * err[r]
        Lx[a] = f0 * wp * s
        for b in range(a, nq):
            s = 0.0
            for r in range(6):
                s += Jee[r, a] * Jee[r, b]
            Lxx[a, b] = f0 * wp * s
            Lxx[b, a] = Lxx[a, b]
    if running:
        for i in range(nq):
            Lx[nq + i] += dt * wv * v[i]
            Lxx[nq + i, nq + i] += dt * wv
            Lu[i] = dt * lim[0, i] * u[i]
    else:
        Lu[:] = 0.0
    if al:
        ms = scale * mu
        for r in range(m):
            e = ms * (c[r] + lam_eq[r] / mu)
            for a in range(n2):
                Lx[a] += C[r, a] * e
        for a in range(n2):
            for b in range(a, n2):
                s = 0.0
                for r in range(m):
                    s += C[r, a] * C[r, b]
                if s != 0.0:
                    Lxx[a, b] += ms * s
                    if b != a:
                        Lxx[b, a] += ms * s
        G = np.zeros(nq)
        for n in range(npair):
            s = lam_in[n] / mu - g[n]
            if s <= 0.0:
                continue
            # the gradient of the pair's distance: n . (w_i x (X - o_i)), + on the first body, - on the second
            dx, dy, dz = P[n, 0] - Q[n, 0], P[n, 1] - Q[n, 1], P[n, 2] - Q[n, 2]
            norm = np.sqrt(dx * dx + dy * dy + dz * dz)
            G[:] = 0.0
            if norm > 0.0:
                nx, ny, nz = dx / norm, dy / norm, dz / norm
                for side in range(2):
                    if rows[n, 0] == 0 or side == 0:
                        jj = seg_j[rows[n, 1 + side]]
                    else:
                        jj = tri_j[rows[n, 2]]
                    if jj == 0:
                        continue
                    sg = 1.0 if side == 0 else -1.0
                    X = P[n] if side == 0 else Q[n]
                    for i in range(nq):
                        if moves[jj, i]:
                            ex, ey, ez = X[0] - O[i, 0], X[1] - O[i, 1], X[2] - O[i, 2]
                            G[i] += sg * (nx * (W[i, 1] * ez - W[i, 2] * ey) + ny * (W[i, 2] * ex - W[i, 0] * ez)
                                          + nz * (W[i, 0] * ey - W[i, 1] * ex))
            for a in range(nq):
                if G[a] == 0.0:
                    continue
                Lx[a] -= ms * G[a] * s
                for b in range(nq):
                    Lxx[a, b] += ms * G[a] * G[b]
        if limits:
            for k4 in range(4):
                off = 0 if k4 < 2 else nq
                for i in range(nq):
                    s = lam_in[npair + k4 * nq + i] / mu - g[npair + k4 * nq + i]
                    if s > 0.0:
                        Lx[off + i] -= ms * (1.0 if k4 % 2 == 0 else -1.0) * s
                        Lxx[off + i, off + i] += ms
    return cost
