"""Summary tables for people: CSV (for pandas) and Markdown (for the report and the terminal)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["fmt_value", "write_table", "write_quantities"]


def fmt_value(v) -> str:
    """A cell for people: floats to 4 significant digits (one decimal from 100), NaN and None empty."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (float, np.floating)):
        return "" if v is None else str(v)
    return "" if np.isnan(v) else f"{v:.1f}" if 100 <= abs(v) < 1e6 else f"{v:.4g}"


def write_table(df: pd.DataFrame, out_csv: str | Path, out_md: str | Path) -> None:
    """A summary table as CSV and as Markdown transposed: one column per row of ``df``, headed
    by its first two fields (e.g. payload and path)."""
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out_csv, index=False)
    md = df.iloc[:, 2:].map(fmt_value).T
    md.columns = [f"{a:g} kg, {b}" if df.columns[0] == "payload_kg" else f"{a} {b}"
                  for a, b in zip(df.iloc[:, 0], df.iloc[:, 1])]
    Path(out_md).write_text(md.to_markdown() + "\n")


def write_quantities(rows: list[tuple[str, object]], out_csv: str | Path, out_md: str | Path) -> pd.DataFrame:
    """A two-column (quantity, value) table as CSV and Markdown; returns it."""
    table = pd.DataFrame(rows, columns=["quantity", "value"])
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(out_csv, index=False)
    Path(out_md).write_text(table.assign(value=table.value.map(fmt_value)).to_markdown(index=False) + "\n")
    return table

