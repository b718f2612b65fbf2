"""What a user sees after the main command: the report builds for the run, opens with the workflow's
description, holds every table as a captioned page and the 3D map; outputs an earlier config left in
the run's folder are named and kept out of the catalogue and the report."""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import pandas as pd

from tests.scenario import ROOT


def _snakemake(work, cfg, *args):
    return subprocess.run(["snakemake", *args, "-s", str(ROOT / "Snakefile"), "-d", str(work), "--cores", "1",
                           "--configfile", str(cfg)], capture_output=True, text=True, timeout=600)


def test_the_report_builds_for_the_run_with_description_tables_and_3d_map(run_dir, tmp_path):
    work, cfg = run_dir
    res = _snakemake(work, cfg, "--report", str(tmp_path / "report.html"))
    assert res.returncode == 0, res.stderr[-2000:]
    page = (tmp_path / "report.html").read_text()
    assert "What this workflow does" in page and "capmap run" in page
    for name in ("catalogue", "capacity_summary", "verify_summary", "gain", "follow_summary", "reconfig_summary",
                 "dualarm_summary", "csqp_check"):
        assert f"results/tiny/report/{name}.html" in page, name
    assert "results/tiny/summary/capacity_3d.html" in page
    assert "results/default" not in page  # nothing of another run


def test_the_3d_map_holds_the_run_s_reachable_voxels(run_dir):
    work, _ = run_dir
    page = (work / "results/tiny/summary/capacity_3d.html").read_text()
    vox = pd.read_parquet(work / "results/tiny/voxels/voxels.parquet")
    reach = vox[vox.n_reachable > 0]
    data = json.loads(re.search(r"const V = (\{.*?\});\n", page).group(1))
    assert len(data["c"]) == len(reach) and abs(sum(data["c"]) - reach.capacity_kg.sum()) < 0.01 * len(reach)
    assert not re.search(r"<script[^>]+src=", page)
    wp = pd.read_parquet(work / "results/tiny/plan/payload_1500kg/waypoints.parquet")
    assert (f"planned path, 1500 kg ({wp.attrs['capmap']['cost_m']:.2f} m)" in page) == (wp.attrs["capmap"]["status"] == "ok")


def test_outputs_of_a_removed_payload_are_named_and_not_presented(run_dir, tmp_path):
    work, cfg = run_dir
    copy = tmp_path / "run"
    shutil.copytree(work, copy, ignore=shutil.ignore_patterns("locks", "incomplete"))
    res = _snakemake(copy, cfg, "all", "-n")
    assert res.returncode == 0 and "not of this config" not in res.stderr, res.stderr[-2000:]
    old = copy / "results/tiny/verify/payload_999kg"
    old.mkdir()
    (old / "workspace.png").write_bytes(b"an earlier config's figure")
    res = _snakemake(copy, cfg, "all", "-n")
    assert res.returncode == 0, res.stderr[-2000:]
    note = [ln for ln in res.stderr.splitlines() if "not of this config" in ln]
    assert len(note) == 1 and "results/tiny/verify/payload_999kg" in note[0]
    assert "report_tables" in res.stdout  # its page lists them: rebuilt with the new list
    res = _snakemake(copy, cfg, "all")
    assert res.returncode == 0, res.stderr[-2000:]
    assert "payload_999kg" in (copy / "results/tiny/report/catalogue.html").read_text()
    assert not pd.read_parquet(copy / "results/tiny/catalogue.parquet").path.str.contains("999").any()
    res = _snakemake(copy, cfg, "--report", str(tmp_path / "report.html"))
    assert res.returncode == 0 and "payload_999kg/workspace.png" not in (tmp_path / "report.html").read_text()
    assert old.is_dir()  # kept: never deleted behind the user's back
