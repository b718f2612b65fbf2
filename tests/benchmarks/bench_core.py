"""Core-engine benchmark: IK points/s per core and capacity motion states/s on all cores.

    python -m tests.benchmarks.bench_core [--points 20000] [--workers 2] [--step 10] [--reference 38cfebe]

Prints its figures (IK: the shortest of 3 runs); targets: IK >= 14,000 points/s per core (closed
form, all branches), >= 14,000 with the SSRMS's joint 3, 4 or 5 locked and >= 5,000 for the general
6R method on the Panda and the xArm7 with any joint locked; capacity >= 30 M states/s on this machine's 2 cores (state =
configuration x direction) and >= 8x the per-configuration Pinocchio path measured in the same run; the
exact minimum over the sphere of directions (issue 26): configurations/s/worker >= 2x the 10-degree grid's
of the commit before issue 26 (``--reference``, default 38cfebe: its own bench_core run from a ``git
worktree`` in this run, after this checkout's figures; ``--reference ''`` skips it).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one thread per worker: cores are the parallelism
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import multiprocessing as mp  # noqa: E402
import re  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402

from capmap.capacity import directions, engine  # noqa: E402
from capmap.capacity.problem import CapacityProblem, point_capacity  # noqa: E402
from capmap.core import ik  # noqa: E402
from capmap.core.dynamics import ArmDynamics  # noqa: E402
from capmap.core.reduction import lock  # noqa: E402
from capmap.robots import load  # noqa: E402
from tests.benchmarks.machine import machine  # noqa: E402

ROBOT = Path(__file__).resolve().parents[2] / "config" / "robots" / "ssrms7.yaml"
R_TASK = pin.rpy.rpyToMatrix(*np.deg2rad([90.0, 0.0, 90.0]))
_worker = {}


def _arm():
    return lock(load(ROBOT), 1, np.deg2rad(100.0))


def _init(step):
    arm = _arm()  # model built once per worker, one Data per worker
    _worker.update(dyn=ArmDynamics(arm), dirs=directions.paper_grid(step), exact=directions.exact(),
                   limits=engine.LoadLimits.uniform(7, 700, 200, 500).for_arm(arm))
    _worker.update(grid_problem=CapacityProblem(arm, np.eye(3), engine.Motion(0.15, 0.03), _worker["limits"], _worker["dirs"]),
                   exact_problem=CapacityProblem(arm, np.eye(3), engine.Motion(0.15, 0.03), _worker["limits"],
                                                 _worker["exact"]))


def _capacity_chunk(args):
    q, n = args
    pc = point_capacity(_worker["grid_problem"], q, n)
    return int(pc.n_states.sum()), resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _exact_chunk(args):
    """The exact minimum over the sphere of directions (directions.kind: exact) of the same points."""
    q, n = args
    point_capacity(_worker["exact_problem"], q, n)
    return int(n.sum())


def _reference_chunk(args):
    """The per-configuration Pinocchio path (16 RNEA + 6 drift calls in Python) and the numpy
    sweep over (configurations, outputs, directions): what the engine replaced."""
    q, n = args
    valid = np.arange(q.shape[1])[None, :] < n[:, None]
    pts, brs = np.nonzero(valid)
    coef = engine.coefficients_pinocchio(_worker["dyn"], q[pts, brs])
    engine.capacity_over_directions(coef, _worker["dirs"], engine.Motion(0.15, 0.03), _worker["dyn"].gravity,
                                    _worker["limits"])
    return len(pts) * len(_worker["dirs"])


def _best_of(runs: int, f):
    """(the result of f(), the shortest of ``runs`` wall times in s): a virtual machine's timer noise
    only ever adds time."""
    best, out = np.inf, None
    for _ in range(runs):
        t = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t)
    return out, best


def erd_chain(name: str, joint: int):
    """The 6-joint chain of example-robot-data's 7-DOF arm ``name`` (fingers held at 0) with ``joint``
    (1-based) locked at mid-range: (Chain, lower (6,), upper (6,)) rad."""
    import example_robot_data as erd
    import pinocchio as pin

    from capmap.core.kinematics import Chain

    model = erd.load(name).model
    arm = [j for j in range(1, model.njoints) if model.joints[j].nq == 1 and "finger" not in model.names[j]][:7]
    model = pin.buildReducedModel(model, [j for j in range(1, model.njoints) if j not in arm], pin.neutral(model))
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    q = pin.neutral(model)
    q[joint - 1] = (lo[joint - 1] + hi[joint - 1]) / 2
    reduced = pin.buildReducedModel(model, [joint], q)
    active = [i for i in range(7) if i != joint - 1]
    return Chain.from_model(reduced, reduced.nframes - 1), lo[active], hi[active]


def reference_rate(commit: str, points: int, workers: int) -> float:
    """The configurations/s/worker of the 10-degree grid that ``commit``'s own bench_core prints, run from a
    ``git worktree`` of it (its package first on PYTHONPATH, its numba cache apart)."""
    root = Path(__file__).resolve().parents[2]
    tmp = Path(tempfile.mkdtemp())
    wt = tmp / "reference"
    subprocess.run(["git", "worktree", "add", "--detach", str(wt), commit], cwd=root, check=True, capture_output=True)
    try:
        env = dict(os.environ, PYTHONPATH=f"{wt / 'src'}{os.pathsep}{wt}", NUMBA_CACHE_DIR=str(tmp / "numba"))
        res = subprocess.run([sys.executable, "-m", "tests.benchmarks.bench_core", "--points", str(points), "--workers",
                              str(workers)], cwd=wt, env=env, capture_output=True, text=True, check=False)
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(wt)], cwd=root, check=False, capture_output=True)
    m = re.search(r"capacity \(.*?([\d,]+) configurations/s/worker", res.stdout)
    if res.returncode != 0 or m is None:
        raise SystemExit(f"bench_core of {commit} failed:\n{res.stderr[-2000:]}")
    return float(m.group(1).replace(",", ""))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=20000)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--step", type=float, default=10.0)
    ap.add_argument("--reference", default="38cfebe", help="the commit whose grid rate the exact minimum is compared with")
    args = ap.parse_args()
    print(f"machine: {machine()}")
    arm = _arm()
    rng = np.random.default_rng(0)

    # IK on poses known to be reachable (generated by FK), and on workspace points at the task orientation
    T = arm.fk(rng.uniform(-np.pi, np.pi, (args.points, 6)))
    ik.solve(arm, T[:50, :3, 3], T[:50, :3, :3])  # load the compiled kernels before timing
    ik.solve(arm, T[:50, :3, 3], R_TASK)
    t = time.perf_counter()
    sol = ik.solve(arm, T[:, :3, 3], T[:, :3, :3])
    dt = time.perf_counter() - t
    closed = args.points / dt  # the reference the other IK figures are compared with, same run
    print(f"IK reachable poses     : {args.points / dt:12,.0f} points/s/core  "
          f"({sol.n_solutions.sum() / args.points:.2f} branches per point, method {sol.method})")
    t = time.perf_counter()
    sol = ik.solve(arm, T[:, :3, 3], R_TASK)
    dt = time.perf_counter() - t
    reach = sol.n_solutions > 0
    print(f"IK task orientation    : {args.points / dt:12,.0f} points/s/core  ({reach.mean():.1%} reachable)")

    # every locked joint (where it stood in the scenario): the method and its speed on reachable poses
    robot = load(ROBOT)
    n_lock = max(args.points // 10, 200)
    for joint, angle in enumerate([100, 124, 98, 130, 146, 174, 57], start=1):
        arm_j = lock(robot, joint, np.deg2rad(angle))
        Tj = arm_j.fk(rng.uniform(-np.pi, np.pi, (n_lock, 6)))
        ik.solve(arm_j, Tj[:20, :3, 3], Tj[:20, :3, :3])  # compile the kernels once
        sol_j, dt = _best_of(3, lambda: ik.solve(arm_j, Tj[:, :3, 3], Tj[:, :3, :3]))
        print(f"IK joint {joint} locked      : {n_lock / dt:12,.0f} points/s/core  ({sol_j.method}, "
              f"{sol_j.n_solutions.mean():.2f} branches per pose, max {sol_j.n_solutions.max()})")
        general = ik.GeneralSixR()
        general.solve_chain(arm_j.chain, Tj[:20], arm_j.q_lower, arm_j.q_upper)
        sol_g, dt = _best_of(3, lambda: general.solve_chain(arm_j.chain, Tj, arm_j.q_lower, arm_j.q_upper))
        print(f"  general 6R, same poses: {n_lock / dt:12,.0f} points/s/core  ({sol_g.n_solutions.sum()} branches, "
              f"{sol_j.method} {sol_j.n_solutions.sum()})")

    # 7-DOF arms from example-robot-data, each joint locked at mid-range: the method and its speed
    for name in ("panda", "xarm7"):
        for joint in range(1, 8):
            chain, lower, upper = erd_chain(name, joint)
            Tj = chain.fk(rng.uniform(lower, upper, (n_lock, 6)))
            ik.solve_chain(chain, Tj[:20], lower, upper)
            sol_j, dt = _best_of(3, lambda: ik.solve_chain(chain, Tj, lower, upper))
            print(f"IK {name:6s} joint {joint} locked: {n_lock / dt:10,.0f} points/s/core  ({sol_j.method}, "
                  f"{sol_j.n_solutions.mean():.2f} branches per pose, max {sol_j.n_solutions.max()}; "
                  f"{n_lock / dt / closed:.3f} of the closed form's rate in this run)")

    # capacity: the reachable points' configuration sets, split across workers
    q, n = sol.q[reach], sol.n_solutions[reach]
    chunks = [(q[i:i + 200], n[i:i + 200]) for i in range(0, len(q), 200)]
    dirs = directions.paper_grid(args.step)
    with mp.get_context("fork").Pool(args.workers, initializer=_init, initargs=(args.step,)) as pool:
        pool.map(_capacity_chunk, chunks[:args.workers])  # warm-up
        t = time.perf_counter()
        out = pool.map(_capacity_chunk, chunks)
        dt = time.perf_counter() - t
        states, peak = sum(o[0] for o in out), max(o[1] for o in out)
        pool.map(_exact_chunk, chunks[:args.workers])  # warm-up
        t = time.perf_counter()
        exact_configs = sum(pool.map(_exact_chunk, chunks))
        dt_exact = time.perf_counter() - t
        ref_chunks = chunks[: max(args.workers, len(chunks) // 20)]  # the reference is slow: a twentieth
        t = time.perf_counter()
        ref_states = sum(pool.map(_reference_chunk, ref_chunks))
        dt_ref = time.perf_counter() - t
    configs = int(n.sum())
    print(f"capacity ({args.workers} workers)  : {states / dt:12,.0f} states/s  "
          f"({configs:,} configurations x {len(dirs)} directions in {dt:.1f} s; "
          f"{configs / dt / args.workers:,.0f} configurations/s/worker; peak memory per worker {peak:.0f} MB, "
          f"chunks of 200 points)")
    print(f"reference ({args.workers} workers) : {ref_states / dt_ref:12,.0f} states/s  (Pinocchio per configuration + "
          f"numpy sweep, same run); ratio {states / dt / (ref_states / dt_ref):.1f}x")
    grid_rate, exact_rate = configs / dt / args.workers, exact_configs / dt_exact / args.workers
    print(f"exact minimum over the sphere ({args.workers} workers): {exact_rate:,.0f} configurations/s/worker "
          f"(coefficients + exact minimum), {exact_rate / grid_rate:.2f}x the {len(dirs)}-direction grid's "
          f"{grid_rate:,.0f} in the same run")
    if args.reference:
        ref = reference_rate(args.reference, args.points, args.workers)
        print(f"reference {args.reference} ({args.workers} workers, its bench_core in this run): {ref:,.0f} "
              f"configurations/s/worker on its {len(dirs)}-direction grid; the exact minimum here is "
              f"{exact_rate / ref:.2f}x that (target: 2x)")


if __name__ == "__main__":
    main()
