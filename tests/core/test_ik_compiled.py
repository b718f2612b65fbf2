"""The compiled IK kernels against independent numpy/LAPACK computations: the companion roots
(:mod:`capmap.core.ik.roots`) against ``numpy.linalg.eigvals`` (LAPACK dgeev), the Newton polish
(:mod:`capmap.core.ik.polish`) against :func:`capmap.core.ik.multistart.newton` and
:func:`capmap.core.kinematics.pose_error`, and the elimination matrices
(:mod:`capmap.core.ik.general.matrices`, a pivoted Householder QR) against an SVD formulation
written here."""

import numpy as np
import pytest

import capmap.core.ik.general.elimination as ik_general
import capmap.core.ik.polish as ik_polish
import capmap.core.ik.roots as ik_roots
from capmap.core.ik.multistart import newton
from capmap.core.kinematics import Chain, inverse_transform, pose_error


def _random_chain(rng, n=6) -> Chain:
    X = np.zeros((n + 1, 4, 4))
    for i in range(n + 1):
        q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
        X[i, :3, :3] = q * np.sign(np.linalg.det(q))
        X[i, :3, 3] = 0.5 * rng.standard_normal(3)
        X[i, 3, 3] = 1.0
    return Chain(X)


@pytest.mark.parametrize("degree", [1, 2, 5, 8, 16, 24])
def test_companion_roots_match_lapack(degree):
    """Every eigenvalue LAPACK finds (as |imag| <= 1 keeps them all) is found, to 1e-9 relative, on
    polynomials whose coefficients span six decades; the kept ones are exactly those with small imag."""
    rng = np.random.default_rng(degree)
    poly = rng.normal(size=(300, degree + 1)) * 10.0 ** rng.uniform(-3, 3, (300, degree + 1))
    comp = np.zeros((300, degree, degree))
    comp[:, 0, :] = -poly[:, degree - 1::-1] / poly[:, degree, None]
    comp[:, np.arange(1, degree), np.arange(degree - 1)] = 1.0
    ref = np.linalg.eigvals(comp)
    roots = ik_roots.real_roots(poly, np.ones(300, dtype=bool), 1e30)  # keep every eigenvalue
    assert not roots.failed.any() and (roots.degree == degree).all()
    for n in range(300):
        mine = roots.x[roots.pose == n] + 1j * roots.imag[roots.pose == n]
        assert len(mine) == degree
        d = np.abs(ref[n][:, None] - mine[None]).min(axis=1) / (1 + np.abs(ref[n]))
        assert d.max() < 1e-9, (n, d.max())
    kept = ik_roots.real_roots(poly, np.ones(300, dtype=bool), 1e-2)
    small = np.abs(ref.imag) <= 1e-2 * (1 + np.abs(ref.real))
    assert len(kept.pose) == small.sum()


def test_dropped_roots_and_their_pseudo_zero_ratio():
    """The eigenvalues not kept are returned with |p(Re z)| / (noise sum |p_j| |Re z|^j), recomputed
    here by numpy's polyval; a real double root split into a complex pair by a perturbation within
    the noise is a pseudo-zero (ratio <= 1), a well-separated complex pair is not."""
    rng = np.random.default_rng(4)
    poly = rng.normal(size=(200, 9))
    noise = np.full(200, 1e-12)
    roots = ik_roots.real_roots(poly, np.ones(200, dtype=bool), 1e-2, noise)
    z = roots.dropped
    assert len(z) + len(roots.x) == 200 * 8
    p = poly[roots.dropped_pose]
    x = z.real
    value = np.abs(np.array([np.polyval(c[::-1], v) for c, v in zip(p, x)]))
    size = np.array([np.polyval(np.abs(c[::-1]), abs(v)) for c, v in zip(p, x)])
    assert roots.pseudo == pytest.approx(value / (1e-12 * size), rel=1e-6, abs=1e-3)
    # (x - 1)^2 (x^2 + 1) + 1e-13: the double root at 1 becomes a pair 1 +- 2.2e-7 i (sqrt(1e-13 / 2))
    double = np.polymul([1.0, -2.0, 1.0], [1.0, 0.0, 1.0])[::-1].copy()
    double[0] += 1e-13
    r = ik_roots.real_roots(double[None], np.ones(1, dtype=bool), 1e-9, np.array([1e-12]))
    near_one = np.abs(r.dropped - 1.0) < 1e-3
    assert near_one.sum() == 2 and (r.pseudo[near_one] <= 1.0).all()
    assert (r.pseudo[~near_one] > 1e6).all()  # +-i: |p(0)| = 1 against 1e-12
    unknown = ik_roots.real_roots(poly[:5], np.ones(5, dtype=bool), 1e-2, np.full(5, np.inf))
    assert len(unknown.pseudo) and np.isinf(unknown.pseudo).all()  # noise not measured (degree 12): no test


def test_companion_roots_trailing_zeros_and_unusable_rows():
    """A vanishing leading coefficient lowers the degree; rows not usable give no roots."""
    poly = np.array([[2.0, -3.0, 1.0, 0.0, 0.0], [1.0, 0.0, -1.0, 0.0, 1e-20], [1.0, 2.0, 1.0, 0.0, 0.0]])
    roots = ik_roots.real_roots(poly, np.array([True, True, False]), 1e-8)
    assert list(roots.degree[:2]) == [2, 2]
    assert sorted(roots.x[roots.pose == 0]) == pytest.approx([1.0, 2.0])
    assert sorted(roots.x[roots.pose == 1]) == pytest.approx([-1.0, 1.0])
    assert not (roots.pose == 2).any()


def test_polish_matches_numpy_newton():
    """Undamped Newton steps from perturbed solutions: the compiled steps and errors equal numpy's
    (same formulas, rounding-level differences), and converge to <= 1e-13."""
    rng = np.random.default_rng(1)
    chain = _random_chain(rng)
    q = rng.uniform(-np.pi, np.pi, (200, 6))
    T = chain.fk(q)
    start = q + 1e-2 * rng.standard_normal(q.shape)
    one, err = ik_polish.polish(chain.X, start, T, np.arange(200), ik_polish.PolishSettings(1, 0.0))
    ref = newton(chain, start, T, iters=1)
    # both solve J J^T (condition number kappa(J)^2) in different orders: forward error <= eps kappa^2 (1 + |step|)
    # (measured 2026-12-02: at most 0.05 of it; 2.4e-10 absolute at kappa = 5,478 on an Intel Xeon)
    kappa = np.linalg.cond(chain.jacobian(start)[1])
    bound = np.finfo(float).eps * kappa**2 * (1 + np.abs(ref - start).max(axis=1))
    assert (np.abs(one - ref).max(axis=1) <= bound).all()
    assert np.abs(err - pose_error(chain.fk(ref), T)).max() < 1e-10
    done, err = ik_polish.polish(chain.X, start, T, np.arange(200), ik_polish.PolishSettings(8, 1e-13))
    ref = newton(chain, start, T, iters=8)
    conv = np.abs(pose_error(chain.fk(ref), T)).max(axis=1) < 1e-12
    assert conv.mean() > 0.9  # random chains, 1e-2 rad off: a few starts lie near a singularity
    assert (np.abs(err[conv]).max(axis=1) < 1e-12).all()
    assert np.abs(np.mod(done[conv] - ref[conv] + np.pi, 2 * np.pi) - np.pi).max() < 1e-8


def test_damped_polish_matches_numpy_newton():
    """A damped step (J J^T + 0.1^2 I, as the multi-start's first phase) from starts 0.3 rad off:
    the compiled step equals numpy's damped one; damping moves it away from the undamped one."""
    rng = np.random.default_rng(3)
    chain = _random_chain(rng)
    q = rng.uniform(-np.pi, np.pi, (200, 6))
    T = chain.fk(q)
    start = q + 0.3 * rng.standard_normal(q.shape)
    damped, _ = ik_polish.polish(chain.X, start, T, np.arange(200),
                                  ik_polish.PolishSettings(1, 0.0, give_up=np.inf, damping=0.1))
    ref = newton(chain, start, T, iters=1, damping=0.1)
    # J J^T + 0.01 I has condition number <= (sigma_max^2 + 0.01) / 0.01: rounding's bound as above
    # (measured 2026-12-03 over 5 seeds: at most 0.2 of it)
    sigma = np.linalg.svd(chain.jacobian(start)[1], compute_uv=False)
    bound = np.finfo(float).eps * (sigma[:, 0] ** 2 + 0.01) / 0.01 * (1 + np.abs(ref - start).max(axis=1))
    assert (np.abs(damped - ref).max(axis=1) <= bound).all()
    plain = newton(chain, start, T, iters=1)
    assert np.median(np.abs(plain - ref).max(axis=1)) > 1e3 * np.median(bound)


@pytest.mark.parametrize("short", [0.0, 5e-5, 3e-4])
def test_polish_rotation_error_near_pi(short):
    """The rotation error of poses turned by pi - short about the tip's z (the symmetric-part branch
    below 1e-4, the antisymmetric one above) equals kinematics'."""
    rng = np.random.default_rng(2)
    chain = _random_chain(rng)
    q = rng.uniform(-np.pi, np.pi, (50, 6))
    T = chain.fk(q)
    c, s_ = np.cos(np.pi - short), np.sin(np.pi - short)
    turn = np.array([[c, -s_, 0, 0], [s_, c, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]])
    T_far = T @ turn
    _, err = ik_polish.polish(chain.X, q, T_far, np.arange(50), ik_polish.PolishSettings(0, 0.0))
    ref = pose_error(chain.fk(q), T_far)
    assert np.abs(err[:, :3] - ref[:, :3]).max() < 1e-12
    assert np.abs(np.linalg.norm(err[:, 3:], axis=1) - (np.pi - short)).max() < 1e-6
    if short == 0.0:  # at pi, w and -w are one rotation (the sign is rounding's): parallel axes
        assert np.abs(np.linalg.norm(np.cross(err[:, 3:], ref[:, 3:]), axis=1)).max() < 1e-6
    else:
        assert np.abs(err[:, 3:] - ref[:, 3:]).max() < 1e-6


def test_distinct_keeps_first_of_repeats():
    wrapped = np.array([[[0.0, 1.0], [1e-8, 1.0], [np.pi, 0.0], [-np.pi + 1e-9, 0.0], [0.5, 0.5]]])
    good = np.array([[True, True, True, True, False]])
    q, count = ik_polish.distinct(wrapped, good, 1e-6)
    assert count[0] == 2
    assert np.allclose(q[0, :2], [[0.0, 1.0], [np.pi, 0.0]]) and np.isnan(q[0, 2:]).all()


def _svd_matrices(X, f, CL, T):
    """The elimination's matrices by an SVD (the formulation before the compiled QR one)."""
    N = len(T)
    A, B = ik_general._sides(X, f, ik_general._G2[:, 0], ik_general._G2[:, 1])
    F = inverse_transform(A)[None] @ T[:, None] @ inverse_transform(B)[None]
    CR = np.einsum("rg,ngq->nrq", ik_general._B2_INV, ik_general.quantities(F))
    Q = np.swapaxes(CR[:, 1:], 1, 2)
    U, S, Vt = np.linalg.svd(Q)
    Nl = np.swapaxes(U[:, :, 8:], 1, 2)
    lstsq = np.swapaxes(Vt, 1, 2) @ (np.swapaxes(U[:, :, :8], 1, 2) / S[:, :, None])
    P = np.broadcast_to(CL, (N, 3, 14, 9)).copy()
    P[:, 0, :, 0] -= CR[:, 0]
    E = np.einsum("nek,nakm->naem", Nl, P) @ ik_general._HH
    M = np.zeros((N, 3, 12, 12))
    M[:, :, :6, :9] = E
    M[:, :, 6:, 3:] = E
    return M, lstsq, CR[:, 0], S[:, 7] / S[:, 0]


@pytest.mark.parametrize("f", [3, 4, 5])
def test_elimination_matrices_match_svd(f):
    """Same least-squares map and constant; det M(qa) equal at random qa (another orthonormal basis
    of Q's left null space changes M by an orthogonal 6 x 6 factor on both row blocks: det by its
    square, 1); the QR rank estimate within a factor sqrt(8) of sigma_8 / sigma_1 ... or more
    conservative (never larger than 8 x)."""
    rng = np.random.default_rng(f)
    chain = _random_chain(rng)
    CL = ik_general.left_coefficients(chain.X, f)
    T = np.ascontiguousarray(chain.fk(rng.uniform(-np.pi, np.pi, (40, 6))))
    M, lstsq, const, rank = ik_general._matrices(chain.X, f, CL, T)
    M_ref, lstsq_ref, const_ref, rank_ref = _svd_matrices(chain.X, f, CL, T)
    assert np.abs(lstsq - lstsq_ref).max() < 1e-9 * np.abs(lstsq_ref).max()
    assert np.abs(const - const_ref).max() < 1e-12 * max(1.0, np.abs(const_ref).max())
    qa = rng.uniform(-np.pi, np.pi, 40)
    at = M[:, 0] + np.cos(qa)[:, None, None] * M[:, 1] + np.sin(qa)[:, None, None] * M[:, 2]
    at_ref = M_ref[:, 0] + np.cos(qa)[:, None, None] * M_ref[:, 1] + np.sin(qa)[:, None, None] * M_ref[:, 2]
    d, d_ref = np.linalg.det(at), np.linalg.det(at_ref)
    assert np.abs(d - d_ref).max() < 1e-8 * np.abs(d_ref).max()
    assert (rank < 8 * rank_ref).all() and (rank > rank_ref / 8).all()


@pytest.mark.parametrize("noise", [1e-14, 1e-6, 1e-3])
def test_doubt_bounds_how_far_noise_moves_a_complex_pair(noise):
    """The doubt of a pose (its dropped complex eigenvalues' first-order error bound over |Im z|)
    against brute force: 200 random relative perturbations of the coefficients at ``noise`` move a
    complex pair by at most doubt * |Im z| (times 2 for the first order), so a pair with doubt < 0.1
    never reaches the real axis."""
    rng = np.random.default_rng(7)
    roots_true = np.array([-2.0, 0.5, 1.5, 3.0 + 0.4j, 3.0 - 0.4j, -0.7 + 0.05j, -0.7 - 0.05j])
    poly = np.real(np.poly(roots_true))[::-1].copy()  # x^0 upward
    r = ik_roots.real_roots(poly[None], np.array([True]), 1e-3, np.array([noise]))
    doubt = r.doubt[0]
    moved = 0.0
    for _ in range(200):
        p = poly * (1 + noise * rng.uniform(-1, 1, poly.shape))
        ev = np.roots(p[::-1])
        for z in roots_true[np.abs(roots_true.imag) > 0]:
            moved = max(moved, np.abs(ev - z).min() / abs(z.imag))
    assert moved <= 2 * doubt + 1e-9
    if doubt < 0.1:
        assert moved < 0.2  # no perturbation brought a pair near the real axis


@pytest.mark.parametrize("noise", [1e-14, 1e-8, 1e-5])
def test_error_bounds_how_far_noise_moves_a_real_root(noise):
    """Each kept root's error bound (first order, as the doubt's) against brute force: 200 random
    relative perturbations of the coefficients at ``noise`` move every real root by at most twice its
    bound (two of the roots 1e-3 apart: a cluster, whose bound is large)."""
    rng = np.random.default_rng(8)
    roots_true = np.array([-2.0, 0.5, 0.501, 1.5, 3.0 + 0.4j, 3.0 - 0.4j])
    poly = np.real(np.poly(roots_true))[::-1].copy()
    r = ik_roots.real_roots(poly[None], np.array([True]), 1e-3, np.array([noise]))
    real = roots_true[roots_true.imag == 0].real
    bound = np.array([r.error[np.abs(r.x - x).argmin()] for x in real])
    moved = np.zeros(len(real))
    for _ in range(200):
        ev = np.roots((poly * (1 + noise * rng.uniform(-1, 1, poly.shape)))[::-1])
        moved = np.maximum(moved, [np.abs(ev - x).min() for x in real])
    assert (moved <= 2 * bound + 1e-12).all()
    assert bound[1] > 100 * bound[0]  # the cluster is flagged


@pytest.mark.parametrize("k", [2, 3, 4])
def test_null_space_split_recovers_every_monomial_vector(k):
    """A null space spanned by k monomial vectors tan(qb/2)^i tan(qc/2)^j (random angles), given in a
    random orthonormal basis: the split returns k vectors whose angles are the k pairs (1e-6 rad)."""
    from capmap.core.ik.general.back import _angles_of, _split

    rng = np.random.default_rng(k)
    for _ in range(200):
        ang = rng.uniform(-np.pi, np.pi, (k, 2))
        x = np.tan(ang / 2)
        vecs = np.array([[xb ** i * xc ** j for i in range(4) for j in range(3)] for xb, xc in x])
        V, _ = np.linalg.qr(vecs.T @ rng.standard_normal((k, k)))  # (12, k) orthonormal, mixed
        out = np.zeros((4, 12))
        found = _split(np.ascontiguousarray(np.hstack([V, np.zeros((12, 4 - k))])), k, out)
        assert found == k
        got = np.array([_angles_of(out[f]) for f in range(found)])
        for a in ang:
            d = np.abs(np.mod(got - a + np.pi, 2 * np.pi) - np.pi).max(axis=1)
            assert d.min() < 1e-6
