"""Wall time of Snakemake on the default config, this checkout against a reference commit measured in
the same run: the kernels' compile from cold, ``all`` from clean, then the what-if a user repeats for every
failure studied, ``capacity_map`` after a lock-angle change (``lock.angle_deg: 95``, ``tasks: []``).

    python -m tests.benchmarks.bench_pipeline [--reference 38cfebe] [--cores 2] [--skip-reference]

Each run is in its own temporary copy of the workflow (results/ of the checkout untouched); the
reference's code is a ``git worktree`` of the commit, put first on PYTHONPATH for its jobs. Prints the
machine, each wall time, the ratio (reference / this) and the longest jobs of this checkout's runs
(from their logs: every job logs its wall time). Targets on 2 cores: the compile <= 30 s, ``all`` from
clean <= 60 s, the what-if <= 20 s. The numba cache starts cold (NUMBA_CACHE_DIR in the copy): this
checkout compiles its kernels first, as the README's install command does (timed apart), the reference
too if it has ``capmap.kernels``, else in its jobs.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import yaml

from tests.benchmarks.machine import machine

ROOT = Path(__file__).resolve().parents[2]


@contextmanager
def reference_worktree(commit: str, env: dict):
    """A ``git worktree`` of ``commit`` and the environment running its code (its src first on PYTHONPATH),
    removed afterwards: (folder, env)."""
    wt = Path(tempfile.mkdtemp()) / "reference"
    subprocess.run(["git", "worktree", "add", "--detach", str(wt), commit], cwd=ROOT, check=True, capture_output=True)
    try:
        yield wt, dict(env, PYTHONPATH=f"{wt / 'src'}{os.pathsep}{env.get('PYTHONPATH', '')}")
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(wt)], cwd=ROOT, check=False, capture_output=True)


def _copy(code: Path, tmp: Path) -> None:
    for item in ("Snakefile", "workflow", "config", "profiles"):
        src = code / item
        if src.exists():
            (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp / item)


def _snakemake(tmp: Path, target: str, cores: int, env: dict, extra: list[str] = ()) -> float:
    t = time.perf_counter()
    res = subprocess.run(["snakemake", target, "--cores", str(cores), *extra], cwd=tmp, env=env, capture_output=True,
                         text=True, check=False)
    wall = time.perf_counter() - t
    if res.returncode != 0:
        raise SystemExit(f"snakemake {target} in {tmp} failed:\n{res.stderr[-3000:]}")
    return wall


def _jobs(run: Path) -> list[tuple[float, str]]:
    """(wall s, job) of every job, from the 'job stage_x: 1.2 s wall' lines of the run's logs."""
    out = []
    for log in (run / "logs").rglob("*.log"):
        for m in re.finditer(r"job (stage_\w+): ([0-9.]+) s wall", log.read_text()):
            out.append((float(m.group(2)), f"{m.group(1)} ({log.relative_to(run / 'logs')})"))
    return sorted(out, reverse=True)


def _measure(code: Path, cores: int, env: dict, label: str, keep: Path | None = None) -> dict:
    """``all`` from clean, then ``capacity_map`` after the lock-angle change, in a copy of ``code``'s workflow."""
    holder = tempfile.TemporaryDirectory()
    tmp = Path(holder.name)
    _copy(code, tmp)
    env = dict(env, NUMBA_CACHE_DIR=str(tmp / "numba_cache"))  # compiled from cold, like a fresh clone
    out = {"compile": 0.0}
    if (code / "src" / "capmap" / "kernels.py").is_file():  # the install command's compile step (then none in the jobs)
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "capmap.kernels"], cwd=tmp, env=env, check=True, capture_output=True)
        out["compile"] = time.perf_counter() - t
    out["all"] = _snakemake(tmp, "all", cores, env)
    jobs_all = _jobs(tmp / "results" / "default")
    if keep is not None:  # the run from clean, kept for reading (before the what-if changes it)
        shutil.copytree(tmp / "results" / "default", keep, dirs_exist_ok=True)
    cfg = yaml.safe_load((tmp / "config" / "config.yaml").read_text())
    cfg["lock"]["angle_deg"] = 95
    cfg["tasks"] = []
    (tmp / "config" / "config.yaml").write_text(yaml.safe_dump(cfg, sort_keys=False))
    before = {p: p.stat().st_mtime for p in (tmp / "results" / "default" / "logs").rglob("*.log")}
    out["what_if"] = _snakemake(tmp, "capacity_map", cores, env)
    logs = tmp / "results" / "default" / "logs"
    rerun = [p for p in logs.rglob("*.log") if before.get(p) != p.stat().st_mtime]
    out["what_if_jobs"] = len(rerun)
    out["jobs_all"] = jobs_all
    print(f"{label}: kernels compiled at install {out['compile']:.1f} s; all from clean {out['all']:.1f} s "
          f"({len(jobs_all)} jobs, {sum(j[0] for j in jobs_all):.1f} s of job compute); capacity_map after lock.angle_deg 95 "
          f"{out['what_if']:.1f} s ({len(rerun)} jobs)", flush=True)
    holder.cleanup()
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--reference", default="38cfebe", help="the commit measured beside this checkout")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--skip-reference", action="store_true")
    ap.add_argument("--keep", type=Path, default=None, help="copy this checkout's run from clean to this folder")
    args = ap.parse_args()
    print(f"machine: {machine()}")
    env = dict(os.environ)
    this = _measure(ROOT, args.cores, env, "this checkout", args.keep)
    ref = None
    if not args.skip_reference:
        with reference_worktree(args.reference, env) as (wt, ref_env):
            ref = _measure(wt, args.cores, ref_env, f"reference {args.reference}")
    for key, target, label in (("compile", 30, "the kernels compiled from cold"), ("all", 60, "snakemake all from clean"),
                               ("what_if", 20, "capacity_map after a lock-angle change")):
        ratio = f"; {ref[key] / this[key]:.2f}x the reference's {ref[key]:.1f} s" if ref and ref[key] else ""
        print(f"{label}: {this[key]:.1f} s (target <= {target} s){ratio}")
    print("longest jobs of this checkout's run from clean:")
    for w, name in this["jobs_all"][:8]:
        print(f"  {w:6.1f} s  {name}")


if __name__ == "__main__":
    main()
