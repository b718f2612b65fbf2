"""Tables for the report: a CSV or Parquet table as a self-contained HTML page (no scripts, no
network), headed by its title and caption, quantity names with units instead of raw columns."""

from __future__ import annotations

import html

import numpy as np
import pandas as pd

from capmap.io.datasets import UNITS
from capmap.io.tables import fmt_value

__all__ = ["quantity_label", "table_html"]

_STYLE = """
body { font-family: system-ui, sans-serif; font-size: 13px; margin: 12px; color: #222; }
h2 { font-size: 16px; margin: 0 0 4px 0; }
p.caption { margin: 0 0 10px 0; max-width: 70em; color: #444; }
table { border-collapse: collapse; }
th, td { border: 1px solid #ccc; padding: 3px 8px; vertical-align: top; }
th { background: #f0f0f0; text-align: left; }
tr th:first-child { white-space: nowrap; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
"""


def quantity_label(column: str) -> str:
    """'capacity_kg' -> 'capacity [kg]', 'tau_j3_nm' -> 'tau j3 [N m]', 'path' -> 'path'."""
    for suffix, unit in sorted(UNITS, key=lambda x: -len(x[0])):
        if column.endswith(suffix) and len(column) > len(suffix):
            return f"{column[: -len(suffix)].replace('_', ' ')} [{unit}]"
    return column.replace("_", " ")


def _cell(v) -> str:
    if isinstance(v, (list, tuple, np.ndarray)):
        return "<br>".join(html.escape(str(x)) for x in v)
    return html.escape(fmt_value(v))


def _td(v) -> str:
    """A cell; numbers right-aligned."""
    num = isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))
    return f"<td{' class=num' if num else ''}>{_cell(v)}</td>"


def table_html(df: pd.DataFrame, title: str, caption: str, transpose: bool = False,
               extra: str = "") -> str:
    """The table as an HTML page. ``transpose``: one column per row of ``df``, headed by its first
    two fields (a summary with a row per payload and path reads down, as in the .md tables);
    ``extra``: further HTML appended (already escaped)."""
    if transpose and len(df.columns) > 2:
        heads = [f"{a:g} kg, {b}" if df.columns[0] == "payload_kg" else f"{a} {b}"
                 for a, b in df.iloc[:, :2].itertuples(index=False)]
        head = "<tr><th>quantity</th>" + "".join(f"<th>{html.escape(h)}</th>" for h in heads) + "</tr>"
        body = "".join(
            "<tr><th>" + html.escape(quantity_label(c)) + "</th>"
            + "".join(map(_td, df[c])) + "</tr>"
            for c in df.columns[2:])
    else:
        head = "<tr>" + "".join(f"<th>{html.escape(quantity_label(c))}</th>" for c in df.columns) + "</tr>"
        body = "".join(
            "<tr>" + "".join(map(_td, row)) + "</tr>"
            for row in df.itertuples(index=False))
    return (f"<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{_STYLE}</style></head><body><h2>{html.escape(title)}</h2>"
            f"<p class='caption'>{html.escape(caption)}</p><table>{head}{body}</table>{extra}</body></html>\n")
