"""A user's cloud file is checked before any job exactly as the scan job will read it (pandas):
header names as pandas gives them, a byte-order mark allowed, the suffix in any case."""

import pandas as pd
import pytest

from capmap.config.inputs import check_cloud_file
from capmap.dualarm.cloud_file import read_cloud
from capmap.errors import ConfigError


def _write(tmp_path, name, data: bytes):
    path = tmp_path / name
    path.write_bytes(data)
    return str(path)


def test_what_the_check_accepts_the_job_reads(tmp_path):
    for name, data in (("bom.csv", b"\xef\xbb\xbfx_m,y_m,z_m\n0,0,1\n"), ("quoted.csv", b'"x_m","y_m","z_m"\n0,0,1\n'),
                       ("crlf.csv", b"x_m,y_m,z_m\r\n0,0,1\r\n")):
        path = _write(tmp_path, name, data)
        check_cloud_file(path)
        assert read_cloud(path, 1)[0].tolist() == [[0.0, 0.0, 1.0]]
    upper = str(tmp_path / "scan.PARQUET")
    pd.DataFrame({"x_m": [0.0], "y_m": [0.0], "z_m": [1.0]}).to_parquet(upper)
    check_cloud_file(upper)
    assert read_cloud(upper, 1)[0].tolist() == [[0.0, 0.0, 1.0]]


def test_what_the_job_could_not_read_is_refused_by_the_check(tmp_path):
    path = _write(tmp_path, "spaced.csv", b"x_m, y_m, z_m\n0,0,1\n")  # pandas names the columns ' y_m', ' z_m'
    with pytest.raises(ConfigError, match="no column y_m"):
        check_cloud_file(path)
    with pytest.raises(ConfigError, match="no column y_m"):
        read_cloud(path, 1)
