"""Distance benchmark: segment-segment and segment-triangle closest points per second on one core,
against coal (one call per pair, the reference library) measured in the same run, and the
cost of one optimal-control node of the default dual-arm problem (calc and calcDiff; an FDDP
iteration runs both on all N + 1 nodes).

    python -m tests.benchmarks.bench_distance [--pairs 2000000]

Target (issue 11): >= 5 M segment pairs/s on one core. Prints its figures.
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

from capmap.config.dualarm import cloud_source, fit_settings, horizon, load_dual_arm_file, weights  # noqa: E402
from capmap.config.scene_file import load_scene  # noqa: E402
from capmap.dualarm.assembly import assemble, warm_start  # noqa: E402
from capmap.dualarm.cloud import fit_envelope  # noqa: E402
from capmap.dualarm.distance import segment_segment, segment_triangle  # noqa: E402
from capmap.dualarm.ocp import Context, NodeModel  # noqa: E402
from capmap.dualarm.robot import build_dual_arm, fit_capsules  # noqa: E402
from capmap.dualarm.scene import nearest_solid, scan  # noqa: E402
from capmap.dualarm.solver import initial_guess, node_pairs  # noqa: E402
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
    _node_costs()


def _node_costs():
    """calc and calcDiff of the default problem's nodes at the warm start, with their pairs."""
    d = yaml.safe_load(open(os.path.join(ROOT, "config", "config.yaml")))["dualarm"]
    robot = fit_capsules(build_dual_arm(load_dual_arm_file(os.path.join(ROOT, d["robot"]))))[0]
    scene = load_scene(os.path.join(ROOT, d["scene"]))
    _, settings, seed = cloud_source(d)
    fit, fit_seed = fit_settings(d)
    env = fit_envelope(scan(scene, settings, np.random.default_rng(seed))[0], fit, np.random.default_rng(fit_seed))
    labels = (nearest_solid(scene, env.tri.mean(axis=1)), nearest_solid(scene, env.seg.mean(axis=1)))
    h = horizon(d)
    asm = assemble(robot, scene, env, labels, h.nodes, h.dt_s, h.pre_insertion_node)
    xs, us = initial_guess(warm_start(asm), asm.task.dt)
    ctx = Context(asm.model, asm.task, asm.collision, weights(d), robot.q_lower, robot.q_upper, robot.v_max, mu=1e4)
    keep = node_pairs(asm, xs[:, :asm.model.nq], d["solver"]["filter_m"])
    models = [NodeModel(ctx, k, asm.pairs.subset(keep[k])) for k in range(h.nodes)]
    datas = [m.createData() for m in models]

    def calc():
        for m, dd, x, u in zip(models, datas, xs, us):
            m.calc(dd, x, u)

    def calc_diff():
        for m, dd, x, u in zip(models, datas, xs, us):
            m.calcDiff(dd, x, u)
    calc()
    t_calc, t_diff = _best(calc, 3) / h.nodes, _best(calc_diff, 3) / h.nodes
    pairs = np.mean([len(m.pairs) for m in models])
    print(f"optimal-control node (default problem, {pairs:.1f} collision pairs per node at the warm start): calc "
          f"{1e6 * t_calc:.0f} us, calcDiff {1e6 * t_diff:.0f} us; one FDDP iteration over N = {h.nodes} nodes "
          f"~{h.nodes * (t_calc + t_diff):.2f} s plus the backward pass")


if __name__ == "__main__":
    main()
