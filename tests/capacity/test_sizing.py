"""The pre-run memory estimate: per kind of job, bounded where the job is (a refine job by its batch), and a run
whose jobs side by side cannot fit this machine refused with one line naming what fixes it. The estimate's
constants are measured (tests/benchmarks/bench_memory.py prints estimate against measured per job)."""

from __future__ import annotations

import subprocess

import pytest

import capmap.capacity.sizing as sizing
from capmap.capacity.refine_data import BATCH_VOXELS
from capmap.config.capacity import SamplingConfig
from capmap.config.estimate import BASE_MB, MAP_VOXEL_KB, REFINE_VOXEL_MB, Estimate, MapJobs
from capmap.errors import ConfigError
from tests.scenario import ROOT
from tests.workflow.runs import config_file


def _estimate(jobs: dict) -> Estimate:
    return Estimate(grid_shape=(1, 1, 1), voxels=1, points=1, states=1.0, jobs_mb=jobs)


KEYS = {"n_points": "sampling.n_points", "edge_m": "voxels.edge_m", "jitter": "sampling.jitter_per_voxel",
        "directions": "directions.n"}


def test_a_refine_job_is_bounded_by_its_batch_not_its_shard(scenario_arm):
    """The grid's voxels per shard up to a batch, then the batch: a finer map (8x the voxels) adds to the jobs
    that read the whole map, not to a refine job past its batch."""
    sampling = SamplingConfig("voxel_fill", 20_000, 20261123)
    coarse, _ = sizing.estimate_map(scenario_arm, sampling, 0.75, 12, 13, MapJobs(4, True), KEYS)
    fine, _ = sizing.estimate_map(scenario_arm, sampling, 0.375, 12, 13, MapJobs(4, True), KEYS)
    assert fine.voxels > 4 * BATCH_VOXELS * 4 > coarse.voxels  # the fine map's shards hold several batches
    assert fine.jobs_mb["refine"] == pytest.approx(BASE_MB + REFINE_VOXEL_MB * BATCH_VOXELS)
    assert coarse.jobs_mb["refine"] == pytest.approx(BASE_MB + REFINE_VOXEL_MB * min(coarse.voxels / 4, BATCH_VOXELS))
    assert fine.jobs_mb["maps"] - BASE_MB == pytest.approx((coarse.jobs_mb["maps"] - BASE_MB) * fine.voxels / coarse.voxels)
    assert fine.jobs_mb["maps"] == pytest.approx(BASE_MB + MAP_VOXEL_KB * fine.voxels / 1024)
    without, _ = sizing.estimate_map(scenario_arm, sampling, 0.75, 12, 13, MapJobs(4, False), KEYS)
    assert "refine" not in without.jobs_mb


def test_jobs_side_by_side_beyond_the_machine_are_refused(monkeypatch):
    monkeypatch.setattr(sizing, "available_memory_mb", lambda: 10_000.0)
    est = _estimate({"refine": 1_000.0, "maps": 600.0})
    sizing.check_parallel_memory(est, cores=8, shards=4)  # 4 jobs x 1 GB: fits 80 % of 10 GB
    with pytest.raises(ConfigError) as info:
        sizing.check_parallel_memory(est, cores=16, shards=16)  # 16 GB
    msg = str(info.value)
    assert msg.startswith("--cores 16: 16 jobs") and "--cores 8)" in msg and "voxels.edge_m" in msg


def test_the_workflow_refuses_them_before_any_job(tmp_path):
    cfg = config_file(tmp_path, shards=256)
    res = subprocess.run(["snakemake", "-n", "all", "-s", str(ROOT / "Snakefile"), "-d", str(tmp_path), "--cores", "256",
                          "--config", f"configfile={cfg}"], capture_output=True, text=True, timeout=300, cwd=ROOT)
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("capmap:")]
    assert res.returncode == 1 and any(ln.startswith("capmap: --cores 256:") for ln in lines), res.stderr[-1500:]
