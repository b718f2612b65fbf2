"""Wall time of Snakemake from clean on a config (default: config/config.yaml): the capacity map
alone (target ``capacity_map``) and the whole workflow (``all``), each in its own temporary copy
of the workflow so that results/ of the checkout is untouched.

    python -m tests.benchmarks.bench_pipeline [--config config/config.yaml] [--cores 2]

Prints the wall times, the capacity engine's point count and motion states, and the longest
jobs (from their logs: every job logs its wall time). Targets: the capacity map from clean in
under 30 s on 2 cores (issue 14); the whole default run is reported with what dominates it.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import pandas as pd

from capmap.config.run import run_name
from capmap.config.validation import load_yaml
from tests.benchmarks.machine import machine

ROOT = Path(__file__).resolve().parents[2]


def _run(target: str, config: Path, cores: int) -> tuple[float, Path, tempfile.TemporaryDirectory]:
    holder = tempfile.TemporaryDirectory()
    tmp = Path(holder.name)
    for item in ("Snakefile", "workflow", "config", "profiles"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp / item)
    t = time.perf_counter()
    res = subprocess.run(["snakemake", target, "--cores", str(cores), "--configfile", str(config)], check=False, cwd=tmp,
                         capture_output=True, text=True)
    wall = time.perf_counter() - t
    if res.returncode != 0:
        raise SystemExit(res.stderr[-3000:])
    return wall, tmp, holder


def _jobs(run: Path) -> list[tuple[float, str]]:
    """(wall s, job) of every job, from the 'job stage_x: 1.2 s wall' lines of the run's logs."""
    out = []
    for log in (run / "logs").rglob("*.log"):
        for m in re.finditer(r"job (stage_\w+): ([0-9.]+) s wall", log.read_text()):
            out.append((float(m.group(2)), f"{m.group(1)} ({log.relative_to(run / 'logs')})"))
    return sorted(out, reverse=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--cores", type=int, default=2)
    args = ap.parse_args()
    print(f"machine: {machine()}")
    cfg = (ROOT / args.config).resolve()
    name = run_name(load_yaml(cfg), str(cfg))  # the run's folder, results/<run>/
    wall, tmp, holder = _run("capacity_map", cfg, args.cores)
    pts = pd.read_parquet(tmp / "results" / name / "voxels/points.parquet")
    vox = pd.read_parquet(tmp / "results" / name / "voxels/voxels.parquet")
    dirs = pts.attrs["capmap"]["config"]["run"]["directions"]
    jobs = _jobs(tmp / "results" / name)
    holder.cleanup()
    print(f"snakemake --cores {args.cores} capacity_map from clean: {wall:.1f} s wall (target < 30 s), "
          f"{len(jobs)} jobs, {sum(j[0] for j in jobs):.1f} s of job compute")
    print(f"  points {len(pts):,} ({int(pts.reachable.sum()):,} reachable at the task orientation), "
          f"motion states {int(pts.n_states.sum()):,}, directions {dirs}")
    print(f"  voxels {len(vox):,} ({int((vox.n_reachable > 0).sum()):,} reachable, "
          f"{int((vox.n_points == 0).sum())} without samples)")
    print(f"  throughput {int(pts.n_states.sum()) / wall:,.0f} states/s end to end")
    wall, tmp, holder = _run("all", cfg, args.cores)
    jobs = _jobs(tmp / "results" / name)
    holder.cleanup()
    print(f"snakemake --cores {args.cores} all from clean: {wall:.1f} s wall, {len(jobs)} jobs, "
          f"{sum(j[0] for j in jobs):.1f} s of job compute; longest jobs:")
    for w, name in jobs[:6]:
        print(f"  {w:6.1f} s  {name}")


if __name__ == "__main__":
    main()
