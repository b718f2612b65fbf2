"""Input files that are not YAML (a user's point cloud), checked before any job: a regular file
of a known kind and bounded size whose columns are there, so that a job never starts on a file
it cannot read (Snakemake deletes a job's outputs before the job runs)."""

from __future__ import annotations

import os
from pathlib import Path

from capmap.config.validation import file_kind, shown, too_big
from capmap.errors import ConfigError

__all__ = ["CLOUD_COLUMNS", "CLOUD_SUFFIXES", "MAX_CLOUD_BYTES", "check_cloud_file"]

CLOUD_COLUMNS = ("x_m", "y_m", "z_m")
CLOUD_SUFFIXES = (".csv", ".parquet")
MAX_CLOUD_BYTES = 1 << 30  # 1 GiB: ~30 M points as CSV; a scan of a work cell is ~1e5


def _regular(path: str, key: str, limit: int) -> os.stat_result:
    name = f"{key} = {shown(path)}"
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ConfigError(f"{name}: no such file") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{name}: cannot read ({getattr(exc, 'strerror', None) or exc})") from None
    file_kind(st.st_mode, name)  # the YAML loader's checks and words
    too_big(st.st_size, name, limit)
    if not os.access(path, os.R_OK):
        raise ConfigError(f"{name}: cannot read (permission denied)")
    return st


def check_cloud_file(path: str, key: str = "dualarm.cloud.file", limit: int = MAX_CLOUD_BYTES,
                     viewpoints: int = 1) -> None:
    """A cloud file (CSV with a header line, or Parquet) that exists, is a regular readable file of
    at most ``limit`` bytes and has the columns x_m, y_m, z_m (and ``viewpoint``, the index of the
    camera that saw each point, when there are several ``viewpoints``); else one ConfigError line naming
    ``key``. Only the header (CSV) or the schema (Parquet) is read: the values are the scan job's."""
    suffix = Path(path).suffix.lower()
    if suffix not in CLOUD_SUFFIXES:
        raise ConfigError(f"{key} = {shown(path)}: not a cloud file (need {' or '.join(CLOUD_SUFFIXES)} with columns "
                          f"{', '.join(CLOUD_COLUMNS)})")
    _regular(path, key, limit)
    if suffix == ".parquet":
        try:
            import pyarrow.parquet as pq  # a user's Parquet cloud only

            columns = pq.read_schema(path).names
        except Exception as exc:  # pyarrow raises several types for a file that is not Parquet
            raise ConfigError(f"{key} = {shown(path)}: not a Parquet file ({str(exc).splitlines()[0][:120]})") from None
    else:
        with open(path, "rb") as f:
            head = f.readline(65536)
        try:
            text = head.decode("utf-8-sig")  # a byte-order mark, as pandas reads it
        except UnicodeDecodeError:
            raise ConfigError(f"{key} = {shown(path)}: not a text (UTF-8) CSV file") from None
        if "\x00" in text:
            raise ConfigError(f"{key} = {shown(path)}: not a text CSV file (it contains NUL bytes)")
        columns = [c.strip('"') for c in text.rstrip("\r\n").split(",")]  # as pandas names them: spaces kept
    missing = [c for c in CLOUD_COLUMNS if c not in columns]
    if missing:
        raise ConfigError(f"{key} = {shown(path)}: no column {missing[0]} (need a header with "
                          f"{', '.join(CLOUD_COLUMNS)})")
    if viewpoints > 1 and "viewpoint" not in columns:
        raise ConfigError(f"{key} = {shown(path)}: no column viewpoint (the index into dualarm.cloud.viewpoints_m of "
                          f"the camera that saw each point: there are {viewpoints} viewpoints)")
