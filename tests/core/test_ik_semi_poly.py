"""The resultant-polynomial IK of the SSRMS middle locks (:mod:`capmap.core.ik.semi.resultant`) against
independent computations: the elimination's claims (P is a trigonometric polynomial of the stated
degree that vanishes at every solution) checked on samples, and the solution sets against two other
algorithms, the 1-D search over joint 0 (:mod:`capmap.core.ik.semi.search`) and the general 6R elimination
(:mod:`capmap.core.ik.general.elimination`), with planted bugs that these checks must catch."""

import numpy as np
import pytest

import capmap.core.ik.semi.resultant as ik_semi_poly
import capmap.core.ik.semi.search as ik_semi
from capmap.core import ik
from capmap.core.ik.finish import _finish
from capmap.core.reduction import lock
from capmap.robots import load
from tests.core.test_ik_general import _missing
from tests.scenario import SSRMS_YAML


def _arm(joint, angle):
    return lock(load(SSRMS_YAML), joint, angle)


def _search(arm, T):
    """The 1-D search alone (no polynomial), through the common IK end."""
    theta, ok = ik_semi.candidates(arm.chain, T)
    return _finish(arm.chain, theta, ok, T, arm.q_lower, arm.q_upper, ik.RESIDUAL_TOL, "search", 8)


@pytest.mark.parametrize("joint", [3, 4, 5])
def test_the_resultant_is_a_trigonometric_polynomial_vanishing_at_every_solution(joint):
    """P sampled at 64 angles: no harmonic above the chain's degree (8) beyond rounding (1e-9 of the
    largest), and at every joint-0 angle of the general 6R method's solutions P is zero to rounding
    (|P| <= 1e-9 of its largest sample; the elimination is exact, so only rounding is left)."""
    arm = _arm(joint, 0.7)
    solver = ik_semi_poly.prepare(arm.chain)
    assert solver.degree == 8
    rng = np.random.default_rng(joint)
    T = arm.chain.fk(rng.uniform(arm.q_lower, arm.q_upper, (40, 6)))
    theta = 2 * np.pi * np.arange(64) / 64
    vals, scale = np.empty((40, 64)), np.empty((40, 64))
    ik_semi_poly.polynomial_samples(solver.k, T, theta, vals, scale)
    coef = np.abs(np.fft.fft(vals, axis=1))
    harmonic = np.minimum(np.arange(64), 64 - np.arange(64))
    assert (coef[:, harmonic > 8].max(axis=1) <= 1e-9 * coef.max(axis=1)).all()
    general = ik.GeneralSixR().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    for n in range(40):
        q0 = np.ascontiguousarray(general.q[n, : general.n_solutions[n], 0])
        at, sc = np.empty((1, len(q0))), np.empty((1, len(q0)))
        ik_semi_poly.polynomial_samples(solver.k, T[n:n + 1], q0, at, sc)
        assert (np.abs(at) <= 1e-9 * np.abs(vals[n]).max()).all()


@pytest.mark.parametrize("joint", [3, 4, 5])
@pytest.mark.parametrize("angle", [0.3, -1.2, 2.5])
def test_nothing_missed_against_two_other_algorithms(joint, angle):
    """300 poses per case: every solution of the 1-D search and of the general 6R method is among the
    polynomial method's, and each of its solutions is found by one of them (2026-12-02: 18,014
    solutions over the 9 cases, none missed by any method; on 15 cases x 1,000 poses, 100,842
    solutions, the polynomial method missed none, the search 2 (two solutions within 2e-3 rad of
    each other beside a fold) and the general method 16 (its eliminations near rank loss); under
    OPENBLAS_CORETYPE=Prescott on another 1,000 x 15, 101,628: none, 2 and 6)."""
    arm = _arm(joint, angle)
    rng = np.random.default_rng(joint)
    T = arm.chain.fk(rng.uniform(arm.q_lower, arm.q_upper, (300, 6)))
    poly = ik.SemiAnalytic().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    assert poly.method == "semi_analytic"
    search = _search(arm, T)
    general = ik.GeneralSixR().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    assert _missing(search, poly) == 0 and _missing(general, poly) == 0
    both = _union(search, general)
    assert _missing(poly, both) == 0


def _union(a, b):
    """Per pose the solutions of a and b joined (IKSolutions-like: q, n_solutions)."""
    K = a.q.shape[1] + b.q.shape[1]
    q = np.full((len(a.q), K, 6), np.nan)
    n = a.n_solutions + b.n_solutions
    for i in range(len(a.q)):
        q[i, : n[i]] = np.concatenate([a.q[i, : a.n_solutions[i]], b.q[i, : b.n_solutions[i]]])
    return ik.IKSolutions(q=q, n_solutions=n, method="union")


def test_a_dropped_root_is_caught(monkeypatch):
    """Planted bug: the companion's first real root of every pose is dropped; the comparison with the
    search must then report missing solutions."""
    arm = _arm(4, 0.3)
    T = arm.chain.fk(np.random.default_rng(2).uniform(arm.q_lower, arm.q_upper, (60, 6)))
    search = _search(arm, T)
    real_roots = ik_semi_poly.real_roots

    def dropped(poly, usable, real_tol, noise):
        r = real_roots(poly, usable, real_tol, noise)
        first = np.ones(len(r.pose), dtype=bool)
        first[1:] = r.pose[1:] != r.pose[:-1]
        return r._replace(pose=r.pose[~first], x=r.x[~first], imag=r.imag[~first], error=r.error[~first])

    monkeypatch.setattr(ik_semi_poly, "real_roots", dropped)
    broken = ik.SemiAnalytic().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    assert _missing(search, broken) > 0


def test_degenerate_poses_go_to_the_search(monkeypatch):
    """Poses the polynomial cannot take (here: every pose marked as vanishing identically) are solved
    by the 1-D search: the same solution set as the search's."""
    arm = _arm(3, -1.2)
    T = arm.chain.fk(np.random.default_rng(3).uniform(arm.q_lower, arm.q_upper, (30, 6)))
    polynomials = ik_semi_poly._polynomials

    def vanishing(solver, T, degree):
        poly, status, noise = polynomials(solver, T, degree)
        return poly, np.ones_like(status), noise

    monkeypatch.setattr(ik_semi_poly, "_polynomials", vanishing)
    sol = ik.SemiAnalytic().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    search = _search(arm, T)
    assert _missing(sol, search) == 0 and _missing(search, sol) == 0
    assert ik_semi_poly.roots(ik_semi_poly.prepare(arm.chain), T).degenerate.all()


def test_clustered_solutions_beside_a_fold():
    """Where two solutions' joint-0 angles lie within 2e-3 rad (P has a near-double root, known to
    ~1e-5 rad only, often just past the fold where two branches of joint 1 meet): every solution the
    search or the general method finds there is found (windows of the 1-D search around such roots).
    2,000 poses with joint 3 locked at 1.7 rad hold 92 such poses (2026-12-02); with the windows
    removed (a planted bug) this test fails."""
    arm = _arm(3, 1.7)
    T = arm.chain.fk(np.random.default_rng(1).uniform(arm.q_lower, arm.q_upper, (2000, 6)))
    poly = ik.SemiAnalytic().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
    ref = _union(_search(arm, T), ik.GeneralSixR().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper))
    q0 = np.sort(np.where(np.arange(ref.q.shape[1]) < ref.n_solutions[:, None], ref.q[..., 0], 1e3), axis=1)
    gap = np.diff(q0, axis=1)
    cluster = np.flatnonzero(((gap > 1e-6) & (gap < 2e-3)).any(axis=1))
    assert len(cluster) >= 20
    pick = lambda s: ik.IKSolutions(q=s.q[cluster], n_solutions=s.n_solutions[cluster], method=s.method)  # noqa: E731
    assert _missing(pick(ref), pick(poly)) == 0
