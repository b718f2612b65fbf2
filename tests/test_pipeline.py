"""The Snakemake pipeline on the tiny config: outputs, provenance, catalogue, exact caching."""

from __future__ import annotations

import hashlib
import re
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from conftest import ROOT

TINY = ROOT / "tests" / "data" / "tiny.yaml"


def _config(tmp: Path, **changes) -> Path:
    doc = yaml.safe_load(TINY.read_text())
    doc["robot"] = str(ROOT / "config" / "robots" / "ssrms7.yaml")
    for dotted, value in changes.items():
        node = doc
        *head, last = dotted.split(".")
        for h in head:
            node = node[h]
        node[last] = value
    path = tmp / f"config_{abs(hash(repr(sorted(changes.items()))))}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def _snakemake(workdir: Path, config: Path, *extra: str) -> subprocess.CompletedProcess:
    cmd = ["snakemake", "all", "-s", str(ROOT / "Snakefile"), "-d", str(workdir), "--cores", "2", *extra,
           "--configfile", str(config)]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600)


def _planned_jobs(workdir: Path, config: Path) -> dict[str, int]:
    """Rules a dry run would execute, with counts (empty when nothing is to be done)."""
    res = _snakemake(workdir, config, "-n")
    assert res.returncode == 0, res.stderr[-2000:]
    out = res.stdout + res.stderr
    m = re.search(r"job\s+count\n-+\s+-+\n(.*?)\ntotal", out, re.S)
    if not m:
        assert "Nothing to be done" in out, out[-2000:]
        return {}
    return {line.split()[0]: int(line.split()[1]) for line in m.group(1).strip().splitlines()}


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pipeline")
    cfg = _config(tmp)
    res = _snakemake(tmp, cfg)
    assert res.returncode == 0, res.stderr[-3000:]
    return tmp, cfg


def test_outputs_and_provenance(run_dir):
    tmp, _ = run_dir
    pts = pd.read_parquet(tmp / "results/voxels/points.parquet")
    vox = pd.read_parquet(tmp / "results/voxels/voxels.parquet")
    for col in ("point_id", "x_m", "y_m", "z_m", "reachable", "n_branches", "capacity_kg", "binding",
                "worst_alpha_deg", "worst_beta_deg", "worst_branch"):
        assert col in pts.columns
    for col in ("i", "j", "k", "x_m", "y_m", "z_m", "n_points", "capacity_kg"):
        assert col in vox.columns
    meta = pts.attrs["capmap"]
    assert meta["stage"] == "voxels" and meta["seed"] == 7 and meta["capmap_version"]
    assert meta["config"]["capacity"]["limits"]["joint_torque_nm"] == 700
    # points: each id exactly once across shards
    assert pts.point_id.is_unique and len(pts) == pd.read_parquet(tmp / "results/sample/points.parquet").shape[0]
    # reachable <=> at least one branch <=> finite capacity
    assert np.array_equal(pts.reachable, pts.n_branches > 0)
    assert np.array_equal(pts.reachable, np.isfinite(pts.capacity_kg))
    assert pts.reachable.sum() > 20


def test_voxel_capacity_is_min_of_points_inside(run_dir):
    tmp, _ = run_dir
    pts = pd.read_parquet(tmp / "results/voxels/points.parquet")
    vox = pd.read_parquet(tmp / "results/voxels/voxels.parquet")
    grid = vox.attrs["capmap"]["grid"]
    edge, lower = grid["edge_m"], np.array(grid["lower_m"])
    # independent binning
    idx = np.floor((pts[["x_m", "y_m", "z_m"]].to_numpy() - lower) / edge).astype(int)
    pts = pts.assign(ii=idx[:, 0], jj=idx[:, 1], kk=idx[:, 2])
    expect = pts[pts.reachable].groupby(["ii", "jj", "kk"]).capacity_kg.min()
    got = vox[vox.n_reachable > 0].set_index(["i", "j", "k"]).capacity_kg
    got.index.names = expect.index.names
    pd.testing.assert_series_equal(got.sort_index(), expect.sort_index(), check_names=False)
    assert vox[vox.n_reachable == 0].capacity_kg.isna().all()
    # centres = lower + (index + 1/2) edge, lower corner on multiples of the edge
    assert np.allclose(vox.x_m, lower[0] + (vox.i + 0.5) * edge)
    assert np.allclose(lower / edge, np.round(lower / edge))
    # voxel_fill evaluated every voxel of the grid
    assert (vox.n_points > 0).all()


def test_catalogue_lists_every_dataset(run_dir):
    tmp, _ = run_dir
    cat = pd.read_parquet(tmp / "results/catalogue.parquet")
    assert set(cat.name) == {"joints", "points", "shard_0_of_2", "shard_1_of_2", "voxels"}  # two 'points'
    assert len(cat) == 6
    for _, row in cat.iterrows():
        data = (tmp / row.path).read_bytes()
        assert hashlib.sha256(data).hexdigest() == row.sha256
        assert row.rows == len(pd.read_parquet(tmp / row.path))
        assert row.config_hash
    cols = cat.set_index("path").loc["results/voxels/voxels.parquet", "columns"]
    assert "capacity_kg [kg]" in list(cols) and "x_m [m]" in list(cols)


def test_caching_reruns_exactly_the_affected_stages(run_dir, tmp_path):
    tmp, cfg = run_dir
    assert _planned_jobs(tmp, cfg) == {}
    downstream_of_capacity = {"capacity", "voxels", "summary", "catalogue", "all"}
    jobs = _planned_jobs(tmp, _config(tmp_path, **{"limits.joint_torque_nm": 650}))
    assert set(jobs) == downstream_of_capacity and jobs["capacity"] == 2
    jobs = _planned_jobs(tmp, _config(tmp_path, **{"limits.base_moment_nm": 450}))
    assert set(jobs) == downstream_of_capacity
    jobs = _planned_jobs(tmp, _config(tmp_path, **{"lock.angle_deg": 95, "task.q_ini_deg": [95, 124, 98, 130, 146, 174, 57]}))
    assert set(jobs) == {"sample"} | downstream_of_capacity
    jobs = _planned_jobs(tmp, _config(tmp_path, **{"lock.joint": 7, "lock.angle_deg": 57}))
    assert set(jobs) == {"sample"} | downstream_of_capacity
    jobs = _planned_jobs(tmp, _config(tmp_path, **{"task.payload_kg": 900}))
    assert not {"model", "sample", "capacity", "voxels"} & set(jobs)


def test_changing_shard_count_recomputes_consistently(run_dir, tmp_path):
    tmp, _ = run_dir
    cfg3 = _config(tmp_path, shards=3)
    jobs = _planned_jobs(tmp, cfg3)
    assert jobs.get("capacity") == 3 and "sample" not in jobs and "model" not in jobs
    before = pd.read_parquet(tmp / "results/voxels/voxels.parquet")
    work3 = tmp_path / "w3"
    work3.mkdir()
    res = _snakemake(work3, cfg3)
    assert res.returncode == 0, res.stderr[-2000:]
    after = pd.read_parquet(work3 / "results/voxels/voxels.parquet")
    pd.testing.assert_series_equal(before.capacity_kg, after.capacity_kg)


@pytest.mark.parametrize("changes, expect", [
    ({"limts": 3}, "unknown key limts"),
    ({"lock.joint": 9}, "lock.joint = 9 is out of range"),
    ({"limits.joint_torque_nm": -5}, "limits.joint_torque_nm"),
    ({"limits.joint_torque_nm": [700, 700]}, "limits.joint_torque_nm has 2 values"),
    ({"directions.n": 0}, "directions.n"),
    ({"task.q_ini_deg": [90, 124, 98, 130, 146, 174, 57]}, "must equal lock.angle_deg"),
])
def test_bad_config_is_one_line_before_any_job(tmp_path, changes, expect):
    res = _snakemake(tmp_path, _config(tmp_path, **changes), "-n")
    assert res.returncode != 0
    err = [line for line in (res.stdout + res.stderr).splitlines() if line.startswith("capmap:")]
    assert len(err) == 1 and expect in err[0], res.stdout + res.stderr
    assert "Traceback" not in res.stdout + res.stderr
    assert not (tmp_path / "results").exists()
