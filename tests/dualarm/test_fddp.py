"""The compiled FDDP against Crocoddyl's own SolverFDDP on the same node models; the pair groups and their
bound against every pair's exact distance; the primitives' motion bound and the node's memory of its
last bounds against brute force and a node without it.

Tolerances: both solvers run the same algorithm in double precision; the compiled one forms Fx^T V Fx
and Quu^-1 in closed form where Crocoddyl multiplies and factorises matrices, so their iterates differ
by rounding (measured <= 1e-12 on the states here), amplified by the iterations: 1e-8 leaves four
orders of margin for other vector units. The group bound is a true lower bound up to rounding of the
distances (~1e-15 m): 1e-12 m.
"""

from __future__ import annotations

import crocoddyl
import numba
import numpy as np
import pytest
from numba.core import types
from numba.core.types.function_type import CompileResultWAP

from capmap.dualarm.geometry.broadphase import MIN_GROUP, BodyBalls, group_bound, pair_groups
from capmap.dualarm.geometry.chain import fk, groups_of, joint_placements, levers, pair_table, place_primitives
from capmap.dualarm.geometry.distance import segment_segment, segment_triangle
from capmap.dualarm.geometry.proximity import batch_distances
from capmap.dualarm.ocp.compiled_nodes import CompiledNodeModel
from capmap.dualarm.ocp.fddp import ALPHAS, fddp
from capmap.dualarm.ocp.packed_nodes import node_function, pack_nodes, unraisable_raised
from capmap.dualarm.ocp.solver import REG_INCREASE


def _models(small, seed):
    asm, ctx, xs, us, keep = small
    rng = np.random.default_rng(seed)
    models = [CompiledNodeModel(ctx, k, asm.pairs.subset(keep[k]), "al", ctx.packed) for k in range(len(xs))]
    for m in models:  # some multipliers on, as after a few outer iterations
        m.lam_eq = rng.normal(size=m.m_eq)
        m.lam_in = np.where(rng.random(m.n_in) < 0.1, np.abs(rng.normal(size=m.n_in)) * 50, 0.0)
    return models


def _crocoddyl(models, xs, us, maxiter, feasible, alphas=ALPHAS):
    problem = crocoddyl.ShootingProblem(xs[0].copy(), models[:-1], models[-1])
    solver = crocoddyl.SolverFDDP(problem)
    solver.th_stop, solver.reg_incFactor, solver.alphas = 1e-9, REG_INCREASE, list(alphas)
    ok = solver.solve(list(xs), list(us), maxiter, feasible)
    return ok, int(solver.iter), float(solver.cost), np.array(solver.xs), np.array(solver.us), solver.isFeasible


def _compiled(models, xs, us, maxiter, feasible, alphas=ALPHAS):
    m = models[0]
    nq = m.Fu.shape[1]
    Luu = np.ascontiguousarray(np.broadcast_to(m.ctx.task.dt * np.diag(m.lim[0]), (len(models) - 1, nq, nq)))
    xs, us = xs.copy(), us.copy()
    P = pack_nodes(models)
    with node_function(P) as ev:
        ok, it, cost, stopped = fddp(P, ev, m.Fx[0, nq], m.Fu[0, 0], Luu, xs[0].copy(), xs, us, maxiter, feasible,
                                     m.ctx.mu, 1e-9, REG_INCREASE, np.asarray(alphas, dtype=float))
    return ok, it, cost, xs, us, stopped


# the feasible start perturbs the controls by 0.005 rad/s^2: larger steps drive cores through each other, where a
# pair's gradient direction comes from rounding (closest points coincide) and two correct solvers part ways
@pytest.mark.parametrize("maxiter, feasible, perturb", [(1, False, 0.0), (3, False, 0.0), (30, False, 0.0),
                                                        (30, True, 0.005)])
def test_compiled_fddp_takes_crocoddyls_steps(small, maxiter, feasible, perturb):
    """The same iterations, acceptance and stop as Crocoddyl's SolverFDDP from an infeasible start (the
    initial guess: gaps between the nodes) and from a feasible one (a rollout of perturbed controls)."""
    asm, ctx, xs, us, _ = small
    models = _models(small, 7)
    if feasible:  # roll the perturbed controls out: no gaps
        us = us + perturb * np.random.default_rng(8).normal(size=us.shape)
        xs = xs.copy()
        for k, m in enumerate(models[:-1]):
            xs[k + 1] = m.Fx @ xs[k] + m.Fu @ us[k]
    ref, fast = _crocoddyl(models, xs, us, maxiter, feasible), _compiled(models, xs, us, maxiter, feasible)
    assert fast[:2] == ref[:2]  # converged, iterations
    assert fast[2] == pytest.approx(ref[2], rel=1e-9)
    assert np.abs(fast[3] - ref[3]).max() < 1e-8 and np.abs(fast[4] - ref[4]).max() < 1e-6
    if maxiter == 30:
        assert ref[1] > 2  # the comparison covered many steps, not one


def test_compiled_fddp_stops_only_trials_that_crocoddyl_rejects(small):
    """At a penalty where many feasible trials fail (mu = 1e6 with multipliers on), the trials the compiled
    FDDP does not roll out or stops by their partial cost are ones Crocoddyl rejects: the same iterations,
    cost and states as Crocoddyl's, which rolls every trial out."""
    asm, ctx, xs, us, _ = small
    models = _models(small, 7)
    us = us + 0.005 * np.random.default_rng(8).normal(size=us.shape)
    xs = xs.copy()
    for k, m in enumerate(models[:-1]):  # a feasible start
        xs[k + 1] = m.Fx @ xs[k] + m.Fu @ us[k]
    mu = ctx.mu
    ctx.mu = 1e6
    try:
        ref, fast = _crocoddyl(models, xs, us, 30, True), _compiled(models, xs, us, 30, True)
    finally:
        ctx.mu = mu
    assert fast[5] > 20  # trials were stopped (56 here)
    assert fast[:2] == ref[:2] and fast[2] == pytest.approx(ref[2], rel=1e-9)
    assert np.abs(fast[3] - ref[3]).max() < 1e-8 and np.abs(fast[4] - ref[4]).max() < 1e-6


def test_compiled_fddp_takes_crocoddyls_partial_steps_across_gaps(small):
    """Step lengths 1/2 and 1/4 only: the trials close part of the initial guess's gaps (FDDP's infeasible
    rollout), which the full default step never exercises on this problem."""
    asm, ctx, xs, us, _ = small
    models = _models(small, 7)
    ref, fast = _crocoddyl(models, xs, us, 3, False, (0.5, 0.25)), _compiled(models, xs, us, 3, False, (0.5, 0.25))
    assert not ref[5]  # still infeasible: every step was partial
    assert fast[:2] == ref[:2] and fast[2] == pytest.approx(ref[2], rel=1e-9)
    assert np.abs(fast[3] - ref[3]).max() < 1e-8 and np.abs(fast[4] - ref[4]).max() < 1e-6


def test_compiled_fddp_refuses_nodes_it_does_not_solve(small):
    asm, ctx, xs, _, keep = small
    with pytest.raises(ValueError, match="mode 'al'"):
        pack_nodes([CompiledNodeModel(ctx, k, asm.pairs.subset(keep[k]), "constrained", ctx.packed) for k in range(3)])


def test_group_bound_never_exceeds_a_pair_distance_and_drops_far_groups(small):
    asm, ctx, xs, _, _ = small
    pk = ctx.packed
    rows, rsum = pair_table(pk, asm.pairs)
    order, groups, spheres = groups_of(pk, rows)
    real = groups[:, 2] > 0
    assert real.sum() > 20 and (groups[real, 1] - groups[real, 0]).sum() > 0.5 * len(rows)  # most pairs are grouped
    nj = pk.chain_f.shape[0]
    R, p = np.empty((nj, 3, 3)), np.empty((nj, 3))
    A, B, V = np.empty((len(pk.seg_f), 3)), np.empty((len(pk.seg_f), 3)), np.empty((len(pk.tri_f), 3, 3))
    D = batch_distances(pk, xs[:, :14], asm.pairs)
    dropped = 0
    for k in range(len(xs)):
        fk(pk.chain_f, pk.chain_i, xs[k, :14], R, p)
        place_primitives(pk.seg_f, pk.seg_j, pk.tri_f, pk.tri_j, R, p, A, B, V)
        for gi in np.flatnonzero(real):
            lb = group_bound(A, B, V, rows, order, groups, spheres, gi)
            members = order[groups[gi, 0]:groups[gi, 1]]
            assert lb <= D[k, members].min() + 1e-12
            dropped += lb > 0.1
    assert dropped > 0.05 * real.sum() * len(xs)  # the bound does drop groups (measured 10 % here at 0.1 m)


@pytest.mark.parametrize("k", [0, 10, 28, 35, 40])
def test_node_with_its_groups_bounded_equals_the_node_with_every_distance(small, k):
    """A group (or pair) skipped by its bound has a zero multiplier and clears the margin: the cost and its
    derivatives are those of every pair's exact distance, bit for bit."""
    asm, ctx, xs, us, keep = small
    rng = np.random.default_rng(300 + k)
    m = CompiledNodeModel(ctx, k, asm.pairs.subset(keep[k] | (rng.random(len(asm.pairs)) < 0.5)), "al", ctx.packed)
    m.lam_eq = rng.normal(size=m.m_eq)
    m.lam_in[:5] = 100.0  # a few pairs on, the rest skippable
    exact = CompiledNodeModel(ctx, k, m.pairs, "al", ctx.packed)
    exact.lam_eq, exact.lam_in = m.lam_eq, m.lam_in
    exact._static = exact._static_exact
    u = None if k == asm.task.N else us[k]
    for x in (xs[k], xs[k] + 0.05 * rng.normal(size=28)):
        da, db = m.createData(), exact.createData()
        for model, d in ((m, da), (exact, db)):
            model.calc(d, x, u) if u is not None else model.calc(d, x)
            model.calcDiff(d, x, u) if u is not None else model.calcDiff(d, x)
        assert da.cost == db.cost
        for name in ("Lx", "Lxx", "Lu", "xnext"):
            assert np.array_equal(getattr(da, name), getattr(db, name)), name


def test_pair_groups_partition_the_pairs_by_moving_primitive_and_body():
    """Every pair in exactly one group; a group is one moving primitive against one static body (two pairs
    at least), anything else a group of its own."""
    rng = np.random.default_rng(0)
    S, T, P = 40, 30, 300
    seg_j, tri_j = rng.integers(0, 3, S), rng.integers(0, 2, T)
    seg_g, tri_g = np.where(seg_j == 0, rng.integers(0, 5, S), -1), np.where(tri_j == 0, rng.integers(0, 5, T), -1)
    balls, seg_r, tri_r = rng.random((5, 4)), rng.random(S), rng.random(T)
    rows = np.column_stack([rng.integers(0, 2, P), rng.integers(0, S, P), np.zeros(P, int)])
    rows[:, 2] = np.where(rows[:, 0] == 0, rng.integers(0, S, P), rng.integers(0, T, P))
    order, groups, spheres = pair_groups(rows, seg_j, seg_r, tri_j, tri_r, BodyBalls(seg_g, tri_g, balls))
    cover = np.zeros(P, int)
    for (s0, s1, col, is_tri), sphere in zip(groups, spheres):
        members = rows[order[s0:s1]]
        cover[order[s0:s1]] += 1
        if not col:
            assert s1 - s0 == 1
            continue
        assert s1 - s0 >= MIN_GROUP and len(set(members[:, col])) == 1  # one moving primitive
        static = members[:, 3 - col]
        tri_static = (members[:, 0] == 1) & (col == 1)
        body = np.where(tri_static, tri_g[np.where(tri_static, static, 0)], seg_g[np.where(tri_static, 0, static)])
        assert len(set(body)) == 1 and body[0] >= 0  # one static body
        moving_r = seg_r[members[0, 1]] if col == 1 else (tri_r if is_tri else seg_r)[members[0, 2]]
        assert np.allclose(sphere, [*balls[body[0], :3], balls[body[0], 3] + moving_r])
    assert np.all(cover == 1)
    assert (groups[:, 2] > 0).sum() > 10


def test_levers_bound_how_far_every_primitive_moves(small):
    """Brute force: each moving segment end and triangle vertex, placed at two configurations, moves at most
    sum |dq_i| lever_i, for small and large steps."""
    asm, ctx, xs, _, _ = small
    pk = ctx.packed
    ms, mt = np.flatnonzero(pk.seg_j > 0), np.flatnonzero(pk.tri_j > 0)
    lever = levers(pk, ms, mt)
    nj, rng = pk.chain_f.shape[0], np.random.default_rng(5)
    R, p = np.empty((2, nj, 3, 3)), np.empty((2, nj, 3))
    ratio = []
    for step in (1e-3, 0.05, 0.5, 2.0):
        for _ in range(20):
            q0 = xs[rng.integers(len(xs)), :14] + rng.normal(size=14) * 0.3
            qs = np.vstack([q0, q0 + step * rng.normal(size=14)])
            joint_placements(pk.chain_f, pk.chain_i, qs, R, p)
            pts = []
            for k in range(2):
                A, B, V = np.empty((len(pk.seg_f), 3)), np.empty((len(pk.seg_f), 3)), np.empty((len(pk.tri_f), 3, 3))
                place_primitives(pk.seg_f, pk.seg_j, pk.tri_f, pk.tri_j, R[k], p[k], A, B, V)
                pts.append((A[ms], B[ms], V[mt]))
            moved = np.concatenate([np.maximum(np.linalg.norm(pts[1][0] - pts[0][0], axis=1),
                                               np.linalg.norm(pts[1][1] - pts[0][1], axis=1)),
                                    np.linalg.norm(pts[1][2] - pts[0][2], axis=2).max(axis=1)])
            bound = lever @ np.abs(qs[1] - qs[0])
            assert np.all(moved <= bound + 1e-12)
            ratio.append(moved.max() / bound.max())
    assert max(ratio) > 0.1  # not vacuous


@pytest.mark.parametrize("k", [0, 20, 35])
def test_node_calc_with_the_bounds_of_its_last_calcdiff_equals_a_fresh_node(small, k):
    """A calc after calcDiff skips the pairs whose bound there, less the primitives' motion since, clears the
    margin: the cost and next state are those of a node without that memory, bit for bit, also where the
    motion brings pairs within the margin."""
    asm, ctx, xs, us, keep = small
    rng = np.random.default_rng(400 + k)
    pairs = asm.pairs.subset(keep[k])
    m = CompiledNodeModel(ctx, k, pairs, "al", ctx.packed)
    m.lam_eq = rng.normal(size=m.m_eq)
    m.lam_in[:3] = 50.0
    u = None if k == asm.task.N else us[k]
    d = m.createData()
    m.calcDiff(d, xs[k], u) if u is not None else m.calcDiff(d, xs[k])
    assert np.isfinite(m.ref_q).all()
    penetrating = 0
    for scale in (1e-4, 1e-2, 0.1, 0.3):
        for _ in range(5):
            x = xs[k] + np.concatenate([scale * rng.normal(size=14), rng.normal(size=14)])
            fresh = CompiledNodeModel(ctx, k, pairs, "al", ctx.packed)
            fresh.lam_eq, fresh.lam_in = m.lam_eq, m.lam_in
            da, db = m.createData(), fresh.createData()
            for model, dd in ((m, da), (fresh, db)):
                model.calc(dd, x, u) if u is not None else model.calc(dd, x)
            assert da.cost == db.cost and np.array_equal(da.xnext, db.xnext)
            penetrating += int((fresh.values(x)[1][:len(pairs)] < 0).any())
    assert penetrating > 0  # some motions did bring pairs within the margin


def test_a_group_holds_one_kind_of_moving_primitive():
    """Segment 2 and triangle 2 are different primitives: their pairs with one static body are two groups, and
    each group's bound holds for its own pairs (found in review: one key for both hid a penetrating triangle)."""
    seg_j, tri_j = np.array([0, 0, 1]), np.array([0, 0, 1])
    seg_g, tri_g = np.array([0, 0, -1]), np.array([-1, -1, -1])
    balls = np.array([[0.0, 0.0, 0.0, 0.2]])
    rows = np.array([[0, 0, 2], [1, 1, 2], [0, 1, 2], [1, 0, 2]])  # static segments 0, 1 vs segment 2, triangle 2
    order, groups, spheres = pair_groups(rows, seg_j, np.full(3, 0.01), tri_j, np.full(3, 0.01), BodyBalls(seg_g, tri_g, balls))
    for s0, s1, col, is_tri in groups:
        kinds = rows[order[s0:s1], 0]
        assert len(set(kinds)) == 1 and (not col or is_tri == (kinds[0] == 1))
    A = np.array([[0.05, 0, 0], [-0.05, 0, 0], [5.0, 0, 0]])
    B = np.array([[0.05, 0.1, 0], [-0.05, 0.1, 0], [5.0, 0.1, 0]])
    V = np.zeros((3, 3, 3))
    V[2] = [[0.0, 0.0, -0.05], [0.1, 0.0, 0.05], [-0.1, 0.0, 0.05]]  # through the body's segments
    for gi in np.flatnonzero(groups[:, 2] > 0):
        lb = group_bound(A, B, V, rows, order, groups, spheres, gi)
        for n in order[groups[gi, 0]:groups[gi, 1]]:
            a, b = rows[n, 1], rows[n, 2]
            if rows[n, 0] == 0:
                core = segment_segment(A[a:a + 1], B[a:a + 1], A[b:b + 1], B[b:b + 1]).distance[0]
            else:
                core = segment_triangle(A[a:a + 1], B[a:a + 1], V[b:b + 1, 0], V[b:b + 1, 1], V[b:b + 1, 2]).distance[0]
            assert lb <= core - 0.02 + 1e-12


@numba.njit
def _raises_when_positive(x):
    if x > 0.0:
        raise ValueError("a positive x")
    return x


@numba.njit
def _call(f, x):
    return f(x)


def test_an_exception_in_a_function_called_through_its_pointer_is_raised():
    """The compiled FDDP calls the node evaluation through a pointer, whose C wrapper only writes an exception
    out (as unraisable): the solve's guard raises it, and a call that raises nothing returns its value."""
    sig = types.float64(types.float64)
    _raises_when_positive.compile(sig.args)
    f = CompileResultWAP(_raises_when_positive.overloads[sig.args])
    with pytest.raises(RuntimeError, match="the call failed: ValueError.*a positive x"):
        with unraisable_raised("the call"):
            _call(f, 1.0)
    with unraisable_raised("the call"):
        assert _call(f, -2.0) == -2.0
