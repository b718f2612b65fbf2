"""The voxel refinement on random voxels of a finished default run (issue 26 item 1): points evaluated
per voxel, rounds, not-converged voxels, and every refined minimum (all branches, each configuration,
each of the 13 per-axis values of both) against brute force, 300 uniform points per voxel.

    python -m tests.benchmarks.bench_refine [--voxels 150] [--seeds 0 1 2] [--run results/default]

The voxels of a seed: the --voxels reachable voxels nearest a random one (a block of neighbours, as in a
slab of the map, so that shared corners count once). Starts each voxel from its centre alone (the
refinement, not the sampling, is measured), with the run's
arm, task, limits, direction set and refinement settings. Prints the machine first; a refined value more
than 1 % above the brute force counts as over (a value 0 there and above 0 here: inf).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from capmap.capacity.build import capacity_problem, refine_settings
from capmap.capacity.evaluator import LockedEvaluator
from capmap.capacity.refine import VoxelMinima, refine
from capmap.capacity.tables import voxel_table
from capmap.checks import check_run_config
from capmap.config.run import run_document
from tests.benchmarks.machine import machine


def _over(x: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Relative excess of refined x over brute force d (0 where either is missing; inf: d = 0 < x)."""
    m = np.isfinite(d) & np.isfinite(x)
    r = np.where(m, (x - d) / np.maximum(d, 1e-9), 0.0)
    return np.where(m & (d == 0) & (x > 1e-9), np.inf, r)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--voxels", type=int, default=150)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--run", type=Path, default=Path("results/default"))
    ap.add_argument("--configfile", default="config/config.yaml")
    args = ap.parse_args()
    print(f"machine: {machine()}")
    run = check_run_config(run_document([args.configfile]), args.configfile)
    problem = capacity_problem(run, per_configuration=True)
    evaluator = LockedEvaluator(problem)
    evaluate = evaluator.evaluate
    settings = refine_settings(run.refine, run.task.payload_kg)
    C = len(problem.labels.names)

    vox, grid = voxel_table(pd.read_parquet(args.run / "capacity" / "points.parquet"), run.voxel_edge_m)  # as sampled
    for seed in args.seeds:
        reach = vox[vox.n_reachable > 0]
        ijk = reach[["i", "j", "k"]].to_numpy()
        # a block of neighbouring voxels around a random one (as a slab of the map: they share corners)
        centre = ijk[np.random.default_rng(seed).integers(len(ijk))]
        idx3 = ijk[np.argsort(np.abs(ijk - centre).max(axis=1), kind="stable")[:args.voxels]]
        ctr = grid.lower + (idx3 + 0.5) * grid.edge_m
        ev0 = evaluate(ctr)
        keep = np.isfinite(ev0.capacity_kg)
        idx3, ctr = idx3[keep], ctr[keep]
        n = int(keep.sum())
        start = VoxelMinima.with_configurations(
            C, voxel=grid.flat(idx3), capacity_kg=ev0.capacity_kg[keep], axis_capacity_kg=ev0.axis_capacity_kg[keep],
            n_points=np.ones(n, dtype=int), n_reachable=np.ones(n, dtype=int), last_change=np.zeros(n),
            converged=np.zeros(n, dtype=bool), worst_m=ctr, binding=ev0.binding[keep], rounds=0, n_evaluated=0)
        t = time.perf_counter()
        res = refine(grid, start, evaluator, settings, np.random.default_rng(seed))
        dt = time.perf_counter() - t
        m = 300
        rng = np.random.default_rng(1000 + seed)
        ev = evaluate(grid.lower + (np.repeat(idx3, m, axis=0) + rng.uniform(0, 1, (m * n, 3))) * grid.edge_m)
        inf = np.where(np.isfinite(ev.capacity_kg), ev.capacity_kg, np.inf)
        dense = np.minimum(inf.reshape(n, m).min(axis=1), start.capacity_kg)
        checks = {"all-branch": (res.capacity_kg, dense),
                  "per-axis": (res.axis_capacity_kg, np.fmin.reduce(ev.axis_capacity_kg.reshape(n, m, -1), axis=1)),
                  "configuration": (res.config_capacity_kg, np.fmin.reduce(ev.config_capacity_kg.reshape(n, m, C), axis=1)),
                  "configuration per-axis": (res.config_axis_capacity_kg,
                                             np.fmin.reduce(ev.config_axis_capacity_kg.reshape(n, m, C, -1), axis=1))}
        over = ", ".join(f"{k} {int((_over(*v) > 0.01).sum())}" for k, v in checks.items())
        print(f"seed {seed}: {n} voxels, {res.n_evaluated / n:.1f} points per voxel, {res.rounds} rounds, "
              f"{int((~res.converged).sum())} not converged, {dt:.1f} s; over 1 % above 300-point brute force: {over}")


if __name__ == "__main__":
    main()
