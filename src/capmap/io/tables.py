"""Summary tables for people: CSV (for pandas) and Markdown (for the report and the terminal)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["fmt_value", "write_table", "write_quantities"]


def fmt_value(v) -> str:
    """A cell for people: a whole number below 1e9 as an integer (a count: 70460, not 70460.0), a small or huge
    number (an error, a bound: below 1e-3 or from 1e6) in scientific notation with 3 digits (1.62e-08),
    others to 4 significant digits (one decimal from 100); NaN and None empty. Numbers written as text (a
    quantity table's mixed value column read back from CSV) are formatted likewise; other text as it is."""
    if isinstance(v, str):
        try:
            x = float(v)
        except ValueError:
            return v
        if v.strip().lower() in ("nan", "inf", "-inf", "infinity", "-infinity") or not v.strip():
            return v
        v = x
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (float, np.floating, int, np.integer)):
        return "" if v is None else str(v)
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if np.isnan(v):
        return ""
    if not np.isfinite(v):
        return str(v)
    if v.is_integer() and abs(v) < 1e9:  # a count; larger whole numbers are bounds (1e+11)
        return str(int(v))
    if abs(v) < 1e-3 or abs(v) >= 1e6:
        return f"{v:.3g}"
    return f"{v:.1f}" if abs(v) >= 100 else f"{v:.4g}"


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

