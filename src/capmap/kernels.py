"""Compile once: numba's compiled kernels written to its on-disk cache before any job needs them.

Every kernel is compiled with ``cache=True``; the first process that calls one compiles it and
writes the cache, the others load it. Parallel jobs started together (the capacity shards) would
each compile the same kernels; :func:`warm` compiles them once, before any job runs (Snakemake's
``onstart``: ``python -m capmap.kernels``), by running each family's
compiled paths on a few inputs of the types the stages use. A marker named by a hash of the kernels'
source files, numba's version and the CPU makes the next call a check of a few milliseconds (after
its imports, about a second).
"""

from __future__ import annotations

import hashlib
import logging
import sys
import time
from pathlib import Path

import llvmlite.binding as ll
import numba
import numpy as np

from capmap.capacity import directions, engine
from capmap.capacity.sphere import min_over_sphere
from capmap.config.robot_file import load
from capmap.core import ik
from capmap.core.dynamics import ArmDynamics
from capmap.core.reduction import lock
from capmap.dualarm import distance

__all__ = ["fingerprint", "warm", "ensure_warm"]

log = logging.getLogger(__name__)
PACKAGE = Path(__file__).resolve().parent
ROBOT = PACKAGE.parents[1] / "config" / "robots" / "ssrms7.yaml"  # a checkout's bundled arm (editable install)


def fingerprint() -> str:
    """Hash of what the compiled code depends on: every source file using numba, numba's version, the CPU."""
    h = hashlib.sha256(f"{numba.__version__} {sys.version} {ll.get_host_cpu_name()}".encode())
    for f in sorted(PACKAGE.rglob("*.py")):
        text = f.read_bytes()
        if b"import numba" in text:
            h.update(str(f.relative_to(PACKAGE)).encode() + text)
    return h.hexdigest()[:16]


def _marker() -> Path:
    """Beside numba's cache: NUMBA_CACHE_DIR when set, else the package's __pycache__ folders."""
    where = Path(numba.config.CACHE_DIR) if numba.config.CACHE_DIR else PACKAGE / "__pycache__"
    return where / f"kernels-{fingerprint()}.ok"


def warm() -> None:
    """Compile (or load) every cached kernel through the stages' own calls on small inputs."""
    rng = np.random.default_rng(0)
    if ROBOT.is_file():
        robot = load(ROBOT)
        for joint in range(1, robot.n_joints + 1):  # every IK method the bundled arm's locks take
            arm = lock(robot, joint, 0.3)
            T = arm.fk(rng.uniform(-np.pi, np.pi, (8, arm.n_active)))
            sol = ik.solve(arm, T[:, :3, 3], T[:, :3, :3])
            if joint == 1:
                ik.GeneralSixR().solve_chain(arm.chain, T, arm.q_lower, arm.q_upper)
                dyn = ArmDynamics(arm)
                limits = engine.LoadLimits.uniform(robot.n_joints, 700, 200, 500).for_arm(arm)
                motion = engine.Motion(0.15, 0.03)
                for dirs in (directions.exact(), directions.sphere(12)):
                    engine.point_capacity(dyn, sol.q, sol.n_solutions, dirs, motion, limits, directions.grid_axes())
                coef = dyn.batch.coefficients(sol.q[:, 0], np.full(len(sol.q), 0.3))
                min_over_sphere(coef.stacked(), coef.S, 0.03, 0.15, dyn.gravity, limits.limit)
    else:
        log.info("no bundled robot at %s: the capacity kernels compile in the first job", ROBOT)
    p = rng.normal(size=(4, 3))
    distance.segment_segment(p, p + 1, p + 2, p + 3)
    distance.point_triangle(p, p + 1, p + 2, p + 3)
    distance.segment_triangle(p, p + 1, p + 2, p + 3, p + 4)


def ensure_warm() -> bool:
    """:func:`warm` unless this code's kernels are known warm (the marker); True if it ran."""
    marker = _marker()
    if marker.is_file():
        return False
    warm()
    try:
        for old in marker.parent.glob("kernels-*.ok"):
            old.unlink()
        marker.parent.mkdir(exist_ok=True)
        marker.write_text("numba cache warm for this code\n")
    except OSError:  # a read-only install: warm each time (loading the cache is quick)
        pass
    return True


if __name__ == "__main__":  # python -m capmap.kernels (the workflow's onstart)
    t0 = time.perf_counter()
    ran = ensure_warm()
    print(f"capmap: numba kernels {'compiled' if ran else 'already compiled'} ({time.perf_counter() - t0:.1f} s)",
          file=sys.stderr)
