"""The stages that gather across families, on tiny inputs (no Snakemake): the catalogue, the
concatenated summaries and the report's table pages."""

import hashlib

import pandas as pd
import pytest

from capmap.io import datasets
from capmap.stages.report import TABLE_TITLES, stage_catalogue, stage_concat_summary, stage_report_tables


@pytest.fixture
def two_datasets(tmp_path):
    """Two datasets as a run writes them: results/<run>/<family>/<name>.parquet, with provenance."""
    paths = []
    for sub, name, n in (("verify/payload_1500kg", "waypoints", 3), ("follow/ground", "timeseries", 5)):
        p = tmp_path / "results" / "tiny" / sub / f"{name}.parquet"
        p.parent.mkdir(parents=True)
        df = pd.DataFrame({"t_s": range(n), "tau_j1_nm": [0.5] * n})
        datasets.write(df, p, datasets.provenance(name, {"run": "tiny"}))
        paths.append(str(p))
    return paths


def test_catalogue_counts_and_hashes_each_file(two_datasets, tmp_path):
    out = tmp_path / "catalogue.parquet"
    stage_catalogue(two_datasets, str(out))
    cat = pd.read_parquet(out)
    assert list(cat.path) == two_datasets
    assert list(cat.rows) == [3, 5]
    for p, sha in zip(cat.path, cat.sha256):  # the file's own bytes, hashed here
        with open(p, "rb") as f:
            assert sha == hashlib.sha256(f.read()).hexdigest()
    assert all("tau_j1_nm [N m]" in list(cols) for cols in cat["columns"])  # the unit read from the name


def test_concat_summary_keeps_every_row_in_order(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    pd.DataFrame({"payload_kg": [500.0], "feasible": [True]}).to_csv(a, index=False)
    pd.DataFrame({"payload_kg": [1500.0, 4000.0], "feasible": [True, False]}).to_csv(b, index=False)
    stage_concat_summary([str(a), str(b)], str(tmp_path / "s.csv"), str(tmp_path / "s.md"), "verify")
    s = pd.read_csv(tmp_path / "s.csv")
    assert list(s.payload_kg) == [500.0, 1500.0, 4000.0] and list(s.feasible) == [True, True, False]
    assert "4000" in (tmp_path / "s.md").read_text()


def test_report_tables_name_each_dataset_by_its_path_and_list_stale_outputs(two_datasets, tmp_path):
    cat, csv = tmp_path / "catalogue.parquet", tmp_path / "gain.csv"
    stage_catalogue(two_datasets, str(cat))
    pd.DataFrame({"payload_kg": [1500.0], "gain_pct": [12.5]}).to_csv(csv, index=False)
    out = {"catalogue": str(tmp_path / "html" / "catalogue.html"), "gain": str(tmp_path / "html" / "gain.html")}
    stage_report_tables({"catalogue": str(cat), "gain": str(csv)}, out, ["results/tiny/verify/payload_9kg/x.csv"],
                        {"catalogue": "Every ``dataset``.", "gain": "The gain."})
    page = (tmp_path / "html" / "catalogue.html").read_text()
    assert TABLE_TITLES["catalogue"][0] in page and "Every dataset." in page  # title, caption without rst marks
    # two datasets both called by their stem would be ambiguous; the page names them by their path in the run
    assert "verify/payload_1500kg/waypoints" in page and "follow/ground/timeseries" in page
    assert "Not of this config" in page and "payload_9kg" in page
    assert "12.5" in (tmp_path / "html" / "gain.html").read_text()
