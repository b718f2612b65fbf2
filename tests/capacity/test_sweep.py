"""The fused direction sweep (numba, u and -u sharing one evaluation) against the plain numpy
evaluation of every (configuration, output, direction) and AffineLimits.largest."""

import numpy as np
import pytest

from capmap.capacity import directions
from capmap.capacity.engine import LoadLimits, Motion, affine_over_directions, coefficients, direction_features
from capmap.capacity.sweep import min_over_directions, min_per_pair
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import lock
from capmap.robots import load
from tests.scenario import SSRMS_YAML


@pytest.mark.parametrize("dirs", [directions.paper_grid(10), directions.paper_grid(30), directions.sphere(60)],
                         ids=["grid10_antipodal", "grid30", "sphere60_no_antipodes"])
@pytest.mark.parametrize("gravity", [False, True])
def test_fused_sweep_equals_the_full_evaluation(dirs, gravity, gravity_robot_yaml):
    arm = lock(load(gravity_robot_yaml if gravity else SSRMS_YAML), 1, np.deg2rad(100))
    dyn = ArmDynamics(arm)
    limits = LoadLimits.uniform(7, 700, 200, 500).for_arm(arm)
    rng = np.random.default_rng(2)
    coef = coefficients(dyn, rng.uniform(-np.pi, np.pi, (40, 6)))
    motion = Motion(0.15, 0.03)
    y0, s = affine_over_directions(coef, dirs.u, motion, dyn.gravity)  # (B, n_out, D): the reference
    bound = limits.upper_from_zero(y0, s, axis=1)
    ref = bound.min(axis=1)  # (B, D)
    a, v = motion.a_max_mps2, motion.v_max_mps
    phi = np.concatenate([np.ones((len(dirs.u), 1)), a * dirs.u, v**2 * direction_features(dirs.u)], axis=1)
    C = np.concatenate([coef.c0[..., None], coef.L, coef.Q], axis=2)
    cap, worst, binding = min_over_directions(C, coef.S, phi, a * dirs.u, dyn.gravity, limits.limit, dirs.pairs)
    # the same coefficients summed in another order (numba loops vs numpy/BLAS), then (limit - y0) / s: measured
    # |difference| <= 3.4e-10 kg (capacities up to 1.5e4 kg) over the 5 OpenBLAS kernels (Prescott, Sandybridge, Haswell,
    # Zen, SkylakeX), at most 0.04 of these tolerances: margin 25
    assert np.allclose(cap, ref.min(axis=1), rtol=1e-12, atol=1e-9)
    rows = np.arange(len(cap))
    assert np.allclose(ref[rows, worst], ref.min(axis=1), rtol=1e-12, atol=1e-9)  # the worst direction is a minimiser
    assert np.allclose(bound[rows, binding, worst], cap, rtol=1e-12, atol=1e-9)  # and its binding output binds
    # per antipodal pair (the line of u): the smaller of the two directions' minima
    per_pair, pairs = min_per_pair(C, coef.S, phi, a * dirs.u, dyn.gravity, limits.limit, dirs.pairs)
    other = np.where(pairs[:, 1] >= 0, pairs[:, 1], pairs[:, 0])
    assert np.allclose(per_pair, np.minimum(ref[:, pairs[:, 0]], ref[:, other]), rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("scale", [1.0, 0.05])
def test_ties_go_to_the_first_direction_in_pair_order(scale):
    # tight limits: most directions violate at zero payload (capacity 0 everywhere, a tie)
    dirs = directions.paper_grid(30)
    arm = lock(load(SSRMS_YAML), 1, np.deg2rad(100))
    dyn = ArmDynamics(arm)
    limits = LoadLimits.uniform(7, 700 * scale, 200 * scale, 500 * scale).for_arm(arm)
    coef = coefficients(dyn, np.random.default_rng(5).uniform(-np.pi, np.pi, (60, 6)))
    motion = Motion(0.15, 0.03)
    y0, s = affine_over_directions(coef, dirs.u, motion, dyn.gravity)
    bound = limits.upper_from_zero(y0, s, axis=1)  # (B, n_out, D)
    order = [d for row in dirs.pairs for d in row if d >= 0]  # u before -u, pair by pair
    a, v = motion.a_max_mps2, motion.v_max_mps
    phi = np.concatenate([np.ones((len(dirs.u), 1)), a * dirs.u, v**2 * direction_features(dirs.u)], axis=1)
    C = np.concatenate([coef.c0[..., None], coef.L, coef.Q], axis=2)
    cap, worst, binding = min_over_directions(C, coef.S, phi, a * dirs.u, dyn.gravity, limits.limit, dirs.pairs)
    for m in range(len(cap)):
        ref_min = bound[m].min()
        d_first = next(d for d in order if bound[m, :, d].min() == ref_min)
        assert worst[m] == d_first and binding[m] == int(np.argmax(bound[m, :, d_first] == ref_min))
    if scale < 1:
        assert (cap == 0).mean() > 0.5  # the tie case is exercised


def test_violated_and_flat_outputs():
    # one output violated at zero payload (bound 0), one with s = 0 (unbounded), one ordinary
    C = np.zeros((1, 3, 10))
    C[0, 0, 0], C[0, 2, 0] = 5.0, 1.0  # |y0| = 5 > 2: violated
    S = np.zeros((1, 3, 3))
    S[0, 2, 0] = 1.0
    u = np.array([[1.0, 0, 0], [-1.0, 0, 0]])
    phi = np.concatenate([np.ones((2, 1)), u, np.zeros((2, 6))], axis=1)
    cap, _, binding = min_over_directions(C, S, phi, u, np.zeros(3), np.array([2.0, 2.0, 2.0]))
    assert cap[0] == 0.0 and binding[0] == 0
    C[0, 0, 0] = 0.0
    cap, worst, binding = min_over_directions(C, S, phi, u, np.zeros(3), np.array([2.0, 2.0, 2.0]))
    assert cap[0] == pytest.approx(1.0) and binding[0] == 2  # |1 + x * (+-1)| <= 2: x <= 1 (u) or 3 (-u)
