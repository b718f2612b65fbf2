"""Joint torques of the held panel (capmap.dualarm.ocp.torques) against independent computations: the
panel's wrench against the finite-difference rate of its momentum, the torques against a second
formulation (the panel's inertia appended to the left arm, the right gripper's wrench as an external
force, Pinocchio's own RNEA), the least-norm distribution against numpy's minimum-norm solution, and the
peak-minimising one against random internal wrenches; its solver (the active rows carried from node to
node) against HiGHS's linear programmes."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import capmap.dualarm.ocp.torques as torques
from capmap.dualarm.ocp.torques import HeldPart, held_torques, part_wrench


@pytest.fixture(scope="module")
def setting(make_assembly, scene):
    asm = make_assembly(nodes=20, dt=0.05, pre=14)
    rng = np.random.default_rng(3)
    nv = asm.model.nv
    K = 6
    q = asm.q_start + rng.uniform(-0.3, 0.3, (K, nv))
    v = rng.uniform(-0.8, 0.8, (K, nv))
    a = rng.uniform(-2.0, 2.0, (K, nv))
    com = np.array([0.002, -0.01, 0.015])  # off-centre, so that every inertia term matters
    Ic = np.diag(scene.panel.inertia) + np.array([[0, 0.001, 0], [0.001, 0, -0.002], [0, -0.002, 0]])
    part = HeldPart(asm.task.panel, scene.panel.mass, com, Ic)
    return asm, part, q, v, a


def test_part_wrench_is_the_rate_of_its_momentum(setting):
    """f (world, about the origin) = d/dt (the panel's spatial momentum, world) - m g: central differences
    along q(t) = q + v t + a t^2 / 2."""
    asm, part, q, v, a = setting
    model, data = asm.model, asm.model.createData()
    inertia = part.inertia()

    def momentum(t, k):
        qt = pin.integrate(model, q[k], v[k] * t + 0.5 * a[k] * t * t)
        vt = v[k] + a[k] * t
        pin.forwardKinematics(model, data, qt, vt)
        pin.updateFramePlacements(model, data)
        vP = pin.getFrameVelocity(model, data, part.frame, pin.ReferenceFrame.LOCAL)
        return data.oMf[part.frame].act(inertia * vP).vector

    h = 1e-5
    for k in range(len(q)):
        pin.forwardKinematics(model, data, q[k], v[k], a[k])
        pin.updateFramePlacements(model, data)
        f_local = pin.Force(part_wrench(model, data, part))
        oMp = data.oMf[part.frame].copy()
        f_world = oMp.act(f_local).vector
        rate = (momentum(h, k) - momentum(-h, k)) / (2 * h)
        weight = pin.Force(model.gravity.linear * part.mass_kg, np.zeros(3))  # at the com, world axes
        weight_at_origin = pin.SE3(np.eye(3), oMp.act(part.com_m)).act(weight).vector
        expected = rate - weight_at_origin
        # central differences: O(h^2) truncation (~1e-8 here) and eps |h| / h rounding (~1e-10)
        assert np.allclose(f_world, expected, atol=1e-7 * (1 + np.abs(expected).max())), (k, f_world, expected)


def _appended(asm, part):
    """The model with the panel's inertia on the left gripper's joint (rigidly held by the left arm)."""
    model = asm.model.copy()
    fr = model.frames[part.frame]
    model.inertias[fr.parentJoint] = model.inertias[fr.parentJoint] + fr.placement.act(part.inertia())
    return model


def test_torques_equal_the_appended_body_formulation(setting):
    """Panel on the left arm's last body, the right gripper's wrench on the panel w_R as external forces
    (+w_R on the panel, -w_R on the right gripper): Pinocchio's RNEA gives the same torques (the left
    gripper's wrench then follows from the panel's motion alone)."""
    asm, part, q, v, a = setting
    model = asm.model
    effort = model.effortLimit.copy()
    out = held_torques(model, (asm.task.left, asm.task.right), part, q, v, a, effort)
    m2 = _appended(asm, part)
    d2 = m2.createData()
    fr = m2.frames[asm.task.right]
    for k in range(len(q)):
        pin.framesForwardKinematics(m2, d2, q[k])
        jl = m2.frames[part.frame].parentJoint
        fext = [pin.Force.Zero() for _ in range(m2.njoints)]
        fext[fr.parentJoint] = fr.placement.act(pin.Force(-out.w_right[k]))  # the panel pushes the right gripper
        fext[jl] = d2.oMi[jl].actInv(d2.oMf[asm.task.right]).act(pin.Force(out.w_right[k]))  # and is pushed by it
        ref = pin.rnea(m2, d2, q[k], v[k], a[k], fext)
        assert np.allclose(out.tau_nm[k], ref, atol=1e-9 * (1 + np.abs(ref).max())), (k, out.tau_nm[k] - ref)
    assert out.residual.max() < 1e-9 * (1 + np.abs(out.f_part).max())


def _grasp(asm, part, data, q, v, a):
    """The grasp map G (6, 12) and the grippers' stacked transposed LOCAL Jacobians (nv, 12) at (q, v, a),
    computed here from Pinocchio's placements (the kinematics left in ``data``)."""
    model, grippers = asm.model, (asm.task.left, asm.task.right)
    pin.forwardKinematics(model, data, q, v, a)
    pin.updateFramePlacements(model, data)
    pin.computeJointJacobians(model, data, q)
    oMp = data.oMf[part.frame]
    G = np.hstack([oMp.actInv(data.oMf[g]).toDualActionMatrix() for g in grippers])
    JT = np.hstack([pin.getFrameJacobian(model, data, g, pin.ReferenceFrame.LOCAL).T for g in grippers])
    return G, JT


def test_least_norm_distribution_is_numpys_minimum_norm_solution(setting):
    asm, part, q, v, a = setting
    model = asm.model
    data = model.createData()
    out = held_torques(model, (asm.task.left, asm.task.right), part, q, v, a, model.effortLimit)
    for k in range(len(q)):
        G, JT = _grasp(asm, part, data, q[k], v[k], a[k])
        W0 = np.linalg.lstsq(G, part_wrench(model, data, part), rcond=None)[0]
        ref = pin.rnea(model, data, q[k], v[k], a[k]) + JT @ W0
        assert np.allclose(out.tau_least_norm_nm[k], ref, atol=1e-9 * (1 + np.abs(ref).max()))


def test_peak_minimising_distribution_beats_random_internal_wrenches(setting):
    """No internal wrench (null-space direction of the grasp map) tried at random gives a smaller peak of
    |tau| / limit than the linear programme's, and the least-norm one is never better."""
    asm, part, q, v, a = setting
    model = asm.model
    data = model.createData()
    effort = model.effortLimit
    out = held_torques(model, (asm.task.left, asm.task.right), part, q, v, a, effort)
    rng = np.random.default_rng(5)
    for k in range(len(q)):
        G, JT = _grasp(asm, part, data, q[k], v[k], a[k])
        N = np.linalg.svd(G)[2][6:].T
        best = np.abs(out.tau_nm[k] / effort).max()
        assert best <= np.abs(out.tau_least_norm_nm[k] / effort).max() + 1e-9
        W = np.concatenate([out.w_left[k], out.w_right[k]])
        for scale in (1e-3, 1e-1, 10.0):
            trial = out.tau_nm[k][None, :] + (JT @ N @ rng.normal(0, scale, (6, 200))).T
            assert (np.abs(trial / effort).max(axis=1) >= best - 1e-7).all()
        assert np.allclose(G @ W, out.f_part[k], atol=1e-9 * (1 + np.abs(out.f_part[k]).max()))


def _peaks(A, b, z):
    return np.abs(np.einsum("kij,kj->ki", A, z) + b).max(axis=1)


@pytest.mark.parametrize("drift", [0.0, 1e-3, 1.0])
def test_active_rows_carried_along_a_motion_give_the_linear_programmes_optimum(drift, monkeypatch):
    """min_z max_i |A z + b|_i along a sequence of problems (A 14 x 6 as the torque LP's): the vertex of the
    previous node's active rows, accepted by its KKT conditions, has HiGHS's optimum (relative 1e-9: both
    are vertices up to HiGHS's 1e-7 tolerances, measured 3e-14 on the default task); drift 0 repeats one
    problem, 1e-3 moves it slowly (the carried rows mostly hold), 1 draws each anew (they mostly do not)."""
    rng = np.random.default_rng(11)
    K, n, m = 200, 14, 6
    A0, b0 = rng.normal(size=(n, m)), rng.normal(size=n)
    steps = np.cumsum(drift * rng.normal(size=(K, n, m + 1)), axis=0) if drift < 1 else rng.normal(size=(K, n, m + 1))
    if drift < 1:
        A, b = A0 + steps[:, :, :m], b0 + steps[:, :, m]
    else:
        A, b = steps[:, :, :m], steps[:, :, m]
    calls = []
    lp = torques._minimax_lp
    monkeypatch.setattr(torques, "_minimax_lp", lambda A_, b_: calls.append(len(A_)) or lp(A_, b_))
    z = torques._minimax(A, b)
    ref = _peaks(A, b, lp(A, b))
    assert np.allclose(_peaks(A, b, z), ref, rtol=1e-9, atol=0)
    if drift < 1:
        assert len(calls) < K / 4  # the carried rows did the work
    else:
        assert len(calls) > K / 2  # and were refused where they are not optimal


def test_degenerate_problems_fall_back_to_the_linear_programme():
    """Rows repeated (more than m + 1 active at the optimum): no vertex to carry, each node's LP."""
    rng = np.random.default_rng(12)
    A1, b1 = rng.normal(size=(7, 6)), rng.normal(size=7)
    A, b = np.tile(np.vstack([A1, A1])[None], (5, 1, 1)), np.tile(np.r_[b1, b1][None], (5, 1))
    z = torques._minimax(A, b)
    assert np.allclose(_peaks(A, b, z), _peaks(A, b, torques._minimax_lp(A, b)), rtol=1e-9, atol=0)


def test_a_vertex_is_accepted_only_at_the_optimum():
    """Vertices of min t s.t. |A z + b| <= t (any m + 1 rows and signs): _vertex accepts the optimal one
    (HiGHS's) and refuses those within every row's bound that are not optimal (a worse t), found by search."""
    rng = np.random.default_rng(13)
    A, b = rng.normal(size=(14, 6)), rng.normal(size=14)
    best = _peaks(A[None], b[None], torques._minimax_lp(A[None], b[None]))[0]
    refused = 0
    for _ in range(20000):
        rows = np.sort(rng.choice(14, 7, replace=False))
        signs = rng.choice([-1.0, 1.0], 7)
        M = np.hstack([signs[:, None] * A[rows], -np.ones((7, 1))])
        x = np.linalg.solve(M, -signs * b[rows])
        if x[6] <= 0 or np.abs(A @ x[:6] + b).max() > x[6] * (1 + 1e-12):
            continue  # not a vertex of the feasible set
        z = torques._vertex(A, b, rows, signs)
        if x[6] > best * (1 + 1e-6):
            assert z is None
            refused += 1
        else:
            assert z is not None and np.abs(A @ z + b).max() == pytest.approx(best, rel=1e-9)
    assert refused > 3
