"""The stages that gather across families, on tiny inputs (no Snakemake): the catalogue, the
concatenated summaries and the report's table pages."""

import hashlib

import pandas as pd
import pytest

from capmap.errors import DataError
from capmap.io import datasets
from capmap.stages.report import TABLE_TITLES, stage_catalogue, stage_concat_summary, stage_report_tables


@pytest.fixture
def two_datasets(tmp_path):
    """Two datasets as a run writes them: results/<run>/<family>/<name>.parquet, with provenance."""
    paths = []
    for sub, name, n in (("verify/payload_1500kg", "timeseries", 3), ("follow/ground", "timeseries", 5)):
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
    # each dataset named uniquely by its place in the run, described, with its units
    assert list(cat.name) == ["verify_1500kg", "follow_ground"] and list(cat.units) == ["N m, s", "N m, s"]
    assert cat.description.str.len().min() > 40 and list(cat.row) == ["time sample of a path", "stored control period"]


def test_catalogue_refuses_two_datasets_of_one_name_and_one_of_no_kind(tmp_path):
    paths = []
    for sub in ("a", "b"):  # two run folders' voxel maps: one name twice
        p = tmp_path / sub / "voxels" / "voxels.parquet"
        datasets.write(pd.DataFrame({"capacity_kg": [1.0]}), p, datasets.provenance("voxel_map", {}))
        paths.append(str(p))
    with pytest.raises(DataError, match="catalogue names used twice: voxels"):
        stage_catalogue(paths, str(tmp_path / "c.parquet"))
    odd = tmp_path / "odd" / "thing.parquet"
    datasets.write(pd.DataFrame({"x_m": [1.0]}), odd, datasets.provenance("x", {}))
    with pytest.raises(DataError, match="no entry in capmap.io.catalogue.DATASETS"):
        stage_catalogue([str(odd)], str(tmp_path / "c.parquet"))


def test_load_reads_a_dataset_by_its_catalogue_name(two_datasets, tmp_path, monkeypatch):
    import capmap

    stage_catalogue(two_datasets, str(tmp_path / "results" / "tiny" / "catalogue.parquet"))
    monkeypatch.chdir(tmp_path / "results")  # elsewhere than the workflow's folder: found under the run folder
    df = capmap.load("tiny", "follow_ground", results=tmp_path / "results")
    assert len(df) == 5 and df.attrs["capmap"]["stage"] == "timeseries"
    assert list(capmap.catalogue("tiny", results=tmp_path / "results").name) == ["verify_1500kg", "follow_ground"]
    with pytest.raises(DataError, match="no dataset 'nope'; there are: verify_1500kg, follow_ground"):
        capmap.load("tiny", "nope", results=tmp_path / "results")


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
    # each dataset by its catalogue name, with its description
    assert "verify_1500kg" in page and "follow_ground" in page and "torque-limited follower" in page
    assert "Not of this config" in page and "payload_9kg" in page
    assert "12.5" in (tmp_path / "html" / "gain.html").read_text()


def test_the_outputs_page_lists_the_registry():
    """docs/outputs.md's dataset table is the registry's (python -m capmap.io.catalogue --write docs/outputs.md)."""
    from pathlib import Path

    from capmap.io.catalogue import outputs_table

    assert outputs_table() in (Path(__file__).parents[2] / "docs" / "outputs.md").read_text()


def test_axis_capacities_are_stored_never_above_the_computed_value():
    """float32 storage of the axis columns rounds toward lower capacity: never above, at most one float32 step
    (1.2e-7 relative) below; NaN and inf kept."""
    import numpy as np

    from capmap.capacity.tables import AXIS_COLUMNS, axes_stored

    x = np.random.default_rng(5).uniform(0, 5000, 10000)
    x[:3] = [np.nan, np.inf, 0.0]
    got = axes_stored(pd.DataFrame({AXIS_COLUMNS[0]: x}))[AXIS_COLUMNS[0]].to_numpy()
    assert got.dtype == np.float32 and np.isnan(got[0]) and np.isinf(got[1]) and got[2] == 0
    g, v = got[3:].astype(float), x[3:]
    assert (g <= v).all() and (v - g <= 2.4e-7 * v).all() and (g < v).any()
