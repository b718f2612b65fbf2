"""Columns of a capmap dataset as NumPy arrays with its provenance, read by pyarrow alone: for the
command line's quick answers (``capmap query``), which would otherwise spend longer importing pandas
than answering. Errors as :func:`capmap.io.datasets.read`'s: one :class:`DataError` line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from capmap.errors import DataError

__all__ = ["read_columns"]


def read_columns(path: str | Path, columns: list[str]) -> tuple[dict[str, np.ndarray], dict]:
    """The named columns of the dataset at ``path`` ({name: (N,) array}; strings as object arrays) and
    its provenance (``df.attrs["capmap"]`` of :func:`capmap.io.datasets.read`, {} if none)."""
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path, columns=columns)
    except FileNotFoundError:
        raise DataError(f"{path} is missing") from None
    except Exception as exc:  # pyarrow raises several types for a damaged file or a missing column
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise DataError(f"{path} is not a readable capmap dataset ({first})") from None
    meta = table.schema.metadata or {}
    try:
        attrs = json.loads(meta.get(b"PANDAS_ATTRS", b"{}")).get("capmap", {})
    except ValueError:
        attrs = {}
    cols = {}
    for name in columns:
        col = table.column(name)
        cols[name] = np.asarray(col.to_pylist(), dtype=object) if col.type in (_str_types()) else col.to_numpy()
    return cols, attrs


def _str_types():
    import pyarrow as pa

    return (pa.string(), pa.large_string(), pa.dictionary(pa.int32(), pa.string()),
            pa.dictionary(pa.int8(), pa.string()))
