"""Wall time of `snakemake --cores 2 all` from clean on a config (default: config/config.yaml).

    python tests/benchmarks/bench_pipeline.py [--config config/config.yaml] [--cores 2]

Runs in a temporary copy of the workflow so results/ of the checkout is untouched, then
prints the wall time, point count and motion states. Target (issue 3): the whole-workspace
default with >= 50,000 points and a 10 deg direction grid in under 5 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[2]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--cores", type=int, default=2)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for item in ("Snakefile", "workflow", "config"):
            src = ROOT / item
            (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp / item)
        cfg = (ROOT / args.config).resolve()
        t = time.perf_counter()
        res = subprocess.run(["snakemake", "all", "--cores", str(args.cores), "--configfile", str(cfg)], cwd=tmp,
                             capture_output=True, text=True)
        wall = time.perf_counter() - t
        if res.returncode != 0:
            raise SystemExit(res.stderr[-3000:])
        pts = pd.read_parquet(tmp / "results/voxels/points.parquet")
        vox = pd.read_parquet(tmp / "results/voxels/voxels.parquet")
        dirs = pts.attrs["capmap"]["config"]["capacity"]["directions"]
        print(f"snakemake --cores {args.cores} all from clean: {wall:.1f} s wall")
        print(f"  points {len(pts):,} ({int(pts.reachable.sum()):,} reachable at the task orientation), "
              f"motion states {int(pts.n_states.sum()):,}, directions {dirs}")
        print(f"  voxels {len(vox):,} ({int((vox.n_reachable > 0).sum()):,} reachable, "
              f"{int((vox.n_points == 0).sum())} without samples)")
        print(f"  throughput {int(pts.n_states.sum()) / wall:,.0f} states/s end to end")


if __name__ == "__main__":
    main()
