"""Results are never silently stale: the code a rule runs and the content of the files it reads
are part of its params (capmap.io.fingerprint), a damaged intermediate is one line naming it and
how to rebuild it, and `python -m capmap check` finds what changed behind the catalogue's back."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess

import pandas as pd
import pytest

from capmap.errors import DataError
from capmap.stages.capacity import stage_voxels
from tests.scenario import ROOT
from tests.workflow.runs import planned_jobs, planned_jobs_of

pytestmark = pytest.mark.slow  # a whole tiny pipeline: .ci/run runs these (-m slow)


def _copy_workflow(dst):
    """Snakefile, workflow/, profiles/ and the package source: a second checkout to edit."""
    shutil.copy(ROOT / "Snakefile", dst / "Snakefile")
    for d in ("workflow", "profiles", "src"):
        shutil.copytree(ROOT / d, dst / d, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))


def _dry(workdir, snakefile, config, env):
    return set(planned_jobs_of(workdir, config, "all", snakefile, env))


def test_code_changes_rerun_their_stages_and_comments_do_not(run_dir, tmp_path):
    work, cfg = run_dir
    _copy_workflow(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "src")}  # the copy's package
    snakefile = tmp_path / "Snakefile"
    assert _dry(work, snakefile, cfg, env) == set()
    # a comment (and a docstring) in a shim script and in a numerics module: nothing
    shim = tmp_path / "workflow" / "scripts" / "capacity.py"
    shim.write_text("# the capacity shard (reworded comment)\n" + shim.read_text())
    engine = tmp_path / "src" / "capmap" / "capacity" / "engine.py"
    engine.write_text(engine.read_text().replace('"""', '"""Reworded. ', 1) + "\n# a trailing comment\n")
    assert _dry(work, snakefile, cfg, env) == set()
    # a change of the capacity numerics: its stages and everything downstream; not the other families
    engine.write_text(engine.read_text() + "\nEXTRA_MARGIN = 1.0\n")
    jobs = _dry(work, snakefile, cfg, env)
    assert {"capacity", "voxels", "summary", "plan", "verify"} <= jobs
    assert not {"reconfig", "dualarm_scan", "dualarm_envelope", "dualarm_capsules", "dualarm_optimise"} & jobs
    # a change of the dual-arm numerics: the dual-arm rules that run it, nothing of the capacity map
    dist = tmp_path / "src" / "capmap" / "dualarm" / "geometry" / "distance.py"
    engine.write_text(engine.read_text().replace("\nEXTRA_MARGIN = 1.0\n", ""))
    dist.write_text(dist.read_text() + "\nEXTRA = 0\n")
    jobs = _dry(work, snakefile, cfg, env)
    assert "dualarm_optimise" in jobs and not {"model", "sample", "capacity", "voxels", "reconfig"} & jobs


def test_an_edited_robot_file_with_its_old_date_reruns(run_dir):
    work, cfg = run_dir
    robot = ROOT / "config" / "robots" / "ssrms7.yaml"
    text, st = robot.read_text(), robot.stat()
    try:
        robot.write_text(text.replace("mass_kg: 70.0", "mass_kg: 71.0", 1))
        os.utime(robot, ns=(st.st_atime_ns, st.st_mtime_ns))  # as cp -p, rsync -a or tar x leave it
        jobs = planned_jobs(work, cfg)
        assert {"model", "sample", "capacity", "voxels", "verify"} <= set(jobs)
    finally:
        robot.write_text(text)
        os.utime(robot, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert planned_jobs(work, cfg) == {}


def test_a_damaged_shard_is_one_line_and_check_finds_it(run_dir, tmp_path):
    work, _ = run_dir
    copy = tmp_path / "run"
    shutil.copytree(work / "results", copy / "results")
    shard = copy / "results" / "tiny" / "capacity" / "points.parquet"
    shard.write_bytes(shard.read_bytes()[: shard.stat().st_size // 2])  # truncated
    with pytest.raises(DataError) as err:
        stage_voxels(str(shard), str(tmp_path / "v.parquet"),
                     json.dumps(pd.read_parquet(work / "results/tiny/voxels/voxels.parquet").attrs["capmap"]["config"]))
    msg = str(err.value)
    assert "\n" not in msg and str(shard) in msg and "snakemake --cores 2 all --forcerun" in msg
    (copy / "results" / "tiny" / "voxels" / "configurations.parquet").unlink()  # and one deleted
    res = subprocess.run(["python", "-m", "capmap", "check", str(copy / "results" / "tiny")], capture_output=True, text=True)
    lines = res.stderr.splitlines()
    assert res.returncode == 1 and len(lines) == 2, res.stderr
    assert any("capacity/points.parquet" in ln and "not a readable Parquet" in ln for ln in lines)
    assert any("voxels/configurations.parquet: missing" in ln for ln in lines)
    ok = subprocess.run(["python", "-m", "capmap", "check", str(work / "results" / "tiny")], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    (copy / "results" / "bare").mkdir()  # a run folder without a catalogue, and one that does not exist
    res = subprocess.run(["python", "-m", "capmap", "check", str(copy / "results" / "bare"), str(copy / "results" / "nope"),
                          str(work / "results" / "tiny")], capture_output=True, text=True)
    lines = res.stderr.splitlines()
    assert res.returncode == 1 and len(lines) == 2, res.stderr
    assert "nope: no such run folder" in lines[0] and "bare: no catalogue.parquet" in lines[1]


def test_a_deleted_intermediate_is_named_with_the_command_that_rebuilds_it(run_dir, tmp_path):
    work, cfg = run_dir
    copy = tmp_path / "run"
    shutil.copytree(work, copy, ignore=shutil.ignore_patterns("locks", "incomplete"))
    assert planned_jobs(copy, cfg) == {}
    (copy / "results" / "tiny" / "capacity" / "points.parquet").unlink()
    res = subprocess.run(["snakemake", "all", "-n", "-s", str(ROOT / "Snakefile"), "-d", str(copy), "--configfile",
                          str(cfg)], capture_output=True, text=True, timeout=600)
    warn = [ln for ln in res.stderr.splitlines() if "capacity/points.parquet is in the catalogue but missing" in ln]
    assert res.returncode == 0 and len(warn) >= 1
    # the printed command carries the run's config: run as printed, it rebuilds the table
    assert f"snakemake --cores 2 all --configfile {cfg} --forcerun results/tiny/capacity/points.parquet" in warn[0]
    res = subprocess.run(["snakemake", "all", "-n", "-s", str(ROOT / "Snakefile"), "-d", str(copy), "--configfile",
                          str(cfg), "--forcerun", "results/tiny/capacity/points.parquet"],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0 and re.search(r"(?m)^points\s+1$", res.stdout + res.stderr), res.stdout[-2000:]
