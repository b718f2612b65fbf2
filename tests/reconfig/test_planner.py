"""The reconfiguration planner: the task follows the law exactly, the null-space part does not
disturb it, m never decreases with the null-space method, the loop stays closed in the full
model, rates and ranges are held (or the run says why not), and the spec's reference numbers."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.core import ik
from capmap.core.kinematics import pose_error
from capmap.reconfig.law import QuinticLaw
from capmap.reconfig.loop import split_loop
from capmap.reconfig.multiarm import platform_model
from capmap.reconfig.planner import reconfigure
from capmap.reconfig.problem import build_problem, closure_errors
from capmap.reconfig.redundancy import evaluate


def _run(problem, method, dt=0.02, kappa0=2e-4, rate_deg_s=100.0, min_time_scale=0.05, ranges=None):
    settings = problem.settings(method, dt, kappa0, np.full(problem.split.moving.dof, np.deg2rad(rate_deg_s)),
                                min_time_scale)
    if ranges is not None:
        settings = type(settings)(**{**settings.__dict__, "q_lower": ranges[0], "q_upper": ranges[1]})
    return settings, reconfigure(problem.split, problem.fixed_end, problem.q0, problem.law, settings)


@pytest.fixture(scope="module")
def spec_runs(spec_problem):
    return {m: _run(spec_problem, m) for m in ("nullspace", "pinv")}


def test_pseudo_inverse_reproduces_the_spec_reference(spec_runs):
    """Spec: m 71.3 -> min 25.5 at 30.4 s, smallest singular value 0.526 -> 0.203, dm/dt < 0 in 1518 of 2000 steps."""
    _, run = spec_runs["pinv"]
    assert run.status == "completed" and run.steps == 2000
    # abs = half the spec's last digit (its rounding); the BLAS kernels move m by <= 7e-13 (see below)
    assert run.m[0] == pytest.approx(71.3, abs=0.05) and run.m.min() == pytest.approx(25.5, abs=0.05)
    assert run.t_s[np.argmin(run.m)] == pytest.approx(30.4, abs=0.05)
    assert run.min_singular_value[0] == pytest.approx(0.526, abs=5e-4)
    assert run.min_singular_value.min() == pytest.approx(0.203, abs=5e-4)
    # an exact count, yet portable: the smallest nonzero |dm/dt| is 7.8e-6, the BLAS kernels (Prescott, Haswell vs
    # SkylakeX) move dm/dt by <= 2.1e-13 and m by <= 7e-13 over the 2000 steps
    assert int((run.dm_dt[:-1] < 0).sum()) == 1518


def test_null_space_method_never_decreases_m_and_is_rest_to_rest(spec_runs):
    _, run = spec_runs["nullspace"]
    assert run.status == "completed"
    assert run.dm_dt.min() >= -1e-9 * np.abs(run.dm_dt).max()
    assert np.all(np.diff(run.m) >= -1e-9 * run.m[0])
    assert run.m[-1] > 1.5 * run.m[0]
    assert np.abs(run.qd[0]).max() == 0 and np.abs(run.qd[-1]).max() < 1e-12  # rest to rest


@pytest.mark.parametrize("method", ["nullspace", "pinv"])
def test_task_follows_the_law_and_the_null_space_part_does_not_disturb_it(spec_problem, spec_runs, method):
    _, run = spec_runs[method]
    sp, law = spec_problem.split, spec_problem.law
    for k in range(0, len(run.t_s), 97):
        ev = evaluate(sp.moving.chain, run.q[k])
        _, _, dth, dd = law.at(run.u[k])
        xdot = sp.twist(spec_problem.fixed_end, np.atleast_1d(run.time_scale[k] * dth / law.duration_s),
                        np.atleast_1d(run.time_scale[k] * dd / law.duration_s))[0]
        assert np.allclose(ev.J @ run.qd[k], xdot, atol=1e-9)  # J qdot = xdot
        particular = ev.pinv @ xdot
        assert np.allclose(ev.J @ (run.qd[k] - particular), 0, atol=1e-9)  # the rest is in the null space
        target = sp.target(spec_problem.fixed_end, run.theta[k], run.d[k])[0]
        # the moving end is on the law: measured 1.8e-15 to 2.7e-15 over the 5 OpenBLAS kernels (Prescott, Sandybridge,
        # Haswell, Zen, SkylakeX), margin 370 (rounding of the forward kinematics, eps x metres)
        assert np.abs(pose_error(ev.pose, target)).max() < 1e-12
    assert np.allclose(run.theta, law.at(run.u)[0]) and np.allclose(run.d, law.at(run.u)[1])


@pytest.mark.parametrize("method", ["nullspace", "pinv"])
def test_loop_closure_from_both_sides_in_the_full_model(platform, spec_problem, spec_runs, method):
    _, run = spec_runs[method]
    err = closure_errors(spec_problem, platform_model(platform), run)
    assert np.linalg.norm(err[:, :3], axis=1).max() < 1e-9 and np.linalg.norm(err[:, 3:], axis=1).max() < 1e-9


def _random_capture(platform, captured, rng, spread_deg=10.0):
    """A closed capture away from the spec's: the short side (arm1 J1, J2) and the long side's joints
    moved at random, then the long side solved back onto the loop by Newton (its 10 joints have a
    4-D self-motion, so a closing configuration is always near)."""
    sp = split_loop(platform, "arm1_arm2", "arm1.P1", captured)
    state = captured.with_values(sp.fixed.joints, sp.fixed.values(captured) + np.deg2rad(rng.uniform(-1, 1, 2)
                                                                                         * spread_deg))
    fixed_end = sp.fixed.chain.fk(sp.fixed.values(state)[None])[0]
    start = sp.moving.values(state) + np.deg2rad(rng.uniform(-1, 1, sp.moving.dof) * spread_deg)
    q = ik.newton(sp.moving.chain, start[None], sp.target(fixed_end, 0.0, 0.0), iters=40, damping=1e-6)
    return state.with_values(sp.moving.joints, q[0])


@pytest.mark.parametrize("seed", range(6))
def test_dm_dt_is_never_negative_on_random_laws_and_captures(platform, captured, seed):
    """Random closed capture configurations and random laws (theta, d within the passive ranges)."""
    rng = np.random.default_rng(seed)
    law = QuinticLaw(0.0, np.deg2rad(rng.uniform(-60, 60)), 0.0, rng.uniform(-0.4, 0.7), rng.uniform(10, 40))
    unlock = str(rng.choice(["arm1.P1", "arm1.P2"]))
    problem = build_problem(platform, "arm1_arm2", unlock, _random_capture(platform, captured, rng), law)
    assert np.rad2deg(np.abs(problem.correction_rad)).max() < 1e-6  # it was closed already
    _, run = _run(problem, "nullspace", dt=0.05, kappa0=rng.uniform(0, 5e-4))
    if run.status != "completed":
        assert "range" in run.message or "rate" in run.message  # a stop says why
    assert run.dm_dt.min() >= -1e-9 * max(1.0, np.abs(run.dm_dt).max())
    assert np.all(np.diff(run.m) >= -1e-8 * run.m[0])
    assert np.abs(run.task_error).max() < 1e-9


def test_rate_limits_are_held_by_slowing_the_law(spec_problem):
    settings, run = _run(spec_problem, "pinv", rate_deg_s=2.0)
    assert run.status == "completed"
    assert np.abs(run.qd).max() <= settings.rate_limit.max() * (1 + 1e-9)
    assert run.time_scale.min() < 0.8 and run.t_s[-1] > spec_problem.law.duration_s  # slower, not faster
    assert run.u[-1] == 1.0


def test_a_run_that_cannot_hold_the_limits_stops_and_says_why(spec_problem):
    _, run = _run(spec_problem, "pinv", rate_deg_s=1.0, min_time_scale=0.6)
    assert run.status == "stopped" and "joint-rate limits allow only" in run.message and run.u[-1] < 1
    lo, hi = np.full(10, -np.pi), np.full(10, np.pi)
    j = spec_problem.split.moving.joints.index("arm2.J4")
    lo[j], hi[j] = spec_problem.q0[j] - 0.05, spec_problem.q0[j] + 0.05  # a joint range it must leave
    _, run = _run(spec_problem, "pinv", ranges=(lo, hi))
    assert run.status == "stopped" and "arm2.J4 would reach" in run.message
    assert np.all(run.q[:, j] >= lo[j]) and np.all(run.q[:, j] <= hi[j])  # nothing recorded outside
