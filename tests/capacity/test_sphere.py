"""The exact minimum over the sphere of directions against independent references: a dense
direction set (200,000 directions, numpy) polished by a local minimiser (scipy Nelder-Mead on the
sphere, per output) for the capacity; dense sampling for the trust-region subproblem."""

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize

from capmap.capacity.directions import paper_grid, sphere
from capmap.capacity.engine import LoadLimits, Motion, coefficients, direction_features, direction_minimum
from capmap.capacity.sphere import _eig3, _trs, min_over_sphere, start_directions
from capmap.capacity.sweep import min_over_directions
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import lock
from capmap.robots import load

ROBOT = Path(__file__).resolve().parents[2] / "config" / "robots" / "ssrms7.yaml"
MOTION = Motion(0.15, 0.03)
DENSE = sphere(200_000).u


def _bounds(C, S, u, motion, gravity, limit):
    """Per output (D, K): the largest payload along each direction u (D, 3) of one configuration C (K, 10),
    S (K, 3), written from the definition (|y0 + m t| <= L for every m in [0, bound])."""
    phi = np.concatenate([np.ones((len(u), 1)), motion.a_max_mps2 * u, motion.v_max_mps**2 * direction_features(u)],
                         axis=1)
    y, t = phi @ C.T, (motion.a_max_mps2 * u - gravity) @ S.T
    with np.errstate(divide="ignore", invalid="ignore"):
        b = np.where(t > 0, (limit - y) / t, np.where(t < 0, (limit + y) / -t, np.inf))
    return np.where(np.abs(y) > limit, 0.0, np.clip(b, 0.0, None))


def _reference(C, S, motion, gravity, limit):
    """The dense set's minimum per output, each polished on the sphere from its dense minimiser."""
    b = _bounds(C, S, DENSE, motion, gravity, limit)
    best = np.inf
    for k in range(C.shape[0]):
        i = int(np.argmin(b[:, k]))
        if not np.isfinite(b[i, k]) or b[i, k] == 0.0:
            best = min(best, b[i, k])
            continue
        u0 = DENSE[i]
        e1 = np.cross(u0, [1.0, 0, 0] if abs(u0[0]) < 0.9 else [0, 1.0, 0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(u0, e1)

        def f(x, u0=u0, e1=e1, e2=e2, k=k):
            u = u0 + x[0] * e1 + x[1] * e2
            return _bounds(C[k:k + 1], S[k:k + 1], (u / np.linalg.norm(u))[None], motion, gravity, limit[k:k + 1])[0, 0]

        r = minimize(f, np.zeros(2), method="Nelder-Mead", options=dict(xatol=1e-11, fatol=1e-13, maxiter=4000,
                                                                        initial_simplex=[[0, 0], [0.01, 0], [0, 0.01]]))
        best = min(best, b[i, k], r.fun)
    return best


@pytest.fixture(scope="module")
def configurations():
    arm = lock(load(ROBOT), 1, np.deg2rad(100.0))
    dyn = ArmDynamics(arm)
    q = np.random.default_rng(7).uniform(-np.pi, np.pi, (40, 6))
    coef = coefficients(dyn, q)
    keep = ~coef.singular
    return coef.stacked()[keep], coef.S[keep], dyn.gravity, LoadLimits.uniform(7, 700, 200, 500).for_arm(arm).limit


def test_exact_minimum_matches_a_polished_dense_reference(configurations):
    C, S, g, limit = configurations
    cap, u, binding, _ = min_over_sphere(C, S, MOTION.a_max_mps2, MOTION.v_max_mps, g, limit)
    dense = np.array([_bounds(C[m], S[m], DENSE, MOTION, g, limit).min() for m in range(len(C))])
    ref = np.array([_reference(C[m], S[m], MOTION, g, limit) for m in range(len(C))])
    # never above any direction's value (here 200,000 of them), within rounding of the formula
    assert np.all(cap <= dense * (1 + 1e-12))
    # the polished reference is a value at an actual direction too: neither may be below the other
    assert np.allclose(cap, ref, rtol=1e-6, atol=0)
    # the reported direction attains the value, on the reported binding output
    at_u = np.array([_bounds(C[m], S[m], u[m][None], MOTION, g, limit)[0] for m in range(len(C))])
    assert np.allclose(at_u.min(axis=1), cap, rtol=1e-12)
    assert np.allclose(at_u[np.arange(len(C)), binding], cap, rtol=1e-12)
    assert np.allclose(np.linalg.norm(u, axis=1), 1.0, atol=1e-14)


def test_exact_minimum_is_below_the_paper_grid_and_the_start_set_is_irrelevant(configurations):
    C, S, g, limit = configurations
    grid = paper_grid(10)
    phi = np.concatenate([np.ones((len(grid), 1)), MOTION.a_max_mps2 * grid.u,
                          MOTION.v_max_mps**2 * direction_features(grid.u)], axis=1)
    on_grid = min_over_directions(C, S, phi, MOTION.a_max_mps2 * grid.u, g, limit, grid.pairs)[0]
    cap = min_over_sphere(C, S, MOTION.a_max_mps2, MOTION.v_max_mps, g, limit)[0]
    assert np.all(cap <= on_grid * (1 + 1e-12)) and np.any(cap < on_grid * (1 - 1e-4))
    for n in (1, 3, 40):  # Dinkelbach's first lambda only
        other = min_over_sphere(C, S, MOTION.a_max_mps2, MOTION.v_max_mps, g, limit, start_directions(n))[0]
        assert np.allclose(other, cap, rtol=1e-9)


def test_a_violation_between_the_start_directions_gives_zero():
    """One output whose payload-free value exceeds its limit only in a small cap around a direction n
    that no start direction is near: the capacity is 0 there; with the cap a little below the limit, the
    capacity is positive (both against the dense reference)."""
    start = start_directions()
    n = np.array([0.3, -0.5, 0.81])
    n /= np.linalg.norm(n)
    assert (start @ n).max() < 0.995
    g = np.array([0.0, 0.0, -9.81])
    a = MOTION.a_max_mps2
    for peak, zero in ((1.0 + 1e-4, True), (1.0 - 1e-3, False)):
        C = np.zeros((1, 1, 10))
        C[0, 0, 1:4] = 100.0 * n / a  # y = c0 + 100 n.u: at most c0 + 100, along n
        C[0, 0, 0] = peak * 1000.0 - 100.0
        S = np.array([[[0.0, 0.0, 1.0]]])
        limit = np.array([1000.0])
        assert _bounds(C[0], S[0], start, MOTION, g, limit).min() > 0
        cap = min_over_sphere(C, S, a, MOTION.v_max_mps, g, limit)[0][0]
        ref = _reference(C[0], S[0], MOTION, g, limit)
        assert (cap == 0.0) == zero and (ref == 0.0) == zero
        assert cap == pytest.approx(ref, rel=1e-6)


def _random_form(rng, hard: str):
    """A 3x3 symmetric A, b: generic, or b orthogonal to the least eigenvector (the hard case), or a
    double least eigenvalue."""
    Qr = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    d = np.sort(rng.normal(size=3) * rng.choice([1e-3, 1.0, 1e3]))
    if hard == "double":
        d[1] = d[0]
    A = Qr @ np.diag(d) @ Qr.T
    b = rng.normal(size=3) * rng.choice([1e-2, 1.0, 1e2])
    if hard in ("hard", "double"):
        b -= Qr[:, 0] * (Qr[:, 0] @ b)
        if hard == "double":
            b -= Qr[:, 1] * (Qr[:, 1] @ b)
        b *= rng.choice([1e-3, 0.1])  # small enough that mu sits at the least eigenvalue
    return A, b


@pytest.mark.parametrize("hard", ["generic", "hard", "double"])
def test_sphere_subproblem_is_the_global_minimum(hard):
    rng = np.random.default_rng({"generic": 1, "hard": 2, "double": 3}[hard])
    fine = sphere(100_000).u
    for _ in range(60):
        A, b = _random_form(rng, hard)
        w, V, work = np.empty(3), np.empty((3, 3)), np.empty((3, 3))
        _eig3(A, w, V, work)
        assert np.allclose(V @ np.diag(w) @ V.T, A, atol=1e-13 * np.abs(A).max())
        u = np.empty(3)
        val, low = _trs(0.5, b, w, V, u, np.empty(3), np.empty(3))
        sampled = 0.5 + fine @ b + np.einsum("di,ij,dj->d", fine, A, fine)
        scale = np.abs(w).sum() + np.linalg.norm(b)
        assert abs(np.linalg.norm(u) - 1) < 1e-14
        assert val == pytest.approx(0.5 + b @ u + u @ A @ u, abs=1e-13 * scale)  # the value at u
        assert val <= sampled.min() + 1e-12 * scale  # no sampled direction is lower
        assert low <= val + 1e-12 * scale and val - low <= 1e-9 * scale  # the dual certifies it


def test_direction_minimum_paper_grid_stays_the_grid(configurations):
    """``directions.kind: paper_grid`` keeps the paper's own numbers: the grid's minimum and its index."""
    C, S, g, limit = configurations
    arm = lock(load(ROBOT), 1, np.deg2rad(100.0))
    dyn = ArmDynamics(arm)
    q = np.random.default_rng(8).uniform(-np.pi, np.pi, (20, 6))
    coef = coefficients(dyn, q)
    grid = paper_grid(10)
    cap, idx, u, _ = direction_minimum(coef, grid, MOTION, dyn.gravity, LoadLimits.uniform(7, 700, 200, 500).for_arm(arm))
    assert np.all(idx >= 0) and np.array_equal(u, grid.u[idx])
    ref = np.array([_bounds(coef.stacked()[m], coef.S[m], grid.u, MOTION, dyn.gravity, limit).min() for m in range(20)])
    ref[coef.singular] = 0.0
    assert np.allclose(cap, ref, rtol=1e-12)
