"""Distance and optimiser benchmark: segment-segment and segment-triangle closest points per second
on one core, against coal (one call per pair, the reference library) measured in the same run;
the cost of one optimal-control node of the default dual-arm problem (calc and calcDiff; an FDDP
iteration runs both on all N + 1 nodes), compiled against the Pinocchio node model in the same
run; and the default problem's whole solve (AL-DDP) and CSQP check with either node model.

    python -m tests.benchmarks.bench_distance [--pairs 2000000] [--no-solve]

Targets: >= 5 M segment pairs/s on one core (issue 11); the default dualarm_optimise <= 3 s on
one core, node models at Crocoddyl's own order of speed (~6 us calc, 17-25 us calcDiff; issue 26).
Prints its figures.
"""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import coal  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)  # tests.reference: the coal shapes of the distance tests

from capmap.checks import check_run_config  # noqa: E402
from capmap.config.dualarm import cloud_source, fit_config, horizon, weights_config  # noqa: E402
from capmap.dualarm.build import al_settings, fit_settings, load_dual_arm_file, scan_settings, weights  # noqa: E402
from capmap.dualarm.geometry.distance import segment_segment, segment_triangle  # noqa: E402
from capmap.dualarm.ocp.assembly import assemble, warm_start  # noqa: E402
from capmap.dualarm.ocp.motion import plan_assembly  # noqa: E402
from capmap.dualarm.ocp.settings import SolveOptions, StopRule  # noqa: E402
from capmap.dualarm.ocp.solver import context, initial_guess, node_model, node_pairs, solve_csqp  # noqa: E402
from capmap.dualarm.scene.cloud import fit_envelope  # noqa: E402
from capmap.dualarm.scene.robot import build_dual_arm, fit_capsules  # noqa: E402
from capmap.dualarm.scene.solids import nearest_solid, scan  # noqa: E402
from capmap.dualarm.scene_file import load_scene  # noqa: E402
from tests.benchmarks.machine import machine  # noqa: E402
from tests.reference.coal_shapes import capsule  # noqa: E402


def _best(fn, repeats=5) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pairs", type=int, default=2_000_000)
    ap.add_argument("--coal-pairs", type=int, default=20_000)
    ap.add_argument("--no-solve", action="store_true", help="skip the whole solves (the Pinocchio one takes ~15 s)")
    args = ap.parse_args()
    print(f"machine: {machine()}")
    rng = np.random.default_rng(0)
    n = args.pairs
    p0, p1, q0, q1, v2 = (rng.normal(size=(n, 3)) for _ in range(5))
    segment_segment(p0[:10], p1[:10], q0[:10], q1[:10])  # compile
    segment_triangle(p0[:10], p1[:10], q0[:10], q1[:10], v2[:10])
    t_ss = _best(lambda: segment_segment(p0, p1, q0, q1))
    t_st = _best(lambda: segment_triangle(p0, p1, q0, q1, v2))
    m = args.coal_pairs
    shapes = [(capsule(p0[i], p1[i], 0.01), capsule(q0[i], q1[i], 0.01)) for i in range(m)]
    req, res = coal.DistanceRequest(), coal.DistanceResult()

    def coal_all():
        for (g1, T1), (g2, T2) in shapes:
            coal.distance(g1, T1, g2, T2, req, res)
    t_coal = _best(coal_all, 3) * n / m
    print(f"segment-segment closest points: {n / t_ss / 1e6:.1f} M pairs/s on one core "
          f"(coal capsule-capsule, one call per pair: {n / t_coal / 1e6:.2f} M pairs/s; ratio {t_coal / t_ss:.0f}x); "
          f"target >= 5 M pairs/s")
    print(f"segment-triangle closest points: {n / t_st / 1e6:.1f} M pairs/s on one core")
    d, robot, parts, asm = _default_problem()
    _node_costs(d, robot, asm)
    if not args.no_solve:
        _solves(robot, parts, asm)


def _default_problem():
    d = yaml.safe_load(open(os.path.join(ROOT, "config", "config.yaml")))["dualarm"]
    scene = load_scene(os.path.join(ROOT, d["scene"]))
    robot = fit_capsules(build_dual_arm(load_dual_arm_file(os.path.join(ROOT, d["robot"])), float(scene.panel.size[0])))[0]
    _, scan_cfg, seed = cloud_source(d)
    settings = scan_settings(scan_cfg)
    fit_cfg, fit_seed = fit_config(d)

    fit = fit_settings(fit_cfg)
    env = fit_envelope(scan(scene, settings, np.random.default_rng(seed))[0], fit, np.random.default_rng(fit_seed))
    labels = (nearest_solid(scene, env.tri.mean(axis=1)), nearest_solid(scene, env.seg.mean(axis=1)))
    h = horizon(d)
    return d, robot, (scene, env, labels), assemble(robot, scene, env, labels, h.nodes, h.dt_s, h.pre_insertion_node)


def _node_costs(d, robot, asm):
    """calc and calcDiff of the default problem's nodes at the warm start, with their pairs, by the
    compiled and the Pinocchio node models."""
    xs, us = initial_guess(warm_start(asm), asm.task.dt)
    N = asm.task.N
    keep = node_pairs(asm, xs[:, :asm.model.nq], d["solver"]["filter_m"])
    times = {}
    for compiled in (True, False):
        ctx = context(asm, weights(weights_config(d)), (robot.q_lower, robot.q_upper, robot.v_max), compiled, mu=1e4)
        models = [node_model(ctx, k, asm.pairs.subset(keep[k])) for k in range(N)]
        datas = [m.createData() for m in models]

        def calc():
            for m, dd, x, u in zip(models, datas, xs, us):
                m.calc(dd, x, u)

        def calc_diff():
            for m, dd, x, u in zip(models, datas, xs, us):
                m.calcDiff(dd, x, u)
        calc()
        calc_diff()
        times[compiled] = (_best(calc, 3) / N, _best(calc_diff, 3) / N)
    pairs = np.mean([len(m.pairs) for m in models])
    (c1, d1), (c0, d0) = times[True], times[False]
    print(f"optimal-control node (default problem, {pairs:.1f} collision pairs per node at the warm start), one "
          f"core: compiled calc {1e6 * c1:.1f} us, calcDiff {1e6 * d1:.1f} us; Pinocchio node model calc "
          f"{1e6 * c0:.0f} us, calcDiff {1e6 * d0:.0f} us (ratios {c0 / c1:.0f}x, {d0 / d1:.0f}x); Crocoddyl's own C++ "
          f"models ~6 us and 17-25 us (crocoddyl PR #1346)")


def _solves(robot, parts, asm):
    """The default dualarm_optimise solve and the CSQP check, each with either node model."""
    da = check_run_config(yaml.safe_load(open(os.path.join(ROOT, "config", "config.yaml")))).dualarm
    limits = (robot.q_lower, robot.q_upper, robot.v_max)
    for compiled in (True, False):
        t0 = time.perf_counter()
        m = plan_assembly(asm, robot, weights(da.weights), al_settings(da.solver), da.fine_factor,
                          SolveOptions(compiled=compiled))
        t = time.perf_counter() - t0
        print(f"default dualarm_optimise ({'compiled' if compiled else 'Pinocchio'} node models): solve {m.solve_s:.2f} s"
              f" ({len(m.sol.stats)} outer / {sum(s.inner_iterations for s in m.sol.stats)} FDDP iterations), "
              f"with warm start and evaluation {t:.2f} s; closed chain {m.errors.closed_chain_pos.max():.1e} m, path "
              f"{m.errors.path_pos.max():.1e} m, {1e3 * m.fine.min_distance.min():.3f} mm on the finer grid, active "
              f"{', '.join(a[0] for a in m.active)}")
    ch = da.check
    casm = assemble(robot, *parts, ch.horizon.nodes, ch.horizon.dt_s, ch.horizon.pre_insertion_node)
    xs0, us0 = initial_guess(warm_start(casm), casm.task.dt)
    for compiled in (True, False):
        t0 = time.perf_counter()
        r = solve_csqp(casm, weights(da.weights), limits, xs0, us0, StopRule(ch.max_iterations, ch.tolerance),
                       compiled=compiled)
        print(f"CSQP check ({'compiled' if compiled else 'Pinocchio'} node models, N = {ch.horizon.nodes}): "
              f"{time.perf_counter() - t0:.2f} s, {r.iterations} iterations, converged {r.converged}")


if __name__ == "__main__":
    main()

