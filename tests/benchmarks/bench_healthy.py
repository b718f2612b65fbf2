"""The healthy arm beside a finished map, this checkout against a reference commit measured in the same
run: the wall time of ``snakemake baseline`` once ``capacity_map`` is done (target <= 2 min on 2 cores),
its shards' core-seconds, and the angle check of its summary (voxels more than 1 % below a 1 deg sweep;
target: none of the 200).

    python -m tests.benchmarks.bench_healthy [--reference 99543d1] [--cores 2] [--skip-reference]

Each run is in its own temporary copy of the workflow (results/ of the checkout untouched) with its own
numba cache, its kernels compiled before the timed runs; the reference's code is a ``git worktree`` of the
commit, put first on PYTHONPATH for its jobs. Prints the machine first.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pandas as pd

from tests.benchmarks.bench_pipeline import _copy, _jobs, _snakemake, reference_worktree
from tests.benchmarks.machine import machine

ROOT = Path(__file__).resolve().parents[2]


def _measure(code: Path, cores: int, env: dict, label: str) -> dict:
    with tempfile.TemporaryDirectory() as holder:
        tmp = Path(holder)
        _copy(code, tmp)
        env = dict(env, NUMBA_CACHE_DIR=str(tmp / "numba_cache"))
        subprocess.run([sys.executable, "-m", "capmap.kernels"], cwd=tmp, env=env, check=True, capture_output=True)
        _snakemake(tmp, "capacity_map", cores, env)
        wall = _snakemake(tmp, "baseline", cores, env)
        run = tmp / "results" / "default"
        shards = [w for w, name in _jobs(run) if "baseline_shard" in name]
        summary = pd.read_csv(run / "baseline" / "summary.csv")
        rows = dict(zip(summary.iloc[:, 0], summary.iloc[:, 1]))
        short = next(v for k, v in rows.items() if k.startswith("angle check: largest shortfall"))
        over = next(v for k, v in rows.items() if k.startswith("angle check: voxels more than 1 %"))
    out = {"wall": wall, "core_s": sum(shards), "short": float(short), "over": int(over)}
    print(f"{label}: snakemake baseline {wall:.1f} s wall, shards {out['core_s']:.0f} core-s ({len(shards)} jobs); "
          f"angle check: largest shortfall {out['short']:.2f} %, {out['over']} of 200 voxels more than 1 % below "
          "a 1 deg sweep", flush=True)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reference", default="99543d1", help="the commit measured beside this checkout")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--skip-reference", action="store_true")
    args = ap.parse_args()
    print(f"machine: {machine()}")
    this = _measure(ROOT, args.cores, dict(os.environ), "this checkout")
    if args.skip_reference:
        return
    with reference_worktree(args.reference, dict(os.environ)) as (wt, env):
        ref = _measure(wt, args.cores, env, f"reference {args.reference}")
    print(f"snakemake baseline: {this['wall']:.1f} s (target <= 120 s); {ref['wall'] / this['wall']:.2f}x faster than "
          f"the reference's {ref['wall']:.1f} s; shards {ref['core_s'] / this['core_s']:.2f}x fewer core-s")


if __name__ == "__main__":
    main()
