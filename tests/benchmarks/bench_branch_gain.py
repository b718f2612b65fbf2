"""What planning on the executed branch gains over the voxel map, on a finished default run.

Random tasks between centres of reachable voxels (seeded) at a payload, each from a random
IK branch at its start: A* on the map (direction-aware moves, every branch's minimum) against
A* over (voxel, IK branch) states; every branch plan is verified (dense samples, continuous
IK, loads carrying the payload) and the verification's configurations at the waypoints are
compared with the planned ones. Prints one line per task and the counts, with the time of each
branch search (an exhaustive search, when there is no path, takes tens of seconds).

    python -m tests.benchmarks.bench_branch_gain [--payload 3200] [--tasks 12] [--seed 1]

Needs results/default/voxels/voxels.parquet and results/default/verify/payload_1500kg/ of the default run.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from capmap.capacity import planning
from capmap.capacity.branch_moves import MoveCache
from capmap.capacity.branch_planning import BranchProblem, _result, _search
from capmap.capacity.build import capacity_problem
from capmap.capacity.plan_verify import branch_deviation_deg
from capmap.capacity.tables import AXIS_COLUMNS, grid_of
from capmap.capacity.verification import judge, verify_path
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.errors import NoPath
from capmap.io import datasets
from capmap.stages.common import stage_config
from tests.benchmarks.machine import machine


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--payload", type=float, default=3200.0)
    ap.add_argument("--tasks", type=int, default=12)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    print(f"machine: {machine()}")
    deps = datasets.read("results/default/verify/payload_1500kg/timeseries.parquet").attrs["capmap"]["config"]
    at = capacity_problem(stage_config(json.dumps(deps)).run)
    arm, rot, motion, limits = at.arm, at.rotation, at.motion, at.limits
    dyn = ArmDynamics(arm)
    vox = datasets.read("results/default/voxels/voxels.parquet")
    grid = grid_of(vox)
    cap, axis_cap = vox.capacity_kg.to_numpy(), vox[AXIS_COLUMNS].to_numpy()
    usable = (vox.n_reachable > 0).to_numpy()
    pb = BranchProblem(dyn, grid, rot, motion, limits, usable)
    cache = MoveCache(pb)
    idx = vox[["i", "j", "k"]].to_numpy()
    rng = np.random.default_rng(a.seed)
    M = a.payload
    counts = {"tasks": 0, "map": 0, "branch": 0, "verified": 0}
    t_all = time.perf_counter()
    while counts["tasks"] < a.tasks:
        s, g = rng.choice(np.flatnonzero(usable), 2, replace=False)
        s_m, g_m = grid.centres(idx[[s]])[0], grid.centres(idx[[g]])[0]
        sol = ik.solve(arm, s_m[None], rot)
        if sol.n_solutions[0] == 0:
            continue
        q0 = sol.q[0, rng.integers(sol.n_solutions[0])]
        counts["tasks"] += 1
        try:
            planning.plan(grid, cap, s_m, g_m, M, axis_cap)
            counts["map"] += 1
            on_map = "path"
        except NoPath:
            on_map = "none"
        t0 = time.perf_counter()
        nodes, goal, expanded = _search(cache, s_m, g_m, q0, M)
        dt = time.perf_counter() - t0
        line = (f"task {counts['tasks']}: map A* {on_map} (voxels {cap[s]:.0f} / {cap[g]:.0f} kg); branch search "
                f"{'path' if goal is not None else 'none'} in {dt:.1f} s ({expanded} states expanded)")
        if goal is not None:
            counts["branch"] += 1
            p = _result(cache, nodes, goal, expanded)
            res = verify_path(dyn, p.waypoints, rot, q0, motion, 0.1, limits)
            _, v = judge(res, arm, limits, M)
            counts["verified"] += int(v.feasible)
            line += (f"; verified {'carrying' if v.feasible else 'NOT carrying'} {M:g} kg (capacity {v.capacity_kg:.0f} kg), "
                     f"largest deviation from the planned configurations {branch_deviation_deg(res, np.rad2deg(p.q)):.1e} deg")
        print(line, flush=True)
    print(f"{M:g} kg, {counts['tasks']} tasks: map A* finds {counts['map']}, the branch search {counts['branch']}, "
          f"verified carrying {counts['verified']} of {counts['branch']}; {time.perf_counter() - t_all:.0f} s in all")


if __name__ == "__main__":
    main()
