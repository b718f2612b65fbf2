"""The 1-D search of the semi-analytical IK (see :mod:`capmap.core.ik`): for a chain of the shape
``0 | 1 | 2 3 parallel | 4 5 intersecting`` and a batch of targets, the roots in q0 of the
planar 2R residual f on each of the four branches of joints 1, 4, 5. The residual itself is
the compiled kernel :mod:`capmap.core.ik.semi.kernels`; here are the grid, the refinement of
suspect intervals, the branch ends and the root polishing (all batched over targets)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import capmap.core.ik.semi.kernels as ik_kernels
from capmap.core.ik.multistart import newton
from capmap.core.kinematics import Chain

__all__ = ["search", "search_windows", "candidates", "SEARCH_STEPS"]

SEARCH_STEPS = 720  # grid of the 1-D search over joint 0 (0.5 deg)
_CHUNK_EVALS = 400_000  # (target, grid point) pairs per batch of the search: bounds memory (~0.1 GB)


def _residual(c: np.ndarray, T: np.ndarray, target: np.ndarray, q0: np.ndarray, branch: np.ndarray):
    """Validity (M,) and residual f (M,) m of branch ``branch`` (M,) of targets T[target] at q0 (M,)."""
    ok, f = np.empty(len(q0), dtype=np.bool_), np.empty(len(q0))
    ik_kernels.evaluate_branch(c, T, np.ascontiguousarray(target, dtype=np.int64), np.ascontiguousarray(q0, dtype=float),
                               np.ascontiguousarray(branch, dtype=np.int64), ok, f)
    return ok, f


def _semi_curve(c: np.ndarray, T: np.ndarray, q0: np.ndarray, curve: np.ndarray):
    """Branch ``curve`` (M,) at targets T (M, 4, 4), joint-0 angles q0 (M,): theta (M, 6), ok (M,), f (M,) m."""
    M = len(q0)
    theta, ok, f = np.empty((M, 4, 6)), np.empty((M, 4), dtype=np.bool_), np.empty((M, 4))
    ik_kernels.evaluate(c, np.ascontiguousarray(T), np.ascontiguousarray(q0, dtype=float), theta, ok, f)
    i = np.arange(M)
    return theta[i, curve], ok[i, curve], f[i, curve]


def search(chain: Chain, T: np.ndarray, steps: int = SEARCH_STEPS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate solutions (N, K, 6) rad for targets T (N, 4, 4), their validity (N, K), and which
    of them are starts at a (near-)double root that still need Newton steps (N, K)."""
    c = ik_kernels.SemiConstants.of(chain.X).packed(chain.X)
    T = np.ascontiguousarray(T)
    N = len(T)
    step = 2 * np.pi / steps
    grid = -np.pi + step * np.arange(-1, steps + 1)  # one point beyond each end: every wrap-around triple
    ok, f = np.empty((N, steps + 2, 4), dtype=np.bool_), np.empty((N, steps + 2, 4))
    ik_kernels.evaluate_grid(c, T, grid, ok, f)
    seq = lambda a: np.moveaxis(a, 2, 1).reshape(N * 4, -1)  # noqa: E731 - one sequence per (target, branch)
    tgt, crv = np.repeat(np.arange(N), 4), np.tile(np.arange(4), N)
    return _roots_of(c, T, tgt, crv, np.broadcast_to(grid, (N * 4, steps + 2)), seq(ok), seq(f), N)


def search_windows(chain: Chain, T: np.ndarray, target: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                   points: int = 16) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`search`, on the intervals [lo, hi] (W,) rad of joint 0 of targets T[target] (W,):
    ``points`` + 1 samples per interval on each branch, then the same refinement."""
    c = ik_kernels.SemiConstants.of(chain.X).packed(chain.X)
    T = np.ascontiguousarray(T)
    W = len(target)
    x = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, points + 1)  # (W, P)
    tgt, crv = np.repeat(target, 4), np.tile(np.arange(4), W)
    x = np.repeat(x, 4, axis=0)
    ok, f = _residual(c, T, np.repeat(tgt, points + 1), x.ravel(), np.repeat(crv, points + 1))
    return _roots_of(c, T, tgt, crv, x, ok.reshape(x.shape), f.reshape(x.shape), len(T))


def _roots_of(c, T, tgt, crv, x, ok, f, N):
    """The refinement of :func:`search` from sampled residual sequences f (B, S) at angles x (B, S) on
    branch crv (B,) of target tgt (B,), valid where ok (B, S)."""
    brackets, seeds, edges = [], [], []
    for level in range(_REFINE_LEVELS + 1):
        br, refine, edge = _scan(tgt, crv, x, ok, f)
        brackets.append(br)
        if level == _REFINE_LEVELS or not (len(refine[0]) or len(edge[0])):
            seeds.append(refine)  # what is still suspect at the finest level: a (near-)double root
            edges.append(edge)
            break
        # subdivide suspect intervals and intervals where the branch ends
        tgt = np.concatenate([refine[0], edge[0]])
        crv = np.concatenate([refine[1], edge[1]])
        lo, hi = np.concatenate([refine[2], edge[2]]), np.concatenate([refine[3], edge[3]])
        x = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, _SUBDIVIDE + 1)
        ok, f = _residual(c, T, np.repeat(tgt, _SUBDIVIDE + 1), x.ravel(), np.repeat(crv, _SUBDIVIDE + 1))
        ok, f = ok.reshape(x.shape), f.reshape(x.shape)
    br = _Brackets.joined(brackets)
    # where a branch ends inside a finest interval: find the end point (bisection on validity);
    # the branch joins its partner there, so bracket [valid end, end point] on every branch
    e_n, e_c, e_v, e_z = (np.concatenate(v) for v in zip(*edges))
    if len(e_n):
        a, z = e_v.copy(), e_z.copy()
        for _ in range(30):
            m = 0.5 * (a + z)
            okm, _ = _residual(c, T, e_n, m, e_c)
            a, z = np.where(okm, m, a), np.where(okm, z, m)
        ok_v, f_v = np.empty((len(a), 4), dtype=np.bool_), np.empty((len(a), 4))
        ok_a, f_a = np.empty((len(a), 4), dtype=np.bool_), np.empty((len(a), 4))
        ik_kernels.evaluate(c, T[e_n], e_v, np.empty((len(a), 4, 6)), ok_v, f_v)
        ik_kernels.evaluate(c, T[e_n], a, np.empty((len(a), 4, 6)), ok_a, f_a)
        i, cc = np.nonzero(ok_v & ok_a & (f_v * f_a <= 0))
        br = _Brackets.joined([br, _Brackets(e_n[i], cc, e_v[i], a[i], f_v[i, cc], f_a[i, cc])])
    # Illinois false position on every bracket; Newton from what stays suspect at the finest level
    x = br.solve(c, T)
    theta_r, ok_r, _ = _semi_curve(c, T[br.target], x, br.curve)
    s_n, s_c, s_lo, s_hi = (np.concatenate(v) for v in zip(*seeds))
    theta_t, ok_t, _ = _semi_curve(c, T[s_n], 0.5 * (s_lo + s_hi), s_c)
    seed = np.r_[np.zeros(len(br.target), dtype=bool), np.ones(len(s_n), dtype=bool)]
    return _pack(np.concatenate([br.target, s_n]), np.concatenate([theta_r, theta_t]),
                 np.concatenate([ok_r, ok_t]), seed, N)


def candidates(chain: Chain, T_target: np.ndarray, steps: int = SEARCH_STEPS) -> tuple[np.ndarray, np.ndarray]:
    """Candidate solutions (N, K, 6) rad and validity (N, K) for targets T_target (N, 4, 4) by the 1-D
    search over joint 0, in chunks of targets (:func:`search`), the (near-)double roots after 8 Newton steps."""
    N = len(T_target)
    per = max(1, _CHUNK_EVALS // steps)
    parts = []
    for s in range(0, N, per):
        theta, ok, seed = search(chain, T_target[s:s + per], steps)
        theta[seed] = newton(chain, theta[seed], np.repeat(T_target[s:s + per], seed.shape[1], 0)[seed.ravel()], iters=8)
        parts.append((theta, ok))
    K = max(1, max(p[0].shape[1] for p in parts))
    theta = np.zeros((N, K, 6))
    ok = np.zeros((N, K), dtype=bool)
    for s, (th, o) in zip(range(0, N, per), parts):
        theta[s:s + len(th), :th.shape[1]], ok[s:s + len(th), :th.shape[1]] = th, o
    return theta, ok


_REFINE_LEVELS = 4  # subdivisions of a suspect grid interval (0.5 deg / 8^4 at the finest)
_SUBDIVIDE = 8
_SUSPECT = 3.0  # an interval is suspect when min |f| at its ends < this x the local change of f


def _scan(tgt, crv, x, ok, f):
    """Sampled residual sequences f (B, S) at increasing angles x (B, S) on branch crv (B,) of
    target tgt (B,), valid where ok (B, S). Returns

    - :class:`_Brackets` at every sign change between valid neighbours;
    - suspect intervals (tgt, crv, lo, hi): same sign at both ends, but |f| there is small
      against the local change of f (the largest |f step| over the interval and its
      neighbours, x ``_SUSPECT``): two roots (or a narrow spike of f) may hide inside;
    - intervals where the branch ends (tgt, crv, valid end, invalid end).
    """
    both = ok[:, :-1] & ok[:, 1:]
    prod = f[:, :-1] * f[:, 1:]
    b_i, j_i = np.nonzero(both & (prod <= 0))
    br = _Brackets(tgt[b_i], crv[b_i], x[b_i, j_i], x[b_i, j_i + 1], f[b_i, j_i], f[b_i, j_i + 1])
    df = np.where(both, np.abs(np.diff(f, axis=1)), 0.0)
    pad = np.zeros((len(df), 1))
    local = np.maximum(df, np.maximum(np.concatenate([pad, df[:, :-1]], 1), np.concatenate([df[:, 1:], pad], 1)))
    small = np.minimum(np.abs(f[:, :-1]), np.abs(f[:, 1:]))
    b_s, j_s = np.nonzero(both & (prod > 0) & (small < _SUSPECT * local))
    suspect = (tgt[b_s], crv[b_s], x[b_s, j_s], x[b_s, j_s + 1])
    b_e, j_e = np.nonzero(ok[:, :-1] != ok[:, 1:])
    first = ok[b_e, j_e]
    edge = (tgt[b_e], crv[b_e], np.where(first, x[b_e, j_e], x[b_e, j_e + 1]),
            np.where(first, x[b_e, j_e + 1], x[b_e, j_e]))
    return br, suspect, edge


@dataclass(frozen=True)
class _Brackets:
    """Root brackets [lo, hi] of branch ``curve`` at target ``target``, with f at both ends (arrays (B,))."""

    target: np.ndarray
    curve: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    f_lo: np.ndarray
    f_hi: np.ndarray

    @classmethod
    def joined(cls, parts: list["_Brackets"]) -> "_Brackets":
        return cls(*(np.concatenate([getattr(p, n) for p in parts]) for n in
                     ("target", "curve", "lo", "hi", "f_lo", "f_hi")))

    def solve(self, c: np.ndarray, T: np.ndarray, iters: int = 90) -> np.ndarray:
        """The root in each bracket (B,) rad: the Illinois variant of false position, with a
        bisection every third step (f can be steep near a wrist singularity, where false
        position alone crawls); stops at |f| <= 1e-12 m or a bracket narrower than 1e-9 rad (Newton polishes every root)."""
        lo, hi, f_lo, f_hi = self.lo.copy(), self.hi.copy(), self.f_lo.copy(), self.f_hi.copy()
        side = np.zeros(len(lo), dtype=int)
        x = np.where(np.abs(f_lo) <= np.abs(f_hi), lo, hi)
        live = np.ones(len(lo), dtype=bool)
        for it in range(iters):
            idx = np.flatnonzero(live)
            if not len(idx):
                break
            l, h, fl, fh = lo[idx], hi[idx], f_lo[idx], f_hi[idx]
            d = fh - fl
            xi = np.where(d != 0, h - fh * (h - l) / np.where(d != 0, d, 1.0), 0.5 * (l + h))
            xi = np.clip(xi, np.minimum(l, h), np.maximum(l, h))
            if it % 3 == 2:
                xi = 0.5 * (l + h)
            okx, fx = _residual(c, T, self.target[idx], xi, self.curve[idx])
            fx = np.where(okx, fx, 0.0)  # a hole inside the bracket: stop there (Newton decides)
            left = fx * fl > 0  # the root is in [x, hi]
            fh = np.where(~left & (side[idx] == -1), 0.5 * fh, fh)
            fl = np.where(left & (side[idx] == 1), 0.5 * fl, fl)
            lo[idx], f_lo[idx] = np.where(left, xi, l), np.where(left, fx, fl)
            hi[idx], f_hi[idx] = np.where(left, h, xi), np.where(left, fh, fx)
            side[idx] = np.where(left, 1, -1)
            x[idx] = xi
            live[idx] = (np.abs(hi[idx] - lo[idx]) > 1e-9) & (np.abs(fx) > 1e-12)
        return x


def _pack(target, theta, ok, seed, N):
    """Rows (B, 6) belonging to targets ``target`` (B,) -> (N, K, 6), validity and seed flags (N, K)."""
    count = np.bincount(target, minlength=N)
    K = max(1, int(count.max(initial=0)))
    order = np.argsort(target, kind="stable")
    slot = np.arange(len(target)) - np.repeat(np.cumsum(count) - count, count)
    out = np.zeros((N, K, 6))
    ok_out, seed_out = np.zeros((N, K), dtype=bool), np.zeros((N, K), dtype=bool)
    out[target[order], slot] = theta[order]
    ok_out[target[order], slot] = ok[order]
    seed_out[target[order], slot] = seed[order]
    return out, ok_out, seed_out
