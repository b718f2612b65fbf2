"""The compiled node models against Pinocchio: the logarithms and their Jacobians, the packed chain's
kinematics, the pair distances, every output of a node (the reference node model, on Pinocchio's
own calls, as the second formulation) and finite differences; the same solve from both.

Tolerances: both sides evaluate the same closed forms in double precision with a different order
of operations (the compiled chain composes joint rotations itself, Pinocchio its own way), so
agreement is to a few hundred ulps of the largest entry (measured <= 1e-14 relative on this
machine); the bounds below (1e-10) leave four orders of margin for other vector units.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from capmap.dualarm.geometry.chain import fk, pack
from capmap.dualarm.geometry.proximity import PairFilter, batch_distances
from capmap.dualarm.ocp.compiled_nodes import CompiledNodeModel
from capmap.dualarm.ocp.crocoddyl_nodes import NodeModel
from capmap.dualarm.ocp.lie import jlog3, jlog6, log3, log6
from capmap.dualarm.ocp.settings import ALSettings, SolveOptions, StopRule
from capmap.dualarm.ocp.solver import solve, solve_csqp
from tests.dualarm.conftest import W

NODES = [0, 10, 27, 28, 29, 35, 39, 40]  # transfer, pre-insertion and around it, insertion, terminal


def _rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.abs(a - b).max() / max(1.0, np.abs(b).max()))


# ---------------------------------------------------------------------------------------------- logarithms
def _rotations():
    rng = np.random.default_rng(3)
    out = []
    for theta in [0.0, 1e-12, 1e-9, 3e-6, 6e-6, 7e-6, 1e-4, 1.2e-4, 1.3e-4, 1e-2, 0.5, 1.0, 2.0, 3.0, np.pi - 1e-3,
                  np.pi - 1e-5]:
        for _ in range(4):
            a = rng.normal(size=3)
            out.append(pin.exp3(theta * a / np.linalg.norm(a)))
    return out


def test_logarithms_and_their_jacobians_equal_pinocchio():
    rng = np.random.default_rng(4)
    w, r6, J3, J6 = np.empty(3), np.empty(6), np.empty((3, 3)), np.empty((6, 6))
    for R in _rotations():
        theta = log3(R, w)
        ref = pin.log3(R)
        # the angle from the trace, as Pinocchio's (below ~1e-8 rad it rounds to sqrt(eps)-level values; the
        # log itself comes from the antisymmetric part there)
        assert theta == pytest.approx(np.linalg.norm(ref), abs=1e-8)
        # near pi the axis comes from the symmetric part: a sign ambiguity only at pi itself
        assert _rel(w, ref) < (1e-7 if np.pi - theta < 1e-4 else 1e-12)
        jlog3(theta, w, J3)
        assert _rel(J3, pin.Jlog3(R)) < (1e-4 if np.pi - theta < 1e-4 else 1e-10)
        p = rng.normal(size=3)
        M = pin.SE3(R, p)
        log6(R, p, r6)
        assert _rel(r6, pin.log6(M).vector) < (1e-6 if np.pi - theta < 1e-4 else 1e-12)
        jlog6(R, p, J6)
        assert _rel(J6, pin.Jlog6(M)) < (1e-3 if np.pi - theta < 1e-4 else 1e-10)


def test_jlog6_is_the_derivative_of_log6():
    """Jlog6 against central differences of log6 under a local perturbation M exp(h e_i)."""
    rng = np.random.default_rng(5)
    r_plus, r_minus, J = np.empty(6), np.empty(6), np.empty((6, 6))
    for theta in (1e-3, 0.7, 2.5):
        a = rng.normal(size=3)
        M = pin.SE3(pin.exp3(theta * a / np.linalg.norm(a)), rng.normal(size=3))
        jlog6(M.rotation, M.translation, J)
        h = 1e-6
        for i in range(6):
            e = np.zeros(6)
            e[i] = h
            Mp, Mm = M * pin.exp6(e), M * pin.exp6(-e)
            log6(Mp.rotation, Mp.translation, r_plus)
            log6(Mm.rotation, Mm.translation, r_minus)
            assert np.allclose(J[:, i], (r_plus - r_minus) / (2 * h), atol=1e-7)


# ---------------------------------------------------------------------------------------------- chain
def test_packed_kinematics_equal_pinocchio(small):
    asm, ctx, xs, _, _ = small
    m, d = asm.model, asm.model.createData()
    pk = ctx.packed
    R, p = np.empty((m.njoints, 3, 3)), np.empty((m.njoints, 3))
    rng = np.random.default_rng(6)
    for q in [xs[0, :14], *rng.uniform(-3, 3, size=(20, 14))]:
        fk(pk.chain_f, pk.chain_i, q, R, p)
        pin.forwardKinematics(m, d, q)
        for j in range(m.njoints):
            assert _rel(R[j], d.oMi[j].rotation) < 1e-12 and _rel(p[j], d.oMi[j].translation) < 1e-12


def test_a_joint_that_is_not_revolute_is_not_packed():
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "hinge")
    model.addJoint(j1, pin.JointModelPZ(), pin.SE3.Identity(), "slider")
    from capmap.dualarm.geometry.collision import Primitives
    why = pack(model, (0, 0, 0), Primitives.empty())
    assert isinstance(why, str) and "'slider'" in why and "not a revolute joint" in why


def test_a_one_joint_chain_is_packed():
    """eigenpy returns a 1-dof model's Jacobian as a vector: the packing still reads its axis."""
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.3])), "hinge")
    frames = tuple(model.addFrame(pin.Frame(n, j, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME)) for n in "lrp")
    from capmap.dualarm.geometry.collision import Primitives
    packed = pack(model, frames, Primitives.empty())
    assert not isinstance(packed, str), packed
    np.testing.assert_allclose(packed.chain_f[1, 12:], [0.0, 1.0, 0.0])


def test_batch_distances_within_keep_a_minimum_that_its_bounds_reach_by_rounding():
    """A segment end over a triangle's inside: the plane bound equals the distance there, and rounding
    puts it above about half the time; the nearest pair's distance must stay exact (not inf), and with
    no pairs at all there is nothing to fail on."""
    from scipy.spatial.transform import Rotation

    from capmap.dualarm.geometry.collision import Pairs, Primitives
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "hinge")
    frames = tuple(model.addFrame(pin.Frame(n, j, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME)) for n in "lrp")
    rng = np.random.default_rng(4)
    obj = np.array(["x"], dtype=object)
    pairs = Pairs(np.zeros((0, 2), int), np.array([[0, 0]]))
    for _ in range(200):
        Rm, h = Rotation.random(random_state=rng).as_matrix(), rng.uniform(0.02, 0.15)
        tri = np.array([[0.0, 0, 0], [2, 0, 0], [0, 2, 0]]) @ Rm.T
        a, b = np.array([0.3, 0.3, h]) @ Rm.T, np.array([0.5, 0.7, h + 0.3]) @ Rm.T
        prims = Primitives(np.array([0]), a[None], b[None], np.zeros(1), obj, np.array([0]), tri[None], np.zeros(1), obj)
        packed = pack(model, frames, prims)
        D = batch_distances(packed, np.zeros((3, 1)), pairs, cutoff=0.2, within=0.01)
        assert np.isfinite(D).all() and np.allclose(D, h, atol=1e-12)
    empty = Pairs(np.zeros((0, 2), int), np.zeros((0, 2), int))
    assert batch_distances(packed, np.zeros((3, 1)), empty, cutoff=0.2, within=0.01).shape == (3, 0)


def test_batch_distances_equal_pinocchio_placements_and_the_cutoff_only_drops_far_pairs(small):
    asm, ctx, xs, _, _ = small
    d = asm.model.createData()
    qs = xs[:, :14]
    D = batch_distances(ctx.packed, qs, asm.pairs)
    Dc = batch_distances(ctx.packed, qs, asm.pairs, cutoff=0.06)
    for k in range(0, len(qs), 5):
        pin.forwardKinematics(asm.model, d, qs[k])
        ref = asm.collision.evaluate(d, asm.pairs).distance
        assert np.abs(D[k] - ref).max() < 1e-12
    far = np.isinf(Dc)
    assert np.all(D[far] > 0.06) and np.array_equal(Dc[~far], D[~far])
    assert far.mean() > 0.5  # the bound does drop most pairs (else it is not worth having)


def test_batch_distances_within_keep_each_minimum_and_every_near_pair_exact(small):
    asm, ctx, xs, _, _ = small
    qs = xs[:, :14]
    D = batch_distances(ctx.packed, qs, asm.pairs)
    Dw = batch_distances(ctx.packed, qs, asm.pairs, cutoff=0.2, within=0.01)
    assert np.array_equal(Dw.min(axis=1), D.min(axis=1)) and np.array_equal(Dw.argmin(axis=1), D.argmin(axis=1))
    keep = np.isfinite(Dw)
    assert np.array_equal(Dw[keep], D[keep])
    assert np.array_equal(keep | (D > np.maximum(0.01, D.min(axis=1))[:, None]), np.ones_like(keep))
    assert keep.mean() < 0.5  # it does skip most pairs


def test_pair_filter_returns_exactly_the_pairs_that_come_within_its_cutoff(small):
    """Over configurations that move by 1e-4 to 0.3 rad per joint and step (small steps: groups skipped on
    their carried bounds; large ones: pairs crossing the cutoff), each update returns exactly the pairs below
    the cutoff (every pair's exact distance, no bound) not returned before."""
    asm, ctx, xs, _, _ = small
    rng = np.random.default_rng(3)
    cutoff = 0.06
    f = PairFilter(ctx.packed, asm.pairs, len(xs), cutoff)
    seen = np.zeros((len(xs), len(asm.pairs)), dtype=bool)
    q = xs[:, :14].copy()
    crossed = 0
    for step in (0.0, 1e-4, 1e-3, 0.02, 1e-4, 0.05, 1e-3, 0.3, 0.01, 1e-4):
        q = q + step * rng.standard_normal(q.shape)
        D = batch_distances(ctx.packed, q, asm.pairs)
        expect = (D < cutoff) & ~seen
        assert np.array_equal(f.update(q), expect)
        crossed += int(expect.sum()) if step else 0
        seen |= expect
        assert np.array_equal(f.keep, seen)
        if step == 1e-4:
            assert (f.lb > cutoff + 0.01).mean() > 0.5  # most groups are then far enough to be skipped
    assert crossed > 100  # pairs did come near after the first call


# ---------------------------------------------------------------------------------------------- node contract
def _pair(ctx, asm, keep, k, mode, rng):
    pairs = asm.pairs.subset(keep[k])
    a, b = NodeModel(ctx, k, pairs, mode), CompiledNodeModel(ctx, k, pairs, mode, ctx.packed)
    if mode == "al":
        a.lam_eq = rng.normal(size=a.m_eq) * 10
        lam = np.abs(rng.normal(size=a.n_in)) * 200  # pairs within 0.2 m active at mu = 1e3
        lam[len(pairs):] = np.where(rng.random(a.n_in - len(pairs)) < 0.3, 1e4, 0.0)  # some limit rows active
        a.lam_in = lam
        b.lam_eq, b.lam_in = a.lam_eq.copy(), a.lam_in.copy()
    return a, b


def _run(m, x, u, diff=True):
    d = m.createData()
    if u is None:
        m.calc(d, x)
        if diff:
            m.calcDiff(d, x)
    else:
        m.calc(d, x, u)
        if diff:
            m.calcDiff(d, x, u)
    return d


def _smooth_state(asm, pairs, x0, dx):
    """x0 + dx, shrunk by halves until no two cores of ``pairs`` intersect (where a pair's distance has no
    gradient: the closest points coincide and both models return 0, but the cost is not differentiable)."""
    d = asm.model.createData()
    for _ in range(8):
        x = x0 + dx
        pin.forwardKinematics(asm.model, d, x[:14])
        ev = asm.collision.evaluate(d, pairs)
        if np.all(np.linalg.norm(ev.p - ev.q, axis=1) > 1e-6):
            return x
        dx = dx / 2
    pytest.fail("no smooth state near the node")


@pytest.mark.parametrize("mode", ["al", "constrained"])
@pytest.mark.parametrize("k", NODES)
def test_compiled_node_equals_the_pinocchio_node(small, k, mode):
    asm, ctx, xs, us, keep = small
    rng = np.random.default_rng(100 + k)
    a, b = _pair(ctx, asm, keep, k, mode, rng)
    x = _smooth_state(asm, a.pairs, xs[k], np.concatenate([0.02 * rng.normal(size=14), 0.3 * rng.normal(size=14)]))
    u = None if k == asm.task.N else rng.normal(size=14)
    da, db = _run(a, x, u), _run(b, x, u)
    assert db.cost == pytest.approx(da.cost, rel=1e-10, abs=1e-14)
    for name in ("Lx", "Lxx", "Lu", "Luu", "Lxu", "xnext", "Fx", "Fu"):
        assert _rel(getattr(db, name), getattr(da, name)) < 1e-10, name
    if mode == "constrained":
        assert _rel(db.g, da.g) < 1e-10 and _rel(db.Gx, da.Gx) < 1e-10 and np.all(db.Gu == 0)
    else:  # the terms the check meant to exercise are there
        g = a.values(x)[1]
        assert np.any(a.lam_in[:len(a.pairs)] / ctx.mu - g[:len(a.pairs)] > 0) or len(a.pairs) == 0
        assert np.any(a.lam_in[len(a.pairs):] / ctx.mu - g[len(a.pairs):] > 0)
    ca, ga = a.values(x)
    cb, gb = b.values(x)
    assert _rel(cb, ca) < 1e-10 and _rel(gb, ga) < 1e-10


@pytest.mark.parametrize("k", NODES)
def test_compiled_node_gradient_and_constraint_jacobian_equal_finite_differences(small, k):
    asm, ctx, xs, us, keep = small
    rng = np.random.default_rng(200 + k)
    _, m = _pair(ctx, asm, keep, k, "al", rng)
    x = xs[k] + 1e-3 * rng.normal(size=28)
    u = None if k == asm.task.N else us[k]
    d = _run(m, x, u)
    Lx, C = np.array(d.Lx), np.array(d.C)
    h = 1e-6
    fd, fdC = np.zeros(28), np.zeros_like(C)
    for i in range(28):
        e = np.zeros(28)
        e[i] = h
        cost, cs = [], []
        for s in (1, -1):
            cost.append(_run(m, x + s * e, u, diff=False).cost)
            cs.append(m.values(x + s * e)[0])
        fd[i] = (cost[0] - cost[1]) / (2 * h)
        fdC[:, i] = (cs[0] - cs[1]) / (2 * h)
    assert np.allclose(Lx, fd, rtol=1e-5, atol=1e-6 * max(1.0, np.abs(fd).max()))
    assert np.allclose(C, fdC, atol=1e-7)


def test_compiled_solve_equals_the_pinocchio_solve(small, robot):
    """The whole AL-DDP with either node model: the same iterations and the same trajectory."""
    asm, _, xs, us, _ = small
    limits = (robot.q_lower, robot.q_upper, robot.v_max)
    st = ALSettings(mu_max=1e12, tolerance=5e-8)
    fast, ref = (solve(asm, W, limits, st, xs, us, SolveOptions(compiled=c)) for c in (True, False))
    assert fast.converged and ref.converged
    assert [s.inner_iterations for s in fast.stats] == [s.inner_iterations for s in ref.stats]
    # the same arithmetic up to rounding, amplified by the solves (measured 2e-13 rad)
    assert np.abs(fast.xs - ref.xs).max() < 1e-8 and np.abs(fast.us - ref.us).max() < 1e-6
    c_fast, c_ref = (solve_csqp(asm, W, limits, xs, us, StopRule(150, 1e-6), compiled=c) for c in (True, False))
    assert c_fast.iterations == c_ref.iterations and np.abs(c_fast.xs - c_ref.xs).max() < 1e-8
