"""The augmented-Lagrangian DDP on a coarse horizon: it converges onto every constraint, and on the
equality-only problem it finds the optimum mim-solvers' CSQP finds (a second solver, another
formulation: constraints, not penalties)."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.dualarm.ocp.assembly import warm_start
from capmap.dualarm.ocp.evaluate import fine_grid, node_errors, safety
from capmap.dualarm.ocp.settings import ALSettings, SolveOptions, StopRule, Weights
from capmap.dualarm.ocp.solver import equality_cost, initial_guess, solve, solve_csqp

W = Weights(control=np.full(14, 1.0), velocity=1.0, panel=0.01, margin_m=0.005)


@pytest.fixture(scope="module")
def coarse(robot, make_assembly):
    asm = make_assembly(40, 0.25, 28)
    xs0, us0 = initial_guess(warm_start(asm), asm.task.dt)
    return asm, (robot.q_lower, robot.q_upper, robot.v_max), xs0, us0


def test_al_ddp_meets_every_constraint(coarse):
    asm, limits, xs0, us0 = coarse
    sol = solve(asm, W, limits, ALSettings(mu_max=1e12, tolerance=5e-8), xs0, us0)
    assert sol.converged, sol.message
    err = node_errors(asm, sol.xs)
    # bounds from the stopping rule: every equality component and inequality deficit is below the tolerance 5e-8, so
    # a 3-vector's norm is below sqrt(3) x 5e-8 = 8.7e-8 < 1e-7 (measured 5.65e-8, the same on the 5 OpenBLAS kernels
    # Prescott, Sandybridge, Haswell, Zen, SkylakeX)
    assert err.closed_chain_pos.max() < 1e-7 and err.path_pos.max() < 1e-7 and err.path_rot.max() < 1e-7
    nq = asm.model.nq
    assert np.all(sol.xs[:, :nq] >= limits[0] - 1e-7) and np.all(sol.xs[:, :nq] <= limits[1] + 1e-7)
    assert np.all(np.abs(sol.xs[:, nq:]) <= limits[2] + 1e-7)
    assert safety(asm, sol.xs[:, :nq]).min_distance.min() >= W.margin_m - 1e-7  # every candidate pair, every node
    assert np.abs(sol.xs[-1, nq:]).max() < 1e-7  # at rest at the end
    _, q_fine, _ = fine_grid(sol.xs, sol.us, asm.task.dt, 5)
    assert safety(asm, q_fine).min_distance.min() >= 0.0


def test_equality_only_optimum_equals_csqp(coarse):
    asm, limits, xs0, us0 = coarse
    al = solve(asm, W, limits, ALSettings(mu_max=1e12, tolerance=1e-9, max_outer=40), xs0, us0,
               SolveOptions(inequalities=False))
    assert al.converged, al.message
    csqp = solve_csqp(asm, W, limits, xs0, us0, StopRule(iterations=150, tolerance=1e-6))
    assert csqp.converged
    xc, uc = csqp.xs, csqp.us
    nq = asm.model.nq
    # measured 6.0e-5 rad and 2.4e-5 rad/s (margins 1.7 and 4), the same to 3 digits on the 5 OpenBLAS kernels
    # (Prescott, Sandybridge, Haswell, Zen, SkylakeX): the gap is the two solvers' stopping points, not rounding
    assert np.abs(al.xs[:, :nq] - xc[:, :nq]).max() < 1e-4  # rad
    assert np.abs(al.xs[:, nq:] - xc[:, nq:]).max() < 1e-4  # rad/s
    c_al, c_sqp = equality_cost(asm, W, al.xs, al.us), equality_cost(asm, W, xc, uc)
    assert c_al == pytest.approx(c_sqp, rel=1e-4)
    assert node_errors(asm, xc).closed_chain_pos.max() < 1e-6  # CSQP's own solution satisfies the constraints


def test_inexact_inner_solves_reach_the_exact_solution(coarse, monkeypatch):
    """The inner stop relative to the violation (solver.inner_stop) against inner solves all run to FDDP's
    tight stop (INEXACT = 0): fewer FDDP iterations, the same outer loop (iterations, penalties), the same
    pairs within 1 cm of the margin, and the same solution up to the stopping points of two converged runs."""
    import capmap.dualarm.ocp.solver as S

    asm, limits, xs0, us0 = coarse
    st = ALSettings(mu_max=1e12, tolerance=5e-8)
    inexact = solve(asm, W, limits, st, xs0, us0)
    monkeypatch.setattr(S, "INEXACT", 0.0)
    exact = solve(asm, W, limits, st, xs0, us0)
    assert inexact.converged and exact.converged
    assert sum(s.inner_iterations for s in inexact.stats) < sum(s.inner_iterations for s in exact.stats)
    assert [s.mu for s in inexact.stats] == [s.mu for s in exact.stats]
    nq = asm.model.nq
    near = []
    for sol in (inexact, exact):
        s = safety(asm, sol.xs[:, :nq])
        near.append(set(s.names[(s.distance < W.margin_m + 0.01).any(axis=0)]))
    assert near[0] == near[1] and near[0]
    # two converged runs, each with every residual below 5e-8, stopped at different points: measured 1.5e-9 rad here
    # (39 vs 50 FDDP iterations), 2.1e-7 rad on the default problem (N = 500; 69 vs 91): bound 5x the latter
    assert np.abs(inexact.xs[:, :nq] - exact.xs[:, :nq]).max() < 1e-6
