"""Datasets written and read in chunks: the same table, categories and provenance as a whole write;
a damaged file is one line naming it."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from capmap.errors import DataError
from capmap.io import datasets


def _chunks(n: int, size: int):
    cats = ["a", "b", "c"]
    for s in range(0, n, size):
        r = np.arange(s, min(s + size, n))
        yield pd.DataFrame({"x_m": r * 0.5, "i": r, "c": pd.Categorical.from_codes(r % 2, cats)})  # "c" never used


def test_chunks_round_trip_like_one_table(tmp_path):
    prov = {"stage": "test", "n": 3}
    rows = datasets.write_chunks(_chunks(23, 5), tmp_path / "c.parquet", prov)
    datasets.write(pd.concat(list(_chunks(23, 23)), ignore_index=True), tmp_path / "w.parquet", prov)
    got, whole = datasets.read(tmp_path / "c.parquet"), datasets.read(tmp_path / "w.parquet")
    assert rows == 23
    pd.testing.assert_frame_equal(got, whole)
    assert list(got.c.cat.categories) == ["a", "b", "c"] and got.attrs == whole.attrs == {"capmap": prov}
    assert datasets.read_provenance(tmp_path / "c.parquet") == prov
    back = list(datasets.read_chunks(tmp_path / "c.parquet", 4))
    assert max(len(b) for b in back) == 4
    pd.testing.assert_frame_equal(pd.concat(back, ignore_index=True), whole, check_categorical=True)


def test_a_failing_chunk_leaves_no_file(tmp_path):
    def broken():
        yield from _chunks(10, 5)
        raise RuntimeError("the job died")

    with pytest.raises(RuntimeError):
        datasets.write_chunks(broken(), tmp_path / "c.parquet", {})
    assert not list(tmp_path.iterdir())


def test_damaged_file_is_one_line(tmp_path):
    p = tmp_path / "bad.parquet"
    p.write_bytes(b"PAR1 not really")
    for read in (lambda: list(datasets.read_chunks(p, 10)), lambda: datasets.read_provenance(p)):
        with pytest.raises(DataError, match="bad.parquet is not a readable Parquet dataset"):
            read()
    with pytest.raises(DataError, match="missing"):
        datasets.read_provenance(tmp_path / "none.parquet")
