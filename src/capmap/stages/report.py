"""Stages that gather across families: the data catalogue and concatenated summary tables."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from capmap.io import datasets
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table

__all__ = ["stage_catalogue", "stage_concat_summary"]


def stage_catalogue(paths: list[str], out: str) -> None:
    """One row per dataset (see :func:`capmap.io.datasets.catalogue`)."""
    cat = datasets.catalogue(paths)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    cat.to_parquet(out, index=False)
    stage_logger(__name__, "catalogue").info(f"{len(cat)} datasets -> {out}")


def stage_concat_summary(tables: list[str], out_csv: str, out_md: str, what: str) -> None:
    """Several summary CSVs (every payload's verification, every follow case) in one table."""
    df = pd.concat([pd.read_csv(t) for t in tables], ignore_index=True)
    write_table(df, out_csv, out_md)
    stage_logger(__name__, f"{what} summary").info(f"{len(df)} rows -> {out_csv}")
