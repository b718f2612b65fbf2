"""The dual-arm scan and envelope stages on a user's cloud file (the documented format: CSV or
Parquet with columns x_m, y_m, z_m in the robot base frame), and bad cloud files."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from capmap.config import canonical, stage_slice
from capmap.config.dualarm import DualArmConfig, cloud_source
from capmap.config.run import RunConfig
from capmap.config.typed import partial, to_doc
from capmap.dualarm.build import scan_settings
from capmap.dualarm.scene.cloud import uncovered
from capmap.dualarm.scene.solids import scan
from capmap.dualarm.scene_file import load_scene
from capmap.dualarm.tables import envelope_from
from capmap.errors import ConfigError
from capmap.io import datasets
from capmap.stages.dualarm import stage_dualarm_envelope, stage_dualarm_scan, stage_dualarm_unknown
from tests.dualarm.conftest import SECTION
from tests.scenario import ROOT

SCENE = str(ROOT / SECTION["scene"])


def _slice(cloud: dict) -> str:
    """The envelope stage's slice (a superset of the scan's) of the dual-arm section with this cloud."""
    da = DualArmConfig.from_doc({**SECTION, "scene": SCENE, "cloud": cloud})
    cfg = partial(RunConfig, json.loads(canonical({"dualarm": to_doc(da)})))
    return canonical(stage_slice(cfg, "dualarm_envelope"))


@pytest.fixture(scope="module")
def user_cloud(tmp_path_factory):
    """A scan of the scene written as a user's CSV file (coarse, from the default viewpoints)."""
    _, scan_cfg, _ = cloud_source(SECTION)
    settings = scan_settings(scan_cfg)
    pts, view = scan(load_scene(SCENE), settings, np.random.default_rng(5))
    path = tmp_path_factory.mktemp("cloud") / "scan.csv"
    pd.DataFrame(pts, columns=["x_m", "y_m", "z_m"]).assign(intensity=1.0, viewpoint=view).to_csv(path, index=False)
    return path, pts, {"file": str(path), "viewpoints_m": settings.viewpoints.tolist()}


def test_a_user_cloud_file_is_fitted_and_covered(user_cloud, tmp_path):
    path, pts, cloud_doc = user_cloud
    stage_dualarm_scan(str(tmp_path / "cloud.parquet"), _slice(cloud_doc))
    cloud = datasets.read(tmp_path / "cloud.parquet")
    assert np.allclose(cloud[["x_m", "y_m", "z_m"]].to_numpy(), pts)  # the file's points, unchanged
    assert cloud.attrs["capmap"]["source"] == f"file {path}, 3 viewpoints"
    stage_dualarm_envelope(str(tmp_path / "cloud.parquet"), str(tmp_path / "env.parquet"), _slice(cloud_doc))
    env, labels = envelope_from(datasets.read(tmp_path / "env.parquet"))
    assert len(uncovered(pts, env)) == 0  # independent of the stage's own check: re-read from Parquet
    assert "bulkhead" in set(labels[0]) | set(labels[1])
    # the space the user's cameras did not see: the same as from the synthetic scan of the same points
    sl = canonical(stage_slice(partial(RunConfig, json.loads(canonical({"dualarm": to_doc(DualArmConfig.from_doc(
        {**SECTION, "scene": SCENE, "cloud": cloud_doc}))}))), "dualarm_unknown"))
    stage_dualarm_unknown(str(tmp_path / "cloud.parquet"), str(tmp_path / "env.parquet"), str(tmp_path / "unk.parquet"), sl)
    assert len(datasets.read(tmp_path / "unk.parquet")) > 0


@pytest.mark.parametrize("content, expect", [
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe", "cannot be read"),
    (b"x,y,z\n0,0,0\n", "no column x_m"),
    (b"x_m,y_m,z_m\n0,0,0\nnan,0,0\n", "1 points are not finite"),
    (b"x_m,y_m,z_m\n0,0,0\n1,abc,0\n", "x_m, y_m, z_m"),
    (b"x_m,y_m,z_m,viewpoint\n0,0,0,0\n1,0,0,3\n", "column viewpoint must index dualarm.cloud.viewpoints_m"),
])
def test_bad_cloud_files_are_one_line_errors(tmp_path, content, expect):
    bad = tmp_path / "bad.csv"
    bad.write_bytes(content)
    with pytest.raises(ConfigError) as err:
        stage_dualarm_scan(str(tmp_path / "cloud.parquet"), _slice({"file": str(bad), "viewpoints_m": [[0, 0, 1]]}))
    msg = str(err.value)
    assert "dualarm.cloud.file" in msg and expect in msg and "\n" not in msg
    assert not (tmp_path / "cloud.parquet").exists()
