"""Parquet datasets with provenance, and the data catalogue.

Every dataset carries ``df.attrs["capmap"]`` (readable with ``pd.read_parquet(p).attrs``):
stage, config slice, config hash, seed, package version. Column names carry their units
as suffixes (``capacity_kg``, ``tau_j3_nm``); :func:`column_unit` decodes them.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pandas as pd

import capmap

__all__ = ["UNITS", "column_unit", "canonical", "config_hash", "provenance", "write", "read", "sha256", "catalogue"]

UNITS = [("_deg", "deg"), ("_rad", "rad"), ("_kg", "kg"), ("_nm", "N m"), ("_n", "N"), ("_mps2", "m/s^2"),
         ("_mps", "m/s"), ("_m", "m"), ("_s", "s"), ("_pct", "%"), ("_rad_s", "rad/s"), ("_rad_s2", "rad/s^2"),
         ("_deg_s", "deg/s"), ("_deg_s2", "deg/s^2")]


def column_unit(name: str) -> str:
    """Unit from a column-name suffix ('' when dimensionless or an identifier)."""
    for suffix, unit in sorted(UNITS, key=lambda x: -len(x[0])):
        if name.endswith(suffix):
            return unit
    return ""


def canonical(obj) -> str:
    """Canonical JSON (sorted keys, no spaces): equal configs give equal strings."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"))


def config_hash(obj) -> str:
    """Short hash of the canonical JSON of a config slice."""
    return hashlib.sha256(canonical(obj).encode()).hexdigest()[:16]


def provenance(stage: str, config_slice: dict, seed: int | None = None, **extra) -> dict:
    return {"stage": stage, "config": config_slice, "config_hash": config_hash(config_slice), "seed": seed,
            "capmap_version": capmap.__version__, **extra}


def write(df: pd.DataFrame, path: str | Path, prov: dict) -> None:
    """Write a Parquet file with provenance in its metadata (atomically: temp file then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    df = df.copy()
    df.attrs = {"capmap": prov}
    tmp = path.with_suffix(".tmp.parquet")
    df.to_parquet(tmp, index=False)
    tmp.replace(path)


def read(path: str | Path) -> pd.DataFrame:
    return pd.read_parquet(path)


def sha256(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def catalogue(paths: list[str | Path]) -> pd.DataFrame:
    """One row per dataset: name, path, stage, rows, columns (with units), sha256, config hash."""
    rows = []
    for p in paths:
        df = read(p)
        meta = df.attrs.get("capmap", {})
        rows.append({
            "name": Path(p).stem,
            "path": str(p),
            "stage": meta.get("stage", ""),
            "rows": len(df),
            "columns": [f"{c} [{column_unit(c)}]" if column_unit(c) else c for c in df.columns],
            "sha256": sha256(p),
            "config_hash": meta.get("config_hash", ""),
            "capmap_version": meta.get("capmap_version", ""),
        })
    return pd.DataFrame(rows)
