"""The node models of one solve packed flat for the compiled FDDP (:mod:`.fddp`), one node's evaluation on
its slice of the pack, and that evaluation as a first-class function.

The compiled FDDP and the constraint evaluation call a node through a pointer (:func:`node_function`)
instead of linking the node kernel's code into theirs, where LLVM would optimise all of it again for each
of them (about 6 s of the kernels' compile). Numba calls such a function through its C wrapper, which only
writes out an exception raised in it (as unraisable): :func:`node_function` raises it when the call returns.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager

import numba
import numpy as np
from numba.core import types
from numba.core.types.function_type import CompileResultWAP

from capmap.dualarm.ocp.node_kernel import node_eval

__all__ = ["pack_nodes", "node_function", "unraisable_raised", "LAM_EQ", "EQ_AT", "LAM_IN", "IN_AT", "C_VALUES", "G_VALUES"]

# where pack_nodes() puts the multipliers, their node offsets and the nodes' constraint values
LAM_EQ, EQ_AT, LAM_IN, IN_AT, C_VALUES, G_VALUES = 29, 30, 31, 32, 33, 35


def _offsets(sizes) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)


def pack_nodes(models: list) -> tuple:
    """The nodes (CompiledNodeModel, N + 1, mode 'al') as one tuple of flat arrays and offsets for
    :func:`capmap.dualarm.ocp.fddp.fddp`; their multipliers are read now (pack again after changing them)."""
    if any(m.mode != "al" or len(m.lam_in) != m.n_in for m in models):
        raise ValueError("the compiled FDDP takes augmented-Lagrangian nodes (mode 'al') only")
    st = [m._static for m in models]
    c = np.ascontiguousarray

    def cat(i, shape):
        parts = [s[i] for s in st]
        return c(np.concatenate(parts) if parts else np.zeros(shape)), _offsets([len(p) for p in parts])

    seg_f, so = cat(5, (0, 6))
    seg_j, _ = cat(6, (0,))
    tri_f, to = cat(7, (0, models[0].packed.tri_f.shape[1]))
    tri_j, _ = cat(8, (0,))
    Aw, _ = cat(9, (0, 3))
    Bw, _ = cat(10, (0, 3))
    Vw, _ = cat(11, (0, 3, 3))
    lever, _ = cat(12, (0, models[0].packed.reach.shape[1]))
    rows, po = cat(15, (0, 3))
    rsum, _ = cat(16, (0,))
    order, _ = cat(17, (0,))
    groups, go = cat(18, (0, 4))
    spheres, _ = cat(19, (0, 4))
    kind = np.array([s[20] for s in st], dtype=np.int64)
    tg, axis, par = (c(np.stack([s[i] for s in st])) for i in (21, 22, 23))
    ref_lb, ref_q = c(np.concatenate([s[13] for s in st])), c(np.stack([s[14] for s in st]))
    lam_eq, eo = c(np.concatenate([m.lam_eq for m in models])), _offsets([m.m_eq for m in models])
    lam_in, io = c(np.concatenate([m.lam_in for m in models])), _offsets([m.n_in for m in models])
    s0 = st[0]
    return (s0[0], s0[1], s0[2], s0[3], s0[4], seg_f, seg_j.astype(np.int64), so, tri_f, tri_j.astype(np.int64), to,
            Aw, Bw, Vw, lever, ref_lb, ref_q, rows.astype(np.int64), rsum, po, order.astype(np.int64),
            groups.astype(np.int64), spheres, go, kind, tg, axis, par, s0[24], lam_eq, eo, lam_in, io,
            np.empty(len(lam_eq)), np.empty((len(lam_eq), len(s0[2][0]) * 2)), np.empty(len(lam_in)))


@numba.njit(cache=True)
def _eval(P, k, x, u, mu, diff, Lx, Lxx, Lu, xnext):
    """Node k's cost (node_eval on its slice of the packed nodes ``P``); Lxx F-ordered, as Crocoddyl's data."""
    (chain_f, chain_i, moves, frame_f, frame_j, seg_f, seg_j, so, tri_f, tri_j, to, Aw, Bw, Vw, lever, ref_lb, ref_q,
     rows, rsum, po, order, groups, spheres, go, kind, tg, axis, par, lim, lam_eq, eo, lam_in, io, c, C, g) = P
    s0, s1, t0, t1, p0, p1 = so[k], so[k + 1], to[k], to[k + 1], po[k], po[k + 1]
    g0, g1, e0, e1, i0, i1 = go[k], go[k + 1], eo[k], eo[k + 1], io[k], io[k + 1]
    return node_eval(chain_f, chain_i, moves, frame_f, frame_j, seg_f[s0:s1], seg_j[s0:s1], tri_f[t0:t1], tri_j[t0:t1],
                     Aw[s0:s1], Bw[s0:s1], Vw[t0:t1], lever[s0 + t0:s1 + t1], ref_lb[p0:p1], ref_q[k], rows[p0:p1],
                     rsum[p0:p1], order[p0:p1], groups[g0:g1], spheres[g0:g1], kind[k], tg[k], axis[k], par[k],
                     lim, lam_eq[e0:e1], lam_in[i0:i1], x, u, mu, diff, c[e0:e1], C[e0:e1], g[i0:i1], Lx, Lxx, Lu, xnext)


@contextmanager
def node_function(P) -> Iterator[CompileResultWAP]:
    """Node k's evaluation on the packed nodes ``P`` (:func:`_eval`) as a first-class function, for the
    compiled callers of :mod:`.fddp`: ``with node_function(P) as ev: fddp(P, ev, ...)``; an exception raised
    in a call of it is raised on leaving the block."""
    v, F = types.float64[::1], types.Array(types.float64, 2, "F")
    sig = types.float64(numba.typeof(P), types.int64, v, v, types.float64, types.boolean, v, F, v, v)
    _eval.compile(sig.args)
    with unraisable_raised("a node evaluation"):
        yield CompileResultWAP(_eval.overloads[sig.args])


@contextmanager
def unraisable_raised(what: str) -> Iterator[None]:
    """An exception written out as unraisable in the block (by numba's C wrapper of a first-class function)
    raised on leaving it, as ``RuntimeError("<what> failed: ...")``."""
    caught, hook = [], sys.unraisablehook
    sys.unraisablehook = caught.append
    try:
        yield
    finally:
        sys.unraisablehook = hook
    if caught:
        raise RuntimeError(f"{what} failed: {caught[0].exc_value!r}") from caught[0].exc_value
