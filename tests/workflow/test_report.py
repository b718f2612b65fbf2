"""What a user sees after the main command: the report builds for the run, opens with the workflow's
description, holds every table as a captioned page and the 3D map; outputs an earlier config left in
the run's folder are named and kept out of the catalogue and the report."""

from __future__ import annotations

import json
import re
import shutil

import pandas as pd
import pytest

from tests.workflow.runs import snakemake

pytestmark = pytest.mark.slow  # a whole tiny pipeline: .ci/run runs these (-m slow)


def test_the_3d_map_holds_the_run_s_reachable_voxels(run_dir):
    work, _ = run_dir
    page = (work / "results/tiny/summary/capacity_3d.html").read_text()
    vox = pd.read_parquet(work / "results/tiny/voxels/voxels.parquet")
    reach = vox[vox.n_reachable > 0]
    maps = json.loads(re.search(r"const M = (\[.*?\]), L = ", page).group(1))
    data = maps[-1]  # the bound for any configuration (the only map without refinement)
    assert len(data["c"]) == len(reach) and abs(sum(data["c"]) - reach.capacity_kg.sum()) < 0.01 * len(reach)
    assert not re.search(r"<script[^>]+src=", page)
    wp = pd.read_parquet(work / "results/tiny/plan/payload_1500kg/waypoints.parquet")
    assert (f"planned path, 1500 kg ({wp.attrs['capmap']['cost_m']:.2f} m)" in page) == (wp.attrs["capmap"]["status"] == "ok")


def test_outputs_of_a_removed_payload_are_named_and_the_report_shows_only_the_run(run_dir, tmp_path):
    work, cfg = run_dir
    copy = tmp_path / "run"
    shutil.copytree(work, copy, ignore=shutil.ignore_patterns("locks", "incomplete"))
    res = snakemake(copy, cfg, "all", "-n")
    assert res.returncode == 0 and "not of this config" not in res.stderr, res.stderr[-2000:]
    old = copy / "results/tiny/verify/payload_999kg"
    old.mkdir()
    (old / "workspace.png").write_bytes(b"an earlier config's figure")
    res = snakemake(copy, cfg, "all", "-n")
    assert res.returncode == 0, res.stderr[-2000:]
    note = [ln for ln in res.stderr.splitlines() if "not of this config" in ln]
    assert len(note) == 1 and "results/tiny/verify/payload_999kg" in note[0]
    assert "report_tables" in res.stdout  # its page lists them: rebuilt with the new list
    res = snakemake(copy, cfg, "all")
    assert res.returncode == 0, res.stderr[-2000:]
    assert "payload_999kg" in (copy / "results/tiny/report/catalogue.html").read_text()
    assert not pd.read_parquet(copy / "results/tiny/catalogue.parquet").path.str.contains("999").any()
    # the report of the run: its description, every table as a captioned page, the 3D map; nothing stale
    res = snakemake(copy, cfg, "--report", str(tmp_path / "report.html"))
    assert res.returncode == 0, res.stderr[-2000:]
    page = (tmp_path / "report.html").read_text()
    expected = ["What this workflow does", "capmap run", "results/tiny/summary/capacity_3d.html",
                *(f"results/tiny/report/{name}.html" for name in ("catalogue", "capacity_summary", "verify_summary",
                                                                 "follow_summary", "reconfig_summary",
                                                                 "dualarm_summary", "csqp_check"))]
    missing = [e for e in expected if e not in page]
    assert not missing, missing  # (a short message: the page is ~19 MB)
    # (the stale folder is named on the catalogue's page; its figure is no result of the report)
    assert not any(s in page for s in ("payload_999kg/workspace.png", "results/default"))  # no 19 MB diff on failure
    assert old.is_dir()  # kept: never deleted behind the user's back


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


def _dom(browser: str, page) -> str:
    """The page's DOM after its scripts ran, in headless Chromium (WebGL on the software renderer)."""
    import subprocess

    res = subprocess.run([browser, "--headless=new", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
                          "--virtual-time-budget=8000", "--dump-dom", page.resolve().as_uri()],
                         capture_output=True, text=True, timeout=120)
    return res.stdout


def test_every_page_of_the_zip_report_renders_in_chromium(run_dir, tmp_path):
    """The README's report (a .zip) keeps each page a file of its own, not a data URL (Chromium shows no
    data-URL page above ~2 MB: the 3D map, the reconfiguration animation); opened in headless Chromium,
    every page renders: the 3D map's plot, the animations' WebGL canvas, every table."""
    browser = _chromium()
    if browser is None:
        pytest.skip("no Chromium on this machine (.ci/run installs it: apt-get install chromium)")
    work, cfg = run_dir
    res = snakemake(work, cfg, "--report", str(tmp_path / "report.zip"))
    assert res.returncode == 0, res.stderr[-2000:]
    shutil.unpack_archive(tmp_path / "report.zip", tmp_path / "unzipped")
    root = next((tmp_path / "unzipped").rglob("report.html")).parent
    index = (root / "report.html").read_text()
    assert "data:text/html" not in index  # no page embedded as a data URL
    pages = sorted((root / "data").rglob("*.html"))
    names = sorted(p.name for p in pages)
    assert "capacity_3d.html" in names and names.count("animation.html") == 2 and "catalogue.html" in names
    for page in pages:
        assert str(page.relative_to(root)) in index  # the report links the file
        dom = _dom(browser, page)
        if page.name == "capacity_3d.html":
            assert 'class="main-svg"' in dom, page  # plotly drew the map
        elif page.name == "animation.html":
            assert "<canvas" in dom, page  # meshcat's WebGL view started
        else:
            assert "<table>" in dom and "<tr>" in dom, page
    assert (tmp_path / "report.zip").stat().st_size < 10e6 and (root / "report.html").stat().st_size < 10e6
