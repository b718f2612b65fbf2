"""Helpers of the workflow tests: a tiny config with changes, Snakemake runs and dry runs."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import yaml

from tests.scenario import ROOT

TINY = ROOT / "tests" / "data" / "tiny.yaml"


def config_file(tmp: Path, **changes) -> Path:
    doc = yaml.safe_load(TINY.read_text())
    doc["robot"] = str(ROOT / "config" / "robots" / "ssrms7.yaml")
    doc["follow"]["ground"]["robot"] = str(ROOT / "config" / "robots" / "ur5.yaml")
    doc["reconfig"]["robot"] = str(ROOT / "config" / "robots" / "reconfig3.yaml")
    doc["dualarm"]["robot"] = str(ROOT / "config" / "robots" / "baxter_dual.yaml")
    doc["dualarm"]["scene"] = str(ROOT / "config" / "scenes" / "satellite_panel.yaml")
    for dotted, value in changes.items():
        node = doc
        *head, last = dotted.split(".")
        for h in head:
            node = node.setdefault(h, {})
        if value is None:
            node.pop(last)
        else:
            node[last] = value
    path = tmp / f"config_{abs(hash(repr(sorted(changes.items()))))}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def snakemake(workdir: Path, config: Path, *args: str, cores: int = 2, timeout: float = 600,
              snakefile: Path = ROOT / "Snakefile", env: dict | None = None) -> subprocess.CompletedProcess:
    """``snakemake *args`` of ``snakefile`` (this checkout's workflow) in ``workdir`` with ``config``."""
    cmd = ["snakemake", *args, "-s", str(snakefile), "-d", str(workdir), "--cores", str(cores),
           "--configfile", str(config)]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)


def snakemake_run(workdir: Path, config: Path, *extra: str) -> subprocess.CompletedProcess:
    return snakemake(workdir, config, "all", *extra)


def job_counts(out: str) -> dict[str, int]:
    """Rules and job counts of a dry run's output (empty when nothing is to be done)."""
    m = re.search(r"job\s+count\n-+\s+-+\n(.*?)\ntotal", out, re.S)
    if not m:
        assert "Nothing to be done" in out, out[-2000:]
        return {}
    return {line.split()[0]: int(line.split()[1]) for line in m.group(1).strip().splitlines()}


def planned_jobs(workdir: Path, config: Path) -> dict[str, int]:
    """Rules a dry run of ``all`` would execute, with counts (empty when nothing is to be done)."""
    return planned_jobs_of(workdir, config, "all")


def planned_jobs_of(workdir: Path, config: Path, target: str, snakefile: Path = ROOT / "Snakefile",
                    env: dict | None = None) -> dict[str, int]:
    """Rules a dry run of ``target`` would execute (of ``snakefile``, in the environment ``env``)."""
    res = snakemake(workdir, config, target, "-n", snakefile=snakefile, env=env)
    assert res.returncode == 0, res.stderr[-2000:]
    return job_counts(res.stdout + res.stderr)
