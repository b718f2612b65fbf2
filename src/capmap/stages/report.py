"""Stages that gather across families: the data catalogue and concatenated summary tables."""

from __future__ import annotations

import html
from pathlib import Path

import pandas as pd

from capmap.io import datasets
from capmap.io.catalogue import catalogue_table
from capmap.io.html_tables import table_html
from capmap.io.logs import stage_logger
from capmap.io.tables import write_table

__all__ = ["stage_catalogue", "stage_concat_summary", "stage_report_tables", "TABLE_TITLES"]


def stage_catalogue(paths: list[str], out: str) -> None:
    """One row per dataset (see :func:`capmap.io.catalogue.catalogue_table`)."""
    cat = catalogue_table(paths)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    cat.to_parquet(out, index=False)
    stage_logger(__name__, "catalogue").info(f"{len(cat)} datasets -> {out}")


def stage_concat_summary(tables: list[str], out_csv: str, out_md: str, what: str) -> None:
    """Several summary CSVs (every payload's verification, every follow case) in one table."""
    df = pd.concat([pd.read_csv(t) for t in tables], ignore_index=True)
    write_table(df, out_csv, out_md)
    stage_logger(__name__, f"{what} summary").info(f"{len(df)} rows -> {out_csv}")


# title of each table's page and whether it reads down (one column per row of the CSV); the caption is the
# report's caption file of the table (workflow/report/*.rst), passed in by the rule
TABLE_TITLES = {
    "catalogue": ("Data catalogue", False),
    "capacity_summary": ("Capacity map summary", False),
    "verify_summary": ("Verification", True),
    "gain": ("Planning gain", False),
    "follow_summary": ("Torque-limited following vs TOPP-RA", True),
    "reconfig_summary": ("Boom reconfiguration", True),
    "dualarm_summary": ("Dual-arm assembly", False),
    "csqp_check": ("Dual-arm check with CSQP", True),
}


def stage_report_tables(tables: dict[str, str], outputs: dict[str, str], stale: list[str],
                        captions: dict[str, str]) -> None:
    """Each table (CSV, or Parquet for the catalogue) as an HTML page for the report, headed by its
    title and caption (reStructuredText, shown as text); the catalogue's page also lists the
    outputs an earlier config of this run left behind (``stale``)."""
    log = stage_logger(__name__, "report tables")
    for name, src in tables.items():
        df = datasets.read(src) if src.endswith(".parquet") else pd.read_csv(src)
        title, transpose = TABLE_TITLES[name]
        caption = " ".join(captions[name].replace("``", "").split())
        extra = ""
        if name == "catalogue":
            df = df.drop(columns=["capmap_version"], errors="ignore")
            df["sha256"] = df.sha256.str[:12]
            extra = ("<h2>Not of this config</h2><p class='caption'>Left on disk by an earlier config of this run "
                     "(a payload, task, case or family since removed): not current, not in this report.</p><ul>"
                     + "".join(f"<li>{html.escape(p)}</li>" for p in stale) + "</ul>") if stale else ""
        Path(outputs[name]).parent.mkdir(parents=True, exist_ok=True)
        Path(outputs[name]).write_text(table_html(df, title, caption, transpose, extra))
    log.info(f"{len(tables)} tables -> {Path(next(iter(outputs.values()))).parent}")
