"""Compile once: numba's compiled kernels written to its on-disk cache before any job needs them.

Every kernel is compiled with ``cache=True``; the first process that calls one compiles it and
writes the cache, the others load it. Parallel jobs started together (the capacity shards) would
each compile the same kernels; :func:`warm` compiles those a run uses once, before its jobs, by
running the stages' compiled calls on a few inputs of their types: the locked arm's IK (whichever
method its chain takes), the capacity kernels, and the dual-arm family's when the run has it (on two
cores in two halves of about equal time: its node models and FDDP in a second process beside the arm's
kernels, its geometry in this one after them). ``python -m capmap.kernels [--configfile FILE]`` (the
README's install command; Snakemake's ``onstart`` runs it for the run's own config). With a config, the dual-arm robot's
pre-run build is done and remembered as well (:func:`remember_dual_arm`). A marker per hash of the
kernels' source files, numba's version and the CPU lists what was warmed, so the next call is a
check of milliseconds (after its imports, about a second).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import capmap.dualarm.ocp.compiled_nodes as nodes
from capmap.capacity import directions, engine
from capmap.capacity.problem import CapacityProblem
from capmap.checks import dual_arm_limits
from capmap.config.parse import parse_config
from capmap.config.run import DEFAULT_CONFIG, run_document
from capmap.core import ik
from capmap.core.reduction import lock
from capmap.dualarm.scene_file import load_scene
from capmap.errors import CapmapError
from capmap.io.kernel_marker import is_warm, record, run_key
from capmap.robots import load

__all__ = ["warm", "ensure_warm", "remember_dual_arm", "main"]


def warm(robot_file: str, joint: int, angle_rad: float, dualarm: bool, here: bool = False) -> None:
    """Compile (or load) the kernels of a run: ``robot_file``'s arm with ``joint`` (1-based) locked at
    ``angle_rad`` (its IK method, the capacity kernels), and the dual-arm family's if ``dualarm``
    (:mod:`capmap.dualarm.ocp.compiled_nodes`: ``warm_up_nodes``, ``warm_up_geometry``). When this process may
    use two cores the family's node models and FDDP compile in a child process beside the arm's kernels, and
    its geometry here after them: the two halves take
    about as long (capmap's environment gives the child the same numba cache folder; the distances both
    call are compiled by the child first and loaded here). ``here``: every kernel in this process (to hold
    them loaded: :mod:`capmap.io.job_server`)."""
    child = None
    if dualarm and not here and len(os.sched_getaffinity(0)) >= 2:
        child = subprocess.Popen([sys.executable, "-c", "import capmap.dualarm.ocp.compiled_nodes as n; n.warm_up_nodes()"])
    try:
        _warm_arm(robot_file, joint, angle_rad)
        if dualarm:
            nodes.warm_up_geometry()
    except BaseException:
        if child is not None:
            child.kill()
            child.wait()
        raise
    if child is None and dualarm:
        nodes.warm_up_nodes()
    elif child is not None and child.wait() != 0:
        raise RuntimeError(f"the dual-arm kernels' process failed (exit code {child.returncode})")


def _warm_arm(robot_file: str, joint: int, angle_rad: float) -> None:
    """The arm's kernels: its IK with ``joint`` locked at ``angle_rad``, the capacity kernels."""
    rng = np.random.default_rng(0)
    arm = lock(load(robot_file), joint, angle_rad)
    T = arm.fk(rng.uniform(np.maximum(arm.q_lower, -np.pi), np.minimum(arm.q_upper, np.pi), (8, arm.n_active)))
    limits = engine.LoadLimits.uniform(arm.robot.n_joints, 700, 200, 500).for_arm(arm)
    for dirs in (directions.exact(), directions.sphere(12)):
        problem = CapacityProblem(arm, T[0, :3, :3], engine.Motion(0.15, 0.03), limits, dirs, directions.grid_axes())
        sol = ik.solve(arm, T[:, :3, 3], T[:, :3, :3])  # each its own orientation: every IK branch kind
        problem.capacity(sol)
    problem.dyn.batch.coefficients(sol.q[:, 0], np.full(len(sol.q), angle_rad))  # the baseline's held angles


def ensure_warm(robot_file: str, joint: int, angle_rad: float, dualarm: bool) -> bool:
    """:func:`warm` unless the marker lists this run's kernels as warm for this code; True if it ran."""
    key = run_key(robot_file, joint, angle_rad, dualarm, load(robot_file).n_joints)
    if is_warm(key):
        return False
    print(f"capmap: compiling the numba kernels for {Path(robot_file).name}, joint {joint} locked"
          f"{' and the dual-arm family' if dualarm else ''}: once per machine and code version (about a minute "
          "on 1 or 2 cores; every checkout of this code then loads them)...", file=sys.stderr, flush=True)
    warm(robot_file, joint, angle_rad, dualarm)
    record(key)
    return True


def remember_dual_arm(robot_file: str, scene_file: str) -> None:
    """The pre-run check's dual-arm build (every visual mesh loaded, ~1.4 s), done now and remembered
    (:func:`capmap.checks.dual_arm_limits`); an error is left to the workflow's check to report."""
    try:
        dual_arm_limits(robot_file, float(load_scene(scene_file).panel.size[0]))
    except CapmapError:
        pass


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m capmap.kernels", description=__doc__.splitlines()[0])
    ap.add_argument("--configfile", default=DEFAULT_CONFIG, help=f"the run's config (default: {DEFAULT_CONFIG})")
    ap.add_argument("--robot", help="instead of a config: the robot file, with --joint, --angle-deg, --dualarm")
    ap.add_argument("--joint", type=int, default=1)
    ap.add_argument("--angle-deg", type=float, default=0.0)
    ap.add_argument("--dualarm", action="store_true")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    try:
        if args.robot:
            robot, joint, angle, dualarm = args.robot, args.joint, args.angle_deg, args.dualarm
        else:
            run = parse_config(run_document([args.configfile]), args.configfile)
            robot, joint, dualarm = run.robot, run.lock.joint, run.dualarm is not None
            angle = run.lock.angle_deg if run.lock.angle_deg is not None else run.task.q_ini_deg[joint - 1]
        ran = ensure_warm(robot, joint, np.deg2rad(angle), dualarm)
        if not args.robot and run.dualarm is not None:
            remember_dual_arm(run.dualarm.robot, run.dualarm.scene)
    except Exception as exc:  # best effort: the workflow's own checks say what is wrong, and the jobs compile
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        print(f"capmap: kernels not compiled before the jobs ({why}); each job compiles its own", file=sys.stderr)
        return 1
    print(f"capmap: numba kernels {'compiled' if ran else 'already compiled'} for {robot}, joint {joint} locked "
          f"({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
