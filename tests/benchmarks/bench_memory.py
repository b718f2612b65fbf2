"""Peak memory per job: the pre-run estimate (``capmap.capacity.sizing.estimate_map``) against what the
jobs measured, per stage, for the default config's capacity map at several voxel edges.

    python -m tests.benchmarks.bench_memory [--edges 0.75 0.375 0.25] [--cores 2]

Each edge is its own run (``run: mem<edge>``, results under results/), ``snakemake capacity_map`` on the
default config with ``voxels.edge_m`` changed. Every job logs its peak resident set (``capmap.io.logs.call``:
``job stage_<name>: ... peak memory N MB``); the largest per stage is printed beside the estimate of that
stage's jobs and their ratio (target: the estimate within 1.5x of the measured peak, and never below it by
more than that), with the machine."""

from __future__ import annotations

import argparse
import re
import subprocess
import time
from pathlib import Path

import yaml

from capmap.checks import check_run_config
from capmap.config.run import run_document
from tests.benchmarks.machine import machine

ROOT = Path(__file__).resolve().parents[2]
STAGE_OF_JOB = {"stage_capacity": "capacity", "stage_voxels": "voxels", "stage_refine": "refine",
                "stage_plan": "plan", "stage_verify": "verify",
                **{s: "maps" for s in ("stage_voxel_map", "stage_summary", "stage_capacity_3d", "stage_verify_plots")}}


def measured_peaks(run_dir: Path) -> dict[str, float]:
    """The largest logged peak (MB) per job kind of a run's logs."""
    peaks: dict[str, float] = {}
    for log in run_dir.glob("logs/**/*.log"):
        for m in re.finditer(r"job (stage_\w+): [\d.]+ s wall, peak memory (\d+) MB", log.read_text()):
            peaks[m.group(1)] = max(peaks.get(m.group(1), 0.0), float(m.group(2)))
    return peaks


def refine_cost(run_dir: Path) -> tuple[int, float]:
    """Points the refine jobs evaluated and their wall seconds (each job on one core), from the logs."""
    points, seconds = 0, 0.0
    for log in run_dir.glob("logs/refine/*.log"):
        text = log.read_text()
        points += sum(int(m) for m in re.findall(r"done: \d+ voxels.*?, (\d+) points evaluated", text))
        seconds += sum(float(m) for m in re.findall(r"job stage_refine: ([\d.]+) s wall", text))
    return points, seconds


def run_edge(edge: float, cores: int) -> tuple[dict, dict, float]:
    doc = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    name = f"mem{str(edge).replace('.', 'p')}"
    doc["run"], doc["voxels"]["edge_m"] = name, edge
    cfg = ROOT / "results" / f"{name}.yaml"
    cfg.parent.mkdir(exist_ok=True)
    cfg.write_text(yaml.safe_dump(doc))
    estimate = check_run_config(run_document([str(cfg)]), str(cfg)).estimate
    t0 = time.perf_counter()
    res = subprocess.run(["snakemake", "--cores", str(cores), "capacity_map", "--config", f"configfile={cfg}"],
                         cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        raise SystemExit(f"edge {edge}: snakemake failed:\n{res.stderr[-3000:]}")
    return estimate.jobs_mb, measured_peaks(ROOT / "results" / name), wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--edges", type=float, nargs="+", default=[0.75, 0.375, 0.25])
    ap.add_argument("--cores", type=int, default=2)
    args = ap.parse_args()
    print(f"machine: {machine()}")
    worst = 0.0
    for edge in args.edges:
        est, got, wall = run_edge(edge, args.cores)
        print(f"\nvoxels.edge_m = {edge} m: capacity_map in {wall:.0f} s on {args.cores} cores")
        print(f"  {'job':<22} {'estimate MB':>12} {'measured MB':>12} {'ratio':>7}")
        for job, kind in STAGE_OF_JOB.items():
            if kind in est and job in got:
                ratio = est[kind] / got[job]
                worst = max(worst, ratio, 1 / ratio) if kind != "maps" else worst  # "maps": their largest, below
                print(f"  {job:<22} {est[kind]:>12.0f} {got[job]:>12.0f} {ratio:>7.2f}")
        maps = max(got.get(j, 0.0) for j, k in STAGE_OF_JOB.items() if k == "maps")
        worst = max(worst, est["maps"] / maps, maps / est["maps"])
        points, seconds = refine_cost(ROOT / "results" / f"mem{str(edge).replace('.', 'p')}")
        print(f"  refinement: {points:,} points in {seconds:.0f} job-s: {1e6 * seconds / max(points, 1):.0f} µs per point")
        top = max(got.values())
        print(f"  largest job measured {top:.0f} MB ({max(got, key=got.get)}); estimate of the largest "
              f"{max(est.values()):.0f} MB (ratio {max(est.values()) / top:.2f})")
    print(f"\nworst ratio either way (each kind's estimate against its largest job): {worst:.2f} (target <= 1.5)")


if __name__ == "__main__":
    main()
