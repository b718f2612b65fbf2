"""Parquet datasets with provenance; checking a run against its catalogue (:mod:`capmap.io.catalogue` writes it).

Every dataset carries ``df.attrs["capmap"]`` (readable with ``pd.read_parquet(p).attrs``):
stage, config slice, config hash, seed, package version. Column names carry their units
as suffixes (``capacity_kg``, ``tau_j3_nm``); :func:`column_unit` decodes them.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import capmap
from capmap.errors import DataError
from capmap.io.fingerprint import file_sha256

if TYPE_CHECKING:  # pandas loads when a table is read or written (capmap query reads columns without it)
    import pandas as pd

__all__ = ["UNITS", "column_unit", "canonical", "config_hash", "provenance", "write", "write_chunks", "read",
           "read_chunks", "read_provenance", "rebuild_hint_config", "verify_catalogue", "missing_catalogued"]

UNITS = [("_deg", "deg"), ("_rad", "rad"), ("_kg", "kg"), ("_nm", "N m"), ("_n", "N"), ("_mps2", "m/s^2"),
         ("_mps", "m/s"), ("_m", "m"), ("_s", "s"), ("_pct", "%"), ("_rad_s", "rad/s"), ("_rad_s2", "rad/s^2"),
         ("_deg_s", "deg/s"), ("_deg_s2", "deg/s^2"), ("_kgm2", "kg m^2"), ("_nms", "N m s/rad")]


def column_unit(name: str) -> str:
    """Unit from a column-name suffix ('' when dimensionless or an identifier)."""
    for suffix, unit in sorted(UNITS, key=lambda x: -len(x[0])):
        if name.endswith(suffix):
            return unit
    return ""


def _plain_numbers(obj):
    """Integral floats as ints (700.0 -> 700), recursively: the same number is written one way."""
    if isinstance(obj, dict):
        return {k: _plain_numbers(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain_numbers(v) for v in obj]
    if isinstance(obj, float) and obj.is_integer() and abs(obj) < 2**53:
        return int(obj)
    return obj


def canonical(obj) -> str:
    """Canonical JSON (sorted keys, no spaces, integral floats as ints): equal configs give equal
    strings, however their numbers were typed."""
    return json.dumps(_plain_numbers(obj), sort_keys=True, separators=(",", ":"))


def config_hash(obj) -> str:
    """Short hash of the canonical JSON of a config slice."""
    return hashlib.sha256(canonical(obj).encode()).hexdigest()[:16]


def provenance(stage: str, config_slice: dict, seed: int | None = None, **extra) -> dict:
    """A dataset's provenance: stage, config slice (with the fingerprint of the code that ran,
    ``code``, when the rule's params carry it), its hash, the seed, the package version."""
    return {"stage": stage, "config": config_slice, "config_hash": config_hash(config_slice), "seed": seed,
            "code": config_slice.get("code", ""), "capmap_version": capmap.__version__, **extra}


def write(df: pd.DataFrame, path: str | Path, prov: dict) -> None:
    """Write a Parquet file with provenance in its metadata (atomically: temp file then rename; zstd:
    about a third smaller than the default snappy on these float tables, read by any Parquet reader)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    df = df.copy()
    df.attrs = {"capmap": prov}
    tmp = path.with_suffix(".tmp.parquet")
    try:
        df.to_parquet(tmp, index=False, compression="zstd")
        tmp.replace(path)
    except BaseException:  # a full disk, a read-only folder, an interrupt: no half-written file left behind
        tmp.unlink(missing_ok=True)
        raise


def write_chunks(chunks: Iterable[pd.DataFrame], path: str | Path, prov: dict) -> int:
    """Write the tables ``chunks`` (the same columns and types, categories included) one after the other
    into one Parquet file with provenance, as :func:`write` does for one table, holding one chunk in memory
    at a time (a row group each); no chunk: nothing is written. Returns the rows written."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.parquet")
    writer, schema, rows = None, None, 0
    try:
        for df in chunks:
            if writer is None:
                table = pa.Table.from_pandas(df, preserve_index=False)
                schema = table.schema.with_metadata({**(table.schema.metadata or {}),
                                                     _ATTRS_KEY: json.dumps({"capmap": prov}).encode()})
                writer = pq.ParquetWriter(tmp, schema, compression="zstd")
            table = pa.Table.from_pandas(df, preserve_index=False, schema=schema)
            writer.write_table(table)
            rows += len(df)
        if writer is not None:
            writer.close()
            tmp.replace(path)
    except BaseException:
        if writer is not None:
            writer.close()
        tmp.unlink(missing_ok=True)
        raise
    return rows


_CONFIG_ARGS_ENV = "CAPMAP_CONFIG_ARGS"  # set by the workflow, inherited by its jobs


def rebuild_hint_config(config_args: str) -> None:
    """The workflow's ``--configfile`` arguments (" --configfile my.yaml", or "") for the rebuild
    commands that :func:`read` prints, in this process and the jobs it starts."""
    os.environ[_CONFIG_ARGS_ENV] = config_args


def read(path: str | Path) -> pd.DataFrame:
    """Read a dataset; a missing, truncated or foreign file is one :class:`DataError` line naming it
    and the command that rebuilds it."""
    import pandas as pd

    with _reading(path):
        return pd.read_parquet(path)


def read_chunks(path: str | Path, rows: int) -> Iterator[pd.DataFrame]:
    """A dataset's rows in order, at most ``rows`` at a time (categories as written; no provenance), so
    that a reader holds one chunk, not the file; errors as :func:`read`'s."""
    import pyarrow.parquet as pq

    with _reading(path):
        f = pq.ParquetFile(path)
        batches = f.iter_batches(batch_size=int(rows))
    while True:
        with _reading(path):
            batch = next(batches, None)
        if batch is None:
            return
        yield batch.to_pandas()


def read_provenance(path: str | Path) -> dict:
    """A dataset's provenance (``attrs["capmap"]``) without reading its rows."""
    import pyarrow.parquet as pq

    with _reading(path):
        meta = pq.read_schema(path).metadata or {}
    return json.loads(meta.get(_ATTRS_KEY, b"{}")).get("capmap", {})


_ATTRS_KEY = b"PANDAS_ATTRS"  # where pandas keeps a table's attrs in Parquet metadata (and reads them back)


@contextmanager
def _reading(path: str | Path):
    """A missing, truncated or foreign file as one :class:`DataError` line naming it and the command
    that rebuilds it."""
    rebuild = f"rebuild it with: snakemake --cores 2 all{os.environ.get(_CONFIG_ARGS_ENV, '')} --forcerun {path}"
    try:
        yield
    except FileNotFoundError:
        raise DataError(f"{path} is missing; {rebuild}") from None
    except DataError:
        raise
    except Exception as exc:  # pyarrow raises several types for a damaged file
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise DataError(f"{path} is not a readable Parquet dataset ({first}); {rebuild}") from None


def verify_catalogue(catalogue_path: str | Path, root: str | Path = ".") -> list[str]:
    """Problems (one line each) of the datasets a catalogue lists: missing, unreadable, or not the
    catalogued sha256 or row count. Empty when every dataset is as catalogued."""
    cat = read(catalogue_path)
    problems = []
    for row in cat.itertuples():
        path = Path(root) / row.path
        if not path.is_file():
            problems.append(f"{row.path}: missing (catalogued with {row.rows} rows)")
            continue
        if file_sha256(path) != row.sha256:
            try:
                n = len(read(path))
                problems.append(f"{row.path}: content differs from the catalogue ({n} rows, catalogued {row.rows})")
            except DataError as exc:
                problems.append(str(exc))
    return problems


def missing_catalogued(catalogue_path: str | Path, root: str | Path = ".") -> list[str]:
    """Paths a catalogue lists that are no longer on disk (cheap: no hashing; [] without a
    readable catalogue). Snakemake does not rebuild a deleted intermediate whose consumers are up
    to date, so the workflow names these before it says "Nothing to be done"."""
    import pandas as pd

    try:
        cat = pd.read_parquet(catalogue_path, columns=["path"])
    except Exception:  # no catalogue yet, or a damaged one (python -m capmap check reports it)
        return []
    return [p for p in cat.path if not (Path(root) / p).is_file()]
