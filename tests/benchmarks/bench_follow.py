"""Follower benchmark: wall time per control period of the online work, and path preparation.

    python -m tests.benchmarks.bench_follow [--repeats 5]

Per period the follower reads the command, interpolates the path dynamics a, b, c at s,
computes the admissible acceleration interval from the torque limits, applies the speed
ceiling and the catch-up law, and integrates (capmap.following.follower.follow); on drives also the
friction at the current speed. Target (issue 5): well under 50 us per period. Prints its figures.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from capmap.core.kinematics import rotation_from_rpy
from capmap.core.limits import AffineLimits
from capmap.core.profiles import scurve
from capmap.core.reduction import free, lock
from capmap.following.follower import follow
from capmap.following.path import line_path
from capmap.following.path_dynamics import path_dynamics, prepare
from capmap.robots import load
from tests.benchmarks.machine import machine

ROOT = Path(__file__).resolve().parents[2]


def cases():
    ur5 = free(load(ROOT / "config/robots/ur5.yaml"))
    q0 = np.deg2rad([0, -68.75, 91.67, -108.86, -90, 0])
    T0 = ur5.fk(q0[None])[0]
    yield ("UR5, 0.5 m line, shoulder pan limited to 14 N m", ur5, T0[:3, 3], T0[:3, 3] + [0, 0.5, 0], T0[:3, :3], q0,
           2.0, np.array([14, 150, 150, 28, 28, 28.0]), (1.0, 4.0, 40.0), 5.0)
    drives = free(load(ROOT / "config/robots/ur5_drives.yaml"))  # the same line with the drives' terms (issue 28)
    yield ("UR5 on drives (rotor inertia, friction), the same line", drives, T0[:3, 3], T0[:3, 3] + [0, 0.5, 0],
           T0[:3, :3], q0, 2.0, np.array([14, 150, 150, 28, 28, 28.0]), (1.0, 4.0, 40.0), 5.0)
    ssrms = lock(load(ROOT / "config/robots/ssrms7.yaml"), 1, np.deg2rad(100))
    R = rotation_from_rpy([90, 0, 90])
    yield ("SSRMS joint 1 locked, 1.30 m segment, 1500 kg, 150 N m", ssrms, np.array([0.375, 4.875, 1.875]),
           np.array([1.125, 4.125, 2.625]), R, np.deg2rad([124.5, 97.3, 130.6, 145.7, 174.3, 56.9]), 1500.0,
           np.full(6, 150.0), (0.15, 0.03, 0.01), 2.0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    print(f"machine: {machine()}")
    print("follower: online work per control period (1 ms), path preparation once per path")
    for name, arm, p0, p1, R, q0, m, lim, (v, a, j), f in cases():
        t0 = time.perf_counter()
        table = line_path(arm, p0, p1, R, q0, ds_m=1e-3)
        t1 = time.perf_counter()
        limits = AffineLimits(lim, tuple(f"tau_j{j}_nm" for j in arm.active_joint_numbers))
        prep = prepare(path_dynamics(arm, table, m), limits, v)
        t2 = time.perf_counter()
        cmd = scurve(table.length_m, v, a, j)
        per = []
        for _ in range(args.repeats):
            s = time.perf_counter()
            res = follow(prep, cmd, 1e-3, f)
            per.append((time.perf_counter() - s) / len(res.t_s))
        per = np.array(per) * 1e6
        print(f"- {name}: {len(res.t_s)} periods ({int(res.limited.sum())} limited); "
              f"{np.median(per):.1f} us/period median of {args.repeats} runs (min {per.min():.1f}, max {per.max():.1f}); "
              f"path preparation {1e3 * (t2 - t0):.0f} ms for {table.length_m:.3f} m on a 1 mm grid "
              f"(IK + derivatives {1e3 * (t1 - t0):.0f} ms, dynamics tables + speed ceiling {1e3 * (t2 - t1):.0f} ms)")


if __name__ == "__main__":
    main()
