"""The general 6R method against independent solutions: the closed forms (another derivation) on the
SSRMS and the UR5, the sampled configuration on random chains, a multi-start search, and a
planted bug (a dropped eigenvalue) that these checks must catch."""

import logging

import numpy as np
import pytest

import capmap.core.ik.general.elimination as ik_general
import capmap.core.ik.general.select as ik_general_select
from capmap.core import ik
from capmap.core.ik.polish import PolishSettings, polish
from capmap.core.kinematics import Chain, pose_error
from capmap.core.reduction import free, lock
from capmap.robots import load
from tests.scenario import SSRMS_YAML

UR5 = SSRMS_YAML.parent / "ur5.yaml"
WRAP = 1e-6  # rad: two solutions are one (the IK's duplicate tolerance)


def _missing(reference, found) -> int:
    """How many of the reference solutions (per pose) are absent from ``found`` (IKSolutions each)."""
    miss = 0
    for n in range(len(reference.n_solutions)):
        A = reference.q[n, : reference.n_solutions[n]]
        B = found.q[n, : found.n_solutions[n]]
        for a in A:
            if not len(B) or (np.abs(np.mod(B - a + np.pi, 2 * np.pi) - np.pi).max(axis=1) > WRAP).all():
                miss += 1
    return miss


def _random_chain(rng) -> Chain:
    X = np.zeros((7, 4, 4))
    for i in range(7):
        q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
        X[i, :3, :3] = q * np.sign(np.linalg.det(q))
        X[i, :3, 3] = 0.5 * rng.standard_normal(3)
        X[i, 3, 3] = 1.0
    return Chain(X)


def _arms():
    ssrms = load(SSRMS_YAML)
    yield "ur5", free(load(UR5))
    for joint in (1, 2, 6, 7):
        yield f"ssrms_j{joint}", lock(ssrms, joint, 0.7)


@pytest.mark.parametrize("name, arm", list(_arms()), ids=lambda v: v if isinstance(v, str) else "")
def test_agrees_with_the_closed_forms(name, arm):
    """Closed-form chains: the general method returns exactly the closed form's solution set (every
    closed-form branch, nothing else: both sets are complete), on 150 reachable poses."""
    rng = np.random.default_rng(4)
    T = arm.chain.fk(rng.uniform(arm.q_lower, arm.q_upper, (150, 6)))
    closed = ik.method_of(arm.chain)
    assert closed.name.startswith("closed_form")
    a = closed.solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    b = ik.GeneralSixR().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    assert _missing(a, b) == 0 and _missing(b, a) == 0


def test_random_chains_every_branch():
    """Five random 6R chains (no special geometry), 60 poses each: every returned solution exact by
    the chain's FK, the sampled configuration among them, and every solution of a 64-start Newton
    search among them."""
    rng = np.random.default_rng(12)
    lo, hi = -np.pi * np.ones(6), np.pi * np.ones(6)
    for _ in range(5):
        chain = _random_chain(rng)
        q = rng.uniform(lo, hi, (60, 6))
        T = chain.fk(q)
        sol = ik.GeneralSixR().solve_chain(chain, T, lo, hi)
        starts = ik.MultiStartNewton().solve_chain(chain, T, lo, hi)
        assert _missing(starts, sol) == 0
        for n in range(len(T)):
            Q = sol.q[n, : sol.n_solutions[n]]
            err = pose_error(chain.fk(Q), np.repeat(T[n][None], len(Q), 0))
            assert np.abs(err).max() <= ik.RESIDUAL_TOL
            assert (np.abs(np.mod(Q - q[n] + np.pi, 2 * np.pi) - np.pi).max(axis=1) < WRAP).any()


def test_a_dropped_eigenvalue_is_caught(monkeypatch):
    """Planted bug: the companion's first real root of every pose is dropped. The closed-form
    comparison above must then report missing branches."""
    real_roots = ik_general._real_roots

    def dropped(poly, usable, noise):
        roots = real_roots(poly, usable, noise)
        first = np.ones(len(roots.pose), dtype=bool)
        first[1:] = roots.pose[1:] != roots.pose[:-1]
        return roots._replace(pose=roots.pose[~first], x=roots.x[~first], imag=roots.imag[~first])

    arm = free(load(UR5))
    T = arm.chain.fk(np.random.default_rng(4).uniform(arm.q_lower, arm.q_upper, (40, 6)))
    closed = ik.method_of(arm.chain).solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    monkeypatch.setattr(ik_general, "_real_roots", dropped)
    broken = ik.GeneralSixR().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    assert _missing(closed, broken) > 0


def test_collinear_axes_are_reported(caplog):
    """Two consecutive collinear axes (a continuum of solutions) cannot be solved exactly: the poses
    are reported degenerate, the search fills in with a warning, and classify says so."""
    ur5 = load(UR5)
    chain = free(ur5).chain
    X = chain.X.copy()
    X[1] = np.eye(4)  # joint 2's axis on joint 1's: one line
    X[1, 2, 3] = 0.1
    col = Chain(X)
    T = col.fk(np.random.default_rng(0).uniform(-np.pi, np.pi, (4, 6)))
    _, _, degenerate = ik_general_select.candidates(ik_general_select.prepare(col), T)
    assert degenerate.all()
    with caplog.at_level(logging.WARNING, logger="capmap.core.ik"):
        sol = ik.solve_chain(col, T, -np.pi * np.ones(6), np.pi * np.ones(6))
    assert "degenerate" in caplog.text and "overstate" in caplog.text
    assert (sol.n_solutions > 0).all()
    info = ik.classify(col)
    assert info.collinear == ((1, 2),) and not info.complete and "COLLINEAR" in info.describe()


def test_classify_known_shapes():
    ur5 = ik.classify(free(load(UR5)).chain)
    assert ur5.pairs == ("intersecting", "parallel", "parallel", "intersecting", "intersecting")
    assert ur5.method == "closed_form" and ur5.complete
    j3 = ik.classify(lock(load(SSRMS_YAML), 3, 0.3).chain)
    assert j3.method == "semi_analytic" and j3.complete and j3.pairs[2] == "parallel"


def test_every_known_configuration_on_1000_poses():
    """SSRMS with joint 4 locked at 130 deg, 1,000 seeded poses FK(q): the arm's method (the resultant
    polynomial, :mod:`capmap.core.ik.semi.resultant`) returns every q. (The general method, solving each
    pose with two eliminations, loses pose 249's under OPENBLAS_CORETYPE=Prescott: joints 2 and 6
    both within 1 deg of the angles at which the two eliminations lose rank.)"""
    arm = lock(load(SSRMS_YAML), 4, np.deg2rad(130))
    q = np.random.default_rng(5).uniform(-np.pi, np.pi, (1000, 6))
    sol = ik.solve_chain(arm.chain, arm.chain.fk(q), np.full(6, -10.0), np.full(6, 10.0))
    assert sol.method == "semi_analytic"
    d = np.abs(np.mod(sol.q - q[:, None] + np.pi, 2 * np.pi) - np.pi).max(axis=-1)
    assert (np.nanmin(d, axis=1) < 1e-6).all()


def _valid(chain, T, theta, ok):
    """Per pose the polished candidates that reach T (N, 4, 4) to 1e-9: theta (N, K, 6), valid (N, K)."""
    N, K, _ = theta.shape
    flat = theta.reshape(-1, 6).copy()
    idx = np.flatnonzero(ok.reshape(-1))
    flat[idx], err = polish(chain.X, flat[idx], T, idx // K, PolishSettings(8, 1e-13))
    good = np.zeros(N * K, dtype=bool)
    good[idx] = np.abs(err).max(axis=1) <= 1e-9
    return flat.reshape(N, K, 6), good.reshape(N, K)


def _lost_on_settled(chain, T, settle) -> int:
    """Solutions of the union of every formulation (each run on every pose) that the first one misses
    on the poses ``settle`` (the rule under test) says it settled. Two solutions within 1e-4 rad are
    one: at condition numbers 1e4-2e7 the FK tolerance (1e-9) admits solutions 2e-6 to 1.3e-5 rad
    apart (measured on the xArm7 with joint 2 locked, the Panda with joint 4)."""
    solver = ik_general_select.prepare(chain)
    parts = [ik_general_select._run(chain, f, solver.left[k], solver.degrees[k], solver.phase, T, solver.structural[k])
             for k, f in enumerate(solver.order)]
    first, theta1 = parts[0]
    settled = settle(solver, first, theta1.copy(), T, 8, 1e-9)
    Q1, g1 = _valid(chain, T, theta1, first.ok)
    lost = 0
    for out, theta in parts[1:]:
        Q, g = _valid(chain, T, theta, out.ok)
        for n in np.flatnonzero(settled):
            a = Q1[n][g1[n]]
            for q in Q[n][g[n]]:
                lost += not len(a) or bool((np.abs(np.mod(a - q + np.pi, 2 * np.pi) - np.pi).max(axis=1) > 1e-4).all())
    return lost


def _solved_only(solver, out, theta, T, steps, tol):
    return out.status == 0


@pytest.mark.parametrize("joint, share", [(6, 0.25), (7, 0.5), (4, 0.75)])
def test_a_settled_pose_lost_nothing(joint, share):
    """The xArm7 with joint 4, 6 or 7 locked (its first formulation loses 50-380 solutions per 2,000
    poses against the union of two, measured 2026-12-02): on 1,500 seeded poses, no solution of any
    other formulation is missing from the first one's on a pose it settles (then no second one runs
    there). Planted: settling every pose the formulation solved lets 70 lost solutions through with
    joint 6 locked (59 under OpenBLAS's Prescott kernels; measured 2026-12-03). Asserted: >= 10.
    Settling by the confirmation alone (every candidate's convergence not required) lets 12 through
    on the default kernels and 0 under Prescott since the near-real pairs are split (6 before), too
    rounding-dependent to be the plant."""
    robot = load(SSRMS_YAML.parent / "xarm7.yaml")
    arm = lock(robot, joint, robot.q_lower[joint - 1] + share * (robot.q_upper[joint - 1] - robot.q_lower[joint - 1]))
    T = np.ascontiguousarray(arm.chain.fk(np.random.default_rng(joint).uniform(-np.pi, np.pi, (1500, 6))))
    assert _lost_on_settled(arm.chain, T, ik_general_select._settled) == 0
    if joint == 6:
        assert _lost_on_settled(arm.chain, T, _solved_only) >= 10


def _no_defences(monkeypatch):
    """The general method without its defences next to a continuum: no Newton rescue, no
    four-parallel test (so no family search either), no pseudo-zero candidates."""
    monkeypatch.setattr(ik_general_select, "_rescued", lambda chain, theta, ok, T, steps, tol: (
        np.zeros((len(T), 0, 6)), np.zeros((len(T), 0), dtype=bool), np.zeros(len(T), dtype=bool),
        ik_general_select._polished(chain, theta, ok, T, steps, tol)))
    monkeypatch.setattr(ik_general_select, "four_parallel", lambda chain, q, tol=0.0: np.zeros(len(q), dtype=bool))
    monkeypatch.setattr(ik_general, "PSEUDO", -1.0)


@pytest.mark.parametrize("plant", [None, "no defences"])
def test_near_a_continuum_lost_solutions_are_recovered(monkeypatch, plant):
    """The SSRMS with joint 5 locked at -1 rad and joint 4 at 0.3 rad (chains the semi-analytical
    method solves completely: the oracle), 600 poses each with q2 and q5 within 8 deg of +-90 deg,
    where four axes become parallel (a continuum): the eliminations' roots crowd there, and the
    band's width puts poses on both sides of the 5 deg four-parallel test and the 10 deg family
    search. Measured 2026-12-03 (Intel Xeon): 0 of 8,346 solutions lost; without all the defences
    (rescue, four-parallel test and family search, pseudo-zero candidates) 39 (12 + 27); each alone
    removed loses 0-9. On held-out sets (the SSRMS with joint 3, 4 or 5 locked at 3 other angles,
    bands of 1.7, 6, 8, 11 and 15 deg, 189,324 solutions) 0 lost. Asserted: at most 0.05 % lost
    (4 of 8,346), the planted omission at least 0.25 % (21; 39 measured); nothing returned that
    the oracle lacks."""
    if plant:
        _no_defences(monkeypatch)
    lost = total = 0
    for joint, angle, seed in ((5, -1.0, 11), (4, 0.3, 4)):
        arm = lock(load(SSRMS_YAML), joint, angle)
        rng = np.random.default_rng(seed)
        q = rng.uniform(-np.pi, np.pi, (600, 6))
        for i in (1, 4):
            q[:, i] = rng.choice([-1, 1], 600) * np.pi / 2 + rng.uniform(-0.14, 0.14, 600)
        T = arm.chain.fk(q)
        reference = ik.method_of(arm.chain).solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
        assert reference.method == "semi_analytic"
        general = ik.GeneralSixR().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
        assert _missing(general, reference) == 0
        lost += _missing(reference, general)
        total += reference.n_solutions.sum()
    if plant:
        assert lost >= 0.0025 * total
    else:
        assert lost <= 0.0005 * total


def test_four_parallel_axes():
    """The SSRMS with joint 4 locked has axes 1, 3, 4, 6 parallel exactly when q2 and q5 are +-90 deg
    (its DH: the other axes are perpendicular to them); 1 deg off is within the 5 deg tolerance, 8 deg off is not."""
    arm = lock(load(SSRMS_YAML), 4, 0.3)
    q = np.zeros((4, 6))
    q[:, 1] = q[:, 4] = np.pi / 2 + np.deg2rad([0.0, 1.0, 8.0, -90.0])
    assert ik_general_select.four_parallel(arm.chain, q).tolist() == [True, True, False, False]
